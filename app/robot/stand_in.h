#pragma once
// The stand-in robot as one object: the twin (TwinHost, its own physics
// thread paced at the real-time factor) behind the link protocol's server
// (net::RobotServer, on its own io_context thread), with link emulation and
// the session log. `simpartner-robot` is a thin main() around it; the
// console runs one in-process.
//
//   sp::Diagnostics diag;
//   auto robot = sp::StandInRobot::create(options, diag);  // loads files
//   if (!robot) { show(diag.format()); return; }
//   if (std::string error = robot->start(); !error.empty()) { show(error); return; }
//   connect a RobotClient to 127.0.0.1:robot->port() with robot->token() ...
//   robot->stop();  // or let the destructor do it
//
// Threads. create(), start(), stop() and the destructor belong to the
// owner's thread (the console's GUI thread); they never wait on a client.
// start() starts two threads: the physics thread (which alone touches the
// World and feeds the log) and the server's io_context thread (sockets,
// lease, safety chain), so the owner's thread stays free. The accessors and
// addNote() may be called from any thread once start() has returned. The
// `lineLog` callback runs on the server's thread: it must be quick, must not
// touch widgets (re-post with a queued call) and must not call stop().

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "net/link_emulator.h"
#include "sim/diagnostics.h"
#include "sim/params.h"
#include "sim/perturbation.h"
#include "sim/robot_model.h"
#include "sim/world.h"

namespace sp {

class TwinHost;
struct LogPrediction;
struct LogCalibration;
class SessionLogWriter;

/// How to run the stand-in robot. Defaults: loopback, the parameters'
/// port.robot and realtime.factor, a generated token, a log in `sessions/`.
struct StandInOptions {
  std::string worldFile;               ///< required
  /// A robot file to run in place of the world's own robot (same name and
  /// pose in the world); "" = the world's.
  std::string robotFile;
  /// A world whose terrain the robot really stands on in place of
  /// worldFile's, which it still announces and logs as its files: ground
  /// its map lacks (a ridge, a hollow; issue 61). "" = the world's.
  std::string groundFile;
  std::string paramsFile;              ///< "" = built-in defaults
  std::vector<std::string> overrides;  ///< key=value, applied after the file
  std::string bind = "127.0.0.1";      ///< any other address needs a token
  std::optional<uint16_t> port;        ///< nullopt = port.robot of the parameters; 0 = any free port
  std::string token;                   ///< >= 32 hex digits; "" = a random one (loopback only)
  std::optional<double> realTimeFactor;  ///< nullopt = realtime.factor; <= 0 = unpaced
  net::LinkEmulatorConfig emulation;   ///< delay, jitter, loss in both directions; inactive by default
  bool log = true;                     ///< write a session log (docs/session-format.md)
  std::string logPath;                 ///< the log file (must not exist); "" = a new file in logDir
  /// Folder for a new `session-YYYYMMDD-HHMMSS.splog` (local time; `-2`,
  /// `-3`, ... appended if taken), created if missing. Relative to the
  /// current directory.
  std::string logDir = "sessions";
  /// Start from this state instead of the world's initial one (a branch
  /// of a logged session: app/log/resimulation.h branchAt); it must fit the
  /// world (the same files).
  std::optional<Snapshot> startState;
  /// Take terrain edits over the link (a simulator's capability, announced
  /// in WELCOME as `terrain_edit`); false behaves as a real robot: refused.
  bool terrainEdits = true;
  /// A robot that is not its twin: hidden deviations from the files drawn
  /// from this seed (sim/perturbation.h); none when unset. WELCOME's file
  /// hashes stay the files'; the session log records the deviations (meta
  /// `perturbation_seed` and `perturbation`), and re-simulation applies them.
  std::optional<uint64_t> perturbSeed;
  /// A factor per wheel motor's torque limit (FL FR RL RR), on top of any
  /// perturbation: a weak motor (Perturbation::wheelTorque). The log records
  /// it (meta `perturbation_wheel_torque`) and re-simulation applies it.
  std::array<double, 4> wheelTorque{1, 1, 1, 1};
  /// A robot that changes while it runs (sim/perturbation.h): its friction
  /// and delay at a time. The log records it (meta `perturbation_change`
  /// and a "note" event when it happens); re-simulation does not apply it,
  /// so a replay's check says the twin diverged from there.
  std::optional<SuddenChange> change;
  /// Further meta for the session log (`parent_log`, `parent_time`).
  std::map<std::string, std::string> logMeta;
  /// Lines for the operator (no newline): connections, refusals, lease
  /// changes, e-stops. May be empty. Runs on the server's thread.
  std::function<void(const std::string&)> lineLog;
};

/// What the server counted over a run (net::RobotServerStats).
struct StandInStats {
  uint64_t clientsAccepted = 0;
  uint64_t framesIn = 0;
  uint64_t badFrames = 0;         ///< connections closed for a malformed frame
  uint64_t telemetryDropped = 0;  ///< for clients that read too slowly
  uint64_t emulatedLost = 0;      ///< frames the emulated link dropped
};

/// The twin standing in for the robot, behind the link. Not copyable.
class StandInRobot {
 public:
  /// Loads the world and parameters (file, then overrides) and builds the
  /// twin; nothing runs yet and no file is written. Returns nullptr with the
  /// reasons in `diag` (`file:line: error: ...`): file errors, a world
  /// without a robot, an open address without a token.
  static std::unique_ptr<StandInRobot> create(const StandInOptions& options, Diagnostics& diag);
  /// Calls stop().
  ~StandInRobot();
  StandInRobot(const StandInRobot&) = delete;
  StandInRobot& operator=(const StandInRobot&) = delete;

