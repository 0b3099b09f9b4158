#pragma once
// The operator console's session, without any GUI: which robot it talks to
// (the stand-in it runs on loopback, or a robot elsewhere), the world it
// draws, the session log, and what arrives over the link turned into the
// frames the views draw. ui/MainWindow is its face; tests drive it directly.
//
//   sp::ConsoleSession session(options);
//   if (std::string error = session.start(); !error.empty()) show(error);
//   connect a RobotClient to session.endpoint() ...
//   on telemetry:  sp::RobotFrame f = session.telemetry(message, wallSeconds);
//   before a command: if (auto why = session.commandRefusal(leaseHeld); !why.empty()) tell(why);
//
// Thread: the owner's (the console's GUI thread) only, but for tap(): the
// link's worker hands telemetry to it (app/console/telemetry_tap.h). The
// stand-in it runs has threads of its own (app/robot/stand_in.h); nothing
// here blocks on them or on the disk.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/calibration/live_calibrator.h"
#include "app/console/telemetry_tap.h"
#include "app/ghost/ghost.h"
#include "app/log/resimulation.h"
#include "app/rehearse/rehearsal.h"
#include "app/state/robot_frame.h"
#include "net/message.h"
#include "net/robot_client.h"
#include "sim/params.h"
#include "sim/perturbation.h"
#include "sim/robot_model.h"

namespace sp {

class StandInRobot;
class TelemetryRecorder;
class TerrainEditor;

/// What the console starts with (the `simpartner` command line).
struct ConsoleSessionOptions {
  std::string world = "terrains/flat.world.xml";  ///< drawn; run by the stand-in
  std::string params;                  ///< parameters file; "" = built-in defaults
  std::vector<std::string> overrides;  ///< KEY=VALUE
  std::string connectTo;               ///< HOST:PORT of a robot; "" = run the stand-in on loopback
  std::string token;                   ///< the robot's shared secret (generated for the stand-in if "")
  bool log = true;                     ///< log the session
  std::string logDir = "sessions";     ///< where new logs go
  double rtf = -1;                     ///< stand-in real-time factor; < 0 = the parameters'
  double delay = 0;                    ///< [s] the stand-in's link emulates this one-way delay (each way)
  double jitter = 0;                   ///< [s] +- on that delay, drawn per frame (each way)
  /// The stand-in is a robot that is not its twin: hidden deviations drawn
  /// from this seed (sim/perturbation.h); the console's twin, ghost and
  /// rehearsals keep the files. nullopt = the stand-in runs the files.
  std::optional<uint64_t> perturbSeed;
  /// The stand-in's wheel motors' torque factors on top (StandInOptions::wheelTorque).
  std::array<double, 4> wheelTorque{1, 1, 1, 1};
  /// The stand-in changes while it runs (StandInOptions::change).
  std::optional<SuddenChange> change;
  /// The stand-in stands on this world's terrain instead of the drawn
  /// world's (StandInOptions::groundFile): ground the console's map lacks.
  std::string ground;
  bool ghost = true;                   ///< run the predictive ghost (app/ghost/ghost.h)
  /// Calibrate the twin from telemetry while driving (app/calibration/
  /// live_calibrator.h; needs the ghost: its clock dates the commands).
  bool calibrate = true;
  LiveCalibrator::Options calibration;  ///< its options
  Ghost::Options ghostOptions;         ///< its options (tests' controls)
};

/// Where the console's link goes.
struct RobotEndpoint {
  std::string host;
  uint16_t port = 0;  ///< 0 = nowhere yet
  std::string token;
  std::string label;  ///< for the operator, e.g. "127.0.0.1:41234 (stand-in, flat.world.xml)"
};

/// The endpoint HOST:PORT with `token` (>= 32 hex digits), or nullopt and
/// `error` saying which of the two is wrong.
std::optional<RobotEndpoint> parseEndpoint(const std::string& hostPort, const std::string& token, std::string& error);

class ConsoleSession {
 public:
  explicit ConsoleSession(ConsoleSessionOptions options);
  /// Stops the stand-in (its log is complete when this returns).
  ~ConsoleSession();
  ConsoleSession(const ConsoleSession&) = delete;
  ConsoleSession& operator=(const ConsoleSession&) = delete;

  /// Loads the world and starts the stand-in on it, or, with connectTo,
  /// checks the endpoint and opens the console's own log of the remote
  /// robot. "" on success, else what went wrong (`file:line: error: ...`
  /// where there is a line).
  std::string start();

  /// Loads `path` as the world. With the stand-in: starts a new one on it
  /// and replaces the running one only once it runs. With a remote robot:
  /// only what is drawn changes. On error returns it and nothing changes.
  std::string openWorld(const std::string& path);
  /// Loads `path` as the robot, in place of the world's own (same place).
  std::string openRobot(const std::string& path);

