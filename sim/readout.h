#pragma once
// One read-out of a robot's state from a World: a plain value, taken between
// steps, that telemetry, the session log, validation and the console's views
// all use, so that they agree on what "the robot's state" is.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/math.h"

namespace sp {

class World;

/// A world object's name and where it is (its frame, not its centre of mass).
struct ObjectReadout {
  std::string name;
  Pose pose;
  friend bool operator==(const ObjectReadout&, const ObjectReadout&) = default;
};

/// The state of one robot at a step boundary. Plain data; any thread.
struct RobotReadout {
  int64_t step = 0;
  double time = 0;                 ///< [s]
  Pose base;                       ///< link 0's frame in the world
  Vec3 baseLinearVelocity;         ///< of link 0's origin, world frame [m/s]
  Vec3 baseAngularVelocity;        ///< world frame [rad/s]
  std::vector<double> jointPositions;  ///< model joint order [rad or m]; 0 for ball/fixed
  std::vector<double> jointRates;      ///< [rad/s or m/s]
  /// The first four wheel_force sensors in model order (FL, FR, RL, RR in
  /// the shipped robot): their latest mean normal and tangential force [N];
  /// 0 for a wheel without a sensor or before its first sample.
  std::array<double, 4> wheelNormal{}, wheelTangential{};
  /// Roll and pitch [rad] of the robot's first IMU; 0 without one.
  double roll = 0, pitch = 0;
  bool hasImu = false;
  /// The world's dynamic objects, in model order (static ones never move).
  std::vector<ObjectReadout> objects;
  std::string health;  ///< "" while healthy, else HealthReport::message()
  friend bool operator==(const RobotReadout&, const RobotReadout&) = default;
};

/// Reads robot `robot` of `world` now. Thread: the World's owner, between steps.
RobotReadout readRobot(const World& world, int robot = 0);

}  // namespace sp
