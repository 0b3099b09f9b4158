#include "ui/main_window.h"

#include <QActionGroup>
#include <QApplication>
#include <QCloseEvent>
#include <QDesktopServices>
#include <QDir>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QInputDialog>
#include <QKeyEvent>
#include <QLabel>
#include <QLineEdit>
#include <QMenu>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QScrollArea>
#include <QSettings>
#include <QStandardPaths>
#include <QStatusBar>
#include <QTimer>
#include <QUrl>
#include <QHBoxLayout>
#include <QVBoxLayout>

#include <cmath>

#include "app/console/console_session.h"
#include "app/data/data_files.h"
#include "app/log/log_player.h"
#include "ui/background_jobs.h"
#include "ui/connect_dialog.h"
#include "ui/console_monitor.h"
#include "ui/icons.h"
#include "ui/limit_spin_box.h"
#include "ui/link_panel.h"
#include "ui/live_plots.h"
#include "ui/robot_connection.h"
#include "ui/robot_feed.h"
#include "ui/scene_view.h"
#include "ui/status_fields.h"

namespace sp {

namespace {

QString qs(const std::string& s) { return QString::fromStdString(s); }

ConsoleSessionOptions toSessionOptions(const ConsoleOptions& o, const QString& logDir) {
  ConsoleSessionOptions s;
  s.world = o.world.toStdString();
  s.params = o.params.toStdString();
  for (const QString& v : o.overrides) s.overrides.push_back(v.toStdString());
  s.connectTo = o.connectTo.toStdString();
  s.token = o.token.toStdString();
  s.log = o.log;
  s.logDir = logDir.toStdString();
  s.rtf = o.rtf;
  s.delay = o.delay;
  s.perturbSeed = o.perturbSeed;
  s.ground = o.ground.toStdString();
  s.ghost = o.ghost;
  s.calibrate = o.calibrate;
  return s;
}

}  // namespace

MainWindow::MainWindow(ConsoleOptions options, ConsoleJobs jobs, QWidget* parent)
    : QMainWindow(parent),
      options_(std::move(options)),
      logDir_(options_.logDir.isEmpty() ? QStandardPaths::writableLocation(QStandardPaths::GenericDataLocation) +
                                              QStringLiteral("/SimPartner/sessions")
                                        : options_.logDir),
      session_(std::make_unique<ConsoleSession>(toSessionOptions(options_, logDir_))) {
  setWindowIcon(appIcon());
  setWindowTitle(tr("SimPartner"));
  // Object names let QSettings restore the docks and toolbars by name.
  setObjectName(QStringLiteral("SimPartnerMainWindow"));

  buildCentral();
  buildFeeds();
  buildPlots();
  buildMenus();
  buildContext();
  // The right docks run the window's full height; the plots sit under the
  // 3D view only (defaultLayout()).
  setCorner(Qt::BottomRightCorner, Qt::RightDockWidgetArea);
  setCorner(Qt::TopRightCorner, Qt::RightDockWidgetArea);
  for (std::unique_ptr<ConsoleJob>& job : jobs) installJob(std::move(job));
  status_ = new StatusFields(statusBar());
  stateChanged();

  startPanelTimer();
  // Esc is the e-stop wherever the focus is, dialogs included: an
  // application-wide filter sees the key before any widget can take it.
  qApp->installEventFilter(this);

  restoreLayout();
  refreshStatus();
}

void MainWindow::buildCentral() {
  auto* central = new QWidget;
  auto* layout = new QVBoxLayout(central);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->setSpacing(0);
  banner_ = new QLabel;
  banner_->setObjectName(QStringLiteral("banner"));
  banner_->setWordWrap(true);
  banner_->setStyleSheet(QStringLiteral("QLabel { background: #c62828; color: white; font-weight: bold; padding: 6px; }"));
  // The way out of a diverged twin or a robot off the terrain, beside the
  // banner that says so (it was only in the Robot menu).
  bannerReset_ = new QPushButton(tr("Reset to the start"));
  bannerReset_->setObjectName(QStringLiteral("bannerReset"));
  bannerReset_->setToolTip(tr("Robot ▸ Reset to the start: the stand-in restarts with the robot where the world puts it"));
  bannerReset_->setFocusPolicy(Qt::NoFocus);
  connect(bannerReset_, &QPushButton::clicked, this, [this] { emit context_->resetRequested(); });
  bannerRow_ = new QWidget;
  auto* bannerLayout = new QHBoxLayout(bannerRow_);
  bannerLayout->setContentsMargins(0, 0, 0, 0);
  bannerLayout->setSpacing(0);
  bannerLayout->addWidget(banner_, 1);
  bannerLayout->addWidget(bannerReset_);
  bannerRow_->hide();
  scene_ = new SceneView;
  scene_->setFocusPolicy(Qt::StrongFocus);
  scene_->setToolTip(tr("Drag to orbit, wheel to zoom, right-drag to pan. Keys: arrows or WASD drive, Space stops, F follows, Esc e-stops."));
  staleLabel_ = new QLabel;
  staleLabel_->setObjectName(QStringLiteral("staleLabel"));
  staleLabel_->setStyleSheet(QStringLiteral("QLabel { background: #616161; color: white; font-weight: bold; padding: 4px; }"));
  staleLabel_->hide();
  layout->addWidget(bannerRow_);
  layout->addWidget(staleLabel_);
  layout->addWidget(scene_, 1);
  setCentralWidget(central);
}

void MainWindow::buildFeeds() {
  // The live link, the ghost and the switch the views draw from.
  connection_ = new RobotConnection(this);
  liveFeed_ = new LiveLinkFeed(connection_, session_.get(), this);
  ghostFeed_ = new GhostFeed(session_.get(), this);
  feeds_ = new FeedSwitch(liveFeed_, this);
  background_ = new BackgroundJobs(this);
  monitor_ = new ConsoleMonitor(connection_, liveFeed_, session_.get(), this);
  connect(monitor_, &ConsoleMonitor::changed, this, &MainWindow::stateChanged);
  connect(monitor_, &ConsoleMonitor::filesDiffer, this, [this](const QString& text) { context_->event(QStringLiteral("link"), text); });
  connect(liveFeed_, &RobotFeed::frame, this, [this](const RobotFrame& f) {
    context_->setMeasuredPositions(f.jointPositions);
    if (const std::optional<GhostError>& e = liveFeed_->lastPrediction()) errorPlot_->addSample(e->time, e->position, e->heading);
  });
  connect(feeds_, &FeedSwitch::frame, this, &MainWindow::onShownFrame);
  connect(feeds_, &FeedSwitch::laser, this, [this](const LaserFrame& scan) {
    scene_->setLaser(scan.angleMin, scan.angleStep, scan.ranges);
    laserPlot_->setScan(scan.angleMin, scan.angleStep, scan.ranges);
  });
  connect(feeds_, &FeedSwitch::terrain, this, [this](const HeightGrid& grid) {
    // The whole grid as one patch: the mesh updated in place.
    scene_->applyTerrainPatch(TerrainPatchCmd{0, 0, grid.columns, grid.rows, grid.heights});
    scene_->finishTerrainEdit();
  });
  connect(feeds_, &FeedSwitch::worldChanged, this, [this] { onFeedSwitched(feeds_->current()); });
  connect(feeds_, &FeedSwitch::switched, this, &MainWindow::onFeedSwitched);
  connect(scene_, &SceneView::frameStarting, this, [this] {
    if (scene_->ghostVisible() && feeds_->showingLive()) ghostFeed_->poll();
  });
  connect(ghostFeed_, &RobotFeed::frame, this,
          [this](const RobotFrame& f) { scene_->setGhostState(f.base, f.jointPositions); });
  connect(ghostFeed_, &GhostFeed::trail, scene_, &SceneView::setGhostTrail);
  connect(ghostFeed_, &GhostFeed::trailBand, scene_, &SceneView::setGhostTrailBand);
  connect(ghostFeed_, &GhostFeed::region, scene_, &SceneView::setGhostRegion);
  // A departure: in the event list (the session log has it from the
  // telemetry's thread), marked on the ground, said by the banner.
  connect(monitor_, &ConsoleMonitor::departure, this, [this](const Vec3& where, const QString& text) {
    departures_.push_back(where);
    scene_->setDepartureMarks(departures_, true);
    context_->event(QStringLiteral("departure"), text, false);
  });
}

void MainWindow::buildPlots() {
  wheelPlot_ = new WheelForcePlot;
  laserPlot_ = new LaserPlot;
  errorPlot_ = new PredictionErrorPlot;
  // The plots replot from the window's panel timer (see there), not their own.
  QWidget* plots = plotRow({{wheelPlot_, 3}, {laserPlot_, 2}, {errorPlot_, 3}});
  plotsDock_ = new QDockWidget(tr("Plots"), this);
  plotsDock_->setObjectName(QStringLiteral("plotsDock"));
  plotsDock_->setWidget(plots);
  addDockWidget(Qt::BottomDockWidgetArea, plotsDock_);
}

void MainWindow::buildContext() {
  ConsoleContext::Parts parts;
  parts.host = this;
  parts.session = session_.get();
  parts.connection = connection_;
  parts.feeds = feeds_;
  parts.ghost = ghostFeed_;
  parts.state = &monitor_->state();
  parts.scene = scene_;
  parts.wheelPlot = wheelPlot_;
  parts.laserPlot = laserPlot_;
  parts.errorPlot = errorPlot_;
  parts.background = background_;
  parts.status = [this](const QString& text, int ms) { showStatus(text, ms); };
  context_ = new ConsoleContext(std::move(parts), this);
  connect(monitor_, &ConsoleMonitor::robotStopped, context_, &ConsoleContext::robotStopped);
}

void MainWindow::startPanelTimer() {
  // Everything around the 3D view is refreshed by one 100 ms timer, in one
  // event-loop pass together with a 3D frame: under software GL every window
  // update composites the whole window, so each widget repainting on its own
  // schedule (measured values at 50 Hz, plots, status) would cost a full
  // composite of its own. Measured: 20.7 -> 28 fps (docs/performance.md).
  auto* panelTimer = new QTimer(this);
  connect(panelTimer, &QTimer::timeout, this, [this] {
    wheelPlot_->tick();
    laserPlot_->tick();
    // The ghost's error is read at a glance, not followed: 2 Hz (a chart's
    // repaint is a whole-window composite under software GL).
    if (panelTicks_ % 5 == 0) errorPlot_->tick();
    emit context_->panelTick();
    updateStale();
    if (++panelTicks_ % 3 == 0) {
      if (session_->standIn())
        monitor_->state().realTime(session_->realTimeFactor(), session_->targetRealTimeFactor(), monitor_->wallSeconds());
      refreshStatus();
    }
    scene_->update();
  });
  panelTimer->start(100);
}

void MainWindow::restoreLayout() {
  // Later runs restore the operator's own layout; the first run gets ours
  // once the window has its size (docks cannot be sized before).
  resize(1280, 800);
  QSettings settings;
  restoreGeometry(settings.value(QStringLiteral("window/geometry")).toByteArray());
  const bool restored = restoreState(settings.value(QStringLiteral("window/state")).toByteArray());
  QTimer::singleShot(0, this, [this, restored] {
    if (!restored) return defaultLayout();
    // A layout saved while squeezed (a small window, a dock dragged wide)
    // must not come back squeezed: the 3D view is what the console is for.
    if (viewShare() < kMinViewShare) {
      defaultLayout();
      showStatus(tr("The saved layout left the 3D view too small: the default layout is back."), 8000);
    }
  });
}

MainWindow::~MainWindow() {
  qApp->removeEventFilter(this);
  // The jobs first (they hold workers and filters), then the client (it
  // releases the lease), then the robot it talks to.
  jobs_.clear();
  delete background_;
  background_ = nullptr;
  delete liveFeed_;
  liveFeed_ = nullptr;
  delete connection_;
  connection_ = nullptr;
  session_.reset();
}

void MainWindow::growDock(QDockWidget* dock, int height, double share) {
  const int wanted = std::min(height, static_cast<int>(this->height() * share));
  if (dock->height() < wanted) resizeDocks({dock}, {wanted}, Qt::Vertical);
}

ConsoleJob* MainWindow::installJob(std::unique_ptr<ConsoleJob> job) {
  job->setObjectName(job->name());
  job->install(*context_);
  jobs_.push_back(std::move(job));
  return jobs_.back().get();
}


QDockWidget* MainWindow::addDock(const QString& title, const QString& objectName, QWidget* panel, DockPlace place,
                                 bool scrolled) {
  auto* dock = new QDockWidget(title, this);
  dock->setObjectName(objectName);  // QSettings restores docks by name
  if (scrolled) {
    // Scrolled: a panel's plots and lists must not make the window taller
    // or wider than the screen.
    auto* scroll = new QScrollArea;
    scroll->setWidgetResizable(true);
    scroll->setFrameShape(QFrame::NoFrame);
    scroll->setWidget(panel);
    dock->setWidget(scroll);
  } else {
    dock->setWidget(panel);
  }
  if (place == DockPlace::Link) {
    linkDock_ = dock;
    addDockWidget(Qt::RightDockWidgetArea, dock);
    menu(tr("&View"))->addAction(dock->toggleViewAction());
  } else if (place == DockPlace::Side) {
    // The first side dock is the anchor: the link dock under it, the others tabs of it.
    if (sideDocks_.empty()) {
      addDockWidget(Qt::RightDockWidgetArea, dock);
      if (linkDock_) splitDockWidget(dock, linkDock_, Qt::Vertical);
    } else {
      tabifyDockWidget(sideDocks_.front(), dock);
      sideDocks_.front()->raise();
    }
    sideDocks_.push_back(dock);
    menu(tr("&View"))->insertAction(menuAnchors_[tr("&View")], dock->toggleViewAction());
  } else {
    tabifyDockWidget(plotsDock_, dock);
    plotsDock_->raise();
    bottomDocks_.push_back(dock);
  }
  return dock;
}

QMenu* MainWindow::menu(const QString& title) {
  for (QAction* a : menuBar()->actions())
    if (a->menu() && a->text() == title) return a->menu();
  return menuBar()->addMenu(title);
}

void MainWindow::addMenuAction(const QString& title, QAction* action) {
  QMenu* m = menu(title);
  const auto anchor = menuAnchors_.find(title);
  m->insertAction(anchor == menuAnchors_.end() ? nullptr : anchor->second, action);
}

double MainWindow::viewShare() const {
  const double window = static_cast<double>(width()) * height();
  return window > 0 ? static_cast<double>(scene_->width()) * scene_->height() / window : 0;
}

void MainWindow::defaultLayout() {
  // The jobs' side docks (tabs) over the link on the right, full height; the
  // plots under the 3D view only. At 1280x800 the view gets over half the
  // window. Every dock is taken out first: re-adding one out of a tab group
  // can leave another in the group (the link dock ended up a tab of the
  // controls).
  std::vector<QDockWidget*> docks = sideDocks_;
  if (linkDock_) docks.push_back(linkDock_);
  docks.push_back(plotsDock_);
  docks.insert(docks.end(), bottomDocks_.begin(), bottomDocks_.end());
  for (QDockWidget* dock : docks) {
    removeDockWidget(dock);
    dock->setFloating(false);
  }
  if (!sideDocks_.empty()) {
    addDockWidget(Qt::RightDockWidgetArea, sideDocks_.front());
    if (linkDock_) splitDockWidget(sideDocks_.front(), linkDock_, Qt::Vertical);
    for (size_t i = 1; i < sideDocks_.size(); ++i) tabifyDockWidget(sideDocks_.front(), sideDocks_[i]);
  } else if (linkDock_) {
    addDockWidget(Qt::RightDockWidgetArea, linkDock_);
  }
  addDockWidget(Qt::BottomDockWidgetArea, plotsDock_);
  for (QDockWidget* dock : bottomDocks_) tabifyDockWidget(plotsDock_, dock);
  for (QDockWidget* dock : docks) dock->show();
  if (!sideDocks_.empty()) sideDocks_.front()->raise();
  plotsDock_->raise();
  emit context_->layoutReset();  // a job hides what it shows only on demand
  if (!sideDocks_.empty()) resizeDocks({sideDocks_.front()}, {320}, Qt::Horizontal);
  if (!sideDocks_.empty() && linkDock_)
    resizeDocks({sideDocks_.front(), linkDock_}, {height() / 2, height() / 2}, Qt::Vertical);
  resizeDocks({plotsDock_}, {178}, Qt::Vertical);
}

void MainWindow::buildMenus() {
  QMenu* file = menu(tr("&File"));
  file->addAction(tr("Open &world…"), QKeySequence::Open, this, [this] {
    const QString current = session_->world() ? qs(session_->world()->file) : options_.world;
    const QString path = QFileDialog::getOpenFileName(this, tr("Open world"), QFileInfo(current).path(),
                                                      tr("World files (*.world.xml);;XML files (*.xml)"));
    if (!path.isEmpty()) openWorld(path);
  });
  // The jobs' File items (session logs, ...) go here, before Open robot.
  menuAnchors_[tr("&File")] = file->addAction(tr("Open &robot…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open robot"), QString::fromStdString(dataSubfolder("robots")),
                                                      tr("Robot files (*.xml)"));
    if (!path.isEmpty()) openRobot(path);
  });
  file->addSeparator();
  file->addAction(tr("Add &note to the log…"), QKeySequence(Qt::CTRL | Qt::Key_N), this, [this] {
    bool ok = false;
    const QString text = QInputDialog::getText(this, tr("Note"), tr("Note for the session log:"), QLineEdit::Normal, {}, &ok);
    if (ok && !text.trimmed().isEmpty()) addNote(text.trimmed());
  });
  file->addAction(tr("Open &log folder"), this, [this] {
    const QString dir = logPath().isEmpty() ? logDir_ : QFileInfo(logPath()).absolutePath();
    QDir().mkpath(dir);
    if (!QDesktopServices::openUrl(QUrl::fromLocalFile(dir)))
      QMessageBox::information(this, tr("Log folder"), tr("The session logs are in\n%1").arg(dir));
  });
  file->addSeparator();
  file->addAction(tr("&Quit"), QKeySequence::Quit, this, &MainWindow::requestQuit);

  menu(tr("&Robot"));  // the link job's items

  QMenu* view = menu(tr("&View"));
  QAction* follow = view->addAction(tr("&Follow the robot"));
  follow->setCheckable(true);
  follow->setChecked(true);
  follow->setShortcut(QKeySequence(Qt::Key_F));
  follow->setShortcutContext(Qt::WidgetWithChildrenShortcut);
  scene_->addAction(follow);
  connect(follow, &QAction::toggled, scene_, &SceneView::setFollow);
  // Camera presets beside follow (issue 59): chase behind the robot, top
  // down, free; the follow action shows whether the camera follows.
  QMenu* cameras = view->addMenu(tr("&Camera"));
  auto* group = new QActionGroup(this);
  const std::pair<QString, SceneView::Camera> presets[] = {{tr("&Follow"), SceneView::Camera::Follow},
                                                           {tr("&Chase (behind the robot)"), SceneView::Camera::Chase},
                                                           {tr("&Top (from above)"), SceneView::Camera::Top},
                                                           {tr("F&ree"), SceneView::Camera::Free}};
  for (const auto& [name, preset] : presets) {
    QAction* a = cameras->addAction(name);
    a->setCheckable(true);
    a->setChecked(preset == scene_->camera());
    a->setObjectName(QStringLiteral("camera%1").arg(static_cast<int>(preset)));
    group->addAction(a);
    connect(a, &QAction::triggered, scene_, [this, p = preset] { scene_->setCamera(p); });
  }
  connect(scene_, &SceneView::cameraChanged, this, [follow, cameras](SceneView::Camera c) {
    const QSignalBlocker block(follow);
    follow->setChecked(c != SceneView::Camera::Free);
    for (QAction* a : cameras->actions())
      a->setChecked(a->objectName() == QStringLiteral("camera%1").arg(static_cast<int>(c)));
  });
  QAction* reset = view->addAction(tr("&Reset view"), scene_, &SceneView::resetView);
  reset->setShortcut(QKeySequence(Qt::Key_Home));
  QAction* beams = view->addAction(tr("Laser &beams"));
  beams->setCheckable(true);
  beams->setChecked(true);
  connect(beams, &QAction::toggled, scene_, &SceneView::setLaserVisible);
  ghostAction_ = view->addAction(tr("&Ghost: the robot predicted over the link's delay"));
  ghostAction_->setCheckable(true);
  ghostAction_->setChecked(options_.ghost);
  ghostAction_->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_G));
  ghostAction_->setToolTip(tr("A translucent robot where the robot will be when a command sent now arrives, "
                              "and its path over the next seconds under the commands sent"));
  connect(ghostAction_, &QAction::toggled, this, [this](bool on) {
    ghostFeed_->reset();  // shown again: the newest view, whatever was polled before
    if (feeds_->showingLive()) scene_->setGhostVisible(on);
    else ghostShownBeforeReplay_ = on;
  });
  scene_->setGhostVisible(ghostAction_->isChecked());
  view->addSeparator();
  // The jobs' side docks are listed before the plots and the link.
  menuAnchors_[tr("&View")] = plotsDock_->toggleViewAction();
  view->addAction(plotsDock_->toggleViewAction());

  menu(tr("&Help"));  // the jobs' items (the drive keys, ...)
}

