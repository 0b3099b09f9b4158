#pragma once
// The twin as a robot behind the link: a World stepped on its own physics
// thread, paced by the monotonic clock, taking commands at step boundaries,
// publishing its state for the server (net::RobotPort), and optionally
// writing the session log (app/log/session_recorder.h).
//
// Thread: the World lives on the physics thread alone (between start() and
// stop()); the RobotPort methods may be called from any one other thread
// (the server's) and exchange values under a short lock. logEvent() and the
// log's status may be called from any thread. The constructor, logTo(),
// start() and stop() belong to the owner's thread.

#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/log/session_recorder.h"
#include "net/robot_server.h"
#include "sim/perturbation.h"
#include "sim/runner.h"
#include "sim/world.h"

namespace sp {

class TwinHost : public net::RobotPort {
 public:
  /// `realTimeFactor` <= 0 runs unpaced.
  TwinHost(std::unique_ptr<World> world, double realTimeFactor);
  /// Calls stop().
  ~TwinHost() override;
  TwinHost(const TwinHost&) = delete;
  TwinHost& operator=(const TwinHost&) = delete;

  /// Logs the session into `writer` (taken; nullptr: no log), from the
  /// physics thread: the initial snapshot, every command applied (source
  /// "operator"), samples at rate.log, robot 0's laser scans, a snapshot and
  /// state hash every sim second and at stop(), a "health" event when the
  /// twin diverges, and the events of logEvent(). Call before start().
  void logTo(std::unique_ptr<SessionLogWriter> writer);
  /// Takes terrain edits (`terrain` commands, checked against the
  /// heightfield) over the link: a simulator's capability, announced in
  /// WELCOME as `terrain_edit`. Off by default: a robot refuses them.
  void acceptTerrainEdits(bool on) { terrainEdits_ = on; }
  /// A robot that is not its twin (sim/perturbation.h): commands take
  /// effect `delay` [s] after they arrive, and the reported roll and pitch
  /// carry these biases [rad]. Before start().
  void setDeviations(double delay, double rollBias, double pitchBias) {
    delay_ = delay;
    rollBias_ = rollBias;
    pitchBias_ = pitchBias;
  }
  /// The robot changes at `change.at` (sim time): the World's friction is
  /// scaled and the delay grows, on the physics thread at a step boundary,
  /// logged as a "note" event. Before start().
  void scheduleChange(const SuddenChange& change) { change_ = change; }
  bool acceptsTerrainEdits() const { return terrainEdits_; }
  /// Starts the physics thread. Once only.
  void start();
  /// Stops and joins the physics thread, then logs the last snapshot and
  /// closes the log (the file is complete when this returns). Commands
  /// queued since the thread's last pass are applied in one more step, so
  /// none that apply() accepted is lost. Idempotent.
  void stop();

  /// Queues an event for the log (kind "link", "estop", "note", ...); the
  /// physics thread writes it with the twin's step and time when it next
  /// takes commands (within a few ms). Without a log it is dropped. Thread:
  /// any; never blocks on the disk.
  void logEvent(std::string kind, std::string text);
  /// The log's writer, or null without one; its failed(), errorMessage()
  /// and dropped() may be read from any thread.
  const SessionLogWriter* log() const { return log_ ? &log_->writer() : nullptr; }
  /// Logs what the console's ghost predicted (app/ghost/ghost.h); dropped without
  /// a log. Thread: the owner's (not after stop()); never blocks on the disk.
  void logPrediction(const LogPrediction& prediction);
  /// A calibration fit's row (app/calibration), from any thread.
  void logCalibration(const LogCalibration& row);

  const RobotModel* model() const override { return &model_; }
  CommandCheck check(const Command& command) const override;
  void apply(const std::vector<Command>& commands) override;
  net::RobotState state() const override;
  std::optional<net::LaserScanState> laserAfter(uint64_t afterCount) const override;
  /// Runs a sequence on board against the twin's clock: refused while one
  /// runs, while the robot moves (> kStillSpeed) or when its base is beyond
  /// the run's tolerances from the rehearsal's start (a stale rehearsal).
  /// Its commands are logged with source "sequence"; an operator's command
  /// arriving while it runs aborts it (the operator took over).
  std::string startSequence(const net::SequenceRun& run) override;
  void abortSequence(const std::string& reason) override;
  static constexpr double kStillSpeed = 0.05;  ///< [m/s] base speed a sequence may start at

 private:
  struct PendingEvent {
    std::string kind, text;
  };
  void run();
  void publish();
  // Writes the queued events with the twin's step and time. Physics thread
  // (or the owner's once it has stopped); only with a log.
  void logQueuedEvents();
  // Logs the queued events, then submits the queued commands and logs those
  // the World took. Physics thread.
  void takeCommands();
  // The scheduled change, now. Physics thread.
  void applyChange();
  /// Submits the delayed commands due by now (all of them when `all`).
  void submitDue(bool all);
  // The "health" event, once, when the World has diverged. Physics thread.
  void logHealth();
  // Starts an accepted sequence, then aborts it for the queued reasons.
  // Physics thread, before takeCommands().
  void takeSequence();
  // Drops the running sequence's remaining commands. Physics thread.
  void abortRunning(const std::string& reason);
  // A scheduled sequence command went to the World. Physics thread.
  void sequenceCommand(const ScheduledCommand& command, const std::string& refusal);
  void logSequenceEvent(const std::string& text);

  std::unique_ptr<World> world_;
  const RobotModel model_;  // a copy: read by the server thread
  // The heightfield's size, for checking terrain edits on the server thread
  // (the heights themselves are the physics thread's); null for a plane.
  std::optional<HeightGrid> terrainShape_;
  std::atomic<bool> terrainEdits_{false};
  std::vector<std::string> jointNames_;  // model order, sent in every state
  double realTimeFactor_;
  std::unique_ptr<SessionRecorder> log_;  // fed by the physics thread only
  bool healthLogged_ = false;             // physics thread
  bool started_ = false;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  bool sequenceActive_ = false;  // physics thread: its commands are in the runner's schedule
  Runner* runner_ = nullptr;     // physics thread: run()'s step loop
  mutable std::mutex mutex_;  // guards the seven below
  std::vector<Command> pending_;
  double delay_ = 0, rollBias_ = 0, pitchBias_ = 0;  // setDeviations()
  std::deque<std::pair<double, Command>> delayed_;    // (sim time due, command); physics thread
  std::optional<SuddenChange> change_;                // scheduleChange(); physics thread once started
  std::vector<PendingEvent> events_;
  net::RobotState state_;
  net::LaserScanState laser_;
  std::optional<net::SequenceRun> acceptedRun_;  // to start at the next pass
  std::vector<std::string> aborts_;
  net::SequenceStatus sequence_;
};

}  // namespace sp
