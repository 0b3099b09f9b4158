#include "app/bridge/topic_robot.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>

#include "sim/command_check.h"
#include "sim/properties.h"
#include "sim/text.h"

namespace sp {
namespace {

/// A ROS graph resource name (topics) or a frame id: letters, digits, _ and /.
bool rosName(std::string_view name, bool frame) {
  static const std::regex topic("^/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*$");
  static const std::regex frameId("^[A-Za-z][A-Za-z0-9_/]*$");
  return std::regex_match(name.begin(), name.end(), frame ? frameId : topic);
}

/// Where a joint's anchor lies in the ground plane.
Vec2 planar(const RobotModel& robot, int joint) {
  const Vec3& a = robot.joints[static_cast<size_t>(joint)].anchor;
  return {a.x, a.y};
}
double distance(Vec2 a, Vec2 b) { return std::hypot(a.x - b.x, a.y - b.y); }

}  // namespace

std::optional<BridgeConfig> parseBridgeConfig(std::string_view text, std::string_view path, const RobotModel& robot,
                                              Diagnostics& diag) {
  BridgeConfig c;
  std::map<std::string, std::string*> topics = {{"ros.cmd_vel", &c.cmdVel},   {"ros.joint_command", &c.jointCommand},
                                                {"ros.odom", &c.odom},        {"ros.joint_states", &c.jointStates},
                                                {"ros.scan", &c.scan},        {"ros.imu", &c.imu}};
  std::map<std::string, std::string*> frames = {{"ros.odom_frame", &c.odomFrame}, {"ros.base_frame", &c.baseFrame}};
  std::map<std::string, int> mappedAt;  // ROS name -> line, for duplicates
  const auto known = [&](std::string_view key) {
    return topics.count(std::string(key)) || frames.count(std::string(key)) || key == "ros.stale_after" ||
           key == "ros.publish_rate" || key.rfind("ros.joint.", 0) == 0;
  };
  const auto set = [&](std::string_view key, std::string_view value, int line) {
    const std::string k(key), v(value);
    if (auto t = topics.find(k); t != topics.end()) {
      if (!rosName(v, false)) {
        diag.error(path, line, k + ": '" + v + "' is not a ROS topic name (letters, digits, _ and /)");
        return false;
      }
      *t->second = v;
      return true;
    }
    if (auto f = frames.find(k); f != frames.end()) {
      if (!rosName(v, true)) {
        diag.error(path, line, k + ": '" + v + "' is not a frame id");
        return false;
      }
      *f->second = v;
      return true;
    }
    if (k == "ros.stale_after" || k == "ros.publish_rate") {
      const std::optional<double> x = parseReal(v);
      const double lo = k == "ros.stale_after" ? 0.05 : 1, hi = k == "ros.stale_after" ? 10 : 100;
      if (!x || *x < lo || *x > hi) {
        diag.error(path, line, k + ": expected a number in [" + shortestText(lo) + ", " + shortestText(hi) + "], got '" + v + "'");
        return false;
      }
      (k == "ros.stale_after" ? c.staleAfter : c.publishRate) = *x;
      return true;
    }
    if (k.rfind("ros.joint.", 0) == 0) {
      const std::string joint = k.substr(10);
      if (robot.findJoint(joint) < 0) {
        diag.error(path, line, k + ": the robot '" + robot.name + "' has no joint '" + joint + "'");
        return false;
      }
      if (!rosName(v, true)) {
        diag.error(path, line, k + ": '" + v + "' is not a ROS joint name");
        return false;
      }
      if (auto m = mappedAt.find(v); m != mappedAt.end()) {
        diag.error(path, line, k + ": '" + v + "' is mapped already (line " + std::to_string(m->second) + ")");
        return false;
      }
      mappedAt[v] = line;
      c.jointNames[joint] = v;
      return true;
    }
    diag.error(path, line, "unknown key '" + k + "' (docs/ros.md lists the bridge's keys)");
    return false;
  };
  if (!readProperties(text, path, diag, known, set)) return std::nullopt;
  // A joint left unmapped keeps its name, which a mapped one must not take.
  for (const JointSpec& j : robot.joints)
    if (!c.jointNames.count(j.name) && mappedAt.count(j.name)) {
      diag.error(path, mappedAt[j.name], "'" + j.name + "' is the name of the robot's own joint '" + j.name +
                                              "' too: map that one as well");
      return std::nullopt;
    }
  return c;
}

std::optional<BridgeConfig> loadBridgeConfig(const std::string& path, const RobotModel& robot, Diagnostics& diag) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    diag.error(path, 0, "cannot open the bridge's parameters file");
    return std::nullopt;
  }
  std::stringstream text;
  text << in.rdbuf();
  return parseBridgeConfig(text.str(), path, robot, diag);
}

