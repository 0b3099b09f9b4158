#include "app/calibration/live_calibrator.h"

#include <cstdio>

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>

namespace sp {

namespace {
constexpr double kCommandMemory = 120;  // [s] of robot time: the commands a window's anchors may need

// Names the calling thread and lowers it to nice 10. Best effort: never at
// the expense of the twin, the ghost's present thread or the window (Linux:
// a thread's nice value is its own).
void inBackground(const char* name) {
  pthread_setname_np(pthread_self(), name);
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10);
}

}  // namespace

LiveCalibrator::LiveCalibrator(WorldModel files, const SimParams& profile, const CalValues& start, const Options& options)
    : files_(std::move(files)), profile_(profile), files0_(filesCalValues()), options_(options) {
  state_.applied = estimate_.value = start;
  updateFullPhysics();
  worker_ = std::thread([this] { run(); });
  if (options_.full) checker_ = std::thread([this] { runChecks(); });
}

LiveCalibrator::~LiveCalibrator() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  checkWake_.notify_all();
  worker_.join();
  if (checker_.joinable()) checker_.join();
}

void LiveCalibrator::frame(const RobotFrame& f, bool suspect) {
  {
    std::lock_guard lock(mutex_);
    if (!frames_.empty() && f.time < frames_.back().time) {  // the robot restarted
      frames_.clear();
      commands_.clear();
      lastFitAt_ = suspectAt_ = -1e300;
    }
    if (suspect) {
      // The world is not the files' here: a fit over it would put a ridge
      // into the tyres. The window starts again after it.
      frames_.clear();
      suspectAt_ = f.time;
      return;
    }
    frames_.push_back(f);
    const double keep = options_.fit.window > 0 ? options_.fit.window + 2 : 60;
    while (frames_.front().time < f.time - keep) frames_.pop_front();
    while (!commands_.empty() && commands_.front().time < f.time - kCommandMemory) commands_.pop_front();
  }
  wake_.notify_one();
}

void LiveCalibrator::command(const Command& c, double arrival) {
  std::lock_guard lock(mutex_);
  commands_.push_back(TimedCommand{arrival, c, 0});
}

CalibrationState LiveCalibrator::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

int64_t LiveCalibrator::version() const {
  std::lock_guard lock(mutex_);
  return state_.version;
}

CalValues LiveCalibrator::applied() const {
  std::lock_guard lock(mutex_);
  return state_.applied;
}

CalValues LiveCalibrator::fullPhysics() const {
  std::lock_guard lock(mutex_);
  return state_.fullPhysics;
}

void LiveCalibrator::updateFullPhysics() {
  state_.fullPhysics = state_.applied;
  if (!options_.full) return;
  for (CalParam p : kFullPhysicsChecked) {
    const size_t i = static_cast<size_t>(p);
    if (!state_.confirmed[i]) state_.fullPhysics[i] = calParams()[i].files;
    else if (isTorqueLimit(p)) state_.fullPhysics[i] = state_.checkedValue[i];
  }
}

void LiveCalibrator::freeze(bool frozen) {
  std::lock_guard lock(mutex_);
  if (state_.frozen == frozen) return;
  state_.frozen = frozen;
  ++state_.version;
}

void LiveCalibrator::reset() {
  std::lock_guard lock(mutex_);
  estimate_ = filesEstimate();
  state_.applied = files0_;
  state_.sigma = {};
  state_.observed = {};
  state_.confirmed = state_.refused = {};
  state_.checkedAt = -1;
  ++resets_;
  updateFullPhysics();
  ++state_.version;
}

