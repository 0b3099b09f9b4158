#pragma once
// What a console job gets to work with. A job (ui/jobs/<name>/: driving,
// rehearsing sequences, replaying logs, editing terrain, ...) is a dock with
// its menu items; it installs itself through a ConsoleContext and never
// reaches into the window (gz-sim's GUI plugins, PlotJuggler's plugins):
//
//   feeds()       which robot the views show (live link, replay) and the ghost
//   sendCommand(), editTerrain(), sendSequence(): the sinks; the lease and
//                the shown feed are checked inside
//   state()       what the console knows of the link (app/console/console_state.h)
//   scene(), the plots: the views, to draw into
//   status(), event(), logEvent(): the status bar, the event list, the log
//   background(): one worker with progress and Cancel for long work
//   host(): a place in the window (addDock(), menu(), growDock()), a parent
//                for dialogs; the window itself is not handed out
//
// Thread: GUI thread only, as every job.

#include <QCommandLineOption>
#include <QMessageBox>
#include <QObject>
#include <QString>

#include <functional>
#include <memory>
#include <vector>

QT_FORWARD_DECLARE_CLASS(QCommandLineParser)

#include "app/console/console_state.h"
#include "app/rehearse/rehearsal.h"
#include "app/rehearse/sequence_guard.h"
#include "net/message.h"
#include "sim/command.h"
#include "sim/params.h"
#include "sim/robot_model.h"
#include "sim/terrain_brush.h"

class QAction;
class QDockWidget;
class QMenu;
class QWidget;

namespace sp {

class BackgroundJobs;
struct BranchPoint;
class ConsoleSession;
class LiveCalibrator;
class TerrainEditor;
class FeedSwitch;
class GhostFeed;
class LaserPlot;
class PredictionErrorPlot;
class RobotConnection;
class SceneView;
class WheelForcePlot;

/// Where a job's dock goes in the default layout.
enum class DockPlace {
  Side,    ///< a tab behind the controls, right of the 3D view
  Bottom,  ///< a tab behind the plots, under the 3D view
  Link,    ///< under the side docks, right of the 3D view (the link's own dock)
};

/// What the console (the window) does for its jobs that a job cannot do on
/// its own, because it changes the whole console. MainWindow implements it.
class ConsoleHost {
 public:
  virtual ~ConsoleHost() = default;
  /// Opens `path` as the console's world: "" or why not (shown unless `quiet`).
  virtual QString openWorld(const QString& path, bool quiet) = 0;
  /// Restarts the stand-in from a replayed log's state: "" or why not
  /// (shown unless `quiet`). The caller closes its replay.
  virtual QString startBranch(const QString& logPath, const BranchPoint& point, bool quiet) = 0;
  /// The session switched robots (connected elsewhere, reset, ...): the
  /// views follow its world (forgetting the old robot's frames when
  /// `clearFrames`), and the link reconnects.
  virtual void restarted(bool clearFrames) = 0;
  /// A dock for `panel` (scrolled when `scrolled`), placed by `place`.
  virtual QDockWidget* addDock(const QString& title, const QString& objectName, QWidget* panel, DockPlace place,
                               bool scrolled) = 0;
  /// The menu bar's menu titled `title` ("&File", "&Robot", "&View", ...), made if missing.
  virtual QMenu* menu(const QString& title) = 0;
  /// Puts `action` into menu `title` among the jobs' items (in the File
  /// menu: after the window's Open items, before the log and Quit items).
  virtual void addMenuAction(const QString& title, QAction* action) = 0;
  /// Makes `dock` at least `height` pixels tall, but no more than `share`
  /// of the window's height (after the window has laid out its docks).
  virtual void growDock(QDockWidget* dock, int height, double share) = 0;
  /// What a job's dialogs and menus are parented to (the console's window).
  virtual QWidget* dialogParent() = 0;
};

/// Everything a job may use; the window owns it and outlives every job.
class ConsoleContext : public QObject {
  Q_OBJECT