TopicRobot::TopicRobot(RobotModel model, BridgeConfig config, TopicOutput& output, std::function<double()> clock)
    : model_(std::move(model)),
      config_(std::move(config)),
      output_(output),
      clock_(std::move(clock)),
      started_(clock_()),
      positions_(model_.joints.size(), 0.0),
      velocities_(model_.joints.size(), 0.0) {
  for (size_t j = 0; j < model_.joints.size(); ++j) {
    const auto mapped = config_.jointNames.find(model_.joints[j].name);
    jointByRosName_[mapped == config_.jointNames.end() ? model_.joints[j].name : mapped->second] = static_cast<int>(j);
  }
  if (const std::optional<DriveSpec>& d = model_.drive; d && d->articulation >= 0) {
    const Vec2 hinge = planar(model_, d->articulation);
    const Vec2 fl = planar(model_, d->wheels[0]), fr = planar(model_, d->wheels[1]);
    const Vec2 rl = planar(model_, d->wheels[2]), rr = planar(model_, d->wheels[3]);
    geometry_.frontLength = distance(hinge, {(fl.x + fr.x) / 2, (fl.y + fr.y) / 2});
    geometry_.rearLength = distance(hinge, {(rl.x + rr.x) / 2, (rl.y + rr.y) / 2});
    geometry_.frontTrack = distance(fl, fr);
    geometry_.rearTrack = distance(rl, rr);
    const JointSpec& a = model_.joints[static_cast<size_t>(d->articulation)];
    maxArticulation_ = a.limited ? std::min(std::abs(a.lower), std::abs(a.upper)) : kPi / 2;
  }
}

double TopicRobot::yawRateOf(double speed, double articulation) const {
  if (speed == 0 || articulation == 0 || !model_.drive) return 0;
  // articulationForTurn grows with the yaw rate (for speed > 0; falls for
  // speed < 0): bisect for the one that gives `articulation`.
  const double sign = speed > 0 ? 1 : -1;
  double lo = -20, hi = 20;
  for (int i = 0; i < 80; ++i) {
    const double mid = (lo + hi) / 2;
    if (sign * articulationForTurn(geometry_, speed, mid, kPi) < sign * articulation) lo = mid;
    else hi = mid;
  }
  return (lo + hi) / 2;
}

void TopicRobot::odometry(const OdometryIn& m) {
  std::lock_guard lock(mutex_);
  odom_ = m;
  odomArrived_ = clock_();
}

void TopicRobot::jointStates(const JointStatesIn& m) {
  std::lock_guard lock(mutex_);
  for (size_t i = 0; i < m.names.size(); ++i) {
    const auto j = jointByRosName_.find(m.names[i]);
    if (j == jointByRosName_.end()) continue;  // a joint the model does not have (a gripper's, say)
    if (i < m.positions.size()) positions_[static_cast<size_t>(j->second)] = m.positions[i];
    if (i < m.velocities.size()) velocities_[static_cast<size_t>(j->second)] = m.velocities[i];
  }
}

void TopicRobot::scan(const ScanIn& m) {
  std::lock_guard lock(mutex_);
  net::LaserScanState s;
  s.count = scan_ ? scan_->count + 1 : 1;
  s.time = clock_() - started_;
  s.angleMin = m.angleMin;
  s.angleStep = m.angleIncrement;
  s.ranges.reserve(m.ranges.size());
  // The link's scans say "nothing" with the maximum range, as the twin's laser does.
  for (double r : m.ranges) s.ranges.push_back(std::isfinite(r) ? std::min(r, m.rangeMax) : m.rangeMax);
  scan_ = std::move(s);
}

