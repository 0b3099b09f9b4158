#pragma once
// Checks a typed command against a robot before it is queued: the joint
// exists and is actuated, the actuator supports the mode, targets and speeds
// lie within the robot's limits, drive commands need the robot's <drive>.
// The robot link answers `out_of_limits` or `invalid` by the kind.

#include <string>

#include "sim/command.h"

namespace sp {

struct RobotModel;

/// The verdict on one command.
struct CommandCheck {
  enum class Kind {
    Ok,
    Invalid,      ///< cannot apply to this robot: unknown joint, no actuator, no <drive>, ...
    OutOfLimits,  ///< a value beyond a joint or actuator limit: refused, never clipped
  };
  Kind kind = Kind::Ok;
  std::string message;  ///< why, without location; "" when ok
  bool ok() const { return kind == Kind::Ok; }
};

/// [rad/s] the slowest wheel motor's max_velocity (infinity without wheel
/// actuators). Needs robot.drive with valid joint indices.
double slowestWheelSpeed(const RobotModel& robot);
/// [m/s] the fastest `drive` or `turn` the robot takes: slowestWheelSpeed()
/// times the wheel radius.
double driveSpeedLimit(const RobotModel& robot);

/// Checks one command (parsed with the same robot) against `robot`. Any thread.
CommandCheck checkCommand(const Command& command, const RobotModel& robot);

}  // namespace sp
