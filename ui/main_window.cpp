#include "ui/main_window.h"

#include <QApplication>
#include <QCloseEvent>
#include <QDesktopServices>
#include <QDir>
#include <QDialog>
#include <QDialogButtonBox>
#include <QDateTime>
#include <QTreeWidget>
#include <QDockWidget>
#include <QFile>
#include <QFileDialog>
#include <QFileInfo>
#include <QInputDialog>
#include <QAbstractSpinBox>
#include <QKeyEvent>
#include <QLineEdit>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QTextEdit>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QScrollArea>
#include <QSettings>
#include <QSplitter>
#include <QStandardPaths>
#include <QStatusBar>
#include <QTimer>
#include <QUrl>
#include <QVBoxLayout>

#include <cmath>

#include "app/console/console_session.h"
#include "app/log/session_recorder.h"
#include "ui/connect_dialog.h"
#include "ui/jobs/drive/control_panel.h"
#include "ui/link_panel.h"
#include "ui/limit_spin_box.h"
#include "ui/live_plots.h"
#include "ui/robot_connection.h"
#include "ui/robot_feed.h"
#include "ui/jobs/replay/replay_panel.h"
#include "ui/scene_view.h"
#include "ui/jobs/sequence/sequence_panel.h"
#include "ui/jobs/terrain/terrain_panel.h"

namespace sp {

namespace {

QString qs(const std::string& s) { return QString::fromStdString(s); }

QString defaultSessionsDir() {
  return QStandardPaths::writableLocation(QStandardPaths::GenericDataLocation) + QStringLiteral("/SimPartner/sessions");
}

ConsoleSessionOptions toSessionOptions(const ConsoleOptions& o) {
  ConsoleSessionOptions s;
  s.world = o.world.toStdString();
  s.params = o.params.toStdString();
  for (const QString& v : o.overrides) s.overrides.push_back(v.toStdString());
  s.connectTo = o.connectTo.toStdString();
  s.token = o.token.toStdString();
  s.log = o.log;
  s.logDir = (o.logDir.isEmpty() ? defaultSessionsDir() : o.logDir).toStdString();
  s.rtf = o.rtf;
  s.delay = o.delay;
  s.ghost = o.ghost;
  return s;
}

}  // namespace

MainWindow::MainWindow(ConsoleOptions options, QWidget* parent)
    : QMainWindow(parent), options_(std::move(options)), session_(std::make_unique<ConsoleSession>(toSessionOptions(options_))) {
  setWindowTitle(tr("SimPartner"));
  // Object names let QSettings restore the docks and toolbars by name.
  setObjectName(QStringLiteral("SimPartnerMainWindow"));

  auto* central = new QWidget;
  auto* layout = new QVBoxLayout(central);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->setSpacing(0);
  banner_ = new QLabel;
  banner_->setObjectName(QStringLiteral("banner"));
  banner_->setWordWrap(true);
  banner_->setStyleSheet(QStringLiteral("QLabel { background: #c62828; color: white; font-weight: bold; padding: 6px; }"));
  banner_->hide();
  scene_ = new SceneView;
  scene_->setFocusPolicy(Qt::StrongFocus);
  scene_->setToolTip(tr("Drag to orbit, wheel to zoom, right-drag to pan. Keys: arrows or WASD drive, Space stops, F follows, Esc e-stops."));
  scene_->installEventFilter(this);
  staleLabel_ = new QLabel;
  staleLabel_->setObjectName(QStringLiteral("staleLabel"));
  staleLabel_->setStyleSheet(QStringLiteral("QLabel { background: #616161; color: white; font-weight: bold; padding: 4px; }"));
  staleLabel_->hide();
  layout->addWidget(banner_);
  layout->addWidget(staleLabel_);
  layout->addWidget(scene_, 1);
  setCentralWidget(central);

  // The views draw what the feed gives; the link dock also talks to the
  // connection itself (it is the live link's control panel).
  connection_ = new RobotConnection(this);
  feed_ = new LiveLinkFeed(connection_, session_.get(), this);
  connect(feed_, &RobotFeed::frame, this, &MainWindow::onFrame);
  connect(scene_, &SceneView::frameStarting, this, &MainWindow::pullGhost);
  connect(feed_, &RobotFeed::laser, this, &MainWindow::onLaser);
  connect(feed_, &RobotFeed::event, this, [this](const QString& kind, const QString& text) {
    link_->appendEvent(text);
    if (kind == QLatin1String("refused") || kind == QLatin1String("error")) statusBar()->showMessage(text, 5000);
  });
  connect(feed_, &RobotFeed::stateChanged, this, [this] { updateBanner(); });
  connect(connection_, &RobotConnection::lease, this, [this](const net::LeaseStateMsg& lease) {
    link_->showLease(lease);
    // Losing or giving up control stops the robot: the controls show that.
    if (leaseHeld_ && !lease.yours) controls_->syncToRobot(modelPositions_);
    leaseHeld_ = lease.yours;
    updateTerrainReach();
    updateControlsEnabled();
  });
  connect(connection_, &RobotConnection::connectionChanged, this, [this](net::ConnectionState s, const QString& d) {
    link_->showConnection(s, d);
    connectionState_ = s;
    connectionDetail_ = d;
    if (s == net::ConnectionState::Ready) {
      // The ghost is only as good as the files it is built from.
      const net::RobotClientStats stats = connection_->stats();
      filesMismatch_ = qs(session_->filesMismatch(stats.robotWorldHash, stats.robotRobotHash));
      if (!filesMismatch_.isEmpty()) linkEvent(QStringLiteral("link"), filesMismatch_);
    }
    updateTerrainReach();
    if (s != net::ConnectionState::Ready && leaseHeld_) {
      leaseHeld_ = false;
      controls_->syncToRobot(modelPositions_);
    }
    updateControlsEnabled();
    updateBanner();
  });
  connect(connection_, &RobotConnection::event, this, [this](const net::EventMsg& m) {
    // The robot says why it stopped; the banner repeats it.
    if (m.kind == net::EventKind::Failsafe) failsafeText_ = qs(m.text);
    if (m.kind == net::EventKind::Failsafe || m.kind == net::EventKind::Estop || m.kind == net::EventKind::Rearmed)
      controls_->syncToRobot(modelPositions_);
    updateBanner();
  });

  buildDocks();
  buildMenus();
  updateActions();

  simTime_ = new QLabel;
  rtfLabel_ = new QLabel;
  health_ = new QLabel;
  logLabel_ = new QLabel;
  logLabel_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  for (QLabel* l : {simTime_, rtfLabel_, health_}) l->setMinimumWidth(l->fontMetrics().horizontalAdvance(QStringLiteral("t = 00000.00 s")));
  ghostLabel_ = new QLabel;
  ghostLabel_->setObjectName(QStringLiteral("ghostLabel"));
  statusBar()->addPermanentWidget(ghostLabel_);
  statusBar()->addPermanentWidget(simTime_);
  statusBar()->addPermanentWidget(rtfLabel_);
  statusBar()->addPermanentWidget(health_);
  statusBar()->addPermanentWidget(logLabel_);
  terrainLabel_ = new QLabel;
  terrainLabel_->setObjectName(QStringLiteral("terrainLabel"));
  statusBar()->insertPermanentWidget(0, terrainLabel_);

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
    if (measuredDirty_) {
      controls_->showMeasured(modelPositions_);
      measuredDirty_ = false;
    }
    updateStale();
    if (++panelTicks_ % 3 == 0) refreshStatus();
    scene_->update();
  });
  panelTimer->start(100);

  // Esc is the e-stop wherever the focus is, dialogs included: an
  // application-wide filter sees the key before any widget can take it.
  qApp->installEventFilter(this);

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
      statusBar()->showMessage(tr("The saved layout left the 3D view too small: the default layout is back."), 8000);
    }
  });
  refreshStatus();
}