QString MainWindow::start() {
  if (const std::string error = session_->start(); !error.empty()) return qs(error);
  sessionChanged();
  for (const auto& job : jobs_)
    if (QString error = job->start(); !error.isEmpty()) return error;
  return {};
}

void MainWindow::sessionChanged() {
  if (session_->worldVersion() != shownWorld_) showWorld(*session_->world(), true);
  const std::string error = session_->logError();
  if (!error.empty()) showStatus(tr("session log: %1").arg(qs(error)), 0);
  emit context_->sessionChanged();
}

void MainWindow::restarted(bool clear) {
  if (clear) clearFrames();
  sessionChanged();
}

void MainWindow::showWorld(const WorldModel& world, bool fresh) {
  shownWorld_ = session_->worldVersion();
  const TerrainSpec& t = world.terrain;
  monitor_->state().terrain(t.kind == TerrainSpec::Kind::Heightfield, t.grid.width, t.grid.depth);
  if (feeds_->showingLive()) {
    scene_->setWorld(world);
    status_->showTerrain(t, false, state().config().edgeWarning);
  }
  if (fresh) {
    for (const SensorSpec& sensor : world.robots.empty() ? std::vector<SensorSpec>{} : world.robots[0].model.sensors)
      if (sensor.type == SensorType::Laser) {
        laserPlot_->setMaxRange(sensor.maxRange);
        laserPlot_->setRangeLimits(sensor.minRange, sensor.maxRange);
        break;
      }
    if (state().connected()) {
      const net::RobotClientStats stats = connection_->stats();
      monitor_->state().filesMismatch(session_->filesMismatch(stats.robotWorldHash, stats.robotRobotHash));
    }
    clearFrames();
    QString title = tr("SimPartner — %1").arg(QFileInfo(qs(world.file)).fileName());
    if (session_->remote()) title += tr(" — robot at %1:%2").arg(qs(session_->endpoint().host)).arg(session_->endpoint().port);
    setWindowTitle(title);
  }
  emit context_->worldChanged(world, fresh);
  stateChanged();
}

