#pragma once
// The robot side of the link protocol backed by a robot's own topics, not the
// twin: what the operator commands goes out as a velocity (a Twist) and joint
// targets, what the robot reports (odometry, joint states, laser, IMU) comes
// back as telemetry. Middleware-free: an adapter moves the messages (ROS 1:
// ros/ros1_adapter.h; a ROS 2 one would sit beside it and use this as is).
//
// The safety chain stays with the link (net/robot_link.h): its deadman,
// e-stop and failsafe apply StopCmd here, which publishes a zero velocity,
// and the link refuses every command until re-armed. Input that goes stale
// (no odometry for `staleAfter`) is a fault: the failsafe fires with the
// reason and fires again after a re-arm while the input stays stale.
//
// Thread: the adapter's callbacks (its threads) and the server's calls (its
// io thread) may run at once; one mutex guards the latest inputs.

#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "net/robot_server.h"
#include "sim/diagnostics.h"
#include "sim/robot_model.h"
#include "sim/world.h"

namespace sp {

/// Topic names, frames and the joint-name map (docs/ros.md: the bridge's
/// parameters file). Defaults are the ROS conventions.
struct BridgeConfig {
  std::string cmdVel = "/cmd_vel";                 ///< geometry_msgs/Twist out
  std::string jointCommand = "/joint_trajectory";  ///< trajectory_msgs/JointTrajectory out
  std::string odom = "/odom";                      ///< nav_msgs/Odometry in
  std::string jointStates = "/joint_states";       ///< sensor_msgs/JointState in
  std::string scan = "/scan";                      ///< sensor_msgs/LaserScan in
  std::string imu = "/imu";                        ///< sensor_msgs/Imu in
  std::string odomFrame = "odom", baseFrame = "base_link";
  double staleAfter = 0.5;   ///< [s] odometry older than this is a fault
  double publishRate = 20;   ///< [Hz] the velocity is published again at this rate (drivers' watchdogs)
  /// Robot-file joint name -> the robot's ROS joint name; a joint not in
  /// the map keeps its name.
  std::map<std::string, std::string> jointNames;
};

/// Reads a bridge parameters file (`key = value`, docs/ros.md): `ros.cmd_vel`,
/// `ros.joint_command`, `ros.odom`, `ros.joint_states`, `ros.scan`, `ros.imu`,
/// `ros.odom_frame`, `ros.base_frame`, `ros.stale_after`, `ros.publish_rate`
/// and `ros.joint.NAME = ROS_NAME` for joints of `robot`. Each error names its
/// line: an unknown key, a topic or frame that is not a ROS name, a joint
/// the robot lacks, two joints mapped to one name. nullopt on any error.
std::optional<BridgeConfig> loadBridgeConfig(const std::string& path, const RobotModel& robot, Diagnostics& diag);
/// The same from text (`path` names it in diagnostics).
std::optional<BridgeConfig> parseBridgeConfig(std::string_view text, std::string_view path, const RobotModel& robot,
                                              Diagnostics& diag);

/// Messages in, as the adapter decodes them. Stamps are the robot's [s].
struct OdometryIn {
  double stamp = 0;
  Pose pose;            ///< base frame in the odometry frame
  Vec3 linear, angular; ///< in the base frame (as nav_msgs/Odometry's twist)
};
struct JointStatesIn {
  double stamp = 0;
  std::vector<std::string> names;  ///< the robot's ROS names
  std::vector<double> positions, velocities;
};
struct ScanIn {
  double stamp = 0;
  double angleMin = 0, angleIncrement = 0, rangeMax = 0;
  std::vector<double> ranges;  ///< NaN or inf: nothing within range
};
struct ImuIn {
  double stamp = 0;
  Quat orientation;
};

/// What the bridge sends; the adapter publishes it.
class TopicOutput {
 public:
  virtual ~TopicOutput() = default;
  /// The velocity to hold [m/s, rad/s] in the base frame (x forward, yaw
  /// left); published now and again at the config's rate until changed.
  virtual void velocity(double linear, double angular) = 0;
  /// Position targets [rad, m] for joints, by their ROS names.
  virtual void jointTargets(const std::vector<std::string>& names, const std::vector<double>& positions) = 0;
};

class TopicRobot : public net::RobotPort {
 public:
  /// `clock` gives the bridge's time [s, monotonic]: telemetry time and the
  /// staleness of input.
  TopicRobot(RobotModel model, BridgeConfig config, TopicOutput& output, std::function<double()> clock);

  // From the adapter (any thread).
  void odometry(const OdometryIn& m);
  void jointStates(const JointStatesIn& m);
  void scan(const ScanIn& m);
  void imu(const ImuIn& m);

  // net::RobotPort (the server's thread).
  const RobotModel* model() const override { return &model_; }
  /// Drive, turn and stop go out as a velocity, joint targets of the legs,
  /// arms and head as joint targets; anything else is refused, saying what
  /// the robot's ROS interface takes.
  CommandCheck check(const Command& command) const override;
  void apply(const std::vector<Command>& commands) override;
  net::RobotState state() const override;
  std::optional<net::LaserScanState> laserAfter(uint64_t afterCount) const override;
  std::string fault() const override;

  /// The yaw rate [rad/s] of a drive at `speed` [m/s] with the hinge at
  /// `articulation` [rad], from the robot's articulated-steering geometry
  /// in its stance (the inverse of articulationForTurn).
  double yawRateOf(double speed, double articulation) const;

 private:
  RobotModel model_;
  BridgeConfig config_;
  TopicOutput& output_;
  std::function<double()> clock_;
  DriveGeometry geometry_;
  double maxArticulation_ = 0;
  double started_;
  std::map<std::string, int> jointByRosName_;  ///< the robot's ROS name -> model joint index
  mutable std::mutex mutex_;
  std::optional<OdometryIn> odom_;
  double odomArrived_ = 0;  ///< [s, clock] of the last odometry
  std::vector<double> positions_, velocities_;
  std::optional<ImuIn> imu_;
  std::optional<net::LaserScanState> scan_;
};

}  // namespace sp
