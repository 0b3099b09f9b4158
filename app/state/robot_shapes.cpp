#include "app/state/robot_shapes.h"

namespace sp {

net::RobotState stateFromReadout(const RobotReadout& r, const std::vector<std::string>& jointNames) {
  net::RobotState s;
  s.time = r.time;
  s.pose = r.base;
  s.baseLinearVelocity = r.baseLinearVelocity;
  s.baseAngularVelocity = r.baseAngularVelocity;
  s.jointNames = jointNames;
  s.jointPositions = r.jointPositions;
  s.jointVelocities = r.jointRates;
  s.wheelNormal = r.wheelNormal;
  s.wheelTangential = r.wheelTangential;
  s.roll = r.roll;
  s.pitch = r.pitch;
  s.health = r.health;
  for (const ObjectReadout& o : r.objects) s.objects.push_back({o.name, o.pose});
  return s;
}

LogSample sampleFromReadout(const RobotReadout& r) {
  LogSample s;
  s.step = r.step;
  s.time = r.time;
  s.base = {r.base.p.x, r.base.p.y, r.base.p.z};
  s.quat = {r.base.q.w, r.base.q.x, r.base.q.y, r.base.q.z};
  // Positions, then rates, in the model's order.
  s.joints.reserve(r.jointPositions.size() + r.jointRates.size());
  s.joints.insert(s.joints.end(), r.jointPositions.begin(), r.jointPositions.end());
  s.joints.insert(s.joints.end(), r.jointRates.begin(), r.jointRates.end());
  s.wheelNormal = r.wheelNormal;
  s.wheelTangential = r.wheelTangential;
  s.roll = r.roll;
  s.pitch = r.pitch;
  return s;
}

LogSample sampleFromTelemetry(const net::TelemetryMsg& t, int64_t step, const RobotModel& robot, JointNameMap& positions,
                              JointNameMap& rates) {
  LogSample s;
  s.step = step;
  s.time = t.time;
  s.base = {t.pose.p.x, t.pose.p.y, t.pose.p.z};
  s.quat = {t.pose.q.w, t.pose.q.x, t.pose.q.y, t.pose.q.z};
  // Positions, then velocities, in the model's order, as the twin logs them.
  s.joints = positions.toModelOrder(t.jointNames, t.jointPositions, robot);
  const std::vector<double> r = rates.toModelOrder(t.jointNames, t.jointVelocities, robot);
  s.joints.insert(s.joints.end(), r.begin(), r.end());
  s.wheelNormal = t.wheelNormal;
  s.wheelTangential = t.wheelTangential;
  s.roll = t.roll;
  s.pitch = t.pitch;
  return s;
}

RobotFrame frameFromTelemetry(const net::TelemetryMsg& t, const RobotModel* robot, JointNameMap& positions,
                              JointNameMap& rates) {
  RobotFrame f;
  f.time = t.time;
  f.base = t.pose;
  if (t.baseVelocity.size() == 6) {
    f.hasBaseVelocity = true;
    f.baseLinearVelocity = {t.baseVelocity[0], t.baseVelocity[1], t.baseVelocity[2]};
    f.baseAngularVelocity = {t.baseVelocity[3], t.baseVelocity[4], t.baseVelocity[5]};
  }
  f.wheelNormal = t.wheelNormal;
  f.wheelTangential = t.wheelTangential;
  f.roll = t.roll;
  f.pitch = t.pitch;
  f.health = t.health;
  f.failsafe = t.failsafe;
  f.estop = t.estop;
  for (const net::ObjectPose& o : t.objects) f.objects.push_back({o.name, o.pose});
  if (robot) {
    f.jointPositions = positions.toModelOrder(t.jointNames, t.jointPositions, *robot);
    f.jointRates = rates.toModelOrder(t.jointNames, t.jointVelocities, *robot);
  }
  return f;
}

RobotFrame frameFromSample(const LogSample& s, size_t joints) {
  RobotFrame f;
  f.time = s.time;
  f.base = Pose{{s.base[0], s.base[1], s.base[2]}, {s.quat[0], s.quat[1], s.quat[2], s.quat[3]}};
  // Positions then rates; a log of another robot (fewer values) reads 0 beyond.
  f.jointPositions.assign(joints, 0.0);
  f.jointRates.assign(joints, 0.0);
  for (size_t j = 0; j < joints && j < s.joints.size(); ++j) f.jointPositions[j] = s.joints[j];
  for (size_t j = 0; j < joints && joints + j < s.joints.size(); ++j) f.jointRates[j] = s.joints[joints + j];
  f.wheelNormal = s.wheelNormal;
  f.wheelTangential = s.wheelTangential;
  f.roll = s.roll;
  f.pitch = s.pitch;
  return f;
}

RobotFrame frameFromReadout(const RobotReadout& r) {
  RobotFrame f;
  f.time = r.time;
  f.base = r.base;
  f.hasBaseVelocity = true;
  f.baseLinearVelocity = r.baseLinearVelocity;
  f.baseAngularVelocity = r.baseAngularVelocity;
  f.jointPositions = r.jointPositions;
  f.jointRates = r.jointRates;
  f.wheelNormal = r.wheelNormal;
  f.wheelTangential = r.wheelTangential;
  f.roll = r.roll;
  f.pitch = r.pitch;
  f.health = r.health;
  return f;
}

RobotFrame frameFromGhost(const GhostView& v) {
  RobotFrame f;
  f.time = v.time;
  f.base = v.base;
  f.jointPositions = v.jointPositions;
  f.objects = v.objects;
  return f;
}

LaserFrame laserFromMessage(const net::LaserMsg& m) { return {m.time, m.angleMin, m.angleStep, m.ranges}; }

}  // namespace sp
