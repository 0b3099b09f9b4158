#pragma once
// The one step loop of the twin: a World, a schedule of commands, "advance to
// step N / time T", a monitor called after every step, and a stop when the
// twin diverges. The headless runner, re-simulation, the stand-in's physics
// thread and the validation experiments all step through it (the ghost and
// rehearsal will too). It never reads a clock: pacing is the caller's
// (sim/pacer.h), as MuJoCo's simulate paces its physics loop.
//
//   sp::Runner runner(*world);
//   runner.schedule(sequence);                      // TimedCommands from a .seq
//   runner.setMonitor([&](const sp::World& w) { log(w); return true; });
//   sp::RunOutcome out = runner.advanceToTime(10.0);
//   if (out.stop == sp::RunOutcome::Stop::Diverged) report(world->health());
//
// Thread: the thread that owns the World; a Runner is not shared.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim/command.h"

namespace sp {

class World;

/// A command waiting for its step boundary: due at the first boundary at
/// or after `time` (sequence files, rehearsals), or at step `step` exactly
/// when step >= 0 (commands logged with their step, for re-simulation).
struct ScheduledCommand {
  Command command;
  double time = 0;      ///< [s]; used when step < 0
  int64_t step = -1;    ///< the step boundary it applies at; -1 = by time
  int robot = 0;
  int line = 0;         ///< its line in a sequence file, 0 if none
};

/// Why an advance ended.
struct RunOutcome {
  enum class Stop {
    Reached,   ///< the step or time asked for
    Diverged,  ///< the World's health failed (World::health() says why)
    Monitor,   ///< the monitor asked to stop
  };
  Stop stop = Stop::Reached;
  int64_t steps = 0;  ///< steps taken by this advance
};

class Runner {
 public:
  /// Called after every step with the World; return false to stop there.
  using Monitor = std::function<bool(const World&)>;
  /// Called for every scheduled command handed to World::submit(), with ""
  /// when the World took it, else why not (a refused command is dropped).
  using SubmitHook = std::function<void(const ScheduledCommand&, const std::string& refusal)>;

  /// `world` must outlive the Runner.
  explicit Runner(World& world) : world_(world) {}

  /// Adds commands to the schedule. Each list must be in non-decreasing
  /// time (or step) order; lists added later are merged after earlier ones
  /// that are due at the same boundary.
  void schedule(const std::vector<TimedCommand>& commands, int robot = 0);
  void schedule(ScheduledCommand command);
  void setMonitor(Monitor monitor) { monitor_ = std::move(monitor); }
  void setSubmitHook(SubmitHook hook) { submitHook_ = std::move(hook); }

  /// Drops, unsubmitted, the scheduled commands due before step `step` (a
  /// run restored from a snapshot at `step`: they are in its state).
  void skipBefore(int64_t step);
  /// Drops every scheduled command not yet submitted (an aborted
  /// sequence); returns how many.
  size_t dropPending();
  /// Submits the scheduled commands due at the current boundary (a step
  /// does this itself; call it only to submit before checking the state).
  void submitDue();
  /// Steps until World::stepCount() == `step`, the twin diverges or the
  /// monitor stops it. Commands due at a boundary are submitted before the
  /// step from it.
  RunOutcome advanceTo(int64_t step);
  /// Steps `n` times (or until stopped as above).
  RunOutcome advanceBy(int64_t n);
  /// Advances to the step nearest `time` [s] (World time = steps x step).
  RunOutcome advanceToTime(double time);

  World& world() { return world_; }
  const World& world() const { return world_; }
  /// Commands the World took so far.
  int commandsApplied() const { return applied_; }
  /// Scheduled commands not yet due.
  size_t pending() const { return queue_.size() - next_; }

 private:
  bool due(const ScheduledCommand& c) const;

  World& world_;
  std::vector<ScheduledCommand> queue_;
  size_t next_ = 0;
  Monitor monitor_;
  SubmitHook submitHook_;
  int applied_ = 0;
};

}  // namespace sp
