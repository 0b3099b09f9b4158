#include "sim/runner.h"

#include <algorithm>
#include <cmath>

#include "sim/world.h"

namespace sp {

void Runner::schedule(const std::vector<TimedCommand>& commands, int robot) {
  for (const TimedCommand& c : commands) schedule(ScheduledCommand{c.command, c.time, -1, robot, c.line});
}

void Runner::schedule(ScheduledCommand command) {
  // Keep the queue ordered by when each is due; equal ones keep their order.
  const double dt = world_.params().step;
  auto when = [dt](const ScheduledCommand& c) { return c.step >= 0 ? static_cast<double>(c.step) * dt : c.time; };
  const double t = when(command);
  auto at = std::upper_bound(queue_.begin() + static_cast<std::ptrdiff_t>(next_), queue_.end(), t,
                             [&](double value, const ScheduledCommand& c) { return value < when(c); });
  queue_.insert(at, std::move(command));
}

bool Runner::due(const ScheduledCommand& c) const {
  // By time: the first boundary at or after it (1e-9 s absorbs the rounding
  // of step x dt).
  return c.step >= 0 ? c.step <= world_.stepCount() : c.time <= world_.time() + 1e-9;
}

void Runner::skipBefore(int64_t step) {
  const double t = static_cast<double>(step) * world_.params().step;
  while (next_ < queue_.size() &&
         (queue_[next_].step >= 0 ? queue_[next_].step < step : queue_[next_].time < t - 1e-9))
    ++next_;
}

size_t Runner::dropPending() {
  const size_t n = queue_.size() - next_;
  queue_.clear();
  next_ = 0;
  return n;
}

void Runner::submitDue() {
  while (next_ < queue_.size() && due(queue_[next_])) {
    const ScheduledCommand& c = queue_[next_++];
    const std::string why = world_.submit(c.command, c.robot);
    if (why.empty()) ++applied_;
    if (submitHook_) submitHook_(c, why);
  }
}

RunOutcome Runner::advanceTo(int64_t step) {
  RunOutcome out;
  while (world_.stepCount() < step) {
    submitDue();
    if (!world_.step()) {
      out.stop = RunOutcome::Stop::Diverged;
      return out;
    }
    ++out.steps;
    // The monitor sees the step that diverged too (to log it), and nothing
    // is submitted after it.
    const bool goOn = !monitor_ || monitor_(world_);
    if (!world_.health().healthy()) {
      out.stop = RunOutcome::Stop::Diverged;
      return out;
    }
    if (!goOn) {
      out.stop = RunOutcome::Stop::Monitor;
      return out;
    }
  }
  if (!world_.health().healthy()) out.stop = RunOutcome::Stop::Diverged;
  return out;
}

RunOutcome Runner::advanceBy(int64_t n) { return advanceTo(world_.stepCount() + std::max<int64_t>(0, n)); }

RunOutcome Runner::advanceToTime(double time) { return advanceTo(std::llround(time / world_.params().step)); }

}  // namespace sp
