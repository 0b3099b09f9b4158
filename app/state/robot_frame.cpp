#include "app/state/robot_frame.h"

#include "sim/robot_model.h"

namespace sp {

std::vector<double> JointNameMap::toModelOrder(const std::vector<std::string>& names, const std::vector<double>& values,
                                               const RobotModel& robot) {
  if (names != names_ || robot_ != &robot) {
    names_ = names;
    robot_ = &robot;
    index_.clear();
    for (const std::string& name : names_) index_.push_back(robot.findJoint(name));
  }
  std::vector<double> out(robot.joints.size(), 0.0);
  for (size_t i = 0; i < index_.size() && i < values.size(); ++i)
    if (index_[i] >= 0) out[static_cast<size_t>(index_[i])] = values[i];
  return out;
}

void RateMeter::add(double wall, double robotTime) {
  if (!samples_.empty() && robotTime < samples_.back().second) samples_.clear();
  samples_.emplace_back(wall, robotTime);
  // One second of wall time, and at least two samples.
  while (samples_.size() > 2 && wall - samples_.front().first > 1.0) samples_.pop_front();
  const double span = samples_.back().first - samples_.front().first;
  if (span > 0.2) factor_ = (samples_.back().second - samples_.front().second) / span;
}

}  // namespace sp
