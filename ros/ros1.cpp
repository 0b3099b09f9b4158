// Built as C++17 (ROS 1's message headers are not C++20); see ros1.h.
#include "ros/ros1.h"

#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>
#include <trajectory_msgs/JointTrajectory.h>

#include <cstdio>
#include <map>
#include <mutex>

namespace sp::ros1 {
namespace {

ros::Time stampOf(double t) { return t > 0 ? ros::Time(t) : ros::Time(0, 1); }  // a bag refuses time 0

void copy3(const double* from, geometry_msgs::Vector3& to) {
  to.x = from[0];
  to.y = from[1];
  to.z = from[2];
}
void copyQ(const double* wxyz, geometry_msgs::Quaternion& q) {
  q.w = wxyz[0];
  q.x = wxyz[1];
  q.y = wxyz[2];
  q.z = wxyz[3];
}

void from3(const geometry_msgs::Vector3& v, double* to) {
  to[0] = v.x;
  to[1] = v.y;
  to[2] = v.z;
}
void fromQ(const geometry_msgs::Quaternion& q, double* wxyz) {
  wxyz[0] = q.w;
  wxyz[1] = q.x;
  wxyz[2] = q.y;
  wxyz[3] = q.z;
}

nav_msgs::Odometry toRos(const Odometry& m) {
  nav_msgs::Odometry o;
  o.header.stamp = stampOf(m.stamp);
  o.header.frame_id = m.frame;
  o.child_frame_id = m.childFrame;
  o.pose.pose.position.x = m.position[0];
  o.pose.pose.position.y = m.position[1];
  o.pose.pose.position.z = m.position[2];
  copyQ(m.orientation, o.pose.pose.orientation);
  copy3(m.linear, o.twist.twist.linear);
  copy3(m.angular, o.twist.twist.angular);
  return o;
}
sensor_msgs::JointState toRos(const JointStates& m) {
  sensor_msgs::JointState j;
  j.header.stamp = stampOf(m.stamp);
  j.name = m.names;
  j.position = m.positions;
  j.velocity = m.velocities;
  return j;
}
sensor_msgs::LaserScan toRos(const Scan& m) {
  sensor_msgs::LaserScan s;
  s.header.stamp = stampOf(m.stamp);
  s.header.frame_id = m.frame;
  s.angle_min = static_cast<float>(m.angleMin);
  s.angle_increment = static_cast<float>(m.angleIncrement);
  s.angle_max = static_cast<float>(m.angleMin + m.angleIncrement * (m.ranges.empty() ? 0.0 : static_cast<double>(m.ranges.size() - 1)));
  s.range_min = static_cast<float>(m.rangeMin);
  s.range_max = static_cast<float>(m.rangeMax);
  s.ranges = m.ranges;
  return s;
}
tf2_msgs::TFMessage toRos(const std::vector<Transform>& m) {
  tf2_msgs::TFMessage tf;
  for (const Transform& t : m) {
    geometry_msgs::TransformStamped s;
    s.header.stamp = stampOf(t.stamp);
    s.header.frame_id = t.parent;
    s.child_frame_id = t.child;
    copy3(t.translation, s.transform.translation);
    copyQ(t.rotation, s.transform.rotation);
    tf.transforms.push_back(s);
  }
  return tf;
}

/// Subscriptions ask for TCP_NODELAY: without it a small message such as a
/// Twist waits on Nagle's algorithm (measured: 15 ms instead of 0.3 ms).
ros::TransportHints noDelay() { return ros::TransportHints().tcpNoDelay(); }

}  // namespace

struct Node::Impl {
  std::unique_ptr<ros::NodeHandle> handle;
  std::unique_ptr<ros::AsyncSpinner> spinner;
  std::map<std::string, ros::Publisher> publishers;
  std::vector<ros::Subscriber> subscribers;
  mutable std::mutex mutex;  // publishers' map (advertise vs publish)

