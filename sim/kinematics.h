#pragma once
// Forward kinematics of a robot model: where each link is, given where the
// base link is and every joint's position. The console draws the robot as
// telemetry reports it (base pose + joint positions) with this, without a
// physics world of its own.

#include <span>
#include <vector>

#include "sim/math.h"
#include "sim/robot_model.h"

namespace sp {

/// World poses of every link of `robot` (robot.links order). `base` is link
/// 0's pose in the world; `jointPositions` holds one value per joint in
/// robot.joints order ([rad] for hinges, [m] for sliders; universal, ball and
/// fixed joints are drawn at zero). Missing values count as zero. Links not
/// reachable from link 0 through joints keep their zero-pose place relative
/// to the base. Uses the same sign conventions as World::jointPosition.
std::vector<Pose> linkPoses(const RobotModel& robot, const Pose& base, std::span<const double> jointPositions);

/// Where a link is and how it moves, in the world: its frame's pose and the
/// linear velocity of its origin and its angular velocity.
struct LinkMotion {
  Pose pose;
  Vec3 linear;   ///< [m/s] of the link frame's origin
  Vec3 angular;  ///< [rad/s]
};

/// linkPoses() plus velocity propagation: every link's motion from the
/// base's pose and twist (of link 0's origin, world frame) and every joint's
/// position and rate (robot.joints order; missing values count as zero).
/// What a robot reports (telemetry) is enough to rebuild its whole state.
std::vector<LinkMotion> linkMotions(const RobotModel& robot, const Pose& base, Vec3 baseLinear, Vec3 baseAngular,
                                    std::span<const double> jointPositions, std::span<const double> jointRates);

/// A wheel's rolling: its spin about its axle and its hub's velocity across
/// the axle, from the wheel link's motion (world frame). It rolls without
/// slip when |spin| x radius = |across|.
struct WheelRolling {
  double spin = 0;  ///< about the axle, the joint's axis in the world [rad/s]
  Vec3 axle;        ///< unit, world frame
  Vec3 across;      ///< the hub's velocity less its part along the axle [m/s]
};
/// `joint` is the wheel's joint (robot.joints), `wheel` its child link's motion.
WheelRolling wheelRolling(const RobotModel& robot, const JointSpec& joint, const LinkMotion& wheel);

}  // namespace sp
