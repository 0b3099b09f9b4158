#include "ui/main_window.h"

#include <QApplication>
#include <QCloseEvent>
#include <QDateTime>
#include <QDesktopServices>
#include <QDir>
#include <QDockWidget>
#include <QElapsedTimer>
#include <QFileDialog>
#include <QFileInfo>
#include <QInputDialog>
#include <QKeyEvent>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QSettings>
#include <QSplitter>
#include <QStandardPaths>
#include <QStatusBar>
#include <QTimer>
#include <QUrl>
#include <QVBoxLayout>

#include <chrono>
#include <cmath>

#include "app/stand_in.h"
#include "app/telemetry_recorder.h"
#include "sim/model_loader.h"
#include "ui/control_panel.h"
#include "ui/link_panel.h"
#include "ui/live_plots.h"
#include "ui/robot_connection.h"
#include "ui/scene_view.h"

namespace sp {

namespace {

double wallSeconds() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

QString qs(const std::string& s) { return QString::fromStdString(s); }

}  // namespace

MainWindow::MainWindow(ConsoleOptions options, QWidget* parent)
    : QMainWindow(parent), options_(std::move(options)) {
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
  layout->addWidget(banner_);
  layout->addWidget(scene_, 1);
  setCentralWidget(central);

  connection_ = new RobotConnection(this);
  connect(connection_, &RobotConnection::telemetry, this, &MainWindow::onTelemetry);
  connect(connection_, &RobotConnection::laser, this, &MainWindow::onLaser);
  connect(connection_, &RobotConnection::reply, this, &MainWindow::onReply);
  connect(connection_, &RobotConnection::event, this, &MainWindow::onEvent);
  connect(connection_, &RobotConnection::connectionChanged, this,
          [this](net::ConnectionState s, const QString& d) { onConnection(static_cast<int>(s), d); });
  connect(connection_, &RobotConnection::lease, this, [this](const net::LeaseStateMsg& lease) {
    link_->showLease(lease);
    linkEvent(QStringLiteral("link"), lease.yours ? tr("control: yours")
                                      : lease.holder.empty() ? tr("control: free")
                                                             : tr("control: held by %1").arg(qs(lease.holder)));
  });
  connect(connection_, &RobotConnection::linkError, this, [this](const QString& reason) {
    link_->appendEvent(tr("error: %1").arg(reason));
    statusBar()->showMessage(reason, 5000);
  });

  buildDocks();
  buildMenus();

  simTime_ = new QLabel;
  rtfLabel_ = new QLabel;
  health_ = new QLabel;
  logLabel_ = new QLabel;
  logLabel_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  for (QLabel* l : {simTime_, rtfLabel_, health_}) l->setMinimumWidth(l->fontMetrics().horizontalAdvance(QStringLiteral("t = 00000.00 s")));
  statusBar()->addPermanentWidget(simTime_);
  statusBar()->addPermanentWidget(rtfLabel_);
  statusBar()->addPermanentWidget(health_);
  statusBar()->addPermanentWidget(logLabel_);

  // Everything around the 3D view is refreshed by one 100 ms timer, in one
  // event-loop pass together with a 3D frame: under software GL every window
  // update composites the whole window, so each widget repainting on its own
  // schedule (measured values at 50 Hz, plots, status) would cost a full
  // composite of its own. Measured: 20.7 -> 28 fps (docs/performance.md).
  auto* panelTimer = new QTimer(this);
  connect(panelTimer, &QTimer::timeout, this, [this] {
    wheelPlot_->tick();
    laserPlot_->tick();
    if (measuredDirty_) {
      controls_->showMeasured(modelPositions_);
      measuredDirty_ = false;
    }
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
  if (!restoreState(settings.value(QStringLiteral("window/state")).toByteArray()))
    QTimer::singleShot(0, this, [this] {
      resizeDocks({controlsDock_, linkDock_}, {380, 330}, Qt::Horizontal);
      resizeDocks({plotsDock_}, {320}, Qt::Vertical);
    });
  refreshStatus();
}

MainWindow::~MainWindow() {
  qApp->removeEventFilter(this);
  // The client first (it releases the lease), then the robot it talks to.
  delete connection_;
  connection_ = nullptr;
  recorder_.reset();
  stopStandIn();
}

void MainWindow::buildDocks() {
  controls_ = new ControlPanel;
  connect(controls_, &ControlPanel::command, this, &MainWindow::sendCommand);
  controlsDock_ = new QDockWidget(tr("Controls"), this);
  controlsDock_->setObjectName(QStringLiteral("controlsDock"));
  controlsDock_->setWidget(controls_);
  addDockWidget(Qt::LeftDockWidgetArea, controlsDock_);

  auto* plots = new QSplitter(Qt::Horizontal);
  wheelPlot_ = new WheelForcePlot;
  laserPlot_ = new LaserPlot;
  // The plots replot from the window's panel timer (see there), not their own.
  wheelPlot_->setOwnTimer(false);
  laserPlot_->setOwnTimer(false);
  plots->addWidget(wheelPlot_);
  plots->addWidget(laserPlot_);
  plots->setStretchFactor(0, 3);
  plots->setStretchFactor(1, 2);
  plotsDock_ = new QDockWidget(tr("Plots"), this);
  plotsDock_->setObjectName(QStringLiteral("plotsDock"));
  plotsDock_->setWidget(plots);
  addDockWidget(Qt::BottomDockWidgetArea, plotsDock_);

  link_ = new LinkPanel;
  linkDock_ = new QDockWidget(tr("Link"), this);
  linkDock_->setObjectName(QStringLiteral("linkDock"));
  linkDock_->setWidget(link_);
  addDockWidget(Qt::RightDockWidgetArea, linkDock_);

  connect(link_, &LinkPanel::connectRequested, this, &MainWindow::connectToRobot);
  connect(link_, &LinkPanel::disconnectRequested, connection_, &RobotConnection::close);
  connect(link_, &LinkPanel::takeControlRequested, connection_, &RobotConnection::acquireLease);
  connect(link_, &LinkPanel::releaseControlRequested, connection_, &RobotConnection::releaseLease);
  connect(link_, &LinkPanel::estopRequested, this, &MainWindow::emergencyStop);
  connect(link_, &LinkPanel::rearmRequested, this, [this] {
    link_->appendEvent(tr("re-arm sent"));
    connection_->rearm();
  });
}

void MainWindow::buildMenus() {
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("Open &world…"), QKeySequence::Open, this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open world"), QFileInfo(worldFile_).path(),
                                                      tr("World files (*.world.xml);;XML files (*.xml)"));
    if (!path.isEmpty()) openWorld(path);
  });
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
    const QString dir = logPath().isEmpty() ? sessionsDir() : QFileInfo(logPath()).absolutePath();
    QDir().mkpath(dir);
    if (!QDesktopServices::openUrl(QUrl::fromLocalFile(dir)))
      QMessageBox::information(this, tr("Log folder"), tr("The session logs are in\n%1").arg(dir));
  });
  file->addSeparator();
  file->addAction(tr("&Quit"), QKeySequence::Quit, this, &QWidget::close);

  QMenu* robot = menuBar()->addMenu(tr("&Robot"));
  robot->addAction(tr("&Connect"), this, &MainWindow::connectToRobot);
  robot->addAction(tr("&Disconnect"), connection_, &RobotConnection::close);
  robot->addSeparator();
  robot->addAction(tr("&Take control"), connection_, &RobotConnection::acquireLease);
  robot->addAction(tr("&Release control"), connection_, &RobotConnection::releaseLease);
  robot->addSeparator();
  // Esc itself is caught by the application filter; the menu shows the key.
  QAction* estop = robot->addAction(tr("&E-stop\tEsc"), this, &MainWindow::emergencyStop);
  estop->setToolTip(tr("Emergency stop"));
  robot->addAction(tr("Re-&arm"), connection_, &RobotConnection::rearm);

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
  view->addSeparator();
  for (QDockWidget* dock : {controlsDock_, plotsDock_, linkDock_}) view->addAction(dock->toggleViewAction());

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
  if (options_.connectTo.isEmpty()) {
    if (QString error = startStandIn(options_.world, {}); !error.isEmpty()) return error;
  } else {
    // A remote robot: the world file only tells what to draw.
    Diagnostics diag;
    auto world = loadWorld(options_.world.toStdString(), diag);
    if (!world) return qs(diag.format()).trimmed();
    if (world->robots.empty()) return tr("%1: error: the world has no <robot>").arg(options_.world);
    worldFile_ = options_.world;
    showWorld(*world);
    const int colon = static_cast<int>(options_.connectTo.lastIndexOf(QLatin1Char(':')));
    bool ok = false;
    const uint port = colon > 0 ? options_.connectTo.mid(colon + 1).toUInt(&ok) : 0;
    if (!ok || port == 0 || port > 65535) return tr("--connect: expected HOST:PORT, got '%1'").arg(options_.connectTo);
    host_ = options_.connectTo.left(colon);
    port_ = static_cast<uint16_t>(port);
    token_ = options_.token;
    link_->setEndpoint(QStringLiteral("%1:%2").arg(host_).arg(port_));
    openRemoteLog();
  }
  connectToRobot();
  return {};
}

