#pragma once
// The ROS 1 adapter (Debian's roscpp and rosbag): the only code that includes
// ROS headers. ROS 1's message headers do not compile as C++20, so ros1.cpp is
// built as C++17 and this header speaks plain C++17 types only; the bridge,
// the twin node and the bag export (C++20, app/bridge/topic_robot.h) use it.
// A ROS 2 adapter would offer the same calls beside it.
//
// Thread: publish() from any thread (roscpp's publishers are thread-safe);
// callbacks run on the node's one spinner thread.

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace sp::ros1 {

/// Plain messages: SI units, quaternions w, x, y, z; stamps [s].
struct Twist {
  double linear = 0, angular = 0;  ///< x forward [m/s], yaw [rad/s]
};
struct Odometry {
  double stamp = 0;
  std::string frame, childFrame;
  double position[3] = {0, 0, 0}, orientation[4] = {1, 0, 0, 0};
  double linear[3] = {0, 0, 0}, angular[3] = {0, 0, 0};  ///< in the child frame
};
struct JointStates {
  double stamp = 0;
  std::vector<std::string> names;
  std::vector<double> positions, velocities;
};
struct JointTargets {
  std::vector<std::string> names;
  std::vector<double> positions;
};
struct Scan {
  double stamp = 0;
  std::string frame;
  double angleMin = 0, angleIncrement = 0, rangeMin = 0, rangeMax = 0;
  std::vector<float> ranges;
};
struct Imu {
  double stamp = 0;
  std::string frame;
  double orientation[4] = {1, 0, 0, 0};
  double angularVelocity[3] = {0, 0, 0};
};
struct Transform {
  double stamp = 0;
  std::string parent, child;
  double translation[3] = {0, 0, 0}, rotation[4] = {1, 0, 0, 0};
};

enum class Kind { Twist, Odometry, JointStates, JointTargets, Scan, Imu, Tf, Text };

/// One ROS node in this process.
class Node {
 public:
  /// Joins the ROS graph as `name` at $ROS_MASTER_URI; nullptr with `error`
  /// when the master does not answer within `timeout` [s].
  static std::unique_ptr<Node> create(const std::string& name, double timeout, std::string& error);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  /// Publishers, each advertised before use (a subscriber needs a moment to
  /// connect: advertise at start, publish later).
  void advertise(Kind kind, const std::string& topic);
  void publish(const std::string& topic, const Twist& m);
  void publish(const std::string& topic, const Odometry& m);
  void publish(const std::string& topic, const JointStates& m);
  void publish(const std::string& topic, const JointTargets& m);
  void publish(const std::string& topic, const Scan& m);
  void publish(const std::string& topic, const Imu& m);
  void publish(const std::string& topic, const std::vector<Transform>& m);  ///< /tf

  void onTwist(const std::string& topic, std::function<void(const Twist&)> f);
  void onOdometry(const std::string& topic, std::function<void(const Odometry&)> f);
  void onJointStates(const std::string& topic, std::function<void(const JointStates&)> f);
  void onJointTargets(const std::string& topic, std::function<void(const JointTargets&)> f);
  void onScan(const std::string& topic, std::function<void(const Scan&)> f);
  void onImu(const std::string& topic, std::function<void(const Imu&)> f);

  /// ROS time [s] (wall time unless the graph runs a /clock).
  double now() const;
  /// False once ROS shuts down (the master went away, a signal).
  bool ok() const;
  /// Subscribers connected to `topic` (published by this node).
  int subscribers(const std::string& topic) const;

 private:
  Node();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A bag being written (rosbag). Messages go in any order of time.
class BagWriter {
 public:
  /// Opens `path` for writing (a temporary beside it: the bag appears whole
  /// on close() or not at all); nullptr with `error` when it cannot.
  static std::unique_ptr<BagWriter> open(const std::string& path, std::string& error);
  ~BagWriter();  ///< without close(): the temporary is removed
  void write(const std::string& topic, double stamp, const Odometry& m);
  void write(const std::string& topic, double stamp, const JointStates& m);
  void write(const std::string& topic, double stamp, const Scan& m);
  void write(const std::string& topic, double stamp, const std::vector<Transform>& m);
  void write(const std::string& topic, double stamp, const std::string& text);  ///< std_msgs/String
  /// Finishes the bag and moves it into place; false with `error` if not.
  bool close(std::string& error);

 private:
  BagWriter();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sp::ros1
