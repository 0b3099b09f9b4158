// simpartner-ros-twin: the twin as a ROS robot. It runs the world's robot in
// real time and speaks ROS as a wheeled robot's drivers do: it takes cmd_vel
// (a Twist: speed and yaw rate, as a `turn`) and joint trajectories, and
// publishes odometry, joint states, the laser scan, an IMU and /tf. The ROS
// bridge (simpartner-ros-bridge) is tested end to end against it, and a ROS
// user can drive the twin with rostopic or teleop tools.

#include <pthread.h>
#include <signal.h>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <thread>

#include "app/bridge/topic_robot.h"
#include "app/robot/twin_host.h"
#include "ros/ros1.h"
#include "ros/ros_setup.h"
#include "sim/perturbation.h"

namespace {

constexpr const char* kUsage = R"(usage:
  simpartner-ros-twin [options]
      The twin as a ROS 1 robot (docs/ros.md): subscribes cmd_vel and the
      joint trajectory topic, publishes odometry, joint states, scan, IMU
      and /tf at rate.telemetry. Needs a ROS master at $ROS_MASTER_URI.
      --world FILE      world to run (default terrains/flat.world.xml)
      --bridge FILE     topic names, frames and joint names, as the bridge's
      --params FILE     parameters; --set KEY=VALUE overrides (repeatable)
      --perturb SEED    a robot that is not its twin (simpartner-robot --help)
      --cmd-timeout S   stop when no cmd_vel came for S seconds (default 0.5,
                        as robot drivers do; 0 = never)
      --node NAME       the ROS node's name (default simpartner_twin)
  Prints `running` when it publishes. Stops on SIGINT or SIGTERM.
)";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  sp::rosapp::CommonOptions options;
  options.nodeName = "simpartner_twin";
  std::optional<uint64_t> perturbSeed;
  double cmdTimeout = 0.5;
  const std::optional<int> exit = sp::rosapp::parse(args, kUsage, options, [&](const std::string& a, const std::string& v) -> std::optional<int> {
    char* end = nullptr;
    if (a == "--perturb") {
      perturbSeed = std::strtoull(v.c_str(), &end, 10);
      if (v.empty() || v[0] == '-' || end == v.c_str() || *end) {
        std::cerr << "<command line>: error: --perturb: expected a seed (an unsigned integer), got '" << v << "'\n";
        return 2;
      }
    } else if (a == "--cmd-timeout") {
      cmdTimeout = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end || !(cmdTimeout >= 0)) {
        std::cerr << "<command line>: error: --cmd-timeout: expected seconds >= 0, got '" << v << "'\n";
        return 2;
      }
    } else {
      std::cerr << "<command line>: error: unknown option '" << a << "'\n" << kUsage;
      return 2;
    }
    return std::nullopt;
  });
  if (exit) return *exit;
  const std::optional<sp::rosapp::Setup> setup = sp::rosapp::load(options);
  if (!setup) return 1;
  const sp::WorldModel* world = &setup->world;
  const sp::SimParams* params = &setup->params;
  const sp::BridgeConfig* config = &setup->config;
  sp::Diagnostics diag;
  const sp::RobotModel& model = world->robots[0].model;
  sp::WorldModel physics = sp::calibratedWorld(*world, *params);
  if (perturbSeed) physics = sp::perturbWorld(physics, sp::drawPerturbation(*perturbSeed, model));
  std::unique_ptr<sp::World> twin = sp::World::create(physics, *params, diag);
  std::cerr << diag.format();
  if (!twin) return 1;

  sigset_t stopSignals;
  std::unique_ptr<sp::ros1::Node> node = sp::rosapp::joinGraph(options.nodeName, stopSignals);
  if (!node) return 1;
  sp::TwinHost host(std::move(twin), params->realTimeFactor);
  host.start();

  // ROS names of the joints, and back.
  std::vector<std::string> rosNames;
  std::map<std::string, std::string> modelName;
  for (const sp::JointSpec& j : model.joints) {
    const auto m = config->jointNames.find(j.name);
    rosNames.push_back(m == config->jointNames.end() ? j.name : m->second);
    modelName[rosNames.back()] = j.name;
  }
  std::mutex cmdMutex;
  auto lastCmd = std::chrono::steady_clock::now();
  bool moving = false;
  node->onTwist(config->cmdVel, [&](const sp::ros1::Twist& t) {
    if (!host.check(sp::TurnCmd{t.linear, t.angular}).ok()) return;  // beyond the robot's limits: ignored, as drivers do
    host.apply({sp::TurnCmd{t.linear, t.angular}});
    std::lock_guard lock(cmdMutex);
    lastCmd = std::chrono::steady_clock::now();
    moving = t.linear != 0 || t.angular != 0;
  });
  node->onJointTargets(config->jointCommand, [&](const sp::ros1::JointTargets& t) {
    std::vector<sp::Command> commands;
    for (size_t i = 0; i < t.names.size() && i < t.positions.size(); ++i) {
      const auto m = modelName.find(t.names[i]);
      if (m == modelName.end()) continue;
      const sp::Command c = sp::JointTargetCmd{m->second, t.positions[i]};
      if (host.check(c).ok()) commands.push_back(c);
    }
    host.apply(commands);
  });
  for (const auto& [kind, topic] : {std::pair{sp::ros1::Kind::Odometry, config->odom},
                                    {sp::ros1::Kind::JointStates, config->jointStates},
                                    {sp::ros1::Kind::Scan, config->scan},
                                    {sp::ros1::Kind::Imu, config->imu},
                                    {sp::ros1::Kind::Tf, std::string("/tf")}})
    node->advertise(kind, topic);

  const int laserSensor = sp::rosapp::laserSensor(model);
  std::cout << "running " << model.name << " on " << world->name << std::endl;

  const auto period = std::chrono::duration<double>(1.0 / params->telemetryRate);
  auto next = std::chrono::steady_clock::now();
  uint64_t laserCount = 0;
  const timespec noWait{0, 0};
  while (sigtimedwait(&stopSignals, nullptr, &noWait) < 0 && node->ok()) {
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
    {
      std::lock_guard lock(cmdMutex);
      if (cmdTimeout > 0 && moving && std::chrono::steady_clock::now() - lastCmd > std::chrono::duration<double>(cmdTimeout)) {
        host.apply({sp::StopCmd{}});  // the driver's watchdog: no fresh cmd_vel, no motion
        moving = false;
      }
    }
    const sp::net::RobotState s = host.state();
    const double stamp = node->now();
    sp::ros1::Odometry odom;
    odom.stamp = stamp;
    odom.frame = config->odomFrame;
    odom.childFrame = config->baseFrame;
    sp::rosapp::toArray(s.pose.p, odom.position);
    sp::rosapp::toArray(s.pose.q, odom.orientation);
    // nav_msgs/Odometry's twist is in the child (base) frame.
    sp::rosapp::toArray(sp::rotate(sp::conjugate(s.pose.q), s.baseLinearVelocity), odom.linear);
    sp::rosapp::toArray(sp::rotate(sp::conjugate(s.pose.q), s.baseAngularVelocity), odom.angular);
    node->publish(config->odom, odom);
    node->publish(config->jointStates, sp::ros1::JointStates{stamp, rosNames, s.jointPositions, s.jointVelocities});
    sp::ros1::Imu imu;
    imu.stamp = stamp;
    imu.frame = config->baseFrame;
    sp::rosapp::toArray(s.pose.q, imu.orientation);
    sp::rosapp::toArray(sp::rotate(sp::conjugate(s.pose.q), s.baseAngularVelocity), imu.angularVelocity);
    node->publish(config->imu, imu);
    std::vector<sp::ros1::Transform> tf{sp::rosapp::transform(stamp, config->odomFrame, config->baseFrame, s.pose)};
    if (laserSensor >= 0) {
      tf.push_back(sp::rosapp::laserTransform(model, laserSensor, s.jointPositions, stamp, config->baseFrame));
      if (const std::optional<sp::net::LaserScanState> scan = host.laserAfter(laserCount)) {
        const sp::SensorSpec& laser = model.sensors[static_cast<size_t>(laserSensor)];
        laserCount = scan->count;
        node->publish(config->scan, sp::ros1::Scan{stamp, "laser", scan->angleMin, scan->angleStep, laser.minRange,
                                                   laser.maxRange, std::vector<float>(scan->ranges.begin(), scan->ranges.end())});
      }
    }
    node->publish("/tf", tf);
  }
  host.apply({sp::StopCmd{}});
  host.stop();
  return 0;
}
