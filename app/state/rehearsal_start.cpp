#include "app/state/rehearsal_start.h"

#include "sim/kinematics.h"

namespace sp {

namespace {

// The position-mode joints hold where the start found them, the wheels
// stand: the robot's controllers at rest. A fresh twin's targets are the
// robot file's initial ones, which a robot that has moved its arms no
// longer holds.
void holdStartPose(World& world) {
  const RobotModel& robot = world.robotModel(0);
  for (size_t a = 0; a < robot.actuators.size(); ++a) {
    const ActuatorSpec& spec = robot.actuators[a];
    const std::string& joint = robot.joints[spec.joint].name;
    if (spec.hasPid && spec.kp > 0 && !spec.continuous)
      world.submit(JointTargetCmd{joint, world.jointPosition(0, spec.joint)});
    else if (spec.mode == JointMode::Velocity)
      world.submit(JointVelocityCmd{joint, 0});
  }
}

}  // namespace

std::string placeRobot(World& world, const RehearsalStart& s, const RigidRobot* held) {
  const RobotModel& robot = world.robotModel(0);
  const std::vector<double> q = held ? rigidJoints(*held, s.jointPositions) : s.jointPositions;
  const std::vector<double> dq = held ? rigidJoints(*held, s.jointRates) : s.jointRates;
  const std::string why =
      world.setRobotMotion(0, linkMotions(robot, s.base, s.baseLinear, s.baseAngular, q, dq), s.objects);
  if (why.empty()) holdStartPose(world);
  return why;
}

}  // namespace sp
