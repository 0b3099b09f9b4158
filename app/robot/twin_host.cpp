#include "app/robot/twin_host.h"

#include "app/state/robot_shapes.h"

#include <chrono>

#include "sim/command_check.h"
#include "sim/pacer.h"
#include "sim/readout.h"
#include "sim/runner.h"
#include "sim/terrain_brush.h"

namespace sp {

namespace {
double monotonic() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

TwinHost::TwinHost(std::unique_ptr<World> world, double realTimeFactor)
    : world_(std::move(world)), model_(world_->robotModel(0)), realTimeFactor_(realTimeFactor) {
  for (const JointSpec& j : model_.joints) jointNames_.push_back(j.name);
  if (const HeightGrid* g = world_->terrainGrid()) terrainShape_ = HeightGrid{g->columns, g->rows, g->width, g->depth, {}};
  publish();
}

TwinHost::~TwinHost() { stop(); }

void TwinHost::logTo(std::unique_ptr<SessionLogWriter> writer) {
  if (writer) log_ = std::make_unique<SessionRecorder>(std::move(writer), *world_);
}

void TwinHost::start() {
  if (started_) return;
  started_ = true;
  thread_ = std::thread([this] { run(); });
}

void TwinHost::stop() {
  stop_ = true;
  if (thread_.joinable()) {
    thread_.join();
    // The physics thread is gone: this thread may touch the World. Events
    // queued since its last pass are logged; commands that came after it
    // (stop the server first) are not applied: they would sit in the last
    // snapshot, never stepped.
    if (log_) {
      logQueuedEvents();
      log_->finish(*world_);
    }
  }
  if (log_) log_->writer().close();
}

void TwinHost::logEvent(std::string kind, std::string text) {
  if (!log_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  events_.push_back({std::move(kind), std::move(text)});
}

void TwinHost::logPrediction(const LogPrediction& prediction) {
  if (log_) log_->writer().logPrediction(prediction);
}

void TwinHost::logCalibration(const LogCalibration& row) {
  if (log_) log_->writer().logCalibration(row);
}

CommandCheck TwinHost::check(const Command& command) const {
  // A terrain edit is the simulator's: a real robot could not carry it out.
  if (const auto* patch = std::get_if<TerrainPatchCmd>(&command)) {
    if (!terrainEdits_) return {CommandCheck::Kind::Invalid, "terrain: a simulator edit, not a robot command"};
    if (std::string why = patchFits(terrainShape_ ? &*terrainShape_ : nullptr, *patch); !why.empty())
      return {CommandCheck::Kind::Invalid, why};
    return {};
  }
  return checkCommand(command, model_);
}

void TwinHost::apply(const std::vector<Command>& commands) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.insert(pending_.end(), commands.begin(), commands.end());
}

net::RobotState TwinHost::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  net::RobotState s = state_;
  s.sequence = sequence_;
  return s;
}

std::string TwinHost::startSequence(const net::SequenceRun& run) {
  std::lock_guard<std::mutex> lock(mutex_);
  char buf[200];
  if (acceptedRun_ || sequence_.state == net::SequenceStateKind::Running)
    return "sequence " + sequence_.hash + " is running: abort it first";
  const double speed = std::hypot(state_.baseLinearVelocity.x, state_.baseLinearVelocity.y);
  if (speed > kStillSpeed) {
    std::snprintf(buf, sizeof buf, "the robot is moving (%.2f m/s): stop it before a sequence", speed);
    return buf;
  }
  const double off = std::hypot(state_.pose.p.x - run.start.p.x, state_.pose.p.y - run.start.p.y);
  const double turn = std::abs(std::remainder(heading(state_.pose.q) - heading(run.start.q), 2 * kPi));
  if (off > run.startPosition) {
    std::snprintf(buf, sizeof buf, "stale rehearsal: the robot is %.3f m from its start (tolerance %.3f m)", off,
                  run.startPosition);
    return buf;
  }
  if (turn > run.startHeading) {
    std::snprintf(buf, sizeof buf, "stale rehearsal: the robot's heading is %.1f deg from its start (tolerance %.1f deg)",
                  radToDeg(turn), radToDeg(run.startHeading));
    return buf;
  }
  acceptedRun_ = run;
  sequence_ = {run.hash, net::SequenceStateKind::Accepted, 0, run.commands.size(), 0, ""};
  return {};
}

void TwinHost::abortSequence(const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  aborts_.push_back(reason);
}

void TwinHost::logSequenceEvent(const std::string& text) {
  if (log_) log_->writer().logEvent(world_->stepCount(), world_->time(), "sequence", text);
}

void TwinHost::takeSequence() {
  std::optional<net::SequenceRun> run;
  std::vector<std::string> aborts;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    run.swap(acceptedRun_);
    aborts.swap(aborts_);
  }
  const double now = world_->time();
  if (run) {
    // t = 0 is this boundary: the robot's own clock from here on.
    for (const TimedCommand& c : run->commands) runner_->schedule(ScheduledCommand{c.command, now + c.time, -1, 0, c.line});
    sequenceActive_ = true;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      sequence_.state = net::SequenceStateKind::Running;
      sequence_.startTime = now;
    }
    logSequenceEvent("started " + run->hash + " (" + std::to_string(run->commands.size()) + " commands)");
  }
  if (!aborts.empty() && sequenceActive_) abortRunning(aborts.front());
}

