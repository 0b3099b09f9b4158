#pragma once
// What the console's views draw of a robot at one moment, whatever the
// source: live telemetry, a logged session, the predictive ghost. Plain
// values, joints in the model's order; Qt-free.

#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "sim/math.h"
#include "sim/readout.h"

namespace sp {

struct RobotModel;

/// One state of the robot for the views.
struct RobotFrame {
  double time = 0;                     ///< [s] robot time
  Pose base;                           ///< link 0 in the world
  bool hasBaseVelocity = false;        ///< the robot reported its base's twist
  Vec3 baseLinearVelocity, baseAngularVelocity;  ///< world frame [m/s], [rad/s]
  std::vector<double> jointPositions;  ///< model joint order [rad or m]; 0 where unknown
  std::vector<double> jointRates;      ///< model joint order; 0 where unknown
  std::array<double, 4> wheelNormal{};  ///< [N] FL FR RL RR
  /// [N] FL FR RL RR, the contacts' force across the normal; all 0 where
  /// not reported (a log written before 2026-12-02).
  std::array<double, 4> wheelTangential{};
  double roll = 0, pitch = 0;          ///< [rad]
  std::vector<ObjectReadout> objects;  ///< dynamic objects by name
  std::string health;                  ///< "" while healthy
  bool failsafe = false, estop = false;  ///< latches on the robot
};

/// One laser scan for the views.
struct LaserFrame {
  double time = 0;  ///< [s] robot time
  double angleMin = 0, angleStep = 0;  ///< [rad]
  std::vector<double> ranges;          ///< [m]; inf = no return, NaN = invalid
};

/// Puts joint values reported by name into a model's joint order. The names
/// travel in every telemetry frame; they are mapped only when they change.
/// Names the model lacks are ignored; joints not reported read 0. Not
/// thread-safe: one per stream.
class JointNameMap {
 public:
  /// `values[i]` belongs to `names[i]` (extra values or names are ignored).
  std::vector<double> toModelOrder(const std::vector<std::string>& names, const std::vector<double>& values,
                                   const RobotModel& robot);
  /// Forgets the mapping (a new robot model).
  void reset() {
    names_.clear();
    index_.clear();
  }

 private:
  std::vector<std::string> names_;
  std::vector<int> index_;  // names_[i] -> model joint, -1 if none
  const RobotModel* robot_ = nullptr;
};

/// The achieved real-time factor: robot time over wall time across the
/// last second of frames. A robot time that goes back (a new session)
/// starts it over.
class RateMeter {
 public:
  /// A frame with robot time `robotTime` arrived at wall time `wall` [s].
  void add(double wall, double robotTime);
  /// 0 until 0.2 s of wall time has been seen.
  double factor() const { return factor_; }
  void reset() {
    samples_.clear();
    factor_ = 0;
  }

 private:
  std::deque<std::pair<double, double>> samples_;  // (wall, robot time)
  double factor_ = 0;
};

}  // namespace sp
