#pragma once
// Holding joints rigid: a robot whose held joints are welded at given
// positions, each held subtree gathered onto the nearest link above it that
// still moves (one ODE body instead of many: fewer constraint rows per
// step). The gathered body keeps the held links' masses, centres and
// inertias exactly (each geom carries its own share), so the robot's total
// mass and centre of mass are those of the full robot in that pose.
//
// The predictive ghost holds the links the operator is not moving (arms,
// head, torso) to run ahead faster (docs/performance.md, bench_ghost).
//
//   std::string error;
//   auto rigid = holdRigid(robot, positions, {robot.findJoint("waist_yaw"), ...}, error);
//   World built from rigid->model; rigid->jointOf maps its joints back.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "sim/robot_model.h"

namespace sp {

struct RigidRobot {
  RobotModel model;          ///< the robot with the held joints welded
  std::vector<int> jointOf;  ///< model's joint index -> the full robot's
  std::vector<int> linkOf;   ///< model's link index -> the full robot's
  /// The full robot's link -> the model's link it moves with (itself or
  /// the link it was gathered onto).
  std::vector<int> ownerOf;
  /// The full robot's joint positions the held ones are welded at.
  std::vector<double> heldPositions;
};

/// `robot` with the joints `held` (indices) welded at `jointPositions`
/// (one per joint, model order). Joints below held ones may still move (a
/// wheel below a held knee): the rigid robot's zero pose is the full one's
/// with the held joints at their positions, and theirs are carried there.
/// Neither the drive's articulation nor its wheels may be held; otherwise
/// nullopt and `error` says which joint.
std::optional<RigidRobot> holdRigid(const RobotModel& robot, std::span<const double> jointPositions,
                                    const std::vector<int>& held, std::string& error);

/// The full robot's joints from the rigid robot's: held ones at their
/// welded positions (rates 0 for those when `rates`).
std::vector<double> fullJoints(const RigidRobot& rigid, std::span<const double> modelJoints, bool rates = false);
/// The rigid robot's joints taken from the full robot's.
std::vector<double> rigidJoints(const RigidRobot& rigid, std::span<const double> fullJoints);

/// The joints of `robot` at and below the joint named `name` (its subtree),
/// in model order; empty if there is no such joint.
std::vector<int> subtreeJoints(const RobotModel& robot, std::string_view name);

/// The joints whose subtrees hold no joint marked in `moved` (one flag per
/// joint), as whole subtrees, outermost first, sorted: what may be welded
/// while the marked ones move.
std::vector<int> unmovedSubtrees(const RobotModel& robot, const std::vector<bool>& moved);

/// The joints a twin of `robot` may hold rigid for the joint names of
/// `names` (comma-separated, or none: ghost.hold, rehearsal.fast_hold):
/// their subtrees, but the drive's wheels and articulation, which keep
/// turning; sorted. nullopt and `error` ("KEY: ...") for a name the robot
/// lacks or one that drives it.
std::optional<std::vector<int>> holdableJoints(const RobotModel& robot, std::string_view names, std::string_view key,
                                               std::string& error);

}  // namespace sp