  /// Listens, opens the session log (after listening, so a refused port
  /// leaves no file) and starts the physics and server threads. Returns ""
  /// on success, else why not (address in use, the log cannot be created);
  /// then nothing runs and stop() is not needed. Once only.
  std::string start();
  /// Stops serving (closes every connection), stops the twin and closes
  /// the log: when it returns the log file is complete. Joins both threads
  /// (a few ms). Idempotent.
  void stop();
  /// A shutdown that leaves the robot still (SIGTERM, SIGINT): every motor
  /// is stopped first, as by an e-stop (latched); every client gets EVENT
  /// estop and ERROR `reason` and is closed; the stop and `reason` are
  /// logged; the twin runs on until the robot is at rest (at most
  /// `maxWait` [s]) and its log has samples of it at rest; then stop().
  /// Returns whether it came to rest in time.
  bool shutdown(const std::string& reason, double maxWait = 3.0);
  /// The link fades for `seconds` from now, both ways (net::RobotServer::
  /// fade): nothing sent meanwhile arrives before the fade ends. Any thread;
  /// does nothing before start().
  void fadeLink(double seconds);

  /// The port listened on (the real one when 0 was asked); 0 before start().
  uint16_t port() const { return port_; }
  /// The shared secret clients must present (given or generated).
  const std::string& token() const { return token_; }
  /// The address listened on.
  const std::string& address() const { return options_.bind; }
  /// The session log's path, "" without a log (or before start()).
  const std::string& logPath() const { return logPath_; }
  /// The world loaded (immutable; any thread).
  const WorldModel& world() const { return world_; }
  /// True once writing the log failed (disk full, I/O error): the twin runs
  /// on, later log items are dropped. Poll it (no callback).
  bool logFailed() const;
  /// Why the log failed, "" if it did not.
  std::string logError() const;
  /// Log items dropped so far (a full queue or a failed disk).
  int64_t logDropped() const;
  /// The server's counts, final once stop() has returned (zeros before:
  /// they live on the server's thread while it runs).
  StandInStats stats() const { return stats_; }
  /// Writes an operator note (event kind "note") into the log at the twin's
  /// current step; dropped without a log. Never blocks on the disk.
  void addNote(std::string text);
  /// Writes an event of `kind` (rehearsal, sequence, guard, ...) the same way.
  void logEvent(std::string kind, std::string text);
  /// Logs a prediction of the console's ghost; dropped without a log.
  void logPrediction(const LogPrediction& prediction);
  void logCalibration(const LogCalibration& row);

 private:
  struct Server;  // the io_context, RobotServer and its thread (Asio stays out of this header)
  StandInRobot(StandInOptions options, WorldModel world, std::unique_ptr<TwinHost> host, SimParams params,
               std::string replacedRobotFile);
  // The log file for this start; "" and `error` set if none can be made.
  std::string chooseLogPath(std::string& error) const;
  /// The session log's extra meta: the options' and the perturbation's.
  std::map<std::string, std::string> logMeta() const;

  StandInOptions options_;
  std::string replacedRobotFile_;  // the world's own robot file, when options_.robotFile replaced it
  const WorldModel world_;
  SimParams params_;
  std::string token_;
  std::unique_ptr<TwinHost> host_;
  std::unique_ptr<Server> server_;
  uint16_t port_ = 0;
  std::string logPath_;
  StandInStats stats_;
  bool started_ = false;
};

}  // namespace sp