double MainWindow::viewShare() const {
  const double window = static_cast<double>(width()) * height();
  return window > 0 ? static_cast<double>(scene_->width()) * scene_->height() / window : 0;
}

void MainWindow::defaultLayout() {
  // Controls over the link on the right, full height; the plots under the
  // 3D view only. At 1280x800 the view gets over half the window. Every
  // dock is taken out first: re-adding one out of a tab group can leave
  // another in the group (the link dock ended up a tab of the controls).
  const std::initializer_list<QDockWidget*> docks{controlsDock_, sequenceDock_, terrainDock_,
                                                  linkDock_,     plotsDock_,    replayDock_};
  for (QDockWidget* dock : docks) {
    removeDockWidget(dock);
    dock->setFloating(false);
  }
  addDockWidget(Qt::RightDockWidgetArea, controlsDock_);
  splitDockWidget(controlsDock_, linkDock_, Qt::Vertical);
  // The Sequence and Terrain docks tabs behind the controls; the Replay
  // dock one behind the plots, shown only while a log is open (its tab bar
  // costs the view).
  tabifyDockWidget(controlsDock_, sequenceDock_);
  tabifyDockWidget(controlsDock_, terrainDock_);
  addDockWidget(Qt::BottomDockWidgetArea, plotsDock_);
  tabifyDockWidget(plotsDock_, replayDock_);
  for (QDockWidget* dock : docks) dock->show();
  controlsDock_->raise();
  replayDock_->setVisible(replaying_);
  (replaying_ ? replayDock_ : plotsDock_)->raise();
  resizeDocks({controlsDock_}, {320}, Qt::Horizontal);
  resizeDocks({controlsDock_, linkDock_}, {height() / 2, height() / 2}, Qt::Vertical);
  resizeDocks({plotsDock_}, {178}, Qt::Vertical);
}

MainWindow::~MainWindow() {
  qApp->removeEventFilter(this);
  // The client first (it releases the lease), then the robot it talks to.
  delete feed_;
  feed_ = nullptr;
  delete connection_;
  connection_ = nullptr;
  session_.reset();
}

QDockWidget* MainWindow::scrolledDock(const QString& title, const QString& name, QWidget* panel) {
  auto* dock = new QDockWidget(title, this);
  dock->setObjectName(name);  // QSettings restores docks by name
  // Scrolled: a panel's plots and lists must not make the window taller
  // or wider than the screen.
  auto* scroll = new QScrollArea;
  scroll->setWidgetResizable(true);
  scroll->setFrameShape(QFrame::NoFrame);
  scroll->setWidget(panel);
  dock->setWidget(scroll);
  return dock;
}

