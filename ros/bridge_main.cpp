// simpartner-ros-bridge: the robot side of the link protocol backed by ROS
// topics (app/bridge/topic_robot.h): a console (or any link client) connects
// to it as to a robot; its drive goes out on cmd_vel, its joint targets as a
// JointTrajectory, and odometry, joint states, laser and IMU come back as
// telemetry. The safety chain (deadman, e-stop, failsafe) is the link's, here.

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <asio.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <thread>

#include "app/bridge/topic_robot.h"
#include "app/robot/line_writer.h"
#include "app/log/session_recorder.h"
#include "net/auth.h"
#include "net/robot_server.h"
#include "ros/ros1.h"
#include "ros/ros_setup.h"

namespace {

constexpr const char* kUsage = R"(usage:
  simpartner-ros-bridge [options]
      The robot side of the SimPartner link protocol, backed by ROS 1 topics
      (docs/ros.md): connect the console to it with --connect HOST:PORT.
      Needs a ROS master at $ROS_MASTER_URI.
      --world FILE      the robot's world (default terrains/flat.world.xml):
                        its robot file names the joints and limits
      --bridge FILE     topics, frames and joint-name map (docs/ros.md);
                        default: /cmd_vel, /joint_trajectory, /odom,
                        /joint_states, /scan, /imu, frames odom, base_link
      --params FILE     link parameters (link.deadman, ...); --set KEY=VALUE
      --port N          TCP port (default: port.robot; 0 = any free port)
      --bind ADDRESS    address to listen on (default 127.0.0.1); any other
                        needs --token
      --token HEX       shared secret, >= 32 hex digits (default: a random
                        one, printed, on loopback only)
      --node NAME       the ROS node's name (default simpartner_bridge)
  Prints `token HEX`, then `listening on ADDRESS:PORT` when ready. Stops on
  SIGINT or SIGTERM, publishing a zero velocity first.
)";

/// Publishes what the bridge sends: the velocity now and again at the
/// configured rate (robot drivers stop without a fresh cmd_vel), joint
/// targets once.
class RosOutput : public sp::TopicOutput {
 public:
  RosOutput(sp::ros1::Node& node, const sp::BridgeConfig& config) : node_(node), config_(config) {
    node_.advertise(sp::ros1::Kind::Twist, config_.cmdVel);
    node_.advertise(sp::ros1::Kind::JointTargets, config_.jointCommand);
    thread_ = std::thread([this] { republish(); });
  }
  ~RosOutput() override {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  void velocity(double linear, double angular) override {
    {
      std::lock_guard lock(mutex_);
      twist_ = {linear, angular};
    }
    node_.publish(config_.cmdVel, sp::ros1::Twist{linear, angular});
  }
  void jointTargets(const std::vector<std::string>& names, const std::vector<double>& positions) override {
    node_.publish(config_.jointCommand, sp::ros1::JointTargets{names, positions});
  }

 private:
  void republish() {
    std::unique_lock lock(mutex_);
    const auto period = std::chrono::duration<double>(1.0 / config_.publishRate);
    while (!wake_.wait_for(lock, period, [this] { return stop_; })) {
      const sp::ros1::Twist t = twist_;
      lock.unlock();
      node_.publish(config_.cmdVel, t);
      lock.lock();
    }
  }

  sp::ros1::Node& node_;
  const sp::BridgeConfig& config_;
  std::mutex mutex_;
  std::condition_variable wake_;
  sp::ros1::Twist twist_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  sp::rosapp::CommonOptions options;
  options.nodeName = "simpartner_bridge";
  std::string bind = "127.0.0.1", token;
  int port = -1;
  const std::optional<int> exit = sp::rosapp::parse(args, kUsage, options, [&](const std::string& a, const std::string& v) -> std::optional<int> {
    if (a == "--bind") bind = v;
    else if (a == "--token") token = v;
    else if (a == "--port") {
      char* end = nullptr;
      const long p = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end || p < 0 || p > 65535) {
        std::cerr << "<command line>: error: --port: expected 0..65535, got '" << v << "'\n";
        return 2;
      }
      port = static_cast<int>(p);
    } else {
      std::cerr << "<command line>: error: unknown option '" << a << "'\n" << kUsage;
      return 2;
    }
    return std::nullopt;
  });
  if (exit) return *exit;
  if (token.empty() && !(bind == "127.0.0.1" || bind == "::1" || bind == "localhost")) {
    std::cerr << "<command line>: error: refusing to listen on " << bind << " without --token\n";
    return 2;
  }
  const std::optional<sp::rosapp::Setup> setup = sp::rosapp::load(options);
  if (!setup) return 1;
  const sp::WorldModel* world = &setup->world;
  const sp::SimParams* params = &setup->params;
  const sp::BridgeConfig* config = &setup->config;