void TopicRobot::imu(const ImuIn& m) {
  std::lock_guard lock(mutex_);
  imu_ = m;
}

CommandCheck TopicRobot::check(const Command& command) const {
  if (std::holds_alternative<StopCmd>(command)) return {};
  if (const auto* d = std::get_if<DriveCmd>(&command)) {
    if (!model_.drive) return {CommandCheck::Kind::Invalid, "the robot has no <drive>"};
    if (std::abs(d->articulation) > maxArticulation_ + 1e-9)
      return {CommandCheck::Kind::OutOfLimits, "articulation beyond the hinge's limit"};
    return checkCommand(command, model_);
  }
  if (std::holds_alternative<TurnCmd>(command)) return checkCommand(command, model_);
  if (const auto* t = std::get_if<JointTargetCmd>(&command)) {
    const int j = model_.findJoint(t->joint);
    if (model_.drive && j >= 0 &&
        (j == model_.drive->articulation ||
         std::find(model_.drive->wheels.begin(), model_.drive->wheels.end(), j) != model_.drive->wheels.end()))
      return {CommandCheck::Kind::Invalid, "'" + t->joint + "' is driven through " + config_.cmdVel + " (drive, turn)"};
    return checkCommand(command, model_);
  }
  const std::string text = toText(command, &model_);
  return {CommandCheck::Kind::Invalid, "the ROS bridge sends drive, turn, stop (" + config_.cmdVel +
                                           ") and joint targets (" + config_.jointCommand + ") only, not '" +
                                           text.substr(0, text.find(' ')) + "'"};
}

void TopicRobot::apply(const std::vector<Command>& commands) {
  for (const Command& command : commands) {
    if (std::holds_alternative<StopCmd>(command)) {
      output_.velocity(0, 0);
    } else if (const auto* d = std::get_if<DriveCmd>(&command)) {
      output_.velocity(d->speed, yawRateOf(d->speed, d->articulation));
    } else if (const auto* t = std::get_if<TurnCmd>(&command)) {
      output_.velocity(t->speed, t->yawRate);
    } else if (const auto* j = std::get_if<JointTargetCmd>(&command)) {
      const auto mapped = config_.jointNames.find(j->joint);
      output_.jointTargets({mapped == config_.jointNames.end() ? j->joint : mapped->second}, {j->position});
    }
  }
}

net::RobotState TopicRobot::state() const {
  std::lock_guard lock(mutex_);
  net::RobotState s;
  s.time = clock_() - started_;
  if (odom_) {
    s.pose = odom_->pose;
    // nav_msgs/Odometry's twist is in the base frame; telemetry's in the world's.
    s.baseLinearVelocity = rotate(odom_->pose.q, odom_->linear);
    s.baseAngularVelocity = rotate(odom_->pose.q, odom_->angular);
  }
  for (const JointSpec& j : model_.joints) s.jointNames.push_back(j.name);
  s.jointPositions = positions_;
  s.jointVelocities = velocities_;
  const Vec3 t = tilt(imu_ ? imu_->orientation : s.pose.q);
  s.roll = t.x;
  s.pitch = t.y;
  return s;
}

std::optional<net::LaserScanState> TopicRobot::laserAfter(uint64_t afterCount) const {
  std::lock_guard lock(mutex_);
  if (!scan_ || scan_->count <= afterCount) return std::nullopt;
  return scan_;
}

std::string TopicRobot::fault() const {
  std::lock_guard lock(mutex_);
  const double now = clock_();
  const double age = now - (odom_ ? odomArrived_ : started_);
  if (age <= config_.staleAfter) return {};
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%.2f", age);
  return "stale ROS input: no odometry on " + config_.odom + (odom_ ? " for " : " since the start, ") +
         seconds + " s (ros.stale_after " + shortestText(config_.staleAfter) + " s)";
}

}  // namespace sp