void MainWindow::buildDocks() {
  controls_ = new ControlPanel;
  connect(controls_, &ControlPanel::command, this, &MainWindow::sendCommand);
  connect(controls_, &ControlPanel::refused, this, [this](const QString& why) {
    statusBar()->showMessage(why, 6000);
    link_->appendEvent(why);
  });
  controls_->setControlsEnabled(false, tr("Take control first (Robot ▸ Take control)"));
  controlsDock_ = new QDockWidget(tr("Controls"), this);
  controlsDock_->setObjectName(QStringLiteral("controlsDock"));
  controlsDock_->setWidget(controls_);
  // The right docks run the window's full height; the plots sit under the
  // 3D view only (defaultLayout()).
  setCorner(Qt::BottomRightCorner, Qt::RightDockWidgetArea);
  setCorner(Qt::TopRightCorner, Qt::RightDockWidgetArea);
  addDockWidget(Qt::RightDockWidgetArea, controlsDock_);

  auto* plots = new QSplitter(Qt::Horizontal);
  wheelPlot_ = new WheelForcePlot;
  laserPlot_ = new LaserPlot;
  errorPlot_ = new PredictionErrorPlot;
  // The plots replot from the window's panel timer (see there), not their own.
  for (LivePlot* p : std::initializer_list<LivePlot*>{wheelPlot_, laserPlot_, errorPlot_}) {
    p->setOwnTimer(false);
    plots->addWidget(p);
  }
  plots->setStretchFactor(0, 3);
  plots->setStretchFactor(1, 2);
  plots->setStretchFactor(2, 3);
  plotsDock_ = new QDockWidget(tr("Plots"), this);
  plotsDock_->setObjectName(QStringLiteral("plotsDock"));
  plotsDock_->setWidget(plots);
  addDockWidget(Qt::BottomDockWidgetArea, plotsDock_);

  link_ = new LinkPanel;
  linkDock_ = new QDockWidget(tr("Link"), this);
  linkDock_->setObjectName(QStringLiteral("linkDock"));
  linkDock_->setWidget(link_);
  splitDockWidget(controlsDock_, linkDock_, Qt::Vertical);

  connect(link_, &LinkPanel::connectRequested, this, &MainWindow::connectToRobot);
  connect(link_, &LinkPanel::disconnectRequested, connection_, &RobotConnection::close);
  connect(link_, &LinkPanel::takeControlRequested, connection_, &RobotConnection::acquireLease);
  connect(link_, &LinkPanel::releaseControlRequested, connection_, &RobotConnection::releaseLease);
  connect(link_, &LinkPanel::estopRequested, this, &MainWindow::emergencyStop);
  connect(link_, &LinkPanel::rearmRequested, this, &MainWindow::rearm);

  terrain_ = new TerrainPanel;
  terrainDock_ = scrolledDock(tr("Terrain"), QStringLiteral("terrainDock"), terrain_);
  tabifyDockWidget(controlsDock_, terrainDock_);
  connect(terrain_, &TerrainPanel::editingChanged, this, [this](bool on) {
    scene_->setTerrainEditing(on);
    if (on) statusBar()->showMessage(tr("Terrain editing: the left button paints; right drag and wheel move the camera"), 8000);
  });
  connect(terrain_, &TerrainPanel::brushRadiusChanged, scene_, &SceneView::setBrushRadius);
  scene_->setBrushRadius(terrain_->brush().radius);
  connect(terrain_, &TerrainPanel::pickRequested, scene_, &SceneView::pickGround);
  connect(scene_, &SceneView::groundPicked, this, [this](const Vec3& g) { terrain_->setFlattenHeight(g.z); });
  connect(scene_, &SceneView::terrainDab, terrain_, &TerrainPanel::dabAt);
  connect(scene_, &SceneView::terrainStrokeEnded, terrain_, &TerrainPanel::endStroke);
  connect(terrain_, &TerrainPanel::strokeEnded, scene_, &SceneView::finishTerrainEdit);
  connect(terrain_, &TerrainPanel::patch, this, &MainWindow::applyTerrainEdit);
  connect(terrain_, &TerrainPanel::openWorldRequested, this, [this](const QString& path) { openWorld(path); });

  sequence_ = new SequencePanel;
  sequenceDock_ = scrolledDock(tr("Sequence"), QStringLiteral("sequenceDock"), sequence_);
  tabifyDockWidget(controlsDock_, sequenceDock_);
  controlsDock_->raise();
  sequence_->setStartProvider([this]() -> std::optional<RehearsalStart> {
    const std::optional<net::TelemetryMsg>& t = lastTelemetry();
    const RobotModel* robot = session_->robot();
    if (!t || !robot) return std::nullopt;
    std::string why;
    std::optional<RehearsalStart> start = startFromTelemetry(*t, *robot, why);
    if (!start) statusBar()->showMessage(tr("Rehearsing from the world's start: %1").arg(qs(why)), 6000);
    return start;
  });
  connect(sequence_, &SequencePanel::sendRequested, connection_, &RobotConnection::sendSequence);
  connect(sequence_, &SequencePanel::abortRequested, connection_, &RobotConnection::abortSequence);
  connect(connection_, &RobotConnection::sequenceState, sequence_, &SequencePanel::onSequenceState);
  sequence_->setGuard(connection_->guard());
  connect(connection_, &RobotConnection::guardTripped, sequence_, &SequencePanel::onGuardTripped);
  connect(sequence_, &SequencePanel::scrubbed, this, [this](const Pose& base, const std::vector<double>& joints) {
    scene_->setRehearsalState(base, joints);
    scene_->setRehearsalVisible(true);
  });
  connect(sequence_, &SequencePanel::pathChanged, this,
          [this](const std::vector<Vec3>& path, const std::vector<Vec3>& envelope) {
            scene_->setRehearsalPath(path);
            scene_->setRehearsalEnvelope(envelope);
            scene_->setRehearsalVisible(!path.empty());
          });
  connect(sequence_, &SequencePanel::logEvent, this,
          [this](const QString& kind, const QString& text) { session_->logEvent(kind.toStdString(), text.toStdString()); });
  connect(sequence_, &SequencePanel::alert, this, [this](const QString& text) {
    link_->appendEvent(text);
    statusBar()->showMessage(text, 10000);
    sequenceDock_->raise();
  });

  replay_ = new ReplayPanel;
  replayDock_ = scrolledDock(tr("Replay"), QStringLiteral("replayDock"), replay_);
  tabifyDockWidget(plotsDock_, replayDock_);
  replayDock_->hide();  // until a log is opened
  plotsDock_->raise();
  connect(replay_, &ReplayPanel::opened, this, [this](const WorldModel& world) {
    QStringList recent = recentLogs();
    const QString path = QFileInfo(qs(replay_->player()->path())).absoluteFilePath();
    recent.removeAll(path);
    recent.prepend(path);
    QSettings().setValue(QStringLiteral("replay/recent"), recent.mid(0, kRecentLogs));
    if (!replaying_) ghostShownBeforeReplay_ = scene_->ghostVisible();
    // The view shows the log's ground: no editing the live terrain meanwhile.
    terrain_->setEditing(false);
    terrain_->setEnabled(false);
    replaying_ = true;
    scene_->setWorld(world);
    scene_->setGhostVisible(false);
    wheelPlot_->clear();
    statusBar()->showMessage(tr("Replaying %1: the live robot goes on unseen; close the replay to see it again")
                                 .arg(QFileInfo(QString::fromStdString(replay_->player()->path())).fileName()));
  });
  connect(replay_, &ReplayPanel::frame, this, [this](const RobotFrame& f) {
    scene_->setRobotState(f.base, f.jointPositions);
    wheelPlot_->addSample(f.time, f.wheelNormal);
    simTime_->setText(tr("replay t = %1 s").arg(formatFixed(f.time, 2)));
  });
  connect(replay_, &ReplayPanel::terrain, this, [this](const HeightGrid& grid) {
    // The whole grid as one patch: the mesh updated in place.
    scene_->applyTerrainPatch(TerrainPatchCmd{0, 0, grid.columns, grid.rows, grid.heights});
    scene_->finishTerrainEdit();
  });
  connect(replay_, &ReplayPanel::laser, this, [this](const LaserFrame& scan) {
    scene_->setLaser(scan.angleMin, scan.angleStep, scan.ranges);
    laserPlot_->setScan(scan.angleMin, scan.angleStep, scan.ranges);
  });
  connect(replay_, &ReplayPanel::branchReady, this,
          [this](const QString& log, std::shared_ptr<const BranchPoint> point) { startBranch(log, *point, false); });
  connect(replay_, &ReplayPanel::failed, this, [this](const QString& message) {
    if (!replay_->isOpen()) replayDock_->hide();  // a log that did not open
    statusBar()->showMessage(message, 10000);
    if (message != tr("Cancelled.")) showLoadErrors(tr("Replay"), message);
  });
  connect(replay_, &ReplayPanel::rehearsalStart, this,
          [this](const RehearsalStart& start, const WorldModel& world, const SimParams& params, const QString& label) {
            sequence_->pinStart(start, world, params, label);
            sequenceDock_->show();
            sequenceDock_->raise();
            statusBar()->showMessage(tr("The Sequence dock rehearses from %1 now").arg(label), 8000);
          });
  connect(replay_, &ReplayPanel::verified, this,
          [this](bool, const QString& verdict) { statusBar()->showMessage(verdict, 15000); });
  connect(replay_, &ReplayPanel::closed, this, [this] {
    replaying_ = false;
    terrain_->setEnabled(true);
    replayDock_->hide();
    showWorld(*session_->world());
    scene_->setGhostVisible(ghostShownBeforeReplay_);
    statusBar()->clearMessage();
  });
}