QString MainWindow::startStandIn(const QString& worldFile, const QString& robotFile) {
  StandInOptions o;
  o.worldFile = worldFile.toStdString();
  o.robotFile = robotFile.toStdString();
  o.paramsFile = options_.params.toStdString();
  for (const QString& s : options_.overrides) o.overrides.push_back(s.toStdString());
  o.port = uint16_t{0};  // any free port: several consoles may run on one machine
  o.token = options_.token.toStdString();
  if (options_.rtf >= 0) o.realTimeFactor = options_.rtf;
  o.log = options_.log;
  o.logDir = (options_.logDir.isEmpty() ? sessionsDir() : options_.logDir).toStdString();
  Diagnostics diag;
  std::unique_ptr<StandInRobot> standIn = StandInRobot::create(o, diag);
  if (!standIn) return qs(diag.format()).trimmed();
  if (const std::string error = standIn->start(); !error.empty()) return qs(error);

  // Only now that the new robot runs is the old one replaced.
  connection_->close();
  stopStandIn();
  standIn_ = std::move(standIn);
  worldFile_ = worldFile;
  robotFile_ = robotFile;
  host_ = QStringLiteral("127.0.0.1");
  port_ = standIn_->port();
  token_ = qs(standIn_->token());
  showWorld(standIn_->world());
  link_->setEndpoint(tr("%1:%2 (stand-in, %3)").arg(host_).arg(port_).arg(QFileInfo(worldFile).fileName()));
  if (standIn_->logFailed()) statusBar()->showMessage(tr("session log: %1").arg(qs(standIn_->logError())));
  return {};
}

