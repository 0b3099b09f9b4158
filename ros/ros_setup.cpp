#include "ros/ros_setup.h"

#include <pthread.h>

#include <iostream>

#include "app/data/data_files.h"
#include "app/state/run_params.h"
#include "sim/kinematics.h"
#include "sim/model_loader.h"

namespace sp::rosapp {

bool CommonOptions::take(const std::string& a, const std::string& v) {
  if (a == "--world") worldFile = v;
  else if (a == "--bridge") bridgeFile = v;
  else if (a == "--params") paramsFile = v;
  else if (a == "--set") overrides.push_back(v);
  else if (a == "--node") nodeName = v;
  else return false;
  return true;
}

std::optional<int> parse(const std::vector<std::string>& args, const char* usage, CommonOptions& options,
                         const std::function<std::optional<int>(const std::string&, const std::string&)>& own) {
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      std::cout << usage;
      return 0;
    }
    if (i + 1 >= args.size()) {
      std::cerr << "<command line>: error: unknown option or missing value '" << a << "'\n" << usage;
      return 2;
    }
    const std::string& v = args[++i];
    if (options.take(a, v)) continue;
    if (std::optional<int> exit = own(a, v)) return exit;
  }
  return std::nullopt;
}

std::optional<Setup> load(CommonOptions o) {
  for (std::string* file : {&o.worldFile, &o.paramsFile, &o.bridgeFile}) {
    std::string error;
    *file = findDataFile(*file, error);
    if (!error.empty()) {
      std::cerr << error << "\n";
      return std::nullopt;
    }
  }
  Diagnostics diag;
  std::optional<WorldModel> world = loadWorld(o.worldFile, diag);
  std::optional<SimParams> params = loadRunParams(o.paramsFile, o.overrides, diag);
  std::optional<BridgeConfig> config = BridgeConfig{};
  if (world && world->robots.empty()) diag.error(o.worldFile, 0, "the world has no <robot>");
  else if (world && !o.bridgeFile.empty()) config = loadBridgeConfig(o.bridgeFile, world->robots[0].model, diag);
  std::cerr << diag.format();
  if (diag.hasErrors() || !world || !params || !config) return std::nullopt;
  return Setup{std::move(*world), std::move(*params), std::move(*config)};
}

std::unique_ptr<ros1::Node> joinGraph(const std::string& nodeName, sigset_t& stopSignals) {
  sigemptyset(&stopSignals);
  sigaddset(&stopSignals, SIGINT);
  sigaddset(&stopSignals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);
  std::string error;
  std::unique_ptr<ros1::Node> node = ros1::Node::create(nodeName, 10, error);
  if (!node) std::cerr << "error: " << error << "\n";
  return node;
}

void toArray(const Quat& q, double* wxyz) {
  wxyz[0] = q.w;
  wxyz[1] = q.x;
  wxyz[2] = q.y;
  wxyz[3] = q.z;
}
void toArray(const Vec3& v, double* xyz) {
  xyz[0] = v.x;
  xyz[1] = v.y;
  xyz[2] = v.z;
}

ros1::Transform transform(double stamp, const std::string& parent, const std::string& child, const Pose& pose) {
  ros1::Transform t;
  t.stamp = stamp;
  t.parent = parent;
  t.child = child;
  toArray(pose.p, t.translation);
  toArray(pose.q, t.rotation);
  return t;
}

int laserSensor(const RobotModel& robot) {
  for (size_t i = 0; i < robot.sensors.size(); ++i)
    if (robot.sensors[i].type == SensorType::Laser) return static_cast<int>(i);
  return -1;
}

ros1::Transform laserTransform(const RobotModel& robot, int laser, const std::vector<double>& positions, double stamp,
                               const std::string& baseFrame) {
  const SensorSpec& s = robot.sensors[static_cast<size_t>(laser)];
  // Link 0 is the base: its frame is base_link.
  const Pose mount = linkPoses(robot, Pose{}, positions)[static_cast<size_t>(s.link)] * s.pose;
  return transform(stamp, baseFrame, "laser", mount);
}

}  // namespace sp::rosapp
