// Divergence checks after each step (non-finite state, speeds,
// accelerations, joints pulled apart, penetration) and their reports.

#include "sim/world_impl.h"

#include <cstdio>

namespace sp {
using namespace world_detail;

void World::checkHealth() {
  Impl& m = *impl_;
  const double dt = params_.step;
  auto fail = [&](HealthReport::Kind kind, std::string where, double value, double limit) {
    if (!health_.healthy()) return;  // the first trouble found is the one reported
    health_ = {kind, std::move(where), steps_, time(), value, limit};
  };
  for (size_t b = 0; b < m.allBodies.size(); ++b) {
    const BodyState now = readBody(m.allBodies[b]);
    const BodyState& before = m.previous[b];
    m.previous[b] = now;
    if (!finite(now.position.data(), 3) || !finite(now.quaternion.data(), 4) ||
        !finite(now.linearVelocity.data(), 3) || !finite(now.angularVelocity.data(), 3)) {
      fail(HealthReport::Kind::NotFinite, m.bodyNames[b], 0, 0);
      continue;
    }
    auto length = [](const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
    auto change = [&](const std::array<double, 3>& a, const std::array<double, 3>& c) {
      return std::sqrt((a[0] - c[0]) * (a[0] - c[0]) + (a[1] - c[1]) * (a[1] - c[1]) + (a[2] - c[2]) * (a[2] - c[2])) / dt;
    };
    const double v = length(now.linearVelocity), w = length(now.angularVelocity);
    if (v > params_.maxLinearSpeed) fail(HealthReport::Kind::Speed, m.bodyNames[b], v, params_.maxLinearSpeed);
    if (w > params_.maxAngularSpeed)
      fail(HealthReport::Kind::AngularSpeed, m.bodyNames[b], w, params_.maxAngularSpeed);
    const double a = change(now.linearVelocity, before.linearVelocity);
    if (a > params_.maxLinearAcceleration)
      fail(HealthReport::Kind::Acceleration, m.bodyNames[b], a, params_.maxLinearAcceleration);
    const double alpha = change(now.angularVelocity, before.angularVelocity);
    if (alpha > params_.maxAngularAcceleration)
      fail(HealthReport::Kind::AngularAcceleration, m.bodyNames[b], alpha, params_.maxAngularAcceleration);
  }
  // Joints pulled apart: the anchor as seen from each of the two bodies.
  for (size_t r = 0; r < m.robots.size(); ++r) {
    const RobotModel& robot = robotModel(static_cast<int>(r));
    for (size_t ji = 0; ji < robot.joints.size(); ++ji) {
      dJointID j = m.robots[r].joints[ji];
      dVector3 a1, a2;
      switch (robot.joints[ji].type) {
        case JointType::Hinge: dJointGetHingeAnchor(j, a1); dJointGetHingeAnchor2(j, a2); break;
        case JointType::Universal: dJointGetUniversalAnchor(j, a1); dJointGetUniversalAnchor2(j, a2); break;
        case JointType::Ball: dJointGetBallAnchor(j, a1); dJointGetBallAnchor2(j, a2); break;
        case JointType::Slider:
        case JointType::Fixed: continue;  // no anchor pair to compare
      }
      const double e = std::sqrt((a1[0] - a2[0]) * (a1[0] - a2[0]) + (a1[1] - a2[1]) * (a1[1] - a2[1]) +
                                 (a1[2] - a2[2]) * (a1[2] - a2[2]));
      if (!(e <= params_.maxJointError))
        fail(HealthReport::Kind::JointSeparation, "joint '" + robot.joints[ji].name + "'", e, params_.maxJointError);
    }
  }
  // A terrain edit may leave bodies inside the new ground: that is the
  // operator's doing, and contacts lift them out (at most
  // contact.max_correcting_velocity), so the check waits a second.
  if (m.deepestContact && m.deepest > params_.maxPenetration && steps_ >= m.penetrationCheckFrom) {
    auto name = [&](dGeomID g) -> std::string {
      const auto* info = static_cast<const GeomInfo*>(dGeomGetData(g));
      if (info->robot >= 0) return "link '" + robotModel(info->robot).links[info->link].name + "'";
      if (info->object >= 0) return "object '" + model_.objects[info->object].name + "'";
      return "the ground";
    };
    fail(HealthReport::Kind::Penetration,
         name(m.deepestContact->g2) + " in " + name(m.deepestContact->g1), m.deepest, params_.maxPenetration);
  }
}

std::string HealthReport::message() const {
  if (healthy()) return "healthy";
  char head[96];
  std::snprintf(head, sizeof head, "step %lld (t = %.3f s): ", static_cast<long long>(step), time);
  auto number = [](double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", x);
    return std::string(b);
  };
  std::string what;
  switch (kind) {
    case Kind::Healthy: break;
    case Kind::NotFinite: return std::string(head) + where + " has a non-finite position or velocity (NaN or Inf)";
    case Kind::EngineFailure: return std::string(head) + "the physics engine failed: " + where;
    case Kind::Speed: what = " speed " + number(value) + " m/s exceeds health.max_linear_speed = "; break;
    case Kind::AngularSpeed:
      what = " angular speed " + number(value) + " rad/s exceeds health.max_angular_speed = ";
      break;
    case Kind::Acceleration:
      what = " acceleration " + number(value) + " m/s^2 exceeds health.max_linear_acceleration = ";
      break;
    case Kind::AngularAcceleration:
      what = " angular acceleration " + number(value) + " rad/s^2 exceeds health.max_angular_acceleration = ";
      break;
    case Kind::JointSeparation:
      what = " pulled apart by " + number(value) + " m, more than health.max_joint_error = ";
      break;
    case Kind::Penetration: what = " by " + number(value) + " m, deeper than health.max_penetration = "; break;
  }
  return head + where + what + number(limit);
}

}  // namespace sp