  sigset_t stopSignals;
  std::unique_ptr<sp::ros1::Node> node = sp::rosapp::joinGraph(options.nodeName, stopSignals);
  if (!node) return 1;
  const sp::RobotModel& model = world->robots[0].model;
  RosOutput output(*node, *config);
  const auto clock = [] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  };
  sp::TopicRobot robot(model, *config, output, clock);
  node->onOdometry(config->odom, [&robot](const sp::ros1::Odometry& m) {
    const double* q = m.orientation;
    robot.odometry({m.stamp,
                    {{m.position[0], m.position[1], m.position[2]}, {q[0], q[1], q[2], q[3]}},
                    {m.linear[0], m.linear[1], m.linear[2]},
                    {m.angular[0], m.angular[1], m.angular[2]}});
  });
  node->onJointStates(config->jointStates, [&robot](const sp::ros1::JointStates& m) {
    robot.jointStates({m.stamp, m.names, m.positions, m.velocities});
  });
  node->onScan(config->scan, [&robot](const sp::ros1::Scan& m) {
    robot.scan({m.stamp, m.angleMin, m.angleIncrement, m.rangeMax, std::vector<double>(m.ranges.begin(), m.ranges.end())});
  });
  node->onImu(config->imu, [&robot](const sp::ros1::Imu& m) {
    const double* q = m.orientation;
    robot.imu({m.stamp, {q[0], q[1], q[2], q[3]}});
  });

  sp::net::RobotServerConfig server;
  server.address = bind;
  server.port = static_cast<uint16_t>(port >= 0 ? port : params->robotPort);
  server.link.robotName = world->robots[0].name;
  server.link.token = token.empty() ? sp::net::randomToken() : token;
  server.link.telemetryRate = params->telemetryRate;
  server.link.worldHash = sp::fileHash(world->file);
  server.link.robotHash = sp::fileHash(model.file);
  server.link.deadman = params->linkDeadman;
  server.link.leaseConfirm = params->linkLeaseConfirm;
  server.maxConnections = static_cast<size_t>(params->linkMaxConnections);
  server.helloTimeout = params->linkHelloTimeout;
  // The link's lines go through their own thread: the link thread (which
  // runs the deadman) never waits for a stderr nobody reads.
  sp::LineWriter lines(STDERR_FILENO, "simpartner-ros-bridge: ");
  server.log = [&lines](const std::string& line) { lines.write(line); };
  server.events = [&lines](const std::string& kind, const std::string& text) {
    lines.write(kind == "link" ? text : kind + ": " + text);
  };
  asio::io_context io;
  sp::net::RobotServer linkServer(io, server, robot);
  if (const std::string why = linkServer.start(); !why.empty()) {
    std::cerr << "error: " << why << "\n";
    return 1;
  }
  std::thread ioThread([&io] { io.run(); });
  if (token.empty()) std::cout << "token " << server.link.token << "\n";
  std::cout << "ros topics " << config->cmdVel << " " << config->jointCommand << " <- link; link <- " << config->odom
            << " " << config->jointStates << " " << config->scan << " " << config->imu << "\n";
  std::cout << "listening on " << bind << ":" << linkServer.port() << std::endl;

  int signal = 0;
  sigwait(&stopSignals, &signal);
  // The robot stops before the bridge goes: a zero velocity, then the link.
  output.velocity(0, 0);
  asio::post(io, [&] {
    linkServer.shutdown(std::string("bridge shutting down (") + (signal == SIGINT ? "SIGINT" : "SIGTERM") + ")");
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  asio::post(io, [&] {
    linkServer.stop();
    io.stop();
  });
  ioThread.join();
  return 0;
}
