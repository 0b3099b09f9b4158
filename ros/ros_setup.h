#pragma once
// What the ROS programs share (C++20 side of ros1.h): their common options
// and files, and the conversions from the twin's types to ros1's plain ones.

#include <signal.h>

#include <functional>
#include <memory>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "app/bridge/topic_robot.h"
#include "ros/ros1.h"
#include "sim/params.h"

namespace sp::rosapp {

/// The options every ROS program takes: --world, --bridge, --params, --set, --node.
struct CommonOptions {
  std::string worldFile = "terrains/flat.world.xml", bridgeFile, paramsFile, nodeName;
  std::vector<std::string> overrides;
  /// Takes option `a` with value `v` if it is a common one.
  bool take(const std::string& a, const std::string& v);
};

/// Reads the command line: --help prints `usage` (exit 0); the common
/// options go to `options`; any other with its value to `own`, which
/// returns an exit code after saying what is wrong (2), or nullopt when
/// it took it. Returns nullopt to go on, else the exit code.
std::optional<int> parse(const std::vector<std::string>& args, const char* usage, CommonOptions& options,
                         const std::function<std::optional<int>(const std::string&, const std::string&)>& own);

/// The files the options name, loaded: the world (with a robot), the
/// parameters, the bridge's topics and names. nullopt after printing every
/// problem (`file:line: error: ...`) on stderr.
struct Setup {
  WorldModel world;
  SimParams params;
  BridgeConfig config;
  const RobotModel& robot() const { return world.robots[0].model; }
};
std::optional<Setup> load(CommonOptions options);

/// Blocks SIGINT and SIGTERM (for sigwait; before any thread starts, so all
/// inherit the mask) and joins the ROS graph as `nodeName`; nullptr after
/// saying why (no master within 10 s).
std::unique_ptr<ros1::Node> joinGraph(const std::string& nodeName, sigset_t& stopSignals);

void toArray(const Quat& q, double* wxyz);
void toArray(const Vec3& v, double* xyz);
/// A transform `parent` -> `child` at `pose`.
ros1::Transform transform(double stamp, const std::string& parent, const std::string& child, const Pose& pose);
/// The robot's laser (its first), or -1.
int laserSensor(const RobotModel& robot);
/// base frame -> "laser" with the joints at `positions` (robot.joints order).
ros1::Transform laserTransform(const RobotModel& robot, int laser, const std::vector<double>& positions, double stamp,
                               const std::string& baseFrame);

}  // namespace sp::rosapp