 public:
  struct Parts {
    ConsoleHost* host = nullptr;
    ConsoleSession* session = nullptr;
    RobotConnection* connection = nullptr;
    FeedSwitch* feeds = nullptr;
    GhostFeed* ghost = nullptr;
    const ConsoleState* state = nullptr;
    SceneView* scene = nullptr;
    WheelForcePlot* wheelPlot = nullptr;
    LaserPlot* laserPlot = nullptr;
    PredictionErrorPlot* errorPlot = nullptr;
    BackgroundJobs* background = nullptr;
    /// The status bar: the window's own.
    std::function<void(const QString&, int)> status;
  };
  ConsoleContext(Parts parts, QObject* parent = nullptr);

  /// What the session knows (robot, world, endpoint, logs, parameters):
  /// read-only; what a job may change of it is below.
  const ConsoleSession& session() const { return *parts_.session; }
  /// The calibration from telemetry (the calibration job freezes and
  /// resets it); null without one.
  LiveCalibrator* calibrator() const;
  /// The console's terrain editor (the terrain job's brushes and undo);
  /// null on a plane.
  TerrainEditor* terrainEditor() const;
  /// The session's robot switched (the link job): the stand-in again, a
  /// robot at HOST:PORT, or the stand-in reset to its start. "" or why not
  /// (nothing changed then).
  std::string useStandIn();
  std::string connectTo(const std::string& hostPort, const std::string& token);
  std::string resetRobot();
  RobotConnection& connection() const { return *parts_.connection; }
  FeedSwitch& feeds() const { return *parts_.feeds; }
  GhostFeed& ghost() const { return *parts_.ghost; }
  const ConsoleState& state() const { return *parts_.state; }
  SceneView& scene() const { return *parts_.scene; }
  WheelForcePlot& wheelPlot() const { return *parts_.wheelPlot; }
  LaserPlot& laserPlot() const { return *parts_.laserPlot; }
  PredictionErrorPlot& errorPlot() const { return *parts_.errorPlot; }
  BackgroundJobs& background() const { return *parts_.background; }
  /// What a job's dialogs, menus and actions are parented to.
  QWidget* dialogParent() const { return parts_.host->dialogParent(); }
  ConsoleHost& host() const { return *parts_.host; }

  /// The live robot's joint positions as last reported (model order).
  const std::vector<double>& measuredPositions() const { return measured_; }
  void setMeasuredPositions(std::vector<double> positions) { measured_ = std::move(positions); }

  /// The command sink: sends `command` to the live robot, or refuses (no
  /// lease, a replay shown, ...) and says why in the status bar. Returns
  /// "" when sent, else the reason.
  QString sendCommand(const Command& command);
  /// The terrain sink: `patch` (made by the session's terrain editor, in
  /// its heights already) goes to the view and the jobs (terrainEdited) and,
  /// while the console holds the lease of a robot that takes edits (a
  /// simulator), to the robot's twin in frame-sized parts. False while a
  /// replay is shown or when the patch does not fit the terrain.
  bool editTerrain(const TerrainPatchCmd& patch);
  /// The robot announced it takes terrain edits (WELCOME capability terrain_edit).
  bool robotTakesTerrainEdits() const;
  /// The sequence sink: SEQUENCE to the live robot while the console holds
  /// the lease and shows the live robot; "" when sent, else why not.
  QString sendSequence(const net::SequenceMsg& message);
  /// ABORT of the sequence `hash` on the live robot.
  void abortSequence(const QString& hash, const QString& reason);
  /// The guard of relayed sequences, fed on the link's worker.
  const std::shared_ptr<SequenceGuard>& guard() const;
  /// A message in the status bar for `ms` milliseconds (0 = until replaced).
  void status(const QString& text, int ms = 5000) const { parts_.status(text, ms); }
  /// An event of the console's own (`kind`: "note", "estop", "link", ...):
  /// in the event list, and in the session log when `log`.
  void event(const QString& kind, const QString& text, bool log = true);
  /// Something the console decided (`kind` "rehearsal", "relay", "guard"),
  /// into the session log only.
  void logEvent(const QString& kind, const QString& text) const;
  /// Shows `text` (errors with file:line) under `title` in a dialog.
  void showError(const QString& title, const QString& text) const;
  /// Asks the operator before something that cannot be taken back: a modal
  /// box named `objectName` (tests find it) whose default is Cancel, so no
  /// stray Enter or Space says yes. True when `yes` was clicked.
  bool confirm(QMessageBox::Icon icon, const QString& title, const QString& text, const QString& objectName,
               const QString& yes, QMessageBox::ButtonRole role = QMessageBox::AcceptRole) const;