void MainWindow::clearFrames() {
  wheelPlot_->clear();
  errorPlot_->clear();
  ghostFeed_->reset();
  liveFeed_->clear();
  monitor_->state().clearFrames();
}

QString MainWindow::openWorld(const QString& path, bool quiet) {
  const bool remote = session_->remote();
  if (const std::string error = session_->openWorld(path.toStdString()); !error.empty()) {
    if (!quiet) context_->showError(remote ? tr("Cannot open the world") : tr("Cannot open the world or start the stand-in on it"), qs(error));
    return qs(error);
  }
  if (remote) showWorld(*session_->world(), true);  // the remote robot runs in its own world: only the drawing changes
  else sessionChanged();
  showStatus(tr("opened %1").arg(path), 5000);
  return {};
}

QString MainWindow::openRobot(const QString& path, bool quiet) {
  const bool remote = session_->remote();
  if (const std::string error = session_->openRobot(path.toStdString()); !error.empty()) {
    if (!quiet) context_->showError(tr("Cannot open the robot"), qs(error));
    return qs(error);
  }
  if (remote) showWorld(*session_->world(), true);
  else sessionChanged();
  showStatus(tr("opened %1").arg(path), 5000);
  return {};
}

QString MainWindow::startBranch(const QString& logPath, const BranchPoint& point, bool quiet) {
  connection_->close();
  if (const std::string error = session_->branchFrom(logPath.toStdString(), point); !error.empty()) {
    emit context_->sessionChanged();  // back to the robot it had
    if (!quiet) context_->showError(tr("Simulate from here"), qs(error));
    return qs(error);
  }
  const double time = static_cast<double>(point.step) * point.logged.params.step;
  context_->event(QStringLiteral("note"), tr("branch of %1 at t = %2 s%3")
                                        .arg(logPath)
                                        .arg(time, 0, 'f', 3)
                                        .arg(point.reconstructed ? tr(" (reconstructed from telemetry)") : QString()));
  clearFrames();
  sessionChanged();
  return {};
}

