// simpartner-ros-export LOG --bag FILE: a session log as a ROS bag
// (`simpartner-sim export LOG --bag FILE` runs it). Topics, all stamped with
// the log's robot time (seconds since the session began, as ROS time from
// the epoch; 0 becomes 1 ns, which a bag takes):
//   /odom                   nav_msgs/Odometry (odom -> base_link; twist from
//                           successive samples, in the base frame)
//   /joint_states           sensor_msgs/JointState (the robot file's names)
//   /scan                   sensor_msgs/LaserScan (frame "laser")
//   /tf                     tf2_msgs/TFMessage (odom -> base_link, base_link -> laser)
//   /simpartner/commands    std_msgs/String "SOURCE: COMMAND"
//   /simpartner/events      std_msgs/String "KIND: TEXT"

#include <cstdio>
#include <iostream>

#include "app/log/session_log.h"
#include "ros/ros1.h"
#include "ros/ros_setup.h"
#include "sim/model_loader.h"

namespace {

sp::Pose poseOf(const sp::LogSample& s) {
  return {{s.base[0], s.base[1], s.base[2]}, {s.quat[0], s.quat[1], s.quat[2], s.quat[3]}};
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string log, bag;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") {
      std::cout << "usage: simpartner-ros-export LOG --bag FILE\n"
                   "  Writes the session log LOG as a ROS bag (docs/ros.md), whole or not at all.\n";
      return 0;
    }
    if (args[i] == "--bag" && i + 1 < args.size()) bag = args[++i];
    else if (log.empty() && !args[i].empty() && args[i][0] != '-') log = args[i];
    else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << args[i] << "'\n";
      return 2;
    }
  }
  if (log.empty() || bag.empty()) {
    std::cerr << "<command line>: error: export needs LOG and --bag FILE\n";
    return 2;
  }
  std::string error;
  std::unique_ptr<sp::SessionLogReader> reader = sp::SessionLogReader::open(log, error);
  if (!reader) {
    std::cerr << error << "\n";
    return 1;
  }
  const std::map<std::string, std::string> meta = reader->meta();
  std::optional<sp::RobotModel> robot;
  if (auto it = meta.find("robot_contents"); it != meta.end()) {
    sp::Diagnostics diag;
    auto name = meta.find("robot_file");
    robot = sp::parseRobot(it->second, name == meta.end() ? "robot" : name->second, diag);
  }
  std::unique_ptr<sp::ros1::BagWriter> out = sp::ros1::BagWriter::open(bag, error);
  if (!out) {
    std::cerr << error << "\n";
    return 1;
  }
  const double all = 1e300;
  const std::vector<sp::LogSample> samples = reader->samplesBetween(-all, all);
  const int laserSensor = robot ? sp::rosapp::laserSensor(*robot) : -1;
  size_t counts[6] = {0, 0, 0, 0, 0, 0};
  for (size_t k = 0; k < samples.size(); ++k) {
    const sp::LogSample& s = samples[k];
    const sp::Pose pose = poseOf(s);
    sp::ros1::Odometry odom;
    odom.stamp = s.time;
    odom.frame = "odom";
    odom.childFrame = "base_link";
    sp::rosapp::toArray(pose.p, odom.position);
    sp::rosapp::toArray(pose.q, odom.orientation);
    if (k > 0 && s.time > samples[k - 1].time) {
      // The twist from this sample and the one before, in the base frame.
      const sp::LogSample& p = samples[k - 1];
      const double dt = s.time - p.time;
      const sp::Pose before = poseOf(p);
      sp::rosapp::toArray(sp::rotate(sp::conjugate(pose.q), (1 / dt) * (pose.p - before.p)), odom.linear);
      const sp::Quat d = sp::conjugate(before.q) * pose.q;  // rotation over dt, in the base frame
      const double sinHalf = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
      const double angle = 2 * std::atan2(sinHalf, d.w);
      if (sinHalf > 1e-12) sp::rosapp::toArray((angle / dt / sinHalf) * sp::Vec3{d.x, d.y, d.z}, odom.angular);
    }
    out->write("/odom", s.time, odom);
    ++counts[0];
    sp::ros1::JointStates joints;
    joints.stamp = s.time;
    const size_t n = s.joints.size() / 2;
    for (size_t j = 0; j < n; ++j) {
      joints.names.push_back(robot && j < robot->joints.size() ? robot->joints[j].name : "joint_" + std::to_string(j));
      joints.positions.push_back(s.joints[j]);
      joints.velocities.push_back(s.joints[n + j]);
    }
    out->write("/joint_states", s.time, joints);
    ++counts[1];
    std::vector<sp::ros1::Transform> tf{sp::rosapp::transform(s.time, "odom", "base_link", pose)};
    if (laserSensor >= 0) {
      const std::vector<double> positions(s.joints.begin(), s.joints.begin() + static_cast<long>(n));
      tf.push_back(sp::rosapp::laserTransform(*robot, laserSensor, positions, s.time, "base_link"));
    }
    out->write("/tf", s.time, tf);
    ++counts[2];
  }
  const sp::SensorSpec* laser = laserSensor >= 0 ? &robot->sensors[static_cast<size_t>(laserSensor)] : nullptr;
  for (const sp::LogLaser& l : reader->laserBetween(-all, all)) {
    out->write("/scan", l.time,
               sp::ros1::Scan{l.time, "laser", l.angleMin, l.angleStep, laser ? laser->minRange : 0,
                              laser ? laser->maxRange : 0, std::vector<float>(l.ranges.begin(), l.ranges.end())});
    ++counts[3];
  }
  for (const sp::LogCommand& c : reader->commands()) {
    out->write("/simpartner/commands", c.time, c.source + ": " + c.text);
    ++counts[4];
  }
  for (const sp::LogEvent& e : reader->events()) {
    out->write("/simpartner/events", e.time, e.kind + ": " + e.text);
    ++counts[5];
  }
  if (!out->close(error)) {
    std::cerr << error << "\n";
    return 1;
  }
  std::cout << "wrote " << bag << ": /odom " << counts[0] << ", /joint_states " << counts[1] << ", /tf " << counts[2]
            << ", /scan " << counts[3] << ", /simpartner/commands " << counts[4] << ", /simpartner/events " << counts[5]
            << " messages\n";
  return 0;
}