  bool remote() const { return !options_.connectTo.empty(); }
  /// Where this session's logs go (and the logs to replay are looked for first).
  const std::string& logDir() const { return options_.logDir; }
  /// Switches to the robot at HOST:PORT with `token`: the stand-in (if any)
  /// stops with its log complete, a new log of what the console sees
  /// starts. On a bad endpoint or token returns why and changes nothing.
  std::string connectTo(const std::string& hostPort, const std::string& token);
  /// Switches back to a stand-in on loopback running the drawn world.
  std::string useStandIn();
  /// Robot > Reset: the stand-in restarts with the robot at its start (the
  /// old log notes it and is complete; the new one names the old). For a
  /// robot elsewhere returns why not.
  std::string resetRobot();
  /// Replay ▸ Simulate from here: a new stand-in starts from the state of
  /// the log at `logPath` at `time` [s] (re-simulated from the snapshot
  /// before it, or reconstructed from a telemetry-only log's sample:
  /// LogPlayer::branchAt), logging into a new log that names its parent
  /// and time; it replaces the running stand-in once it runs. Needs the
  /// log's world, robot and parameters to be the files the console runs
  /// (else says which differs); a robot elsewhere cannot be branched. ""
  /// or why not.
  std::string branchFrom(const std::string& logPath, double time);
  /// The same from a branch point computed already (on a worker thread,
  /// with progress: LogPlayer::branchAt).
  std::string branchFrom(const std::string& logPath, const BranchPoint& point);
  /// The robot announced (WELCOME) the hashes of the files it runs ("" =
  /// not announced): "" when they match the files the console's twin and
  /// ghost are built from, else what differs, for the operator.
  std::string filesMismatch(const std::string& worldHash, const std::string& robotHash) const;
  /// How far `base` is inside the edge of a heightfield terrain [m]
  /// (negative: beyond it); nullopt on a plane, which has no edge.
  std::optional<double> edgeDistance(const Pose& base) const;
  /// The world drawn (its robots[0] is the one controlled); null before start().
  const WorldModel* world() const { return world_ ? &*world_ : nullptr; }
  /// robots[0]'s model, or null.
  const RobotModel* robot() const;
  /// Counts world changes: views rebuild when it moves on.
  int worldVersion() const { return worldVersion_; }
  const RobotEndpoint& endpoint() const { return endpoint_; }
  /// How the console's client of endpoint() behaves, named `name` (HELLO):
  /// the parameters' keep-alive period, command expiry and handshake
  /// timeout (link.hello_timeout), and the robot file's joints and limits
  /// that every TELEMETRY is checked against (net/link_check.h).
  net::RobotClientConfig clientConfig(const std::string& name) const;
  /// The parameters (file, then overrides) as loaded by start(): the
  /// client's keep-alive period and command expiry come from them.
  const SimParams& params() const { return params_; }
  /// The stand-in running, or null (remote, or before start()).
  const StandInRobot* standIn() const { return standIn_.get(); }

  /// The session log's path, "" without one.
  std::string logPath() const;
  /// Why the log failed, "" while it works.
  std::string logError() const;

  /// Where telemetry goes on arrival (app/console/telemetry_tap.h): the
  /// link's worker hands each frame to it; the session binds it to its
  /// log, ghost and calibrator, whichever they are now.
  const std::shared_ptr<TelemetryTap>& tap() const { return tap_; }
  /// A telemetry frame through tap() here and now (tests; a console's
  /// link hands frames to the tap on its own thread), then takeCalibration():
  /// the frame to draw (joints in the model's order), logged when the
  /// robot is remote; it re-anchors the ghost; what the ghost had
  /// predicted for the frame's time is then lastPrediction(), and logged.
  /// `roundTrip` [s] is the link's as the client measures it (0 = not
  /// yet; the robot's own figure in the message is used then).
  RobotFrame telemetry(const net::TelemetryMsg& message, double wall, double roundTrip = 0);
  /// Hands a new calibration (a fit landed) to the ghost and logs the fits
  /// made since the last call: the GUI calls it as frames come in.
  void takeCalibration();
  /// The predictive ghost of the drawn world's robot; null without one
  /// (options.ghost false, or it could not be built: ghostError()).
  const Ghost* ghost() const { return ghost_.get(); }
  const std::string& ghostError() const { return ghostError_; }
  /// The calibration from telemetry; null without a ghost (or with
  /// options.calibrate false). Its applied values reach the ghost at the
  /// next telemetry frame and twinParams() at once.
  LiveCalibrator* calibrator() { return calibrator_.get(); }
  const LiveCalibrator* calibrator() const { return calibrator_.get(); }
  /// The parameters with the calibration applied now: what the twins the
  /// console starts (rehearsals, robustness runs, sweeps) are built with
  /// (the calibrator's fullPhysics(): the radius splits once the full
  /// physics confirmed them).
  SimParams twinParams() const;
  /// What the console knows of the robot for robustness draws: the
  /// calibration's deviations where its fits observed a parameter, the
  /// prior's range where not; nullopt without a calibrator (the rules'
  /// fixed ranges then).
  std::optional<RobotEstimate> twinEstimate() const;
  /// The last telemetry frame against the ghost's prediction for its time;
  /// nullopt when the ghost had shown nothing for that time.
  std::optional<GhostError> lastPrediction() const;
  /// A laser scan through tap() here and now: the frame to draw, logged when remote.
  LaserFrame laser(const net::LaserMsg& message);
  /// The real-time factor the stand-in is asked to run at (`--rtf`, else
  /// the parameters').
  double targetRealTimeFactor() const { return options_.rtf >= 0 ? options_.rtf : params_.realTimeFactor; }
  /// The achieved real-time factor over the last second of telemetry.
  double realTimeFactor() const;

