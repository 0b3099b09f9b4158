#include "sim/kinematics.h"

#include <deque>

namespace sp {

namespace {

/// The joint's motion at position q, in the robot frame at zero pose: the
/// transform that carries the child's zero pose to its moved pose, seen from
/// the parent.
Pose jointMotion(const JointSpec& joint, double q) {
  switch (joint.type) {
    case JointType::Hinge: {
      // Rotation about the axis through the anchor: T(a) R T(-a).
      const Quat r = quatFromAxisAngle(joint.axis, q);
      return Pose{joint.anchor - rotate(r, joint.anchor), r};
    }
    case JointType::Slider:
      return Pose{q * joint.axis, Quat{}};
    case JointType::Universal:
    case JointType::Ball:
    case JointType::Fixed:
      break;
  }
  return Pose{};
}

}  // namespace

std::vector<Pose> linkPoses(const RobotModel& robot, const Pose& base, std::span<const double> jointPositions) {
  const size_t n = robot.links.size();
  std::vector<Pose> poses(n);
  if (n == 0) return poses;
  // With every joint at zero, link i sits at base * inverse(L0) * Li.
  const Pose robotFrame = base * inverse(robot.links[0].pose);
  for (size_t i = 0; i < n; ++i) poses[i] = robotFrame * robot.links[i].pose;

  // Breadth-first from the base, so each parent is placed before its child.
  // A joint's child may be either end; joints are walked parent -> child or
  // child -> parent, whichever side is already placed.
  std::vector<bool> placed(n, false);
  placed[0] = true;
  std::deque<size_t> frontier{0};
  while (!frontier.empty()) {
    const size_t at = frontier.front();
    frontier.pop_front();
    for (size_t j = 0; j < robot.joints.size(); ++j) {
      const JointSpec& joint = robot.joints[j];
      if (joint.parent < 0 || joint.child < 0) continue;
      const auto parent = static_cast<size_t>(joint.parent), child = static_cast<size_t>(joint.child);
      if (parent >= n || child >= n) continue;
      const double q = j < jointPositions.size() ? jointPositions[j] : 0.0;
      const Pose motion = jointMotion(joint, q);
      size_t next;
      if (parent == at && !placed[child]) {
        // child = parent_world * inv(P0) * motion * C0
        poses[child] = poses[parent] * inverse(robot.links[parent].pose) * motion * robot.links[child].pose;
        next = child;
      } else if (child == at && !placed[parent]) {
        poses[parent] = poses[child] * inverse(robot.links[child].pose) * inverse(motion) * robot.links[parent].pose;
        next = parent;
      } else {
        continue;
      }
      placed[next] = true;
      frontier.push_back(next);
    }
  }
  return poses;
}

}  // namespace sp
