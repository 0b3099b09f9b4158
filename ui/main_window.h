#pragma once
// The operator console's main window: the 3D view of the robot as telemetry
// reports it, docks for the controls, the live plots and the link, a status
// bar with the twin's time, real-time factor and health, and the menus to
// open robot and world files and the session log folder.
//
// By default the window starts the stand-in robot (the twin behind the link
// protocol) on loopback and connects to it; with a `connectTo` endpoint it
// connects to any robot that speaks the protocol instead.
//
// Thread: GUI thread only. The stand-in's physics and network threads and
// the link client's worker thread reach the window only through queued
// signals (RobotConnection).

#include <QMainWindow>
#include <QString>
#include <QStringList>

#include <deque>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "net/message.h"
#include "sim/robot_model.h"

class QLabel;
class QDockWidget;

namespace sp {

class ControlPanel;
class LaserPlot;
class LinkPanel;
class RobotConnection;
class SceneView;
class StandInRobot;
class TelemetryRecorder;
class WheelForcePlot;

/// What the console starts with (the `simpartner` command line).
struct ConsoleOptions {
  QString world = QStringLiteral("terrains/flat.world.xml");  ///< world file (drawn; run by the stand-in)
  QString params;             ///< parameters file; "" = the built-in defaults
  QStringList overrides;      ///< KEY=VALUE parameter overrides
  QString connectTo;          ///< HOST:PORT of a robot; "" = start the stand-in on loopback
  QString token;              ///< the robot's shared secret (generated for the stand-in if "")
  bool log = true;            ///< log the session
  QString logDir;             ///< where logs go; "" = the user's data folder, `sessions/`
  double rtf = -1;            ///< stand-in real-time factor; < 0 = the parameters'
  bool takeControl = true;    ///< ask for the lease as soon as connected
};

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  explicit MainWindow(ConsoleOptions options, QWidget* parent = nullptr);
  ~MainWindow() override;

  /// Loads the world, starts the stand-in (unless connecting elsewhere) and
  /// connects. Returns "" or what went wrong (with file:line where there is one).
  QString start();

  // For tests and the status of the session.
  SceneView* sceneView() const { return scene_; }
  ControlPanel* controlPanel() const { return controls_; }
  LinkPanel* linkPanel() const { return link_; }
  WheelForcePlot* wheelForcePlot() const { return wheelPlot_; }
  LaserPlot* laserPlot() const { return laserPlot_; }
  RobotConnection* connection() const { return connection_; }
  /// The latest telemetry received, if any.
  const std::optional<net::TelemetryMsg>& lastTelemetry() const { return lastTelemetry_; }
  int64_t telemetryReceived() const { return telemetryCount_; }
  int64_t laserReceived() const { return laserCount_; }
  /// The session log being written, "" if none.
  QString logPath() const;
  /// The achieved real-time factor over the last second of telemetry.
  double realTimeFactor() const { return rtf_; }
  /// The text of the banner over the 3D view ("" when nothing is latched).
  QString bannerText() const;

  /// Loads `path` as the world; on errors shows them (file:line) in a
  /// dialog (unless `quiet`) and returns them, leaving the session as it was.
  QString openWorld(const QString& path, bool quiet = false);
  /// Loads `path` as the robot, placed where the current world's robot is.
  QString openRobot(const QString& path, bool quiet = false);
  /// Adds an operator note to the session log.
  void addNote(const QString& text);

 public slots:
  void emergencyStop();

 protected:
  bool eventFilter(QObject* watched, QEvent* event) override;
  void closeEvent(QCloseEvent* event) override;

 private:
  void buildMenus();
  void buildDocks();
  /// Replaces what is drawn and controlled by `world` (its first robot).
  void showWorld(const WorldModel& world);
  /// Starts the stand-in on `world` (a file, and optionally another robot
  /// file) and connects to it. "" or the error.
  QString startStandIn(const QString& worldFile, const QString& robotFile);
  void stopStandIn();
  void connectToRobot();
  void onTelemetry(const net::TelemetryMsg& message);
  void onLaser(const net::LaserMsg& message);
  void onReply(const net::ReplyMsg& message);
  void onEvent(const net::EventMsg& message);
  void onConnection(int state, const QString& detail);
  void sendCommand(const Command& command);
  void refreshStatus();
  void updateBanner();
  QString sessionsDir() const;
  void showLoadErrors(const QString& title, const QString& text);
  /// Starts the console's own log of a remote robot's session.
  void openRemoteLog();
  /// A link event, shown in the link dock and logged.
  void linkEvent(const QString& kind, const QString& text);

  ConsoleOptions options_;
  std::optional<WorldModel> world_;  // what is drawn; its robots[0] is the one controlled
  QString worldFile_, robotFile_;    // the stand-in's files ("" robot = the world's own)
  std::unique_ptr<StandInRobot> standIn_;
  std::unique_ptr<TelemetryRecorder> recorder_;  // the log when connected to a remote robot
  RobotConnection* connection_ = nullptr;
  QString host_;
  uint16_t port_ = 0;
  QString token_;

  SceneView* scene_ = nullptr;
  ControlPanel* controls_ = nullptr;
  LinkPanel* link_ = nullptr;
  WheelForcePlot* wheelPlot_ = nullptr;
  LaserPlot* laserPlot_ = nullptr;
  QDockWidget* controlsDock_ = nullptr;
  QDockWidget* plotsDock_ = nullptr;
  QDockWidget* linkDock_ = nullptr;
  QLabel* banner_ = nullptr;
  QLabel* simTime_ = nullptr;
  QLabel* rtfLabel_ = nullptr;
  QLabel* health_ = nullptr;
  QLabel* logLabel_ = nullptr;

  std::optional<net::TelemetryMsg> lastTelemetry_;
  std::vector<std::string> jointNames_;  // of the last telemetry, to map names once
  std::vector<int> jointIndex_;          // telemetry joint i -> model joint
  std::vector<double> modelPositions_;   // joint positions in model order
  int64_t telemetryCount_ = 0, laserCount_ = 0;
  std::deque<std::pair<double, double>> timing_;  // (wall [s], robot time [s]) over the last second
  double rtf_ = 0;
  bool measuredDirty_ = false;  // modelPositions_ changed since the controls showed them
  int64_t panelTicks_ = 0;
  bool failsafe_ = false, estop_ = false;
  QString healthText_;
};

}  // namespace sp