void MainWindow::addNote(const QString& text) {
  session_->note(text.toStdString());
  emit context_->eventShown(tr("note: %1").arg(text));
  showStatus(tr("note logged"), 3000);
}

void MainWindow::onShownFrame(const RobotFrame& f) {
  scene_->setRobotState(f.base, f.jointPositions);
  std::vector<NamedPose> objects;
  for (const ObjectReadout& o : f.objects) objects.push_back({o.name, o.pose});
  scene_->setObjectPoses(objects);
  wheelPlot_->addSample(f.time, f.wheelNormal);
  if (!feeds_->showingLive()) status_->showReplayTime(f.time);
}

void MainWindow::onFeedSwitched(RobotFeed* feed) {
  const bool live = feed == liveFeed_;
  if (!live) {
    if (!state().replaying()) ghostShownBeforeReplay_ = scene_->ghostVisible();
    const WorldModel* world = feed->shownWorld();
    if (world) {
      scene_->setWorld(*world);
      status_->showTerrain(world->terrain, true, state().config().edgeWarning);
    }
    scene_->setGhostVisible(false);
    wheelPlot_->clear();
    monitor_->state().replay(feed->label().toStdString());
  } else if (state().replaying()) {
    monitor_->state().replay({});
    showWorld(*session_->world(), false);
    scene_->setGhostVisible(ghostShownBeforeReplay_);
    wheelPlot_->clear();
  }
  monitor_->notify();
  refreshStatus();
}

