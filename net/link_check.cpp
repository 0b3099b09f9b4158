#include "net/link_check.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "sim/robot_model.h"

namespace sp::net {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string number(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

Refusal refusal(std::string kind, std::string detail) { return {"telemetry: " + std::move(kind), std::move(detail)}; }

// The first of `values` that is not finite, named `what[i]`, or "".
template <typename Values>
std::string notFinite(const char* what, const Values& values) {
  size_t i = 0;
  for (double v : values) {
    if (!std::isfinite(v)) return std::string(what) + "[" + std::to_string(i) + "] = " + number(v);
    ++i;
  }
  return {};
}

}  // namespace

TelemetryBounds telemetryBounds(const RobotModel& robot) {
  TelemetryBounds b;
  for (const JointSpec& j : robot.joints) {
    b.joints.push_back(j.name);
    // Limits bound the joint only where the file limits it; a hinge may
    // turn on (a wheel), its angle accumulating.
    b.lower.push_back(j.limited ? j.lower : -kInf);
    b.upper.push_back(j.limited ? j.upper : kInf);
    const int a = robot.findActuator(j.name);
    b.maxVelocity.push_back(a >= 0 ? robot.actuators[static_cast<size_t>(a)].maxVelocity : 0);
  }
  return b;
}

Refusal TelemetryCheck::check(const TelemetryMsg& m, double wall) {
  Refusal r = judge(m, wall);
  if (!r.kind.empty()) return r;
  have_ = true;
  lastTime_ = m.time;
  lastWall_ = wall;
  lastPosition_ = m.pose.p;
  return {};
}

Refusal TelemetryCheck::judge(const TelemetryMsg& m, double wall) const {
  const TelemetryBounds& b = bounds_;
  // Finite first: every later test compares numbers.
  if (!std::isfinite(m.time)) return refusal("not finite", "time = " + number(m.time));
  const double pose[] = {m.pose.p.x, m.pose.p.y, m.pose.p.z, m.pose.q.w, m.pose.q.x, m.pose.q.y, m.pose.q.z};
  for (const auto& [what, values] : {std::pair<const char*, std::vector<double>>{"pose", {std::begin(pose), std::end(pose)}},
                                     {"base_velocity", m.baseVelocity},
                                     {"joint_positions", m.jointPositions},
                                     {"joint_velocities", m.jointVelocities},
                                     {"wheel_normal", {m.wheelNormal.begin(), m.wheelNormal.end()}},
                                     {"wheel_tangential", {m.wheelTangential.begin(), m.wheelTangential.end()}},
                                     {"roll, pitch", {m.roll, m.pitch}},
                                     {"rtt_ms, heard_ms", {m.rttMs, m.heardMs}}})
    if (std::string bad = notFinite(what, values); !bad.empty()) return refusal("not finite", bad);
  for (const ObjectPose& o : m.objects) {
    const double op[] = {o.pose.p.x, o.pose.p.y, o.pose.p.z, o.pose.q.w, o.pose.q.x, o.pose.q.y, o.pose.q.z};
    if (std::string bad = notFinite(("object " + o.name).c_str(), op); !bad.empty()) return refusal("not finite", bad);
    if (std::abs(o.pose.p.x) > b.extent || std::abs(o.pose.p.y) > b.extent || std::abs(o.pose.p.z) > b.extent)
      return refusal("out of bounds", "object " + o.name + " at more than " + number(b.extent) + " m");
  }

  // Physical bounds.
  const Vec3& p = m.pose.p;
  if (std::abs(p.x) > b.extent || std::abs(p.y) > b.extent || std::abs(p.z) > b.extent)
    return refusal("out of bounds",
                   "pose (" + number(p.x) + ", " + number(p.y) + ", " + number(p.z) + ") m beyond " + number(b.extent) + " m");
  const Quat& q = m.pose.q;
  const double norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (std::abs(norm - 1) > 0.01) return refusal("out of bounds", "pose quaternion of norm " + number(norm) + ", not 1");
  if (m.time < 0) return refusal("out of bounds", "time " + number(m.time) + " s");
  for (size_t i = 0; i < 4; ++i)
    if (std::abs(m.wheelNormal[i]) > b.maxForce || std::abs(m.wheelTangential[i]) > b.maxForce)
      return refusal("out of bounds", "wheel force beyond " + number(b.maxForce) + " N");
  if (m.rttMs < 0 || m.rttMs > b.maxRoundTripMs)
    return refusal("out of bounds", "rtt_ms " + number(m.rttMs) + " (at most " + number(b.maxRoundTripMs) + ")");
  if (m.heardMs < 0 || m.heardMs > b.maxRoundTripMs) return refusal("out of bounds", "heard_ms " + number(m.heardMs));

  // Joints: those of the robot file, each within its limits.
  if (m.jointPositions.size() != m.jointNames.size() || m.jointVelocities.size() != m.jointNames.size())
    return refusal("joints", std::to_string(m.jointNames.size()) + " names, " + std::to_string(m.jointPositions.size()) +
                                 " positions, " + std::to_string(m.jointVelocities.size()) + " velocities");
  if (!b.joints.empty()) {
    std::vector<bool> seen(b.joints.size(), false);
    for (size_t k = 0; k < m.jointNames.size(); ++k) {
      size_t i = 0;
      while (i < b.joints.size() && b.joints[i] != m.jointNames[k]) ++i;
      if (i == b.joints.size()) return refusal("joints", "joint '" + m.jointNames[k] + "' is not in the robot file");
      if (seen[i]) return refusal("joints", "joint '" + m.jointNames[k] + "' reported twice");
      seen[i] = true;
      const double v = m.jointPositions[k];
      const double slack = b.jointSlack;
      if (v < b.lower[i] - slack || v > b.upper[i] + slack)
        return refusal("joint beyond its limits", m.jointNames[k] + " = " + number(v) + " outside [" + number(b.lower[i]) +
                                                      ", " + number(b.upper[i]) + "]");
      // A motor driven past its speed limit by the ground, but not tenfold.
      const double vmax = b.maxVelocity[i] > 0 ? 10 * b.maxVelocity[i] + 10 : 1000;
      if (std::abs(m.jointVelocities[k]) > vmax)
        return refusal("joint beyond its limits",
                       m.jointNames[k] + " moving at " + number(m.jointVelocities[k]) + " (at most " + number(vmax) + ")");
    }
    for (size_t i = 0; i < b.joints.size(); ++i)
      if (!seen[i]) return refusal("joints", "joint '" + b.joints[i] + "' of the robot file is missing");
  }

  // Against the last frame accepted: time runs on, at most so fast, and the
  // robot does not leap.
  if (have_) {
    const double dt = m.time - lastTime_;
    if (dt < 0) return refusal("time went back", number(lastTime_) + " s -> " + number(m.time) + " s");
    const double wallDt = std::max(0.0, wall - lastWall_);
    if (dt > b.maxTimeRate * wallDt + 1)
      return refusal("time jumped",
                     "+" + number(dt) + " s of robot time in " + number(wallDt) + " s (" + number(lastTime_) + " s -> " +
                         number(m.time) + " s)");
    const double dx = p.x - lastPosition_.x, dy = p.y - lastPosition_.y, dz = p.z - lastPosition_.z;
    const double jump = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (jump > b.maxSpeed * dt + 0.5)
      return refusal("pose jumped", number(jump) + " m in " + number(dt) + " s of robot time");
  }
  return {};
}

std::string welcomeProblem(const WelcomeMsg& m) {
  if (!(m.telemetryRate >= kMinTelemetryRate && m.telemetryRate <= kMaxTelemetryRate))
    return "WELCOME telemetry_rate " + number(m.telemetryRate) + " Hz is outside [" + number(kMinTelemetryRate) + ", " +
           number(kMaxTelemetryRate) + "]";
  if (!(m.deadman == 0 || (m.deadman >= kMinDeadman && m.deadman <= kMaxDeadman)))
    return "WELCOME deadman " + number(m.deadman) + " s is outside [" + number(kMinDeadman) + ", " +
           number(kMaxDeadman) + "] (0: none)";
  return {};
}

std::string limitsProblem(const LimitsMsg& m) {
  const size_t n = m.joints.size();
  if (m.lower.size() != n || m.upper.size() != n || m.maxVelocity.size() != n || m.maxTorque.size() != n)
    return "LIMITS lists " + std::to_string(n) + " joints but not one value of each per joint";
  for (size_t i = 0; i < n; ++i) {
    const std::string& j = m.joints[i];
    if (std::isnan(m.lower[i]) || std::isnan(m.upper[i]) || m.lower[i] > m.upper[i])
      return "LIMITS " + j + ": lower " + number(m.lower[i]) + " is not at most upper " + number(m.upper[i]);
    if (!(m.maxVelocity[i] > 0 && m.maxVelocity[i] < 1e4))
      return "LIMITS " + j + ": max velocity " + number(m.maxVelocity[i]) + " is outside (0, 1e4)";
    if (!(m.maxTorque[i] > 0 && m.maxTorque[i] < 1e7))
      return "LIMITS " + j + ": max torque " + number(m.maxTorque[i]) + " is outside (0, 1e7)";
  }
  if (!(m.driveSpeed >= 0 && m.driveSpeed <= 100)) return "LIMITS drive speed " + number(m.driveSpeed) + " m/s is outside [0, 100]";
  if (!(m.wheelSpeed >= 0 && m.wheelSpeed <= 1e4)) return "LIMITS wheel speed " + number(m.wheelSpeed) + " rad/s is outside [0, 1e4]";
  return {};
}

bool RefusalTally::add(const Refusal& r) {
  ++total_;
  const bool first = counts_[r.kind]++ == 0;
  if (!first) {
    Since& s = since_[r.kind];
    ++s.count;
    s.last = r.detail;
  }
  return first;
}

std::vector<std::string> RefusalTally::report() {
  std::vector<std::string> lines;
  for (const auto& [kind, s] : since_)
    if (s.count > 0) lines.push_back(kind + ": " + std::to_string(s.count) + " more (last: " + s.last + ")");
  since_.clear();
  return lines;
}

std::string escapeText(const std::string& text, size_t max) {
  std::string out;
  for (unsigned char c : text) {
    if (out.size() >= max) {
      out += "...";
      break;
    }
    if (c == '\\') {
      out += "\\\\";
    } else if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

}  // namespace sp::net
