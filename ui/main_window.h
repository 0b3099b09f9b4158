#pragma once
// The operator console's main window: the 3D view of the robot as telemetry
// reports it, docks for the controls, the live plots and the link, a status
// bar with the twin's time, real-time factor and health, and the menus to
// open robot and world files and the session log folder.
//
// The window hosts, lays out and routes menus; it does not do the console's
// jobs. The session (the stand-in robot it runs on loopback or the robot
// elsewhere it connects to, the world, the log) is a Qt-free ConsoleSession
// (app/console/console_session.h); what is known of the link, and what it
// allows, is a Qt-free ConsoleState (app/console/console_state.h); the views
// draw what the feed switch shows (ui/robot_feed.h: the live link or a
// replay); each job (ui/jobs/: drive, sequence, terrain, replay) installs its
// docks and menu items through a ConsoleContext (ui/console_context.h).
//
// Thread: GUI thread only. The stand-in's physics and network threads and
// the link client's worker thread reach the window only through queued
// signals (RobotConnection).

#include <QElapsedTimer>
#include <QMainWindow>
#include <QString>
#include <QStringList>

#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "app/console/console_state.h"
#include "app/state/robot_frame.h"
#include "net/message.h"
#include "net/robot_client.h"
#include "sim/robot_model.h"
#include "ui/console_context.h"

class QAction;
class QLabel;
class QPushButton;
class QDockWidget;
class QMenu;

namespace sp {

class BackgroundJobs;
class ConsoleMonitor;
class StatusFields;
struct BranchPoint;
class ConsoleSession;
class FeedSwitch;
class GhostFeed;
class LiveLinkFeed;
class RobotFeed;
class LaserPlot;
class PredictionErrorPlot;
class RobotConnection;
class SceneView;
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
  std::optional<uint64_t> perturbSeed;  ///< the stand-in is a robot that is not its twin (sim/perturbation.h)
  QString ground;  ///< the stand-in stands on this world's terrain (ConsoleSessionOptions::ground)
  bool ghost = true;          ///< run and show the predictive ghost
  bool calibrate = true;      ///< calibrate the twin from telemetry (app/calibration/live_calibrator.h)
};

class MainWindow : public QMainWindow, public ConsoleHost {
  Q_OBJECT

 public:
  /// Installs `jobs` (ui/jobs/jobs.h builtInJobs(), having taken the
  /// command line) once the window's own views exist.
  MainWindow(ConsoleOptions options, ConsoleJobs jobs, QWidget* parent = nullptr);
  ~MainWindow() override;

  /// Loads the world, starts the stand-in (unless connecting elsewhere),
  /// connects, and lets each job open what the command line named. Returns
  /// "" or what went wrong (with file:line where there is one).
  QString start();

  /// Installs `job` (a dock with its menu items) into the running window.
  /// The built-in jobs are installed by the constructor (ui/jobs/jobs.cpp).
  ConsoleJob* installJob(std::unique_ptr<ConsoleJob> job);
  /// The installed job of type J, or null.
  template <class J>
  J* job() const {
    for (const auto& j : jobs_)
      if (auto* found = qobject_cast<J*>(j.get())) return found;
    return nullptr;
  }
  ConsoleContext& context() const { return *context_; }
  const ConsoleState& consoleState() const { return state(); }

  // For tests and the status of the session.
  SceneView* sceneView() const { return scene_; }
  /// A replay is shown instead of the live robot.
  bool replaying() const { return state().replaying(); }
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
  /// The first-run layout: the jobs' side docks (tabs) over the link on the
  /// right, the plots (and bottom docks) under the 3D view.
  void defaultLayout();
  /// The text of the banner over the 3D view ("" when nothing is shown).
  QString bannerText() const;

  /// Loads `path` as the world; on errors shows them (file:line) in a
  /// dialog (unless `quiet`) and returns them, leaving the session as it was.
  QString openWorld(const QString& path, bool quiet = false) override;
  /// Loads `path` as the robot, placed where the current world's robot is.
  QString openRobot(const QString& path, bool quiet = false);
  /// Adds an operator note to the session log.
  void addNote(const QString& text);

