#include "sim/perturbation.h"

#include <cstdio>

#include "sim/random.h"

namespace sp {

namespace {

std::string number(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

}  // namespace

Perturbation drawPerturbation(uint64_t seed, const RobotModel& robot, const PerturbationRanges& r) {
  Random rng(seed);
  const auto around = [&](double range) { return 1 + range * (2 * rng.uniform() - 1); };
  const auto within = [&](double range) { return range * (2 * rng.uniform() - 1); };
  Perturbation p;
  p.seed = seed;
  // A fixed order of draws: the same seed gives the same robot.
  for (double& w : p.wheelRadius) w = around(r.wheelRadius);
  for (size_t i = 0; i < robot.links.size(); ++i) {
    p.linkMass.push_back(around(r.mass));
    p.centreOfMass.push_back({within(r.centreOfMass), within(r.centreOfMass), within(r.centreOfMass)});
  }
  p.friction = around(r.friction);
  p.torqueLimit = around(r.torqueLimit);
  p.velocityGain = around(r.velocityGain);
  p.delay = r.maxDelay * rng.uniform();
  p.rollBias = within(r.imuBias);
  p.pitchBias = within(r.imuBias);
  return p;
}

WorldModel perturbWorld(WorldModel world, const Perturbation& p) {
  if (world.robots.empty()) return world;
  RobotModel& robot = world.robots[0].model;
  for (size_t i = 0; i < robot.links.size() && i < p.linkMass.size(); ++i) {
    robot.links[i].mass *= p.linkMass[i];
    robot.links[i].centreOfMassShift = robot.links[i].centreOfMassShift + p.centreOfMass[i];  // composes
  }
  if (robot.drive)
    for (size_t w = 0; w < 4; ++w) {
      const int joint = robot.drive->wheels[w];
      if (joint < 0) continue;
      // The tyre's effective radius: the wheel link's round geoms.
      for (GeomSpec& g : robot.links[static_cast<size_t>(robot.joints[static_cast<size_t>(joint)].child)].geoms)
        if (g.type == GeomType::Cylinder || g.type == GeomType::Sphere) g.radius *= p.wheelRadius[w];
      for (ActuatorSpec& a : robot.actuators)
        if (a.joint == joint) {
          a.maxTorque *= p.torqueLimit;
          a.velocityScale *= p.velocityGain;
        }
    }
  world.defaultContact.mu *= p.friction;
  for (ContactSpec& c : world.contacts) c.mu *= p.friction;
  return world;
}

WorldModel calibratedWorld(const WorldModel& world, const SimParams& params) {
  if (!params.calibrated() || world.robots.empty()) return world;
  Perturbation p;
  const double front = params.calWheelRadius * (1 + params.calWheelRadiusSplit / 2);
  const double rear = params.calWheelRadius * (1 - params.calWheelRadiusSplit / 2);
  const double left = 1 + params.calWheelRadiusSide / 2, right = 1 - params.calWheelRadiusSide / 2;
  p.wheelRadius = {front * left, front * right, rear * left, rear * right};  // FL FR RL RR
  const size_t links = world.robots[0].model.links.size();
  p.linkMass.assign(links, params.calMass);
  p.centreOfMass.assign(links, Vec3{});
  p.friction = params.calFriction;
  p.velocityGain = params.calMotorGain;
  return perturbWorld(world, p);
}

std::string Perturbation::report(const RobotModel& robot) const {
  std::string out = "seed = " + std::to_string(seed) + "\n";
  static const char* kWheels[] = {"fl", "fr", "rl", "rr"};
  for (size_t w = 0; w < 4; ++w) out += std::string("wheel_radius.") + kWheels[w] + " = " + number(wheelRadius[w]) + "\n";
  for (size_t i = 0; i < robot.links.size() && i < linkMass.size(); ++i) {
    out += "mass." + robot.links[i].name + " = " + number(linkMass[i]) + "\n";
    const Vec3& c = centreOfMass[i];
    out += "centre_of_mass." + robot.links[i].name + " = " + number(c.x) + " " + number(c.y) + " " + number(c.z) + "\n";
  }
  out += "friction = " + number(friction) + "\n";
  out += "wheel_torque_limit = " + number(torqueLimit) + "\n";
  out += "wheel_velocity_gain = " + number(velocityGain) + "\n";
  out += "actuator_delay = " + number(delay) + "\n";
  out += "imu_roll_bias = " + number(rollBias) + "\n";
  out += "imu_pitch_bias = " + number(pitchBias) + "\n";
  return out;
}

}  // namespace sp