QString MainWindow::startBranch(const QString& logPath, const BranchPoint& point, bool quiet) {
  const std::string log = logPath.toStdString();
  connection_->close();
  if (const std::string error = session_->branchFrom(log, point); !error.empty()) {
    connectToRobot();
    if (!quiet) showLoadErrors(tr("Simulate from here"), qs(error));
    return qs(error);
  }
  replay_->close();
  const double time = static_cast<double>(point.step) * point.logged.params.step;
  linkEvent(QStringLiteral("note"), tr("branch of %1 at t = %2 s%3")
                                        .arg(logPath)
                                        .arg(time, 0, 'f', 3)
                                        .arg(point.reconstructed ? tr(" (reconstructed from telemetry)") : QString()));
  feed_->clear();
  wheelPlot_->clear();
  sessionChanged();
  return {};
}

QStringList MainWindow::recentLogs() const {
  QStringList logs;
  for (const QString& path : QSettings().value(QStringLiteral("replay/recent")).toStringList())
    if (QFileInfo::exists(path)) logs << path;
  return logs;
}

void MainWindow::showSessionLogs() {
  // The log folder's logs, newest first, with their sizes: open one for
  // replay, or delete old ones (never the one being written).
  QDialog dialog(this);
  dialog.setWindowTitle(tr("Session logs"));
  auto* layout = new QVBoxLayout(&dialog);
  const QString dir = qs(toSessionOptions(options_).logDir);
  auto* where = new QLabel(tr("In %1 (parameter log.keep: how many are kept)").arg(dir), &dialog);
  layout->addWidget(where);
  auto* list = new QTreeWidget(&dialog);
  list->setHeaderLabels({tr("Log"), tr("Size"), tr("Written")});
  list->setRootIsDecorated(false);
  list->setSelectionMode(QAbstractItemView::ExtendedSelection);
  layout->addWidget(list);
  const auto fill = [this, list, dir] {
    list->clear();
    for (const SessionLogFile& f : listSessionLogs(dir.toStdString())) {
      auto* item = new QTreeWidgetItem(list, {QFileInfo(qs(f.path)).fileName(),
                                              QStringLiteral("%1 MB").arg(static_cast<double>(f.bytes) / 1e6, 0, 'f', 1),
                                              QDateTime::fromSecsSinceEpoch(f.modified).toString(Qt::ISODate)});
      item->setData(0, Qt::UserRole, qs(f.path));
      if (qs(f.path) == logPath()) item->setText(0, item->text(0) + tr(" (this session)"));
    }
    for (int c = 0; c < 3; ++c) list->resizeColumnToContents(c);
  };
  fill();
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, &dialog);
  QPushButton* open = buttons->addButton(tr("Replay"), QDialogButtonBox::ActionRole);
  QPushButton* remove = buttons->addButton(tr("Delete…"), QDialogButtonBox::ActionRole);
  layout->addWidget(buttons);
  connect(buttons, &QDialogButtonBox::rejected, &dialog, &QDialog::reject);
  connect(open, &QPushButton::clicked, &dialog, [&] {
    if (QTreeWidgetItem* item = list->currentItem()) {
      openLogInBackground(item->data(0, Qt::UserRole).toString());
      dialog.accept();
    }
  });
  connect(remove, &QPushButton::clicked, &dialog, [&] {
    QStringList paths;
    for (QTreeWidgetItem* item : list->selectedItems())
      if (item->data(0, Qt::UserRole).toString() != logPath()) paths << item->data(0, Qt::UserRole).toString();
    if (paths.isEmpty()) return;
    if (QMessageBox::question(&dialog, tr("Delete session logs"), tr("Delete %n log(s)? This cannot be undone.", "", static_cast<int>(paths.size())),
                              QMessageBox::Yes | QMessageBox::Cancel, QMessageBox::Cancel) != QMessageBox::Yes)
      return;
    for (const QString& p : paths)
      if (const std::string e = deleteSessionLog(p.toStdString()); !e.empty()) QMessageBox::warning(&dialog, tr("Delete"), qs(e));
    fill();
  });
  dialog.resize(640, 400);
  dialog.exec();
}

QString MainWindow::openLog(const QString& path, bool quiet) {
  const QString error = replay_->open(path);
  if (!error.isEmpty()) {
    if (!quiet) showLoadErrors(tr("Open session log"), error);
    return error;
  }
  replayDock_->show();
  replayDock_->raise();
  return {};
}

void MainWindow::openLogInBackground(const QString& path) {
  replayDock_->show();  // its progress row shows the opening, with Cancel
  replayDock_->raise();
  replay_->openInBackground(path);
}

