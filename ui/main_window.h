#pragma once
// The operator console's main window: the 3D view of the robot as telemetry
// reports it, docks for the controls, the live plots and the link, a status
// bar with the twin's time, real-time factor and health, and the menus to
// open robot and world files and the session log folder.
//
// The session itself (the stand-in robot it runs on loopback or the robot
// elsewhere it connects to, the world, the log) is a Qt-free ConsoleSession
// (app/console/console_session.h); the views draw what a RobotFeed gives them (today
// the live link, ui/robot_feed.h).
//
// Thread: GUI thread only. The stand-in's physics and network threads and
// the link client's worker thread reach the window only through queued
// signals (RobotConnection).

#include <QElapsedTimer>
#include <QMainWindow>
#include <QString>
#include <QStringList>

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "app/console/robot_frame.h"
#include "net/message.h"
#include "net/robot_client.h"
#include "sim/robot_model.h"

class QAction;
class QLabel;
class QDockWidget;

namespace sp {

struct BranchPoint;
class ConsoleSession;
class ControlPanel;
class LiveLinkFeed;
class LaserPlot;
class LinkPanel;
class PredictionErrorPlot;
class RobotConnection;
class ReplayPanel;
class SceneView;
class SequencePanel;
class TerrainPanel;
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
  double delay = 0;           ///< [s] one-way delay the stand-in's link emulates (each way)
  bool ghost = true;          ///< run and show the predictive ghost
  bool takeControl = true;    ///< ask for the lease as soon as connected
  QString rules;              ///< flight rules file for rehearsals; "" = the built-in defaults
  QString sequence;           ///< a sequence file to open in the Sequence dock
  QString replay;             ///< a session log to open in the Replay dock
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
  SequencePanel* sequencePanel() const { return sequence_; }
  TerrainPanel* terrainPanel() const { return terrain_; }
  /// Terrain edits applied since the start (each dab, undo or redo).
  int64_t terrainEdits() const { return terrainEdits_; }
  ReplayPanel* replayPanel() const { return replay_; }
  /// File ▸ Open session log: the views show the log at the replay cursor
  /// (the live link goes on unseen) until the replay is closed. "" or why
  /// not (shown in a dialog unless `quiet`).
  QString openLog(const QString& path, bool quiet = false);
  /// File ▸ Session logs: the log folder's logs with sizes; replay or delete.
  void showSessionLogs();
  bool replaying() const { return replaying_; }
  /// Opens a log for replay on the Replay dock's worker, with progress.
  void openLogInBackground(const QString& path);
  /// File ▸ Recent session logs: the last kRecentLogs logs opened for
  /// replay that still exist, newest first.
  QStringList recentLogs() const;
  static constexpr int kRecentLogs = 8;
  WheelForcePlot* wheelForcePlot() const { return wheelPlot_; }
  LaserPlot* laserPlot() const { return laserPlot_; }
  PredictionErrorPlot* predictionErrorPlot() const { return errorPlot_; }
  /// View > Ghost: shows or hides the predictive ghost and its trail.
  QAction* ghostAction() const { return ghostAction_; }
  /// The status bar's ghost text ("ghost +1.02 s, 1.3 cm / 0.2°").
  QString ghostStatus() const;
  RobotConnection* connection() const { return connection_; }
  /// The console's session (robot, world, log).
  ConsoleSession* session() const { return session_.get(); }
  /// The latest telemetry received, if any.
  const std::optional<net::TelemetryMsg>& lastTelemetry() const;
  int64_t telemetryReceived() const;
  int64_t laserReceived() const;
  /// The session log being written, "" if none.
  QString logPath() const;
  /// The achieved real-time factor over the last second of telemetry.
  double realTimeFactor() const;
  /// The share of the window's area the 3D view has (0..1).
  double viewShare() const;
  /// Below this share a restored layout is replaced by the default one.
  static constexpr double kMinViewShare = 0.35;
  /// The first-run layout: controls over link on the right, plots below.
  void defaultLayout();
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
  /// Asks the operator to confirm, then re-arms (clears a latched failsafe
  /// or e-stop) and zeroes the controls.
  void rearm();
  /// Robot > Connect to…: a robot's HOST:PORT and token, or the stand-in.
  void openConnectDialog();
  /// Robot > Reset to the start: restarts the stand-in (logged).
  void resetRobot();

 protected:
  bool eventFilter(QObject* watched, QEvent* event) override;
  void closeEvent(QCloseEvent* event) override;

