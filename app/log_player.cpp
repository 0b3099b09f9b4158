#include "app/log_player.h"

#include <algorithm>

namespace sp {

std::unique_ptr<LogPlayer> LogPlayer::open(const std::string& path, std::string& error) {
  std::unique_ptr<LogPlayer> p(new LogPlayer);
  p->path_ = path;
  p->reader_ = SessionLogReader::open(path, error);
  if (!p->reader_) return nullptr;
  std::optional<LoggedWorld> world = loggedWorld(*p->reader_, path, error);
  if (!world) return nullptr;
  p->logged_ = std::move(*world);
  const std::optional<std::pair<double, double>> range = p->reader_->sampleTimeRange();
  if (!range) {
    error = path + ": the log holds no samples to replay";
    return nullptr;
  }
  p->start_ = range->first;
  p->end_ = range->second;
  p->events_ = p->reader_->events();
  return p;
}

std::optional<RobotFrame> LogPlayer::frameAt(double time) const {
  std::optional<LogSample> s = reader_->sampleAt(std::max(time, start_));
  if (!s) return std::nullopt;
  const RobotModel& robot = logged_.world.robots[0].model;
  const size_t n = robot.joints.size();
  RobotFrame f;
  f.time = s->time;
  f.base = Pose{{s->base[0], s->base[1], s->base[2]}, {s->quat[0], s->quat[1], s->quat[2], s->quat[3]}};
  // positions then rates; a log of another robot (fewer values) reads 0 beyond.
  f.jointPositions.assign(n, 0.0);
  f.jointRates.assign(n, 0.0);
  for (size_t j = 0; j < n && j < s->joints.size(); ++j) f.jointPositions[j] = s->joints[j];
  for (size_t j = 0; j < n && n + j < s->joints.size(); ++j) f.jointRates[j] = s->joints[n + j];
  f.wheelNormal = s->wheelNormal;
  f.roll = s->roll;
  f.pitch = s->pitch;
  return f;
}

std::optional<LaserFrame> LogPlayer::laserAt(double time) const {
  const std::vector<LogLaser> scans = reader_->laserBetween(time - 1.0, time);
  if (scans.empty()) return std::nullopt;
  const LogLaser& l = scans.back();
  return LaserFrame{l.time, l.angleMin, l.angleStep, l.ranges};
}

}  // namespace sp