void MainWindow::stateChanged() {
  const ConsoleState& now = state();
  QStringList lines;
  for (const std::string& line : now.bannerLines()) lines << qs(line);
  banner_->setText(lines.join(QLatin1Char('\n')));
  banner_->setVisible(!lines.isEmpty());
  bannerRow_->setVisible(!lines.isEmpty());
  const bool stuck = !now.healthReport().empty() || (now.edgeDistance() && *now.edgeDistance() < 0);
  bannerReset_->setVisible(stuck && !now.replaying() && session_->standIn());
  // Red for an alarm (the latch's colour), amber for a warning, blue for
  // a replay shown without alarms.
  const char* background = now.bannerAlarm() ? "#c62828" : now.replaying() ? "#1565c0" : "#e65100";
  banner_->setStyleSheet(
      QStringLiteral("QLabel { background: %1; color: white; font-weight: bold; padding: 6px; }").arg(QLatin1String(background)));
  banner_->setProperty("alarm", now.bannerAlarm());
  if (const bool on = !now.departureText().empty(); on != departureOn_) {
    departureOn_ = on;
    scene_->setDepartureMarks(departures_, on);
  }
  emit context_->stateChanged();
}

void MainWindow::updateStale() {
  monitor_->tick();
  const QString text = qs(state().staleText(monitor_->wallSeconds()));
  staleLabel_->setText(text);
  staleLabel_->setVisible(!text.isEmpty());
  if (const bool grey = !text.isEmpty(); grey != scene_->stale()) {
    scene_->setStale(grey);
    refreshStatus();
  }
}