void MainWindow::buildMenus() {
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("Open &world…"), QKeySequence::Open, this, [this] {
    const QString current = session_->world() ? qs(session_->world()->file) : options_.world;
    const QString path = QFileDialog::getOpenFileName(this, tr("Open world"), QFileInfo(current).path(),
                                                      tr("World files (*.world.xml);;XML files (*.xml)"));
    if (!path.isEmpty()) openWorld(path);
  });
  file->addAction(tr("Open session &log…"), QKeySequence(Qt::CTRL | Qt::Key_L), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open session log"), qs(toSessionOptions(options_).logDir),
                                                      tr("Session logs (*.splog);;All files (*)"));
    if (!path.isEmpty()) openLogInBackground(path);
  });
  // The last logs replayed, newest first (settings "replay/recent"); a
  // file gone since is left out when the menu opens.
  QMenu* recent = file->addMenu(tr("&Recent session logs"));
  connect(recent, &QMenu::aboutToShow, this, [this, recent] {
    recent->clear();
    for (const QString& path : recentLogs())
      recent->addAction(QFileInfo(path).fileName(), this, [this, path] { openLogInBackground(path); })->setToolTip(path);
    if (recent->isEmpty()) recent->addAction(tr("(none yet)"))->setEnabled(false);
  });
  recent->setToolTipsVisible(true);
  file->addAction(tr("Session &logs…"), this, [this] { showSessionLogs(); });
  file->addAction(tr("Close replay"), this, [this] { replay_->close(); });
  file->addAction(tr("Open &robot…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open robot"), QStringLiteral("robots"),
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
    const QString dir = logPath().isEmpty() ? qs(toSessionOptions(options_).logDir) : QFileInfo(logPath()).absolutePath();
    QDir().mkpath(dir);
    if (!QDesktopServices::openUrl(QUrl::fromLocalFile(dir)))
      QMessageBox::information(this, tr("Log folder"), tr("The session logs are in\n%1").arg(dir));
  });
  file->addSeparator();
  file->addAction(tr("&Quit"), QKeySequence::Quit, this, &QWidget::close);

  QMenu* robot = menuBar()->addMenu(tr("&Robot"));
  robot->addAction(tr("&Connect to…"), this, &MainWindow::openConnectDialog);
  reconnectAction_ = robot->addAction(tr("&Reconnect"), this, &MainWindow::connectToRobot);
  disconnectAction_ = robot->addAction(tr("&Disconnect"), connection_, &RobotConnection::close);
  robot->addSeparator();
  takeAction_ = robot->addAction(tr("&Take control"), connection_, &RobotConnection::acquireLease);
  releaseAction_ = robot->addAction(tr("Re&lease control"), connection_, &RobotConnection::releaseLease);
  robot->addSeparator();
  // Esc itself is caught by the application filter; the menu shows the key.
  QAction* estop = robot->addAction(tr("&E-stop\tEsc"), this, &MainWindow::emergencyStop);
  estop->setToolTip(tr("Emergency stop"));
  rearmAction_ = robot->addAction(tr("Re-&arm…"), this, &MainWindow::rearm);
  robot->addSeparator();
  resetAction_ = robot->addAction(tr("Re&set to the start"), this, &MainWindow::resetRobot);
  resetAction_->setToolTip(tr("Restart the stand-in with the robot where the world file puts it (logged)"));

  QMenu* view = menuBar()->addMenu(tr("&View"));
  QAction* follow = view->addAction(tr("&Follow the robot"));
  follow->setCheckable(true);
  follow->setChecked(true);
  follow->setShortcut(QKeySequence(Qt::Key_F));
  follow->setShortcutContext(Qt::WidgetWithChildrenShortcut);
  scene_->addAction(follow);
  connect(follow, &QAction::toggled, scene_, &SceneView::setFollow);
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
  connect(ghostAction_, &QAction::toggled, scene_, &SceneView::setGhostVisible);
  scene_->setGhostVisible(ghostAction_->isChecked());
  view->addSeparator();
  for (QDockWidget* dock : {controlsDock_, sequenceDock_, terrainDock_, plotsDock_, linkDock_})
    view->addAction(dock->toggleViewAction());

  QMenu* help = menuBar()->addMenu(tr("&Help"));
  help->addAction(tr("&Keys"), this, [this] {
    QMessageBox::information(this, tr("Keys"),
                             tr("Esc\temergency stop (anywhere)\n"
                                "Up/Down, W/S\tspeed ± 0.05 m/s (3D view focused)\n"
                                "Left/Right, A/D\tarticulation ± 2°\n"
                                "Space\tstop driving\n"
                                "F\tfollow the robot\nHome\treset the view\n"
                                "Ctrl+N\tnote in the session log"));
  });
}

QString MainWindow::start() {
  if (!options_.rules.isEmpty()) {
    FlightRules rules;
    Diagnostics diag;
    if (!loadFlightRules(options_.rules.toStdString(), rules, diag)) return qs(diag.format()).trimmed();
    sequence_->setRules(rules);
  }
  if (!options_.sequence.isEmpty()) {
    QFile f(options_.sequence);
    if (!f.open(QIODevice::ReadOnly) || f.size() > 1 << 20)
      return tr("%1: error: cannot read sequence file (or larger than 1 MiB)").arg(options_.sequence);
    sequence_->setText(QString::fromUtf8(f.readAll()));
  }
  if (const std::string error = session_->start(); !error.empty()) return qs(error);
  sessionChanged();
  if (!options_.replay.isEmpty()) return openLog(options_.replay, true);
  return {};
}

void MainWindow::sessionChanged() {
  const RobotEndpoint& e = session_->endpoint();
  link_->setEndpoint(qs(e.label));
  if (session_->worldVersion() != shownWorld_) showWorld(*session_->world());
  const std::string error = session_->logError();
  if (!error.empty()) statusBar()->showMessage(tr("session log: %1").arg(qs(error)));
  connectToRobot();
}

void MainWindow::connectToRobot() {
  const RobotEndpoint& e = session_->endpoint();
  if (e.port == 0) return;
  net::RobotClientConfig config;
  config.host = e.host;
  config.port = e.port;
  config.token = e.token;
  config.name = QStringLiteral("console@%1").arg(QCoreApplication::applicationPid()).toStdString();
  config.keepaliveInterval = session_->params().linkKeepalive;
  config.commandExpiryMs = static_cast<uint64_t>(std::llround(session_->params().linkCommandExpiry * 1000));
  connection_->open(config);
  if (options_.takeControl) connection_->acquireLease();
}

