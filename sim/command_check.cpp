#include "sim/command_check.h"

#include <charconv>
#include <algorithm>
#include <cmath>
#include <limits>
#include <system_error>

#include "sim/gait.h"
#include "sim/math.h"
#include "sim/robot_model.h"

namespace sp {
namespace {

/// A number for messages: 6 significant digits, as the model loader prints.
std::string show(double value) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, 6);
  return ec == std::errc() ? std::string(buf, end) : std::string("?");
}

CommandCheck invalid(std::string message) { return {CommandCheck::Kind::Invalid, std::move(message)}; }
CommandCheck outOfLimits(std::string message) { return {CommandCheck::Kind::OutOfLimits, std::move(message)}; }

constexpr const char* kWheelNames[4] = {"front-left", "front-right", "rear-left", "rear-right"};

/// The joint `name` and its actuator, or an error message.
struct Actuated {
  const JointSpec* joint = nullptr;
  const ActuatorSpec* actuator = nullptr;
  std::string error;
};

Actuated findActuated(const RobotModel& robot, const std::string& name) {
  Actuated out;
  const int j = robot.findJoint(name);
  if (j < 0) {
    out.error = "unknown joint '" + name + "'";
    return out;
  }
  const int a = robot.findActuator(name);
  if (a < 0) {
    out.error = "joint '" + name + "' has no actuator";
    return out;
  }
  out.joint = &robot.joints[j];
  out.actuator = &robot.actuators[a];
  return out;
}

std::string needsPid(const std::string& joint) {
  return "joint '" + joint + "': position mode needs PID gains on its actuator";
}

bool angular(const JointSpec& joint) { return joint.type != JointType::Slider; }

/// Value [rad or m] in the file's unit (degrees or metres) for messages.
std::string showInFileUnit(const JointSpec& joint, double value) {
  return show(angular(joint) ? radToDeg(value) : value);
}

/// Checks of one command against the robot; ok() when valid.
struct Checker {
  const RobotModel& robot;

  CommandCheck operator()(const JointTargetCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return invalid(a.error);
    if (!a.actuator->hasPid) return invalid(needsPid(c.joint));
    const JointSpec& j = *a.joint;
    if (j.limited && (c.position < j.lower || c.position > j.upper)) {
      const std::string unit = angular(j) ? " deg" : " m";
      return outOfLimits("target " + showInFileUnit(j, c.position) + unit + " is outside joint '" + j.name + "' limits [" +
             showInFileUnit(j, j.lower) + ", " + showInFileUnit(j, j.upper) + "]" + unit);
    }
    return {};
  }

  CommandCheck operator()(const JointVelocityCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return invalid(a.error);
    if (std::abs(c.velocity) > a.actuator->maxVelocity) {
      const std::string unit = angular(*a.joint) ? " deg/s" : " m/s";
      return outOfLimits("velocity " + showInFileUnit(*a.joint, c.velocity) + unit + " exceeds joint '" + c.joint +
             "' max_velocity " + showInFileUnit(*a.joint, a.actuator->maxVelocity) + unit);
    }
    return {};
  }

  CommandCheck operator()(const JointTorqueCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return invalid(a.error);
    if (std::abs(c.torque) > a.actuator->maxTorque) {
      const std::string unit = angular(*a.joint) ? " N m" : " N";
      return outOfLimits("torque " + show(c.torque) + unit + " exceeds joint '" + c.joint + "' max_torque " +
             show(a.actuator->maxTorque) + unit);
    }
    return {};
  }

  CommandCheck operator()(const JointModeCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return invalid(a.error);
    if (c.mode == JointMode::Position && !a.actuator->hasPid) return invalid(needsPid(c.joint));
    return {};
  }

  CommandCheck operator()(const WheelsCmd& c) const {
    if (CommandCheck e = needDrive(); !e.ok()) return e;
    for (size_t i = 0; i < 4; ++i) {
      const JointSpec& joint = robot.joints[robot.drive->wheels[i]];
      const int a = robot.findActuator(joint.name);
      if (a < 0) return invalid("wheel joint '" + joint.name + "' has no actuator");
      const double max = robot.actuators[a].maxVelocity;
      if (std::abs(c.omega[i]) > max)
        return outOfLimits(std::string(kWheelNames[i]) + " wheel speed " + show(c.omega[i]) + " rad/s exceeds joint '" +
               joint.name + "' max_velocity " + show(max) + " rad/s (" + show(radToDeg(max)) + " deg/s)");
    }
    return {};
  }