void MainWindow::refreshStatus() {
  status_->refresh(state(), *session_, *liveFeed_);
}

bool MainWindow::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() == QEvent::KeyPress && static_cast<QKeyEvent*>(event)->key() == Qt::Key_Escape) {
    // An open list (a combo box's) takes its Esc to close: a replay's
    // signal list closed with Esc e-stopped the live robot.
    QWidget* popup = QApplication::activePopupWidget();
    if (popup && !qobject_cast<QMenu*>(popup)) return QMainWindow::eventFilter(watched, event);
    // A menu open, or the menu bar taking keys, is closed as the robot is
    // stopped: left open, the next keystrokes went into it (and wrote a
    // junk note into the session log).
    for (int i = 0; i < 8; ++i)  // a submenu over its menu: each closes
      if (auto* menu = qobject_cast<QMenu*>(QApplication::activePopupWidget())) menu->close();
    if (menuBar()->activeAction()) menuBar()->setActiveAction(nullptr);
    if (menuBar()->hasFocus()) setFocus();
    if (!static_cast<QKeyEvent*>(event)->isAutoRepeat()) context_->emergencyStop();
    return true;
  }
  return QMainWindow::eventFilter(watched, event);
}

void MainWindow::showStatus(const QString& text, int ms) {
  QStatusBar* bar = statusBar();
  bar->setToolTip(text);
  if (text.isEmpty()) {
    bar->clearMessage();
    return;
  }
  // A message wider than the room left of the fields runs under them
  // (issue 59): elided to that room, the whole text in the tooltip and,
  // when it does not fit, in the event list too.
  int fields = 0;
  for (QWidget* w : bar->findChildren<QWidget*>(QString(), Qt::FindDirectChildrenOnly))
    if (w->isVisible() && w->property("permanentField").toBool()) fields += w->width() + 6;
  const int room = std::max(80, bar->width() - fields - 24);
  const QString shown = bar->fontMetrics().elidedText(text, Qt::ElideRight, room);
  if (shown != text) context_->event(QStringLiteral("status"), text, false);
  bar->showMessage(shown, ms);
}