void MainWindow::showWorld(const WorldModel& world) {
  shownWorld_ = session_->worldVersion();
  if (terrainLabel_) {
    const TerrainSpec& t = world.terrain;
    const bool field = t.kind == TerrainSpec::Kind::Heightfield;
    terrainLabel_->setText(field ? tr("terrain %1 × %2 m").arg(formatFixed(t.grid.width, 1), formatFixed(t.grid.depth, 1))
                                 : tr("terrain: endless plane"));
    terrainLabel_->setToolTip(field ? tr("The heightfield spans x %1..%2 m, y %3..%4 m around its centre; the console warns within %5 m of its edge")
                                          .arg(formatFixed(t.pose.p.x - t.grid.width / 2, 1), formatFixed(t.pose.p.x + t.grid.width / 2, 1),
                                               formatFixed(t.pose.p.y - t.grid.depth / 2, 1), formatFixed(t.pose.p.y + t.grid.depth / 2, 1),
                                               formatFixed(kEdgeWarning, 1))
                                    : QString());
  }
  scene_->setWorld(world);
  sequence_->setWorld(world, session_->params());
  if (terrainWorld_ != shownWorld_) {  // a new world, not the same one shown again after a replay
    terrain_->setWorld(world);
    terrainWorld_ = shownWorld_;
  }
  if (!world.robots.empty()) {
    const RobotModel& robot = world.robots[0].model;
    controls_->setRobot(robot);
    for (const SensorSpec& sensor : robot.sensors)
      if (sensor.type == SensorType::Laser) {
        laserPlot_->setMaxRange(sensor.maxRange);
        laserPlot_->setRangeLimits(sensor.minRange, sensor.maxRange);
        break;
      }
  }
  if (connectionState_ == net::ConnectionState::Ready) {
    const net::RobotClientStats stats = connection_->stats();
    filesMismatch_ = qs(session_->filesMismatch(stats.robotWorldHash, stats.robotRobotHash));
  }
  wheelPlot_->clear();
  errorPlot_->clear();
  ghostVersion_ = -1;
  ghostTrailTime_ = -1;
  feed_->clear();
  QString title = tr("SimPartner — %1").arg(QFileInfo(qs(world.file)).fileName());
  if (!options_.connectTo.isEmpty()) title += tr(" — robot at %1").arg(options_.connectTo);
  setWindowTitle(title);
}

QString MainWindow::openWorld(const QString& path, bool quiet) {
  const bool remote = session_->remote();
  if (const std::string error = session_->openWorld(path.toStdString()); !error.empty()) {
    if (!quiet) showLoadErrors(remote ? tr("Cannot open the world") : tr("Cannot open the world or start the stand-in on it"), qs(error));
    return qs(error);
  }
  if (remote) showWorld(*session_->world());  // the remote robot runs in its own world: only the drawing changes
  else sessionChanged();
  statusBar()->showMessage(tr("opened %1").arg(path), 5000);
  return {};
}

QString MainWindow::openRobot(const QString& path, bool quiet) {
  const bool remote = session_->remote();
  if (const std::string error = session_->openRobot(path.toStdString()); !error.empty()) {
    if (!quiet) showLoadErrors(tr("Cannot open the robot"), qs(error));
    return qs(error);
  }
  if (remote) showWorld(*session_->world());
  else sessionChanged();
  statusBar()->showMessage(tr("opened %1").arg(path), 5000);
  return {};
}

void MainWindow::showLoadErrors(const QString& title, const QString& text) {
  QMessageBox box(QMessageBox::Warning, title, title + tr(". The running session is unchanged."), QMessageBox::Ok, this);
  box.setDetailedText(text);
  box.setInformativeText(text.section(QLatin1Char('\n'), 0, 4));
  box.exec();
}

void MainWindow::addNote(const QString& text) {
  session_->note(text.toStdString());
  link_->appendEvent(tr("note: %1").arg(text));
  statusBar()->showMessage(tr("note logged"), 3000);
}

void MainWindow::emergencyStop() {
  connection_->estop(tr("operator e-stop"));
  linkEvent(QStringLiteral("estop"), tr("E-STOP sent"));
  statusBar()->showMessage(tr("E-STOP sent"), 5000);
}

void MainWindow::rearm() {
  // Deliberate: a confirmation whose default is No, so that no stray Enter
  // or Space re-arms a stopped robot.
  QMessageBox box(QMessageBox::Question, tr("Re-arm"),
                  tr("Re-arm the robot?\n\nThe latch clears; the robot stays stopped until the next command, "
                     "and the deadman counts from now."),
                  QMessageBox::NoButton, this);
  box.setObjectName(QStringLiteral("rearmConfirm"));
  QPushButton* yes = box.addButton(tr("Re-arm"), QMessageBox::AcceptRole);
  QPushButton* no = box.addButton(tr("Cancel"), QMessageBox::RejectRole);
  box.setDefaultButton(no);
  box.exec();
  if (box.clickedButton() != yes) return;
  controls_->syncToRobot(modelPositions_);
  linkEvent(QStringLiteral("rearm"), tr("re-arm sent"));
  connection_->rearm();
}

void MainWindow::openConnectDialog() {
  ConnectDialog dialog(this, [](const QString& hostPort, const QString& token) {
    std::string error;
    return parseEndpoint(hostPort.toStdString(), token.toStdString(), error) ? QString() : qs(error);
  });
  if (dialog.exec() != QDialog::Accepted) return;
  connection_->close();
  const std::string error = dialog.standIn() ? session_->useStandIn()
                                             : session_->connectTo(dialog.hostPort().toStdString(), dialog.token().toStdString());
  if (!error.empty()) {
    showLoadErrors(tr("Cannot connect"), qs(error));
    connectToRobot();  // back to where the console was
    return;
  }
  if (!dialog.standIn()) ConnectDialog::remember(dialog.hostPort());
  options_.connectTo = dialog.standIn() ? QString() : dialog.hostPort();
  linkEvent(QStringLiteral("link"), tr("connecting to %1").arg(qs(session_->endpoint().label)));
  sessionChanged();
}

void MainWindow::resetRobot() {
  connection_->close();
  if (const std::string error = session_->resetRobot(); !error.empty()) {
    statusBar()->showMessage(qs(error), 6000);
    connectToRobot();
    return;
  }
  linkEvent(QStringLiteral("note"), tr("reset: the robot is back at its start"));
  feed_->clear();
  wheelPlot_->clear();
  edgeDistance_.reset();
  sessionChanged();
}