  CommandCheck operator()(const DriveCmd& c) const {
    if (CommandCheck e = needDrive(); !e.ok()) return e;
    if (CommandCheck e = speedWithinLimit(c.speed); !e.ok()) return e;
    const JointSpec& j = robot.joints[robot.drive->articulation];
    if (j.limited && (c.articulation < j.lower || c.articulation > j.upper))
      return outOfLimits("articulation " + show(radToDeg(c.articulation)) + " deg is outside joint '" + j.name +
             "' limits [" + show(radToDeg(j.lower)) + ", " + show(radToDeg(j.upper)) + "] deg");
    return {};
  }

  CommandCheck operator()(const StopCmd&) const { return {}; }

  // Whether the patch fits the terrain is the World's to say (it knows the
  // grid); here only its own consistency.
  CommandCheck operator()(const TerrainPatchCmd& c) const {
    if (c.columns <= 0 || c.rows <= 0 ||
        c.heights.size() != static_cast<size_t>(c.columns) * static_cast<size_t>(c.rows))
      return invalid("terrain: the patch's size and its heights disagree");
    for (double h : c.heights)
      if (!std::isfinite(h)) return invalid("terrain: a height is not finite");
    return {};
  }

  CommandCheck operator()(const TurnCmd& c) const {
    if (CommandCheck e = needDrive(); !e.ok()) return e;
    if (CommandCheck e = speedWithinLimit(c.speed); !e.ok()) return e;
    if (!std::isfinite(c.yawRate)) return outOfLimits("yaw rate " + show(radToDeg(c.yawRate)) + " deg/s is not finite");
    return {};
  }

  // The hinge speed a drive may ask for: the slowest wheel motor's top speed
  // on a straight line (in a turn the outer wheels run faster still, and the
  // actuators' own limits hold them).
  CommandCheck speedWithinLimit(double speed) const {
    const double top = driveSpeedLimit(robot);
    if (!(std::abs(speed) <= top))
      return outOfLimits("speed " + show(speed) + " m/s exceeds the drive's " + show(top) +
                         " m/s (wheel max_velocity x wheel radius)");
    return {};
  }

  CommandCheck operator()(const GaitCmd&) const {
    if (CommandCheck e = needDrive(); !e.ok()) return e;
    const auto legs = findLegs(robot);
    if (!legs) return invalid("robot '" + robot.name + "' has no hip-knee-wheel legs for gaits");
    for (const LegJoints& leg : *legs)
      for (int j : {leg.hip, leg.knee}) {
        const int a = robot.findActuator(robot.joints[j].name);
        if (a < 0 || !robot.actuators[a].hasPid) return invalid(needsPid(robot.joints[j].name));
      }
    return {};
  }

  // The robot's <drive>, with joint indices checked so that the checks above
  // cannot index out of range on a hand-built model.
  CommandCheck needDrive() const {
    if (!robot.drive) return invalid("robot '" + robot.name + "' has no <drive>");
    const auto valid = [&](int j) { return j >= 0 && static_cast<size_t>(j) < robot.joints.size(); };
    bool ok = valid(robot.drive->articulation);
    for (int w : robot.drive->wheels) ok = ok && valid(w);
    return ok ? CommandCheck{} : invalid("robot '" + robot.name + "' has a <drive> with unknown joints");
  }
};

}  // namespace

double slowestWheelSpeed(const RobotModel& robot) {
  double top = std::numeric_limits<double>::infinity();
  for (int w : robot.drive->wheels)
    if (const int a = robot.findActuator(robot.joints[w].name); a >= 0)
      top = std::min(top, robot.actuators[a].maxVelocity);
  return top;
}

double driveSpeedLimit(const RobotModel& robot) { return slowestWheelSpeed(robot) * robot.drive->wheelRadius; }

CommandCheck checkCommand(const Command& command, const RobotModel& robot) {
  return std::visit(Checker{robot}, command);
}

}  // namespace sp