 public slots:
  /// Sends the e-stop to the live robot (whatever the views show) before
  /// anything else: then the event list, the log and the status bar.
  void emergencyStop();

 signals:
  /// The session's robot endpoint may have changed: the link (re)connects.
  void sessionChanged();
  /// An event for the event list (event()).
  void eventShown(const QString& text);
  /// The console's (live) world changed: a new world, robot or session.
  /// `fresh` is false when the same world is shown again (after a replay).
  void worldChanged(const sp::WorldModel& world, bool fresh);
  /// state() changed: what is enabled and why may differ.
  void stateChanged();
  /// The robot stopped on its own (a latch, the lease lost, re-armed):
  /// controls go back to its state (measuredPositions()).
  void robotStopped();
  /// The window's panel timer (every 100 ms): replot, show measured values.
  void panelTick();
  /// The console's terrain changed (an edit applied to its world).
  void terrainEdited(const sp::TerrainPatchCmd& patch);
  /// The default layout was put back: a job shows or hides its docks.
  void layoutReset();
  /// The operator asked to put the robot back at its start (the banner's
  /// button): the link job resets the stand-in.
  void resetRequested();
  /// The robot's SEQUENCE_STATE (after the guard took it).
  void sequenceState(const sp::net::SequenceStateMsg& state);
  /// The guard tripped; its ABORT has gone out already.
  void guardTripped(const QString& hash, const sp::GuardDeparture& departure);
  /// Rehearse from a logged moment (the Replay job asks, the Sequence job does).
  void rehearseFrom(const sp::RehearsalStart& start, const sp::WorldModel& world, const sp::SimParams& params,
                    const QString& label);

 private:
  /// Why nothing goes to the robot now (a replay shown, no lease), or "".
  std::string sinkRefusal() const;

  Parts parts_;
  std::vector<double> measured_;
};

/// A console job: installs its dock(s), menu items and wiring through the
/// context. Jobs are listed in ui/jobs/jobs.cpp; a test may install its own.
class ConsoleJob : public QObject {
  Q_OBJECT

 public:
  using QObject::QObject;
  /// A short name ("drive", "sequence", ...): the job's object name.
  virtual QString name() const = 0;
  /// Builds the job's widgets into `context`'s window; called once, after
  /// the window's own views exist. `context` outlives the job.
  virtual void install(ConsoleContext& context) = 0;
  /// The job's own command-line options (ui/jobs/jobs.h addJobOptions():
  /// the console's parser takes them beside its own); none by default.
  virtual QList<QCommandLineOption> commandLineOptions() const { return {}; }
  /// The command line parsed, before install(): the job takes its options'
  /// values. "" or what is wrong with them, naming where (`FILE: error: ...`,
  /// `<command line>: error: --option: ...`).
  virtual QString takeCommandLine(const QCommandLineParser& parser) {
    Q_UNUSED(parser);
    return {};
  }
  /// The console is starting (after every job is installed): a job may
  /// open what the command line named. "" or why the console cannot start.
  virtual QString start() { return {}; }
};

/// Jobs, in the order their docks are laid out (ui/jobs/jobs.h).
using ConsoleJobs = std::vector<std::unique_ptr<ConsoleJob>>;

}  // namespace sp