  template <typename Msg>
  void send(const std::string& topic, const Msg& msg) {
    std::lock_guard<std::mutex> lock(mutex);
    auto p = publishers.find(topic);
    if (p != publishers.end()) p->second.publish(msg);
  }
};

Node::Node() : impl_(std::make_unique<Impl>()) {}

std::unique_ptr<Node> Node::create(const std::string& name, double timeout, std::string& error) {
  int argc = 0;
  ros::init(argc, nullptr, name, ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
  if (!ros::master::check()) {
    // roscpp waits for the master by itself; say where it looked instead of hanging.
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(timeout);
    while (!ros::master::check() && ros::WallTime::now() < until) ros::WallDuration(0.1).sleep();
    if (!ros::master::check()) {
      error = "no ROS master at " + ros::master::getURI() + " (ROS_MASTER_URI; is roscore running?)";
      return nullptr;
    }
  }
  std::unique_ptr<Node> node(new Node());
  node->impl_->handle = std::make_unique<ros::NodeHandle>();
  node->impl_->spinner = std::make_unique<ros::AsyncSpinner>(1);
  node->impl_->spinner->start();
  return node;
}

Node::~Node() {
  impl_->spinner->stop();
  impl_->subscribers.clear();
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->publishers.clear();
  }
  impl_->handle.reset();
  ros::shutdown();
}

void Node::advertise(Kind kind, const std::string& topic) {
  ros::NodeHandle& h = *impl_->handle;
  ros::Publisher p;
  switch (kind) {
    case Kind::Twist: p = h.advertise<geometry_msgs::Twist>(topic, 10); break;
    case Kind::Odometry: p = h.advertise<nav_msgs::Odometry>(topic, 10); break;
    case Kind::JointStates: p = h.advertise<sensor_msgs::JointState>(topic, 10); break;
    case Kind::JointTargets: p = h.advertise<trajectory_msgs::JointTrajectory>(topic, 10); break;
    case Kind::Scan: p = h.advertise<sensor_msgs::LaserScan>(topic, 5); break;
    case Kind::Imu: p = h.advertise<sensor_msgs::Imu>(topic, 10); break;
    case Kind::Tf: p = h.advertise<tf2_msgs::TFMessage>(topic, 10); break;
    case Kind::Text: p = h.advertise<std_msgs::String>(topic, 10); break;
  }
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->publishers[topic] = p;
}

void Node::publish(const std::string& topic, const Twist& m) {
  geometry_msgs::Twist t;
  t.linear.x = m.linear;
  t.angular.z = m.angular;
  impl_->send(topic, t);
}
void Node::publish(const std::string& topic, const Odometry& m) { impl_->send(topic, toRos(m)); }
void Node::publish(const std::string& topic, const JointStates& m) { impl_->send(topic, toRos(m)); }
void Node::publish(const std::string& topic, const JointTargets& m) {
  trajectory_msgs::JointTrajectory t;
  t.header.stamp = ros::Time::now();
  t.joint_names = m.names;
  trajectory_msgs::JointTrajectoryPoint point;
  point.positions = m.positions;
  point.time_from_start = ros::Duration(0);  // as soon as the controller can
  t.points.push_back(point);
  impl_->send(topic, t);
}
void Node::publish(const std::string& topic, const Scan& m) { impl_->send(topic, toRos(m)); }
void Node::publish(const std::string& topic, const Imu& m) {
  sensor_msgs::Imu i;
  i.header.stamp = stampOf(m.stamp);
  i.header.frame_id = m.frame;
  copyQ(m.orientation, i.orientation);
  copy3(m.angularVelocity, i.angular_velocity);
  i.linear_acceleration_covariance[0] = -1;  // no estimate of it (sensor_msgs/Imu's convention)
  impl_->send(topic, i);
}
void Node::publish(const std::string& topic, const std::vector<Transform>& m) { impl_->send(topic, toRos(m)); }

void Node::onTwist(const std::string& topic, std::function<void(const Twist&)> f) {
  impl_->subscribers.push_back(impl_->handle->subscribe<geometry_msgs::Twist>(
      topic, 10, [f](const geometry_msgs::Twist::ConstPtr& t) { f(Twist{t->linear.x, t->angular.z}); }, ros::VoidConstPtr(), noDelay()));
}
void Node::onOdometry(const std::string& topic, std::function<void(const Odometry&)> f) {
  impl_->subscribers.push_back(impl_->handle->subscribe<nav_msgs::Odometry>(topic, 10, [f](const nav_msgs::Odometry::ConstPtr& o) {
    Odometry m;
    m.stamp = o->header.stamp.toSec();
    m.frame = o->header.frame_id;
    m.childFrame = o->child_frame_id;
    const auto& p = o->pose.pose;
    m.position[0] = p.position.x;
    m.position[1] = p.position.y;
    m.position[2] = p.position.z;
    fromQ(p.orientation, m.orientation);
    from3(o->twist.twist.linear, m.linear);
    from3(o->twist.twist.angular, m.angular);
    f(m);
  }, ros::VoidConstPtr(), noDelay()));
}
void Node::onJointStates(const std::string& topic, std::function<void(const JointStates&)> f) {
  impl_->subscribers.push_back(impl_->handle->subscribe<sensor_msgs::JointState>(
      topic, 10, [f](const sensor_msgs::JointState::ConstPtr& j) {
        f(JointStates{j->header.stamp.toSec(), j->name, j->position, j->velocity});
      }, ros::VoidConstPtr(), noDelay()));
}
void Node::onJointTargets(const std::string& topic, std::function<void(const JointTargets&)> f) {
  impl_->subscribers.push_back(impl_->handle->subscribe<trajectory_msgs::JointTrajectory>(
      topic, 10, [f](const trajectory_msgs::JointTrajectory::ConstPtr& t) {
        if (t->points.empty()) return;
        f(JointTargets{t->joint_names, t->points.back().positions});  // where the trajectory ends
      }, ros::VoidConstPtr(), noDelay()));
}
void Node::onScan(const std::string& topic, std::function<void(const Scan&)> f) {
  impl_->subscribers.push_back(impl_->handle->subscribe<sensor_msgs::LaserScan>(
      topic, 5, [f](const sensor_msgs::LaserScan::ConstPtr& s) {
        f(Scan{s->header.stamp.toSec(), s->header.frame_id, s->angle_min, s->angle_increment, s->range_min,
               s->range_max, s->ranges});
      }, ros::VoidConstPtr(), noDelay()));
}
void Node::onImu(const std::string& topic, std::function<void(const Imu&)> f) {
  impl_->subscribers.push_back(impl_->handle->subscribe<sensor_msgs::Imu>(topic, 10, [f](const sensor_msgs::Imu::ConstPtr& i) {
    Imu m;
    m.stamp = i->header.stamp.toSec();
    m.frame = i->header.frame_id;
    fromQ(i->orientation, m.orientation);
    from3(i->angular_velocity, m.angularVelocity);
    f(m);
  }, ros::VoidConstPtr(), noDelay()));
}

double Node::now() const { return ros::Time::now().toSec(); }
bool Node::ok() const { return ros::ok(); }
int Node::subscribers(const std::string& topic) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  auto p = impl_->publishers.find(topic);
  return p == impl_->publishers.end() ? 0 : static_cast<int>(p->second.getNumSubscribers());
}