double MainWindow::robotSpeed() const {
  const std::optional<net::TelemetryMsg>& t = liveFeed_->lastTelemetry();
  if (!t || t->baseVelocity.size() < 2) return 0;
  return std::hypot(t->baseVelocity[0], t->baseVelocity[1]);
}

void MainWindow::requestQuit() {
  // Holding control of a moving robot, a quit would leave it to the
  // deadman: the operator chooses (issue 59: Ctrl+Q quit at once).
  if (state().leaseHeld() && !state().latched() && robotSpeed() > 0.05) {
    if (!context_->confirm(QMessageBox::Warning, tr("Quit"),
                           tr("You hold control of a robot moving at %1 m/s.\n\nQuitting now leaves it to its "
                              "deadman, which stops it once the keep-alives stop.")
                               .arg(robotSpeed(), 0, 'f', 2),
                           QStringLiteral("quitConfirm"), tr("Stop the robot and quit")))
      return;
    context_->sendCommand(StopCmd{});
  }
  close();
}

void MainWindow::closeEvent(QCloseEvent* event) {
  QSettings settings;
  settings.setValue(QStringLiteral("window/geometry"), saveGeometry());
  settings.setValue(QStringLiteral("window/state"), saveState());
  event->accept();
}

const ConsoleState& MainWindow::state() const { return monitor_->state(); }
QString MainWindow::ghostStatus() const { return status_->ghostText(); }
QString MainWindow::bannerText() const { return banner_->isVisible() ? banner_->text() : QString(); }
QString MainWindow::logPath() const { return qs(session_->logPath()); }
const std::optional<net::TelemetryMsg>& MainWindow::lastTelemetry() const { return liveFeed_->lastTelemetry(); }
int64_t MainWindow::telemetryReceived() const { return liveFeed_->telemetryCount(); }
int64_t MainWindow::laserReceived() const { return liveFeed_->laserCount(); }
double MainWindow::realTimeFactor() const { return session_->realTimeFactor(); }

void MainWindow::emergencyStop() { context_->emergencyStop(); }

}  // namespace sp
