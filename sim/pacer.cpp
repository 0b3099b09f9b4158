#include "sim/pacer.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace sp {

namespace {
// Absorbs rounding when the wall time is exactly a step's deadline, so that a
// caller waking at nextDeadline() gets that step and does not spin.
constexpr double kStepEpsilon = 1e-9;
}  // namespace

Pacer::Pacer(Config config) : config_(config) {
  assert(config_.step > 0);
  assert(config_.maxStepsPerPass > 0);
}

void Pacer::start(double wallNow, int64_t simSteps) {
  wallStart_ = firstWall_ = wallNow;
  stepsAtStart_ = firstSteps_ = steps_ = simSteps;
  resyncs_ = 0;
  slipped_ = 0;
}

int64_t Pacer::stepsDue(double wallNow) {
  if (!paced()) return config_.maxStepsPerPass;
  // Too far behind to catch up without a spiral: restart the schedule here,
  // so that sim time = wall x factor now, and account for the time given up.
  const double behind = -lead(wallNow);  // sim seconds
  if (behind > config_.maxLag * config_.realTimeFactor) {
    slipped_ += behind;
    ++resyncs_;
    wallStart_ = wallNow;
    stepsAtStart_ = steps_;
  }
  // The absolute schedule: steps due since the origin, whole steps only.
  const double scheduled = (wallNow - wallStart_) * config_.realTimeFactor / config_.step;
  const int64_t target = static_cast<int64_t>(std::floor(scheduled + kStepEpsilon)) + stepsAtStart_;
  return std::clamp<int64_t>(target - steps_, 0, config_.maxStepsPerPass);
}

double Pacer::nextDeadline() const {
  if (!paced()) return -std::numeric_limits<double>::infinity();
  const double stepsFromOrigin = static_cast<double>(steps_ + 1 - stepsAtStart_);
  return wallStart_ + stepsFromOrigin * config_.step / config_.realTimeFactor;
}

// Unpaced, there is no schedule to lead or lag: 0.
double Pacer::lead(double wallNow) const {
  if (!paced()) return 0;
  return static_cast<double>(steps_ - stepsAtStart_) * config_.step -
         (wallNow - wallStart_) * config_.realTimeFactor;
}

// 0 until wall time has passed since start().
double Pacer::achievedFactor(double wallNow) const {
  const double elapsed = wallNow - firstWall_;
  if (!(elapsed > 0)) return 0;
  return static_cast<double>(steps_ - firstSteps_) * config_.step / elapsed;
}

}  // namespace sp
