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

/// Walks the joint tree breadth-first from link 0 and calls
/// visit(joint, from, to, sign) once per link reached, `from` already placed,
/// `sign` +1 when the walk goes parent -> child and -1 the other way (a
/// joint's child may be either end). Returns which links were reached.
template <class Visit>
std::vector<bool> walkFromBase(const RobotModel& robot, size_t n, Visit visit) {
  std::vector<bool> placed(n, false);
  if (n == 0) return placed;
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
      size_t next;
      double sign;
      if (parent == at && !placed[child]) {
        next = child;
        sign = 1;
      } else if (child == at && !placed[parent]) {
        next = parent;
        sign = -1;
      } else {
        continue;
      }
      visit(j, at, next, sign);
      placed[next] = true;
      frontier.push_back(next);
    }
  }
  return placed;
}

}  // namespace

std::vector<LinkMotion> linkMotions(const RobotModel& robot, const Pose& base, Vec3 baseLinear, Vec3 baseAngular,
                                    std::span<const double> jointPositions, std::span<const double> jointRates) {
  const std::vector<Pose> poses = linkPoses(robot, base, jointPositions);
  const size_t n = poses.size();
  std::vector<LinkMotion> out(n);
  for (size_t i = 0; i < n; ++i) out[i].pose = poses[i];
  if (n == 0) return out;
  out[0].linear = baseLinear;
  out[0].angular = baseAngular;
  // The same walk as linkPoses(): each link's twist from the placed one's
  // through the joint between them. A joint's axis and anchor are given in
  // the robot frame at zero pose; a link's world pose times the inverse of
  // its zero pose carries them into the world.
  const auto toWorld = [&](size_t link, Vec3 p) { return transformPoint(poses[link] * inverse(robot.links[link].pose), p); };
  const auto axisWorld = [&](size_t link, Vec3 a) {
    return rotate(poses[link].q * conjugate(robot.links[link].pose.q), a);
  };
  const std::vector<bool> placed = walkFromBase(robot, n, [&](size_t j, size_t at, size_t next, double sign) {
    const JointSpec& joint = robot.joints[j];
    const double rate = j < jointRates.size() ? jointRates[j] : 0.0;
    const Vec3 a = axisWorld(at, joint.axis);
    const Vec3 from = poses[at].p, to = poses[next].p;
    const LinkMotion& m = out[at];
    // The next link's origin moves with the placed link, plus the joint
    // (sign: the child moves by +rate relative to the parent).
    Vec3 linear = m.linear + cross(m.angular, to - from);
    Vec3 angular = m.angular;
    if (joint.type == JointType::Hinge) {
      const Vec3 anchor = toWorld(at, joint.anchor);
      angular = angular + (sign * rate) * a;
      linear = linear + cross((sign * rate) * a, to - anchor);
    } else if (joint.type == JointType::Slider) {
      linear = linear + (sign * rate) * a;
    }
    out[next].linear = linear;
    out[next].angular = angular;
  });
  // Links not reached move rigidly with the base.
  for (size_t i = 1; i < n; ++i)
    if (!placed[i]) {
      out[i].angular = baseAngular;
      out[i].linear = baseLinear + cross(baseAngular, poses[i].p - poses[0].p);
    }
  return out;
}

std::vector<Pose> linkPoses(const RobotModel& robot, const Pose& base, std::span<const double> jointPositions) {
  const size_t n = robot.links.size();
  std::vector<Pose> poses(n);
  if (n == 0) return poses;
  // With every joint at zero, link i sits at base * inverse(L0) * Li.
  const Pose robotFrame = base * inverse(robot.links[0].pose);
  for (size_t i = 0; i < n; ++i) poses[i] = robotFrame * robot.links[i].pose;

  // Breadth-first from the base, so each placed link places the next.
  walkFromBase(robot, n, [&](size_t j, size_t at, size_t next, double sign) {
    const JointSpec& joint = robot.joints[j];
    const double q = j < jointPositions.size() ? jointPositions[j] : 0.0;
    const Pose motion = jointMotion(joint, q);
    // child = parent_world * inv(P0) * motion * C0, and the other way round.
    poses[next] = sign > 0 ? poses[at] * inverse(robot.links[at].pose) * motion * robot.links[next].pose
                           : poses[at] * inverse(robot.links[at].pose) * inverse(motion) * robot.links[next].pose;
  });
  return poses;
}

WheelRolling wheelRolling(const RobotModel& robot, const JointSpec& joint, const LinkMotion& wheel) {
  const Pose& zero = robot.links[static_cast<size_t>(joint.child)].pose;
  const Pose& at = wheel.pose;
  const Vec3 hub = transformPoint(at * inverse(zero), joint.anchor);
  WheelRolling r;
  r.axle = normalized(rotate(at.q * conjugate(zero.q), joint.axis));
  const Vec3 v = wheel.linear + cross(wheel.angular, hub - at.p);
  r.spin = dot(wheel.angular, r.axle);
  r.across = v - dot(v, r.axle) * r.axle;
  return r;
}

}  // namespace sp