void MainWindow::stopStandIn() {
  if (!standIn_) return;
  standIn_->stop();
  standIn_.reset();
}

void MainWindow::connectToRobot() {
  if (port_ == 0) return;
  net::RobotClientConfig config;
  config.host = host_.toStdString();
  config.port = port_;
  config.token = token_.toStdString();
  config.name = QStringLiteral("console@%1").arg(QCoreApplication::applicationPid()).toStdString();
  connection_->open(config);
  if (options_.takeControl) connection_->acquireLease();
}

void MainWindow::showWorld(const WorldModel& world) {
  world_ = world;
  scene_->setWorld(*world_);
  if (!world_->robots.empty()) {
    const RobotModel& robot = world_->robots[0].model;
    controls_->setRobot(robot);
    for (const SensorSpec& sensor : robot.sensors)
      if (sensor.type == SensorType::Laser) {
        laserPlot_->setMaxRange(sensor.maxRange);
        laserPlot_->setRangeLimits(sensor.minRange, sensor.maxRange);
        break;
      }
  }
  jointNames_.clear();
  jointIndex_.clear();
  wheelPlot_->clear();
  lastTelemetry_.reset();
  timing_.clear();
  QString title = tr("SimPartner — %1").arg(QFileInfo(qs(world_->file)).fileName());
  if (!options_.connectTo.isEmpty()) title += tr(" — robot at %1").arg(options_.connectTo);
  setWindowTitle(title);
}

QString MainWindow::openWorld(const QString& path, bool quiet) {
  Diagnostics diag;
  auto world = loadWorld(path.toStdString(), diag);
  if (!world || world->robots.empty()) {
    QString text = qs(diag.format()).trimmed();
    if (world) text = tr("%1: error: the world has no <robot> to control").arg(path);
    if (!quiet) showLoadErrors(tr("Cannot open the world"), text);
    return text;
  }
  if (options_.connectTo.isEmpty()) {
    if (QString error = startStandIn(path, {}); !error.isEmpty()) {
      if (!quiet) showLoadErrors(tr("Cannot start the stand-in on this world"), error);
      return error;
    }
    connectToRobot();
  } else {
    worldFile_ = path;
    showWorld(*world);  // the remote robot runs in its own world: this only changes what is drawn
  }
  statusBar()->showMessage(tr("opened %1").arg(path), 5000);
  return {};
}