struct BagWriter::Impl {
  rosbag::Bag bag;
  std::string path, temporary;
  bool open = false;
};

BagWriter::BagWriter() : impl_(std::make_unique<Impl>()) {}

BagWriter::~BagWriter() {
  if (impl_->open) {
    try {
      impl_->bag.close();
    } catch (const std::exception&) {
    }
    std::remove(impl_->temporary.c_str());
  }
}

std::unique_ptr<BagWriter> BagWriter::open(const std::string& path, std::string& error) {
  std::unique_ptr<BagWriter> w(new BagWriter());
  w->impl_->path = path;
  w->impl_->temporary = path + ".writing";
  try {
    w->impl_->bag.open(w->impl_->temporary, rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    error = path + ": error: cannot write the bag: " + e.what();
    return nullptr;
  }
  w->impl_->open = true;
  return w;
}

void BagWriter::write(const std::string& topic, double stamp, const Odometry& m) { impl_->bag.write(topic, stampOf(stamp), toRos(m)); }
void BagWriter::write(const std::string& topic, double stamp, const JointStates& m) { impl_->bag.write(topic, stampOf(stamp), toRos(m)); }
void BagWriter::write(const std::string& topic, double stamp, const Scan& m) { impl_->bag.write(topic, stampOf(stamp), toRos(m)); }
void BagWriter::write(const std::string& topic, double stamp, const std::vector<Transform>& m) {
  impl_->bag.write(topic, stampOf(stamp), toRos(m));
}
void BagWriter::write(const std::string& topic, double stamp, const std::string& text) {
  std_msgs::String s;
  s.data = text;
  impl_->bag.write(topic, stampOf(stamp), s);
}

bool BagWriter::close(std::string& error) {
  try {
    impl_->bag.close();
  } catch (const std::exception& e) {
    error = impl_->path + ": error: cannot write the bag: " + e.what();
    return false;
  }
  impl_->open = false;
  if (std::rename(impl_->temporary.c_str(), impl_->path.c_str()) != 0) {
    std::remove(impl_->temporary.c_str());
    error = impl_->path + ": error: cannot move the bag into place";
    return false;
  }
  return true;
}

}  // namespace sp::ros1