void LiveCalibrator::run() {
  inBackground("calibrate");
  for (;;) {
    std::vector<RobotFrame> frames;
    std::vector<TimedCommand> commands;
    CalEstimate start;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] {
        return stop_ || (!frames_.empty() && frames_.back().time - lastFitAt_ >= options_.period &&
                         frames_.back().time - frames_.front().time >= options_.fit.horizon * 2);
      });
      if (stop_) return;
      frames.assign(frames_.begin(), frames_.end());
      commands.assign(commands_.begin(), commands_.end());
      start = estimate_;
      lastFitAt_ = frames.back().time;
    }
    CalibrationFit fit;
    // A fit builds twins of values the data suggests; whatever a robot's
    // telemetry makes them (a mass ODE refuses), a throw must not end the
    // console: the fit is refused and says why.
    try {
      fit = fitCalibration(files_, profile_, frames, commands, start, options_.fit, [&] {
        if (options_.duringFit) options_.duringFit();
        std::lock_guard lock(mutex_);
        return stop_;
      });
    } catch (const std::exception& e) {
      fit = CalibrationFit{};
      fit.value = start.value;
      fit.from = frames.front().time;
      fit.to = frames.back().time;
      fit.refused = std::string("the fit failed: ") + e.what();
    }
    std::unique_lock lock(mutex_);
    if (stop_) return;
    ++state_.fits;
    if (fit.refused.empty() && suspectAt_ >= fit.from) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "the robot departed from its twin at %.1f s (the ground or the robot differ from the files "
                    "there): that stretch is left out",
                    suspectAt_);
      fit.refused = text;
    }
    if (!fit.refused.empty()) {
      ++state_.refusals;
      state_.lastRefusal = fit.refused;
      state_.lastRefusalWantsDriving = fit.wantsDriving;
    } else if (!state_.frozen && estimate_.value == start.value) {  // not reset meanwhile
      estimate_ = fuse(estimate_, fit, options_.fit.window / options_.period);
      state_.applied = significantValues(estimate_);
      state_.sigma = estimate_.sigma;
      state_.observed = estimate_.observed;
    }
    state_.history.push_back(fit);
    if (state_.history.size() > CalibrationState::kHistory) state_.history.erase(state_.history.begin());
    bool pending = false, any = false;  // a split applied that no check judged; any split applied
    for (CalParam p : kFullPhysicsChecked) {
      const size_t i = static_cast<size_t>(p);
      if (state_.applied[i] == calParams()[i].files) state_.confirmed[i] = state_.refused[i] = false;
      else any = true;
      pending |= state_.applied[i] != calParams()[i].files && !state_.confirmed[i] && !state_.refused[i];
    }
    updateFullPhysics();
    ++state_.version;
    // A new split is checked soon; the verdicts again now and then (tyres
    // wear, loads move); nothing while frozen (nothing new is applied).
    const double since = state_.checkedAt < 0 ? 1e300 : fit.to - state_.checkedAt;
    if (!options_.full || state_.frozen || !fit.refused.empty() || !any || checkWanted_ || checking_ ||
        since < options_.checkPeriod ||
        (!pending && since < 4 * options_.checkPeriod))
      continue;
    // On the checker's thread: a check takes a few seconds of full physics,
    // and the fits must land every period meanwhile.
    checkFrames_ = std::move(frames);
    checkCommands_ = std::move(commands);
    checkWanted_ = true;
    lock.unlock();
    checkWake_.notify_one();
  }
}

void LiveCalibrator::runChecks() {
  inBackground("calib-check");
  for (;;) {
    std::vector<RobotFrame> frames;
    std::vector<TimedCommand> commands;
    {
      std::unique_lock lock(mutex_);
      checkWake_.wait(lock, [&] { return stop_ || checkWanted_; });
      if (stop_) return;
      checkWanted_ = false;
      checking_ = true;
      frames = std::move(checkFrames_);
      commands = std::move(checkCommands_);
    }
    check(frames, commands);
    std::lock_guard lock(mutex_);
    checking_ = false;
  }
}

void LiveCalibrator::check(const std::vector<RobotFrame>& frames, const std::vector<TimedCommand>& commands) {
  CalValues applied;
  int64_t resets = 0;
  {
    std::lock_guard lock(mutex_);
    applied = state_.applied;
    resets = resets_;
  }
  FullPhysicsCheck c;
  try {
    c = fullPhysicsValues(files_, *options_.full, frames, commands, applied, options_.fit.window, 1, [&] {
      if (options_.duringFit) options_.duringFit();
      std::lock_guard lock(mutex_);
      return stop_;
    });
  } catch (const std::exception& e) {  // as a fit's (run()): the check is given up, nothing changes
    c.problem = std::string("the check failed: ") + e.what();
  }
  std::lock_guard lock(mutex_);
  // Reset or frozen meanwhile: the next fit asks again. The fits that
  // landed meanwhile moved the values a little; the verdict is on whether
  // the robot has the split, so it stands.
  if (stop_ || state_.frozen || !c.problem.empty() || resets_ != resets) return;
  state_.checkedAt = frames.back().time;
  for (CalParam p : kFullPhysicsChecked) {
    const size_t i = static_cast<size_t>(p);
    if (applied[i] == calParams()[i].files || state_.applied[i] == calParams()[i].files) continue;
    state_.confirmed[i] = c.values[i] != calParams()[i].files;  // a split kept, or a limit found
    state_.refused[i] = !state_.confirmed[i];
    state_.checkedValue[i] = c.values[i];
  }
  updateFullPhysics();
  ++state_.version;
}

}  // namespace sp