QString MainWindow::openRobot(const QString& path, bool quiet) {
  Diagnostics diag;
  auto robot = loadRobot(path.toStdString(), diag);
  if (!robot) {
    const QString text = qs(diag.format()).trimmed();
    if (!quiet) showLoadErrors(tr("Cannot open the robot"), text);
    return text;
  }
  if (options_.connectTo.isEmpty()) {
    if (QString error = startStandIn(worldFile_, path); !error.isEmpty()) {
      if (!quiet) showLoadErrors(tr("Cannot start the stand-in with this robot"), error);
      return error;
    }
    connectToRobot();
  } else if (world_ && !world_->robots.empty()) {
    WorldModel world = *world_;
    world.robots[0].model = *robot;
    showWorld(world);
  }
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
  if (standIn_) standIn_->addNote(text.toStdString());
  if (recorder_) recorder_->event("note", text.toStdString());
  link_->appendEvent(tr("note: %1").arg(text));
  statusBar()->showMessage(tr("note logged"), 3000);
}

void MainWindow::emergencyStop() {
  connection_->estop(tr("operator e-stop"));
  linkEvent(QStringLiteral("estop"), tr("E-STOP sent"));
  statusBar()->showMessage(tr("E-STOP sent"), 5000);
}

void MainWindow::sendCommand(const Command& command) {
  const RobotModel* robot = world_ && !world_->robots.empty() ? &world_->robots[0].model : nullptr;
  if (!link_->leaseHeld()) {
    statusBar()->showMessage(tr("Not sent: take control first (Robot ▸ Take control)"), 4000);
    return;
  }
  connection_->send(command, robot);
  if (recorder_) recorder_->command(command, robot);
}

bool MainWindow::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() == QEvent::KeyPress) {
    auto* key = static_cast<QKeyEvent*>(event);
    if (key->key() == Qt::Key_Escape) {
      if (!key->isAutoRepeat()) emergencyStop();
      return true;
    }
    if (watched == scene_ && controls_->handleKey(key->key())) return true;
  }
  return QMainWindow::eventFilter(watched, event);
}

void MainWindow::closeEvent(QCloseEvent* event) {
  QSettings settings;
  settings.setValue(QStringLiteral("window/geometry"), saveGeometry());
  settings.setValue(QStringLiteral("window/state"), saveState());
  event->accept();
}

void MainWindow::onTelemetry(const net::TelemetryMsg& t) {
  ++telemetryCount_;
  if (!world_ || world_->robots.empty()) return;
  const RobotModel& robot = world_->robots[0].model;
  if (t.jointNames != jointNames_) {
    // Names travel in every frame; they are mapped only when they change.
    jointNames_ = t.jointNames;
    jointIndex_.clear();
    for (const std::string& name : jointNames_) jointIndex_.push_back(robot.findJoint(name));
  }
  modelPositions_.assign(robot.joints.size(), 0.0);
  for (size_t i = 0; i < jointIndex_.size() && i < t.jointPositions.size(); ++i)
    if (jointIndex_[i] >= 0) modelPositions_[static_cast<size_t>(jointIndex_[i])] = t.jointPositions[i];
  scene_->setRobotState(t.pose, modelPositions_);
  std::vector<NamedPose> objects;
  for (const net::ObjectPose& o : t.objects) objects.push_back({o.name, o.pose});
  scene_->setObjectPoses(objects);
  measuredDirty_ = true;  // shown by the panel timer
  wheelPlot_->addSample(t.time, t.wheelNormal);
  if (recorder_) recorder_->telemetry(t, robot);

  const double now = wallSeconds();
  if (!timing_.empty() && t.time < timing_.back().second) timing_.clear();  // a new session restarted time
  timing_.emplace_back(now, t.time);
  while (timing_.size() > 2 && now - timing_.front().first > 1.0) timing_.pop_front();
  const double wall = timing_.back().first - timing_.front().first;
  rtf_ = wall > 0.2 ? (timing_.back().second - timing_.front().second) / wall : rtf_;

  if (t.failsafe != failsafe_ || t.estop != estop_ || qs(t.health) != healthText_) {
    failsafe_ = t.failsafe;
    estop_ = t.estop;
    healthText_ = qs(t.health);
    link_->showLatches(failsafe_, estop_);
    updateBanner();
  }
  lastTelemetry_ = t;
}

void MainWindow::onLaser(const net::LaserMsg& m) {
  ++laserCount_;
  scene_->setLaser(m.angleMin, m.angleStep, m.ranges);
  laserPlot_->setScan(m.angleMin, m.angleStep, m.ranges);
  if (recorder_) recorder_->laser(m);
}

