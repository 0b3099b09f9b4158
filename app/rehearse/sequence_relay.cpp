#include "app/rehearse/sequence_relay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sp {

const char* toString(SequenceRelay::Phase phase) {
  switch (phase) {
    case SequenceRelay::Phase::Idle: return "idle";
    case SequenceRelay::Phase::Sent: return "sent";
    case SequenceRelay::Phase::Running: return "running";
    case SequenceRelay::Phase::Done: return "done";
    case SequenceRelay::Phase::Aborted: return "aborted";
    case SequenceRelay::Phase::Refused: return "refused";
  }
  return "?";
}

std::optional<net::SequenceMsg> sequenceMessage(const RehearsalPlan& plan, const RehearsalResult& result,
                                                std::string& why) {
  if (!result.passed) {
    why = "only a sequence that passed its rehearsal is sent (" + result.summary() + ")";
    return std::nullopt;
  }
  if (result.fast || plan.fast) {
    // The robot runs at the twin's full fidelity; a coarser twin's pass
    // says where to look, not that it is safe.
    why = "a fast-profile rehearsal is a preview: only a full-fidelity pass is sent";
    return std::nullopt;
  }
  if (plan.commands.empty()) {
    why = "the sequence is empty";
    return std::nullopt;
  }
  const RobotModel& robot = plan.world.robots[0].model;
  const std::string text = sequenceText(plan.commands, &robot);
  net::SequenceMsg m;
  m.hash = sequenceHash(text);
  m.commands = text.substr(0, text.size() - 1);  // lines joined by ';', no trailing one
  std::replace(m.commands.begin(), m.commands.end(), '\n', ';');
  m.start = result.path.front().base;
  m.startPosition = plan.rules.startPosition;
  m.startHeading = degToRad(plan.rules.startHeading);
  return m;
}

std::optional<RehearsalStart> startFromTelemetry(const net::TelemetryMsg& t, const RobotModel& robot,
                                                 std::string& why) {
  RehearsalStart s;
  s.base = t.pose;
  if (t.baseVelocity.size() == 6) {
    s.baseLinear = {t.baseVelocity[0], t.baseVelocity[1], t.baseVelocity[2]};
    s.baseAngular = {t.baseVelocity[3], t.baseVelocity[4], t.baseVelocity[5]};
  }
  s.jointPositions.assign(robot.joints.size(), 0);
  s.jointRates.assign(robot.joints.size(), 0);
  std::vector<bool> seen(robot.joints.size(), false);
  for (size_t i = 0; i < t.jointNames.size() && i < t.jointPositions.size() && i < t.jointVelocities.size(); ++i) {
    const int j = robot.findJoint(t.jointNames[i]);
    if (j < 0) continue;
    s.jointPositions[j] = t.jointPositions[i];
    s.jointRates[j] = t.jointVelocities[i];
    seen[j] = true;
  }
  for (size_t j = 0; j < seen.size(); ++j)
    if (!seen[j] && (robot.joints[j].type == JointType::Hinge || robot.joints[j].type == JointType::Slider)) {
      why = "telemetry does not report joint '" + robot.joints[j].name + "'";
      return std::nullopt;
    }
  for (const net::ObjectPose& o : t.objects) s.objects.emplace_back(o.name, o.pose);
  return s;
}

std::string GuardDeparture::message() const {
  if (!unjudged.empty()) return "telemetry the guard cannot judge: " + unjudged;
  char buf[200];
  const bool metres = what == "position";
  std::snprintf(buf, sizeof buf, "%s %.3g %s from the rehearsal at t = %.2f s (guard %.3g %s)", what.c_str(), value,
                metres ? "m" : "deg", time, limit, metres ? "m" : "deg");
  return buf;
}