void TwinHost::abortRunning(const std::string& reason) {
  runner_->dropPending();
  sequenceActive_ = false;
  std::string hash;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    sequence_.state = net::SequenceStateKind::Aborted;
    sequence_.reason = reason;
    hash = sequence_.hash;
  }
  logSequenceEvent("aborted " + hash + ": " + reason);
}

void TwinHost::sequenceCommand(const ScheduledCommand& command, const std::string& refusal) {
  World& w = *world_;
  if (!refusal.empty()) {
    // What the link's checks passed but the twin refused when due: the
    // sequence cannot run as rehearsed, so it ends here, saying which
    // (SEQUENCE_STATE aborted to every client, the robot's log and stderr).
    uint64_t index = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      index = sequence_.index + 1;
    }
    abortRunning("command " + std::to_string(index) + " refused: " + refusal);
    return;
  }
  if (log_) log_->writer().logCommand(w.stepCount(), w.time(), "sequence", command.command, &model_);
  std::lock_guard<std::mutex> lock(mutex_);
  ++sequence_.index;
  if (sequence_.index < sequence_.count) return;
  sequence_.state = net::SequenceStateKind::Done;
  sequenceActive_ = false;
  if (log_) log_->writer().logEvent(w.stepCount(), w.time(), "sequence", "done " + sequence_.hash);
}

std::optional<net::LaserScanState> TwinHost::laserAfter(uint64_t afterCount) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (laser_.count <= afterCount) return std::nullopt;
  return laser_;
}

void TwinHost::publish() {
  // Built outside the lock; the lock only swaps values in.
  const World& w = *world_;
  const RobotReadout r = readRobot(w, 0);
  net::RobotState s = stateFromReadout(r, jointNames_);
  // What the robot's IMU reports, its bias included (the log keeps the truth).
  s.roll += rollBias_;
  s.pitch += pitchBias_;
  int laser = -1;
  for (size_t i = 0; i < model_.sensors.size() && laser < 0; ++i)
    if (model_.sensors[i].type == SensorType::Laser) laser = static_cast<int>(i);
  std::optional<net::LaserScanState> scan;
  if (laser >= 0) {
    const SensorSample& sample = w.sensorSample(0, laser);
    if (const auto* l = std::get_if<LaserReading>(&sample.value); l && sample.step >= 0)
      scan = net::LaserScanState{static_cast<uint64_t>(sample.step), sample.time, l->angleMin, l->angleStep, l->ranges};
  }
  std::lock_guard<std::mutex> lock(mutex_);
  state_ = std::move(s);
  if (scan && scan->count > laser_.count) laser_ = std::move(*scan);
}