void MainWindow::onReply(const net::ReplyMsg& m) {
  if (m.status == net::ReplyStatus::Ok) return;
  const QString text = tr("command %1 %2: %3").arg(m.seq).arg(QLatin1String(net::toString(m.status)), qs(m.reason));
  linkEvent(QStringLiteral("link"), text);
  statusBar()->showMessage(text, 5000);
}

void MainWindow::onEvent(const net::EventMsg& m) {
  linkEvent(QLatin1String(net::toString(m.kind)), tr("robot %1: %2").arg(QLatin1String(net::toString(m.kind)), qs(m.text)));
}

void MainWindow::onConnection(int state, const QString& detail) {
  const auto s = static_cast<net::ConnectionState>(state);
  link_->showConnection(s, detail);
  linkEvent(QStringLiteral("link"), tr("link %1%2").arg(QLatin1String(net::toString(s)), detail.isEmpty() ? QString() : QStringLiteral(": ") + detail));
  updateBanner();
}

void MainWindow::refreshStatus() {
  const net::RobotClientStats stats = connection_->stats();
  link_->showStats(stats);
  if (lastTelemetry_) {
    simTime_->setText(tr("t = %1 s").arg(lastTelemetry_->time, 0, 'f', 2));
    rtfLabel_->setText(tr("RTF %1").arg(rtf_, 0, 'f', 2));
  } else {
    simTime_->setText(tr("t = –"));
    rtfLabel_->setText(tr("RTF –"));
  }
  if (!healthText_.isEmpty()) health_->setText(QStringLiteral("<b style='color:#c62828'>%1</b>").arg(tr("diverged")));
  else if (lastTelemetry_) health_->setText(QStringLiteral("<span style='color:#2e7d32'>%1</span>").arg(tr("healthy")));
  else health_->setText(tr("no telemetry"));
  health_->setToolTip(healthText_);
  const QString log = logPath();
  logLabel_->setText(log.isEmpty() ? tr("log: off") : tr("log: %1").arg(QFileInfo(log).fileName()));
  logLabel_->setToolTip(log);
  QString logError;
  if (standIn_ && standIn_->logFailed()) logError = qs(standIn_->logError());
  if (recorder_ && recorder_->writer().failed()) logError = qs(recorder_->writer().errorMessage());
  if (!logError.isEmpty())
    logLabel_->setText(QStringLiteral("<b style='color:#c62828'>%1</b>").arg(tr("log failed: %1").arg(logError.toHtmlEscaped())));
}

void MainWindow::updateBanner() {
  QStringList lines;
  if (!healthText_.isEmpty()) lines << tr("The twin diverged and stopped: %1").arg(healthText_);
  if (estop_) lines << tr("E-STOP latched: the robot is stopped. Re-arm to continue.");
  if (failsafe_) lines << tr("FAILSAFE latched: the link was lost and the robot stopped. Re-arm to continue.");
  banner_->setText(lines.join(QLatin1Char('\n')));
  banner_->setVisible(!lines.isEmpty());
}

QString MainWindow::bannerText() const { return banner_->isVisible() ? banner_->text() : QString(); }

QString MainWindow::logPath() const {
  if (standIn_) return qs(standIn_->logPath());
  return recorder_ ? qs(recorder_->path()) : QString();
}

void MainWindow::openRemoteLog() {
  recorder_.reset();
  if (!options_.log || !world_) return;
  const QString dir = options_.logDir.isEmpty() ? sessionsDir() : options_.logDir;
  QDir().mkpath(dir);
  const QString stamp = QDateTime::currentDateTime().toString(QStringLiteral("yyyyMMdd-HHmmss"));
  QString path;
  for (int n = 1; n < 1000 && (path.isEmpty() || QFileInfo::exists(path)); ++n)
    path = QDir(dir).filePath(QStringLiteral("session-%1%2.splog").arg(stamp, n > 1 ? QStringLiteral("-%1").arg(n) : QString()));
  std::string error;
  recorder_ = TelemetryRecorder::open(path.toStdString(), *world_, QStringLiteral("%1:%2").arg(host_).arg(port_).toStdString(), error);
  if (!recorder_) statusBar()->showMessage(tr("session log: %1").arg(qs(error)));
}

void MainWindow::linkEvent(const QString& kind, const QString& text) {
  link_->appendEvent(text);
  if (recorder_) recorder_->event(kind.toStdString(), text.toStdString());
}

QString MainWindow::sessionsDir() const {
  return QStandardPaths::writableLocation(QStandardPaths::GenericDataLocation) + QStringLiteral("/SimPartner/sessions");
}

}  // namespace sp