void SequenceRelay::relayed(const net::SequenceMsg& message, RehearsalResult result, const FlightRules& rules,
                            const RobotModel& robot) {
  phase_ = Phase::Sent;
  hash_ = message.hash;
  reason_.clear();
  index_ = 0;
  count_ = static_cast<uint64_t>(std::count(message.commands.begin(), message.commands.end(), ';') + 1);
  tripped_ = false;
  result_ = std::move(result);
  rules_ = rules;
  worstPosition_ = worstHeading_ = 0;
  compared_ = 0;
  jointNames_.clear();
  guarded_.clear();
  for (const JointSpec& j : robot.joints) {
    jointNames_.push_back(j.name);
    // Legs and steering: limited hinges below the waist carry the robot;
    // the arms' joints are free to differ (they are not the guard's business).
    const int a = robot.findActuator(j.name);
    guarded_.push_back(a >= 0 && j.type == JointType::Hinge && j.limited &&
                       (j.name.starts_with("hip_") || j.name.starts_with("knee_") ||
                        (robot.drive && robot.joints[robot.drive->articulation].name == j.name)));
  }
}

void SequenceRelay::state(const net::SequenceStateMsg& s) {
  if (s.hash != hash_ || phase_ == Phase::Idle) return;
  index_ = s.index;
  if (s.count > 0) count_ = s.count;
  switch (s.state) {
    case net::SequenceStateKind::Accepted: break;
    case net::SequenceStateKind::Refused:
      phase_ = Phase::Refused;
      reason_ = s.reason;
      break;
    case net::SequenceStateKind::Running:
      phase_ = Phase::Running;
      startTime_ = s.startTime;
      break;
    case net::SequenceStateKind::Done:
      phase_ = Phase::Done;
      startTime_ = s.startTime;
      break;
    case net::SequenceStateKind::Aborted:
      phase_ = Phase::Aborted;
      reason_ = s.reason;
      break;
  }
}

std::optional<GuardDeparture> SequenceRelay::cannotJudge(const std::string& why) {
  // A sequence sent or running is stopped: the robot's own word on where it
  // is cannot be compared with the rehearsal, so the guard cannot vouch for it.
  if (tripped_ || (phase_ != Phase::Sent && phase_ != Phase::Running)) return std::nullopt;
  tripped_ = true;
  GuardDeparture d;
  d.what = "telemetry";
  d.unjudged = why;
  return d;
}

std::optional<GuardDeparture> SequenceRelay::guard(const net::TelemetryMsg& t) {
  if (tripped_ || (phase_ != Phase::Running && phase_ != Phase::Done)) return std::nullopt;
  const double time = t.time - startTime_;
  const std::optional<RehearsalSample> r = result_.at(time);
  if (!r) return std::nullopt;  // before its start or after the rehearsal's end
  ++compared_;
  GuardDeparture d;
  d.time = time;
  d.reported = t.pose;
  d.rehearsed = r->base;
  const double position = std::hypot(t.pose.p.x - r->base.p.x, t.pose.p.y - r->base.p.y);
  const double headingError = radToDeg(std::abs(std::remainder(heading(t.pose.q) - heading(r->base.q), 2 * kPi)));
  worstPosition_ = std::max(worstPosition_, position);
  worstHeading_ = std::max(worstHeading_, headingError);
  auto trip = [&](std::string what, double value, double limit) {
    tripped_ = true;
    d.what = std::move(what);
    d.value = value;
    d.limit = limit;
    return d;
  };
  if (position > rules_.guardPosition) return trip("position", position, rules_.guardPosition);
  if (headingError > rules_.guardHeading) return trip("heading", headingError, rules_.guardHeading);
  for (size_t i = 0; i < t.jointNames.size() && i < t.jointPositions.size(); ++i) {
    const auto it = std::find(jointNames_.begin(), jointNames_.end(), t.jointNames[i]);
    if (it == jointNames_.end()) continue;
    const size_t j = static_cast<size_t>(it - jointNames_.begin());
    if (!guarded_[j] || j >= r->jointPositions.size()) continue;
    const double off = radToDeg(std::abs(t.jointPositions[i] - r->jointPositions[j]));
    if (off > rules_.guardJoint) return trip("joint '" + t.jointNames[i] + "'", off, rules_.guardJoint);
  }
  return std::nullopt;
}

}  // namespace sp
