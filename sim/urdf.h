#pragma once
// A robot as URDF (the ROS robot description), for RViz and other tools:
// links with their inertia as the twin computes it, visual and collision
// geometry, joints with their limits, efforts and damping.
//
// URDF puts a child link's frame at its joint, so each link gets the frame
// (its joint's anchor, its own orientation); the root link keeps its own.
// What URDF cannot say is written in its terms: a capsule is a cylinder and
// two spheres; a universal joint two revolute ones and a ball three, through
// massless links named `<joint>_1`, `<joint>_2`. docs/formats.md ("URDF").

#include <optional>
#include <string>

#include "sim/robot_model.h"

namespace sp {

/// The robot as a URDF document, or nullopt with `error` saying why (a link
/// that is the child of two joints closes a loop; links not joined to the
/// root). A joint to the world (parent -1) hangs off a link named "world".
std::optional<std::string> robotUrdf(const RobotModel& robot, std::string& error);

}  // namespace sp