  // ConsoleHost
  QString startBranch(const QString& logPath, const BranchPoint& point, bool quiet) override;
  void restarted(bool clearFrames) override;
  QDockWidget* addDock(const QString& title, const QString& objectName, QWidget* panel, DockPlace place,
                       bool scrolled) override;
  QMenu* menu(const QString& title) override;
  void addMenuAction(const QString& title, QAction* action) override;
  void growDock(QDockWidget* dock, int height, double share) override;
  QWidget* dialogParent() override { return this; }

 public slots:
  /// Sends the e-stop to the live robot (whatever the views show).
  void emergencyStop();
  /// File ▸ Quit (Ctrl+Q): quits, after asking when this console holds
  /// control of a robot that moves (stop it first, or cancel).
  void requestQuit();
  /// Shows `text` in the status bar for `ms` (0: until replaced), elided
  /// to the room the fields leave, whole in the tooltip (and the event list
  /// when elided).
  void showStatus(const QString& text, int ms);
  /// The live robot's ground speed [m/s] by its newest telemetry (0 without one).
  double robotSpeed() const;

 protected:
  bool eventFilter(QObject* watched, QEvent* event) override;
  void closeEvent(QCloseEvent* event) override;

 private:
  // The constructor's parts, in order.
  void buildCentral();     // the banner, the stale label and the 3D view
  void buildFeeds();       // the link, the ghost, the feed switch and what they draw
  void buildPlots();       // the plots dock
  void buildContext();     // what the jobs are given
  void startPanelTimer();  // the one refresh of everything around the 3D view
  void restoreLayout();    // the operator's saved layout, or ours
  void buildMenus();
  /// The console's world changed (`fresh`: a new one, not the same shown
  /// again): jobs and, while the live robot is shown, the views follow.
  void showWorld(const WorldModel& world, bool fresh);
  /// After the session started or switched robots: redraw, reconnect.
  void sessionChanged();
  /// A frame of the feed shown: drawn.
  void onShownFrame(const RobotFrame& frame);
  void onFeedSwitched(RobotFeed* feed);
  /// The console's state changed: banner, menus, jobs follow.
  void stateChanged();
  const ConsoleState& state() const;
  void refreshStatus();
  void updateStale();
  /// A new session or world: forget the last robot's frames and plots.
  void clearFrames();

  ConsoleOptions options_;
  QString logDir_;
  std::unique_ptr<ConsoleSession> session_;
  ConsoleMonitor* monitor_ = nullptr;
  int shownWorld_ = -1;  // the session's worldVersion() the jobs have
  RobotConnection* connection_ = nullptr;
  LiveLinkFeed* liveFeed_ = nullptr;
  GhostFeed* ghostFeed_ = nullptr;
  FeedSwitch* feeds_ = nullptr;
  BackgroundJobs* background_ = nullptr;
  ConsoleContext* context_ = nullptr;
  std::vector<std::unique_ptr<ConsoleJob>> jobs_;

  SceneView* scene_ = nullptr;
  WheelForcePlot* wheelPlot_ = nullptr;
  LaserPlot* laserPlot_ = nullptr;
  PredictionErrorPlot* errorPlot_ = nullptr;
  QDockWidget* plotsDock_ = nullptr;
  QDockWidget* linkDock_ = nullptr;
  std::vector<QDockWidget*> sideDocks_, bottomDocks_;  // the jobs', in install order
  std::map<QString, QAction*> menuAnchors_;  // jobs' items go before these
  QAction* ghostAction_ = nullptr;
  bool ghostShownBeforeReplay_ = false;
  QLabel* banner_ = nullptr;
  std::vector<Vec3> departures_;  // where the robot departed from its twin (marked on the ground)
  bool departureOn_ = false;
  QWidget* bannerRow_ = nullptr;        // the banner and its Reset button
  QPushButton* bannerReset_ = nullptr;  // shown when the twin diverged or the robot is off the terrain
  QLabel* staleLabel_ = nullptr;
  StatusFields* status_ = nullptr;
  int64_t panelTicks_ = 0;
};

}  // namespace sp