void TwinHost::logQueuedEvents() {
  std::vector<PendingEvent> events;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    events.swap(events_);
  }
  for (PendingEvent& e : events)
    log_->writer().logEvent(world_->stepCount(), world_->time(), std::move(e.kind), std::move(e.text));
}

void TwinHost::takeCommands() {
  if (log_) logQueuedEvents();
  std::vector<Command> commands;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    commands.swap(pending_);
  }
  World& w = *world_;
  if (!commands.empty() && sequenceActive_) {
    // The operator took over: the rest of the sequence must not follow.
    // (An ABORT or a stop of the link's came through takeSequence() first.)
    abortRunning("an operator command took over");
  }
  // A robot with an actuator delay acts on a command that long after it
  // arrived (0 s: at once, in arrival order as always).
  for (Command& c : commands) delayed_.emplace_back(w.time() + delay_, std::move(c));
  submitDue(false);
}

void TwinHost::submitDue(bool all) {
  World& w = *world_;
  while (!delayed_.empty() && (all || delayed_.front().first <= w.time() + 1e-9)) {
    const Command& c = delayed_.front().second;
    // Checked by the server already; a command the World still refuses was
    // not applied, so it is not logged either.
    if (w.submit(c).empty() && log_) log_->writer().logCommand(w.stepCount(), w.time(), "operator", c, &model_);
    delayed_.pop_front();
  }
}

void TwinHost::applyChange() {
  const SuddenChange c = *change_;
  change_.reset();
  const std::string why = world_->scaleFriction(c.friction);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (why.empty()) delay_ += std::max(0.0, c.delay);
  }
  if (log_)
    log_->writer().logEvent(world_->stepCount(), world_->time(), "note",
                            why.empty() ? "the stand-in changed: " + c.describe() : "the stand-in's change refused: " + why);
}

void TwinHost::run() {
  Pacer pacer({world_->params().step, realTimeFactor_, 0.1, 50});
  pacer.start(monotonic());
  const int64_t publishEvery = std::max<int64_t>(1, std::llround(0.01 / world_->params().step));  // 100 Hz
  if (log_) log_->start(*world_);
  // Operator commands reach the World from takeCommands(); only a sequence's
  // are scheduled, at their times on the twin's clock.
  Runner runner(*world_);
  runner_ = &runner;
  runner.setSubmitHook([this](const ScheduledCommand& c, const std::string& why) { sequenceCommand(c, why); });
  runner.setMonitor([&](const World& w) {
    if (change_ && w.time() >= change_->at - 1e-9) applyChange();
    if (log_) log_->stepped(w);
    if (!delayed_.empty()) submitDue(false);  // a delayed command acts at its step
    if (w.stepCount() % publishEvery == 0) publish();
    return true;
  });
  while (!stop_) {
    const int64_t due = pacer.stepsDue(monotonic());
    // Commands only when a step follows: none is left pending in the last
    // snapshot when the loop stops.
    if (due > 0) {
      takeSequence();
      takeCommands();
    }
    runner.advanceBy(due);  // a diverged twin stops there and says so in state().health
    logHealth();
    pacer.stepped(due);
    if (due == 0) {
      if (pacer.paced()) {
        const double wait = std::min(pacer.nextDeadline() - monotonic(), 0.002);
        if (wait > 0) std::this_thread::sleep_for(std::chrono::duration<double>(wait));
      }
    }
    if (!world_->health().healthy()) {
      publish();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  // One more step for commands queued since the last pass: a command the
  // server accepted (an e-stop's stop, say) is applied and logged, not lost.
  bool queued = !delayed_.empty();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queued = queued || !pending_.empty();
  }
  if (queued) {
    takeSequence();
    takeCommands();
    submitDue(true);  // a delayed one too: nothing is left unapplied
    runner.advanceBy(1);
    logHealth();
    publish();
  }
}

void TwinHost::logHealth() {
  if (!log_ || healthLogged_ || world_->health().healthy()) return;
  const HealthReport& h = world_->health();
  log_->writer().logEvent(h.step, h.time, "health", h.message());
  healthLogged_ = true;
}

}  // namespace sp
