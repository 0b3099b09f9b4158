#pragma once
// The twin's typed command API. Commands are plain values: the GUI, the robot
// link, sequence files and gaits queue them, and the physics thread applies
// them at step boundaries. Units: SI, angles in radians.

#include <array>
#include <string>
#include <variant>
#include <vector>

#include "sim/joint_mode.h"

namespace sp {

/// Joint velocity [rad/s or m/s]; switches the joint to Velocity mode.
struct JointVelocityCmd {
  std::string joint;
  double velocity = 0;
  friend bool operator==(const JointVelocityCmd&, const JointVelocityCmd&) = default;
};
/// Joint target [rad or m]; switches the joint to Position mode.
struct JointTargetCmd {
  std::string joint;
  double position = 0;
  friend bool operator==(const JointTargetCmd&, const JointTargetCmd&) = default;
};
/// Joint torque [N m or N]; switches the joint to Torque mode.
struct JointTorqueCmd {
  std::string joint;
  double torque = 0;
  friend bool operator==(const JointTorqueCmd&, const JointTorqueCmd&) = default;
};
/// Switches a joint's mode, keeping its current set-point for that mode.
struct JointModeCmd {
  std::string joint;
  JointMode mode = JointMode::Free;
  friend bool operator==(const JointModeCmd&, const JointModeCmd&) = default;
};
/// Wheel angular velocities [rad/s], front-left, front-right, rear-left, rear-right.
struct WheelsCmd {
  std::array<double, 4> omega{};
  friend bool operator==(const WheelsCmd&, const WheelsCmd&) = default;
};
/// Drive at `speed` [m/s] (at the articulation hinge) with the articulation
/// hinge at `articulation` [rad]; wheel speeds follow articulated-steering
/// kinematics so that the tyres do not fight each other.
struct DriveCmd {
  double speed = 0;
  double articulation = 0;
  friend bool operator==(const DriveCmd&, const DriveCmd&) = default;
};
/// Leg gaits (sim/gait.h). Off returns the legs to the stance pose with the
/// wheels braked.
enum class Gait { Off, Caterpillar, Rolking };
const char* toString(Gait gait);

/// Starts a gait (or stops one with Gait::Off); a drive, wheels, stop or
/// leg joint command ends it.
struct GaitCmd {
  Gait gait = Gait::Off;
  friend bool operator==(const GaitCmd&, const GaitCmd&) = default;
};

/// Drive at `speed` [m/s] turning at `yawRate` [rad/s] (> 0 turns left):
/// the articulation angle that gives this turn with the current leg
/// geometry is recomputed every step; wheel speeds as for DriveCmd.
struct TurnCmd {
  double speed = 0;
  double yawRate = 0;
  friend bool operator==(const TurnCmd&, const TurnCmd&) = default;
};

/// Every actuated joint to zero velocity (wheels) or to hold its angle.
struct StopCmd {
  friend bool operator==(const StopCmd&, const StopCmd&) = default;
};

/// A terrain edit: new heights [m] for a rectangle of the heightfield's
/// samples, `columns` x `rows` of them from sample (column, row) (grid axes
/// as in sim/height_grid.h), row by row. Applied at a step boundary like
/// every command, so it is logged, re-simulated and part of snapshots.
/// A world command: the robot it is submitted for does not matter.
struct TerrainPatchCmd {
  int column = 0, row = 0;
  int columns = 0, rows = 0;
  std::vector<double> heights;  ///< rows x columns, index r * columns + c
  friend bool operator==(const TerrainPatchCmd&, const TerrainPatchCmd&) = default;
};

using Command = std::variant<JointVelocityCmd, JointTargetCmd, JointTorqueCmd, JointModeCmd,
                             WheelsCmd, DriveCmd, StopCmd, GaitCmd, TurnCmd, TerrainPatchCmd>;

/// A command with the sim time [s] at which it applies.
struct TimedCommand {
  double time = 0;
  Command command;
  int line = 0;  ///< source line in a sequence file, 0 if none
};

struct RobotModel;

/// The command in sequence-file syntax, e.g. `drive 0.5 10`: angles in
/// degrees; `target` and `velocity` values in metres for the slider joints
/// of `robot` (without a robot every joint is written as a hinge). It reads
/// back with parseCommand given the same robot.
std::string toText(const Command& command, const RobotModel* robot = nullptr);

}  // namespace sp
