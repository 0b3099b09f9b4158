#pragma once
// Real-time pacing of a fixed-step simulation against a monotonic clock the
// caller reads (sim/ never reads the clock). The schedule is absolute, from
// the start instant, so sim time cannot drift from wall time x factor; when
// the machine falls behind by more than `maxLag` the pacer resyncs instead of
// spiralling into catch-up, and counts the time it gave up.

#include <cstdint>

namespace sp {

/// Not thread-safe; used by the one thread that steps the world.
class Pacer {
 public:
  struct Config {
    double step = 0.001;           ///< sim step [s], > 0
    double realTimeFactor = 1.0;   ///< sim s per wall s, > 0; <= 0 means as fast as possible
    double maxLag = 0.1;           ///< wall seconds behind before a resync
    int64_t maxStepsPerPass = 100; ///< cap on stepsDue() per call
  };

  explicit Pacer(Config config);

  /// Starts the schedule at wall time `wallNow` [s] with `simSteps` done.
  void start(double wallNow, int64_t simSteps = 0);

  /// Steps to take now to reach wall x factor, at most maxStepsPerPass.
  /// Resyncs first if behind by more than maxLag. Unpaced: maxStepsPerPass.
  int64_t stepsDue(double wallNow);

  /// Tells the pacer `n` steps were taken.
  void stepped(int64_t n) { steps_ += n; }

  /// Wall time [s] at which the next step falls due (to sleep until).
  double nextDeadline() const;

  /// Sim time minus wall time x factor [s], over the schedule since the
  /// last resync; negative when behind.
  double lead(double wallNow) const;

  /// Sim seconds per wall second since start().
  double achievedFactor(double wallNow) const;

  int64_t steps() const { return steps_; }
  double simTime() const { return static_cast<double>(steps_) * config_.step; }
  int64_t resyncCount() const { return resyncs_; }
  /// Sim time [s] not run in real time because of resyncs.
  double slippedTime() const { return slipped_; }
  bool paced() const { return config_.realTimeFactor > 0; }

 private:
  Config config_;
  double wallStart_ = 0;      // wall time of the schedule origin
  int64_t stepsAtStart_ = 0;  // steps done at the schedule origin
  double firstWall_ = 0;      // wall time of start(), for achievedFactor
  int64_t firstSteps_ = 0;
  int64_t steps_ = 0;
  int64_t resyncs_ = 0;
  double slipped_ = 0;
};

}  // namespace sp