 private:
  void buildMenus();
  void buildDocks();
  /// Replaces what is drawn and controlled by `world` (its first robot).
  void showWorld(const WorldModel& world);
  /// After the session started or switched robots: redraw, reconnect.
  void sessionChanged();
  void connectToRobot();
  void onFrame(const RobotFrame& frame);
  void onLaser(const LaserFrame& scan);
  /// At every 3D frame: the ghost's newest view into the scene.
  void pullGhost();
  void sendCommand(const Command& command);
  void refreshStatus();
  void updateBanner();
  /// Controls enabled only while connected, holding the lease and unlatched.
  void updateControlsEnabled();
  /// Menu items follow the state: what cannot be done now is greyed.
  void updateActions();
  /// No telemetry for console.stale_after: the robot greys, the status says so.
  void updateStale();
  void showLoadErrors(const QString& title, const QString& text);
  /// An event of the console's own (e-stop sent, re-arm sent), shown in the
  /// link dock and logged.
  void linkEvent(const QString& kind, const QString& text);

  ConsoleOptions options_;
  std::unique_ptr<ConsoleSession> session_;
  int shownWorld_ = -1;  // the session's worldVersion() the views show
  RobotConnection* connection_ = nullptr;
  LiveLinkFeed* feed_ = nullptr;

  SceneView* scene_ = nullptr;
  ControlPanel* controls_ = nullptr;
  LinkPanel* link_ = nullptr;
  SequencePanel* sequence_ = nullptr;
  TerrainPanel* terrain_ = nullptr;
  QDockWidget* terrainDock_ = nullptr;
  int64_t terrainWorld_ = -1;  // the world version the terrain panel edits
  int64_t terrainEdits_ = 0;
  static constexpr size_t kTerrainPartHeights = 2000;  // per COMMAND: fits a 64 KiB frame
  void applyTerrainEdit(const TerrainPatchCmd& patch);
  /// A dock named `name` holding `panel` in a scroll area.
  QDockWidget* scrolledDock(const QString& title, const QString& name, QWidget* panel);
  bool robotTakesTerrainEdits() const;
  void updateTerrainReach();
  QDockWidget* sequenceDock_ = nullptr;
  /// Replay ▸ Simulate from here, once the dock has the state: the
  /// stand-in restarts from it, the replay closes and the views show it live.
  QString startBranch(const QString& logPath, const BranchPoint& point, bool quiet);
  ReplayPanel* replay_ = nullptr;
  QDockWidget* replayDock_ = nullptr;
  bool replaying_ = false;
  bool ghostShownBeforeReplay_ = false;
  WheelForcePlot* wheelPlot_ = nullptr;
  LaserPlot* laserPlot_ = nullptr;
  PredictionErrorPlot* errorPlot_ = nullptr;
  QAction* ghostAction_ = nullptr;
  QLabel* ghostLabel_ = nullptr;
  int64_t ghostVersion_ = -1;     // of the view the scene shows
  double ghostTrailTime_ = -1;    // of the trail the scene shows
  QDockWidget* controlsDock_ = nullptr;
  QDockWidget* plotsDock_ = nullptr;
  QDockWidget* linkDock_ = nullptr;
  QLabel* banner_ = nullptr;
  QLabel* staleLabel_ = nullptr;
  QAction* reconnectAction_ = nullptr;
  QAction* disconnectAction_ = nullptr;
  QAction* takeAction_ = nullptr;
  QAction* releaseAction_ = nullptr;
  QAction* rearmAction_ = nullptr;
  QAction* resetAction_ = nullptr;
  QLabel* terrainLabel_ = nullptr;
  /// [m] within this of a heightfield's edge the banner warns.
  static constexpr double kEdgeWarning = 1.5;
  std::optional<double> edgeDistance_;  // of the last frame; nullopt on a plane
  double shownEdge_ = 0;                // the distance the banner shows
  QLabel* simTime_ = nullptr;
  QLabel* rtfLabel_ = nullptr;
  QLabel* health_ = nullptr;
  QLabel* logLabel_ = nullptr;

  std::vector<double> modelPositions_;   // joint positions in model order
  bool measuredDirty_ = false;  // modelPositions_ changed since the controls showed them
  int64_t panelTicks_ = 0;
  bool failsafe_ = false, estop_ = false;
  bool leaseHeld_ = false;
  net::ConnectionState connectionState_ = net::ConnectionState::Stopped;
  QString connectionDetail_;
  QString failsafeText_;
  QString filesMismatch_;  // the robot's files are not the console's ("" = same or not announced)  // the robot's EVENT text: why it stopped
  QElapsedTimer lastFrameClock_;
  bool haveFrame_ = false, stale_ = false;
  QString healthText_;
};

}  // namespace sp