void MainWindow::updateActions() {
  const bool ready = connectionState_ == net::ConnectionState::Ready;
  const bool open = connectionState_ != net::ConnectionState::Stopped;
  reconnectAction_->setEnabled(!open);
  disconnectAction_->setEnabled(open);
  takeAction_->setEnabled(ready && !leaseHeld_);
  releaseAction_->setEnabled(ready && leaseHeld_);
  rearmAction_->setEnabled(ready && (failsafe_ || estop_));
  resetAction_->setEnabled(!session_->remote());
}

void MainWindow::updateControlsEnabled() {
  updateActions();
  QString why;
  if (connectionState_ != net::ConnectionState::Ready) why = tr("Not connected to the robot");
  else if (!leaseHeld_) why = tr("Take control first (Robot ▸ Take control)");
  else if (estop_ || failsafe_) why = tr("The robot is stopped and latched: re-arm first");
  controls_->setControlsEnabled(why.isEmpty(), why);
  sequence_->setLinkReady(why.isEmpty());
}

void MainWindow::updateStale() {
  const double staleAfter = session_->params().consoleStaleAfter;
  const bool connected = connectionState_ == net::ConnectionState::Ready;
  const double age = haveFrame_ ? static_cast<double>(lastFrameClock_.elapsed()) / 1000.0 : 0;
  const bool stale = connected && haveFrame_ && age > staleAfter;
  if (stale) staleLabel_->setText(tr("no data %1 s: the robot drawn is where it was %1 s ago").arg(formatFixed(age, 1)));
  staleLabel_->setVisible(stale);
  if (stale != stale_) {
    stale_ = stale;
    scene_->setStale(stale);
    refreshStatus();
  }
}

void MainWindow::applyTerrainEdit(const TerrainPatchCmd& patch) {
  if (replaying_) return;  // the view shows the log's world
  if (!session_->terrainEdited(patch)) return;
  scene_->applyTerrainPatch(patch);
  sequence_->terrainEdited(patch);
  // The robot's twin, when it is a simulator that takes edits (WELCOME
  // capability terrain_edit), in frame-sized parts; it logs them.
  if (robotTakesTerrainEdits() && link_->leaseHeld())
    for (const TerrainPatchCmd& part : splitPatch(patch, kTerrainPartHeights)) connection_->send(part, session_->robot());
  ++terrainEdits_;
}

bool MainWindow::robotTakesTerrainEdits() const {
  if (connectionState_ != net::ConnectionState::Ready) return false;
  const std::string caps = " " + connection_->stats().robotCapabilities + " ";
  return caps.find(" terrain_edit ") != std::string::npos;
}

void MainWindow::updateTerrainReach() {
  if (!terrain_) return;
  if (robotTakesTerrainEdits())
    terrain_->setReach(link_->leaseHeld() ? tr("Edits reach the robot's twin (a simulator) and the console's.")
                                          : tr("Take control to edit the robot's twin too; now only the console's twin."));
  else
    terrain_->setReach(tr("The robot does not take terrain edits (a real robot, or not connected): only the "
                          "console's twin, ghost and rehearsals see them."));
}

void MainWindow::sendCommand(const Command& command) {
  if (const std::string why = session_->commandRefusal(link_->leaseHeld()); !why.empty()) {
    statusBar()->showMessage(qs(why), 4000);
    return;
  }
  connection_->send(command, session_->robot());
  session_->commandSent(command);
}

bool MainWindow::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() == QEvent::KeyPress) {
    auto* key = static_cast<QKeyEvent*>(event);
    if (key->key() == Qt::Key_Escape) {
      if (!key->isAutoRepeat()) emergencyStop();
      return true;
    }
    // Drive keys wherever the focus is in this window, except where keys
    // are typed (a number box, a text field): no button or slider with the
    // focus ever turns Space into a click or an arrow into a step.
    auto* widget = qobject_cast<QWidget*>(watched);
    const auto* line = qobject_cast<QLineEdit*>(watched);
    const auto* plain = qobject_cast<QPlainTextEdit*>(watched);
    const auto* rich = qobject_cast<QTextEdit*>(watched);
    const bool typing = qobject_cast<QAbstractSpinBox*>(watched) || (line && !line->isReadOnly()) ||
                        (plain && !plain->isReadOnly()) || (rich && !rich->isReadOnly());
    if (widget && widget->window() == this && !typing && key->modifiers() == Qt::NoModifier &&
        isDriveKey(key->key())) {
      if (controls_->controlsEnabled()) controls_->handleKey(key->key());
      else if (!key->isAutoRepeat()) statusBar()->showMessage(controls_->toolTipWhenDisabled(), 3000);
      return true;
    }
  }
  return QMainWindow::eventFilter(watched, event);
}

void MainWindow::closeEvent(QCloseEvent* event) {
  QSettings settings;
  settings.setValue(QStringLiteral("window/geometry"), saveGeometry());
  settings.setValue(QStringLiteral("window/state"), saveState());
  event->accept();
}

void MainWindow::onFrame(const RobotFrame& f) {
  if (!session_->robot() || replaying_) return;
  lastFrameClock_.restart();
  haveFrame_ = true;
  if (stale_) updateStale();
  modelPositions_ = f.jointPositions;
  // Near a heightfield's edge the operator is warned before the robot
  // drives off into a fall (and a divergence).
  const std::optional<double> edge = session_->edgeDistance(f.base);
  const bool wasNear = edgeDistance_ && *edgeDistance_ < kEdgeWarning;
  edgeDistance_ = edge;
  if (wasNear != (edge && *edge < kEdgeWarning) ||
      (edge && *edge < kEdgeWarning && std::abs(*edge - shownEdge_) > 0.1)) {
    shownEdge_ = edge.value_or(0);
    updateBanner();
  }
  scene_->setRobotState(f.base, modelPositions_);
  if (const std::optional<GhostError>& e = session_->lastPrediction()) errorPlot_->addSample(e->time, e->position, e->heading);
  std::vector<NamedPose> objects;
  for (const ObjectReadout& o : f.objects) objects.push_back({o.name, o.pose});
  scene_->setObjectPoses(objects);
  measuredDirty_ = true;  // shown by the panel timer
  wheelPlot_->addSample(f.time, f.wheelNormal);
  if (f.failsafe != failsafe_ || f.estop != estop_ || qs(f.health) != healthText_) {
    // A latch that comes on stopped the robot: the controls show it.
    if ((f.failsafe && !failsafe_) || (f.estop && !estop_)) controls_->syncToRobot(modelPositions_);
    failsafe_ = f.failsafe;
    estop_ = f.estop;
    healthText_ = qs(f.health);
    link_->showLatches(failsafe_, estop_);
    updateControlsEnabled();
    updateBanner();
  }
}

