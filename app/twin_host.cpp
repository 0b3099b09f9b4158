#include "app/twin_host.h"

#include <chrono>

#include "sim/command_file.h"
#include "sim/pacer.h"

namespace sp {

namespace {
double monotonic() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

TwinHost::TwinHost(std::unique_ptr<World> world, double realTimeFactor)
    : world_(std::move(world)), model_(world_->robotModel(0)), realTimeFactor_(realTimeFactor) {
  publish();
}

TwinHost::~TwinHost() { stop(); }

void TwinHost::start() { thread_ = std::thread([this] { run(); }); }

void TwinHost::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

std::string TwinHost::check(const Command& command) const { return checkCommand(command, model_); }

void TwinHost::apply(const std::vector<Command>& commands) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.insert(pending_.end(), commands.begin(), commands.end());
}

net::RobotState TwinHost::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

std::optional<net::LaserScanState> TwinHost::laserAfter(uint64_t afterCount) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (laser_.count <= afterCount) return std::nullopt;
  return laser_;
}

void TwinHost::publish() {
  // Built outside the lock; the lock only swaps values in.
  const World& w = *world_;
  net::RobotState s;
  s.time = w.time();
  s.pose = w.linkPose(0, 0);
  for (size_t j = 0; j < model_.joints.size(); ++j) {
    s.jointNames.push_back(model_.joints[j].name);
    s.jointPositions.push_back(w.jointPosition(0, static_cast<int>(j)));
    s.jointVelocities.push_back(w.jointRate(0, static_cast<int>(j)));
  }
  int wheel = 0, laser = -1;
  for (size_t i = 0; i < model_.sensors.size(); ++i) {
    const SensorSample& sample = w.sensorSample(0, static_cast<int>(i));
    if (const auto* f = std::get_if<WheelForceReading>(&sample.value); f && wheel < 4) {
      s.wheelNormal[static_cast<size_t>(wheel)] = f->normal;
      s.wheelTangential[static_cast<size_t>(wheel++)] = f->tangential;
    }
    if (const auto* imu = std::get_if<ImuReading>(&sample.value)) {
      s.roll = imu->roll;
      s.pitch = imu->pitch;
    }
    if (model_.sensors[i].type == SensorType::Laser && laser < 0) laser = static_cast<int>(i);
  }
  s.health = w.health().healthy() ? std::string() : w.health().message();
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

void TwinHost::run() {
  Pacer pacer({world_->params().step, realTimeFactor_, 0.1, 50});
  pacer.start(monotonic());
  const int64_t publishEvery = std::max<int64_t>(1, std::llround(0.01 / world_->params().step));  // 100 Hz
  while (!stop_) {
    std::vector<Command> commands;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      commands.swap(pending_);
    }
    for (const Command& c : commands) world_->submit(c);
    const int64_t due = pacer.stepsDue(monotonic());
    for (int64_t i = 0; i < due; ++i) {
      world_->step();  // a diverged twin stops stepping and says so in state().health
      if (world_->stepCount() % publishEvery == 0) publish();
    }
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
}

}  // namespace sp
