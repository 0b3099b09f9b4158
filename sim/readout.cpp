#include "sim/readout.h"

#include <variant>

#include "sim/world.h"

namespace sp {

RobotReadout readRobot(const World& world, int robot) {
  RobotReadout r;
  r.step = world.stepCount();
  r.time = world.time();
  r.base = world.linkPose(robot, 0);
  r.baseLinearVelocity = world.linkLinearVelocity(robot, 0);
  r.baseAngularVelocity = world.linkAngularVelocity(robot, 0);
  const RobotModel& model = world.robotModel(robot);
  const int joints = static_cast<int>(model.joints.size());
  r.jointPositions.reserve(model.joints.size());
  r.jointRates.reserve(model.joints.size());
  for (int j = 0; j < joints; ++j) {
    r.jointPositions.push_back(world.jointPosition(robot, j));
    r.jointRates.push_back(world.jointRate(robot, j));
  }
  size_t wheel = 0;
  for (size_t i = 0; i < model.sensors.size(); ++i) {
    const SensorValue& value = world.sensorSample(robot, static_cast<int>(i)).value;
    if (model.sensors[i].type == SensorType::WheelForce && wheel < 4) {
      if (const auto* f = std::get_if<WheelForceReading>(&value)) {
        r.wheelNormal[wheel] = f->normal;
        r.wheelTangential[wheel] = f->tangential;
      }
      ++wheel;
    } else if (model.sensors[i].type == SensorType::Imu && !r.hasImu) {
      r.hasImu = true;
      if (const auto* imu = std::get_if<ImuReading>(&value)) {
        r.roll = imu->roll;
        r.pitch = imu->pitch;
      }
    }
  }
  const std::vector<ObjectSpec>& objects = world.model().objects;
  for (size_t i = 0; i < objects.size(); ++i)
    if (!objects[i].isStatic) r.objects.push_back({objects[i].name, world.objectPose(static_cast<int>(i))});
  if (!world.health().healthy()) r.health = world.health().message();
  return r;
}

}  // namespace sp
