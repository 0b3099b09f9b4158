#pragma once
// Replaying a session log (issue 15): the robot as the log says it was at
// any time, for the console's replay feed and for tests. Opens the log,
// rebuilds the logged world from the files the log stores (as re-simulation
// does), and answers "the state at time t" with one row from the samples'
// time index, so a seek costs the same in a one-hour log as in a short one.
// Logs of remote robots (telemetry only) have samples too and replay the same.
//
//   std::string error;
//   auto player = sp::LogPlayer::open(path, error);
//   if (!player) show(error);
//   for (const sp::LogEvent& e : player->events()) timeline.mark(e.time, e.kind);
//   if (auto f = player->frameAt(t)) scene.setRobotState(f->base, f->jointPositions);
//
// Thread: one at a time (it owns a SessionLogReader).

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/log/resimulation.h"
#include "app/state/rehearsal_start.h"
#include "app/state/robot_frame.h"
#include "app/log/session_log.h"

namespace sp {

class LogPlayer {
 public:
  /// nullptr and `error` (naming the file) when it is not a log, holds no
  /// samples, or its world cannot be rebuilt.
  static std::unique_ptr<LogPlayer> open(const std::string& path, std::string& error);

  const std::string& path() const { return path_; }
  /// The logged world (robots[0] is the robot the samples describe).
  const WorldModel& world() const { return logged_.world; }
  const SimParams& params() const { return logged_.params; }
  /// First and last sample times [s].
  double startTime() const { return start_; }
  double endTime() const { return end_; }
  /// Every logged event, in step order (links, notes, rehearsals, ...).
  const std::vector<LogEvent>& events() const { return events_; }
  /// The logged state at `time`: the latest sample at or before it (the
  /// first one before the log's start); joints in the model's order.
  std::optional<RobotFrame> frameAt(double time) const;
  /// The latest laser scan at or before `time`, if one is within 1 s.
  std::optional<LaserFrame> laserAt(double time) const;

  /// The robot's state at `time` reconstructed from the samples, as a
  /// rehearsal's or a branch's start: pose, joints and rates as logged;
  /// the base's velocity from the sample before (samples hold no base
  /// twist; zero when there is none within 0.5 s); objects where the
  /// world puts them (samples hold none).
  std::optional<RehearsalStart> startAt(double time) const;
  /// Whether the log holds snapshots (a stand-in's or a headless run's
  /// log; a remote robot's telemetry log holds none).
  bool hasSnapshots() const { return hasSnapshots_; }
  /// A new simulation's start at `time`. Logs with snapshots re-simulate
  /// from the nearest one to the step (sp::branchAt: bit-exact, `progress`
  /// as it goes, false cancels); telemetry-only logs are reconstructed:
  /// startAt(time) placed in the logged world (BranchPoint::reconstructed).
  /// Opens its own reader: any thread, while the player is used elsewhere.
  std::optional<BranchPoint> branchAt(double time, std::string& error,
                                      const std::function<bool(double)>& progress = {}) const;

  /// Terrain edits made during the session (its `terrain` commands), for
  /// drawing the ground as it was: how many apply at or before `time`, and
  /// the logged heightfield with the first `count` of them applied.
  size_t terrainEditsAt(double time) const;
  HeightGrid terrainAfter(size_t count) const;

  /// The signals a replay can plot (PlotJuggler's habit: pick any): base
  /// x, y, z, roll, pitch, yaw; the four wheel normal forces; every joint's
  /// position and rate; the ghost's predicted x, y and its position and
  /// heading error (logs with predictions). Names with units, e.g.
  /// "base x [m]", "knee_fl position [deg]".
  std::vector<std::string> signalNames() const;
  /// Signal `index` of signalNames() at about `points` times evenly over
  /// [t0, t1] (each the latest sample at or before it; a seek each, so a
  /// one-hour log costs what a short one does): (time, value) pairs, times
  /// of the samples found, without repeats.
  std::vector<std::pair<double, double>> signal(int index, double t0, double t1, int points) const;

 private:
  LogPlayer() = default;

  std::string path_;
  std::unique_ptr<SessionLogReader> reader_;
  LoggedWorld logged_;
  double start_ = 0, end_ = 0;
  std::vector<LogEvent> events_;
  bool hasSnapshots_ = false;
  std::vector<std::pair<double, TerrainPatchCmd>> terrainEdits_;  // (time, edit), in order
};

}  // namespace sp