void MainWindow::pullGhost() {
  const Ghost* ghost = session_->ghost();
  if (!ghost || !scene_->ghostVisible()) return;
  if (ghost->viewVersion() == ghostVersion_) return;
  const GhostView v = ghost->view();
  ghostVersion_ = v.version;
  if (v.version == 0) return;  // nothing predicted yet: the ghost stays where it is
  scene_->setGhostState(v.base, v.jointPositions);
  if (v.trailTime != ghostTrailTime_) {
    ghostTrailTime_ = v.trailTime;
    scene_->setGhostTrail(v.trail);
  }
}

QString MainWindow::ghostStatus() const { return ghostLabel_->text(); }

void MainWindow::onLaser(const LaserFrame& scan) {
  if (replaying_) return;
  scene_->setLaser(scan.angleMin, scan.angleStep, scan.ranges);
  laserPlot_->setScan(scan.angleMin, scan.angleStep, scan.ranges);
}

void MainWindow::refreshStatus() {
  const net::RobotClientStats stats = connection_->stats();
  link_->showStats(stats);
  const std::optional<net::TelemetryMsg>& last = feed_->lastTelemetry();
  if (replaying_) {
    // the replay's frames set the time shown
  } else if (last) {
    simTime_->setText(tr("t = %1 s").arg(last->time, 0, 'f', 2));
    rtfLabel_->setText(tr("RTF %1").arg(session_->realTimeFactor(), 0, 'f', 2));
  } else {
    simTime_->setText(tr("t = –"));
    rtfLabel_->setText(tr("RTF –"));
  }
  if (!healthText_.isEmpty()) health_->setText(QStringLiteral("<b style='color:#c62828'>%1</b>").arg(tr("diverged")));
  else if (stale_) health_->setText(QStringLiteral("<b style='color:#616161'>%1</b>").arg(tr("no data")));
  else if (connectionState_ != net::ConnectionState::Ready) health_->setText(tr("not connected"));
  else if (last) health_->setText(QStringLiteral("<span style='color:#2e7d32'>%1</span>").arg(tr("healthy")));
  else health_->setText(tr("no telemetry"));
  health_->setToolTip(healthText_);
  ghostLabel_->setToolTip(tr("The ghost: how far ahead of the newest telemetry it shows the robot (the link's round "
                             "trip and the telemetry's age), and its error against the telemetry, median over 10 s"));
  if (const Ghost* ghost = session_->ghost(); !ghost) {
    ghostLabel_->setText(session_->ghostError().empty() ? tr("ghost off") : tr("ghost failed"));
    if (!session_->ghostError().empty()) ghostLabel_->setToolTip(qs(session_->ghostError()));
  } else if (const GhostView v = ghost->view(); !v.problem.empty()) {
    ghostLabel_->setText(QStringLiteral("<b style='color:#c62828'>%1</b>").arg(tr("ghost stopped")));
    ghostLabel_->setToolTip(qs(v.problem));
  } else if (v.version == 0) {
    ghostLabel_->setText(tr("ghost –"));
  } else {
    QString text = tr("ghost +%1 s").arg(v.span, 0, 'f', 2);
    if (const auto median = ghost->errorMedian())
      text += tr(", %1 cm / %2°").arg(median->first * 100, 0, 'f', 1).arg(radToDeg(median->second), 0, 'f', 2);
    ghostLabel_->setText(text);
  }
  const QString log = logPath();
  logLabel_->setText(log.isEmpty() ? tr("log: off") : tr("log: %1").arg(QFileInfo(log).fileName()));
  logLabel_->setToolTip(log);
  const QString logError = qs(session_->logError());
  if (!logError.isEmpty())
    logLabel_->setText(QStringLiteral("<b style='color:#c62828'>%1</b>").arg(tr("log failed: %1").arg(logError.toHtmlEscaped())));
}

void MainWindow::updateBanner() {
  QStringList lines;
  if (!healthText_.isEmpty()) lines << tr("The twin diverged and stopped: %1").arg(healthText_);
  if (estop_) lines << tr("E-STOP latched: the robot is stopped. Re-arm to continue.");
  if (failsafe_)
    lines << (failsafeText_.isEmpty()
                  ? tr("FAILSAFE latched: the robot stopped itself. Re-arm to continue.")
                  : tr("FAILSAFE latched: %1; the robot stopped. Re-arm to continue.").arg(failsafeText_));
  if (edgeDistance_ && *edgeDistance_ < kEdgeWarning) {
    const TerrainSpec& t = session_->world()->terrain;
    lines << (*edgeDistance_ < 0
                  ? tr("The robot is off the terrain (%1 m beyond its edge): Robot ▸ Reset puts it back.")
                        .arg(formatFixed(-*edgeDistance_, 1))
                  : tr("Near the terrain's edge: %1 m left of the %2 × %3 m heightfield; beyond it the robot falls.")
                        .arg(formatFixed(*edgeDistance_, 1), formatFixed(t.grid.width, 1), formatFixed(t.grid.depth, 1)));
  }
  if (!filesMismatch_.isEmpty()) lines << filesMismatch_;
  if (connectionState_ == net::ConnectionState::Waiting || connectionState_ == net::ConnectionState::Refused)
    lines << tr("Robot link down (%1): the robot's own deadman stops it; reconnecting.").arg(connectionDetail_);
  banner_->setText(lines.join(QLatin1Char('\n')));
  banner_->setVisible(!lines.isEmpty());
}

QString MainWindow::bannerText() const { return banner_->isVisible() ? banner_->text() : QString(); }

QString MainWindow::logPath() const { return qs(session_->logPath()); }

const std::optional<net::TelemetryMsg>& MainWindow::lastTelemetry() const { return feed_->lastTelemetry(); }
int64_t MainWindow::telemetryReceived() const { return feed_->telemetryCount(); }
int64_t MainWindow::laserReceived() const { return feed_->laserCount(); }
double MainWindow::realTimeFactor() const { return session_->realTimeFactor(); }

void MainWindow::linkEvent(const QString& kind, const QString& text) {
  link_->appendEvent(text);
  session_->event(kind.toStdString(), text.toStdString());
}

}  // namespace sp