  /// "" when a command may go to the robot now, else why not (for the
  /// operator): only the lease holder commands.
  std::string commandRefusal(bool leaseHeld) const;
  /// A command went out: logged when the robot is remote (the stand-in logs
  /// what it applies itself), and handed to the ghost.
  void commandSent(const Command& command);
  /// The link went down (`why`): the ghost stops predicting from the last
  /// telemetry (it would run on from it as if the robot drove on) until
  /// the next frame.
  void linkDown(const std::string& why);
  /// An e-stop went out: the ghost (and the calibration) stop the robot
  /// where it lands, as a `stop` sent now.
  void estopSent();
  /// The console's terrain: the editor of the world's heightfield, which
  /// edits world()'s heights in place (what is drawn, rehearsed and saved),
  /// with its undo history; null on a plane. Replaced with the world.
  TerrainEditor* terrainEditor() { return terrain_.get(); }
  /// A terrain edit made through terrainEditor() (already in world()'s
  /// heights): the ghost takes it now, and a remote robot's telemetry log
  /// records it (the stand-in logs what it applies). Sending it to the
  /// robot's twin is the caller's (when the robot announces
  /// `terrain_edit`). False when it does not fit the terrain.
  bool terrainEdited(const TerrainPatchCmd& patch);
  /// An operator note into the session log.
  void note(const std::string& text);
  /// Something the console did or decided (kind "rehearsal", "relay",
  /// "guard"), into the session log whichever robot it is.
  void logEvent(const std::string& kind, const std::string& text);
  /// A link event the console saw ("link", "estop", ...): logged when remote
  /// (the stand-in logs its own link events).
  void event(const std::string& kind, const std::string& text);

 private:
  std::string startStandIn(const std::string& worldFile, const std::string& robotFile,
                           const Snapshot* startState = nullptr, std::map<std::string, std::string> logMeta = {});
  void setWorld(WorldModel world);
  void openRemoteLog();
  /// Deletes logs beyond log.keep in the log folder (never the current one).
  void pruneLogs();
  /// The tap handed frames to the parts as they are now.
  void bindTap();
  /// Unbinds the tap while the parts change, binds them again after.
  struct TapRebind {
    explicit TapRebind(ConsoleSession& s) : session(s) { s.tap_->unbind(); }
    ~TapRebind() { session.bindTap(); }
    ConsoleSession& session;
  };

  ConsoleSessionOptions options_;
  SimParams params_;
  std::optional<WorldModel> world_;
  std::unique_ptr<TerrainEditor> terrain_;  // edits world_'s heights
  int worldVersion_ = 0;
  std::string worldFile_;  // the stand-in's world file
  std::string robotFile_;  // the robot file replacing the world's, "" for the world's own
  std::unique_ptr<StandInRobot> standIn_;
  std::unique_ptr<TelemetryRecorder> recorder_;  // the log of a remote robot
  std::string recorderError_;
  RobotEndpoint endpoint_;
  std::unique_ptr<Ghost> ghost_;
  std::unique_ptr<LiveCalibrator> calibrator_;
  int64_t calibrationSeen_ = 0;  // the calibrator's version the ghost and the log have
  int calibrationFitsLogged_ = 0;
  CalValues ghostCalibration_{};  // the calibration the ghost was last handed
  std::string ghostError_;
  std::shared_ptr<TelemetryTap> tap_ = std::make_shared<TelemetryTap>();
};

}  // namespace sp
