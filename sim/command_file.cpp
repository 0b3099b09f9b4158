#include "sim/command_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <system_error>

#include "sim/math.h"
#include "sim/gait.h"
#include "sim/robot_model.h"
#include "sim/text.h"

// Units in sequence files: `target` and `velocity` take degrees and deg/s on
// hinge joints and metres and m/s on slider joints, so parsing needs the
// robot to know which is which (without one, every joint reads as a hinge);
// drive articulation in degrees, drive speed in m/s, wheel speeds in rad/s
// (as customary for wheels), torques in N m (forces in N on sliders).

namespace sp {
namespace {

/// A number for messages: 6 significant digits, as the model loader prints.
std::string show(double value) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, 6);
  return ec == std::errc() ? std::string(buf, end) : std::string("?");
}

/// Arguments of one command; number() records the first bad one.
struct ArgReader {
  std::string_view command;
  std::vector<std::string_view> args;
  std::string error;
  const RobotModel* robot = nullptr;

  /// Argument `v` as a value of the joint named by argument `j`: degrees
  /// converted to radians, unless the robot says the joint is a slider.
  double jointValue(size_t j, size_t v) {
    const double x = number(v);
    const int joint = robot ? robot->findJoint(args[j]) : -1;
    if (joint >= 0 && robot->joints[joint].type == JointType::Slider) return x;
    return degToRad(x);
  }

  double number(size_t i) {
    const std::optional<double> v = parseReal(args[i]);
    if (!v && error.empty()) error = std::string(command) + ": bad number '" + std::string(args[i]) + "'";
    return v.value_or(0);
  }
  std::string word(size_t i) const { return std::string(args[i]); }
  Gait gait(size_t i) {
    for (Gait g : {Gait::Off, Gait::Caterpillar, Gait::Rolking})
      if (args[i] == toString(g)) return g;
    if (error.empty())
      error = std::string(command) + ": unknown gait '" + std::string(args[i]) + "' (expected off, caterpillar or rolking)";
    return Gait::Off;
  }
  JointMode mode(size_t i) {
    for (JointMode m : {JointMode::Velocity, JointMode::Position, JointMode::Torque, JointMode::Free})
      if (args[i] == toString(m)) return m;
    if (error.empty())
      error = std::string(command) + ": unknown mode '" + std::string(args[i]) +
              "' (expected velocity, position, torque or free)";
    return JointMode::Free;
  }
};

/// One command of the file syntax: its name, arguments and how to build it.
struct Syntax {
  std::string_view name;
  size_t arity;
  std::string_view help;  // the arguments, for the arity message
  Command (*build)(ArgReader& a);
};

// Braced initializers evaluate left to right, so the first bad argument is
// the one reported.
const Syntax kSyntax[] = {
    {"drive", 2, "speed m/s, articulation deg",
     [](ArgReader& a) -> Command { return DriveCmd{a.number(0), degToRad(a.number(1))}; }},
    {"wheels", 4, "front-left, front-right, rear-left, rear-right rad/s",
     [](ArgReader& a) -> Command { return WheelsCmd{{a.number(0), a.number(1), a.number(2), a.number(3)}}; }},
    {"target", 2, "joint, angle deg or position m",
     [](ArgReader& a) -> Command { return JointTargetCmd{a.word(0), a.jointValue(0, 1)}; }},
    {"velocity", 2, "joint, velocity deg/s or m/s",
     [](ArgReader& a) -> Command { return JointVelocityCmd{a.word(0), a.jointValue(0, 1)}; }},
    {"torque", 2, "joint, torque N m",
     [](ArgReader& a) -> Command { return JointTorqueCmd{a.word(0), a.number(1)}; }},
    {"mode", 2, "joint, velocity|position|torque|free",
     [](ArgReader& a) -> Command { return JointModeCmd{a.word(0), a.mode(1)}; }},
    {"stop", 0, "", [](ArgReader&) -> Command { return StopCmd{}; }},
    {"turn", 2, "speed m/s, yaw rate deg/s",
     [](ArgReader& a) -> Command { return TurnCmd{a.number(0), degToRad(a.number(1))}; }},
    {"gait", 1, "off|caterpillar|rolking", [](ArgReader& a) -> Command { return GaitCmd{a.gait(0)}; }},
};

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

/// Checks of one command against the robot; "" when valid.
struct Checker {
  const RobotModel& robot;

  std::string operator()(const JointTargetCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return a.error;
    if (!a.actuator->hasPid) return needsPid(c.joint);
    const JointSpec& j = *a.joint;
    if (j.limited && (c.position < j.lower || c.position > j.upper)) {
      const std::string unit = angular(j) ? " deg" : " m";
      return "target " + showInFileUnit(j, c.position) + unit + " is outside joint '" + j.name + "' limits [" +
             showInFileUnit(j, j.lower) + ", " + showInFileUnit(j, j.upper) + "]" + unit;
    }
    return {};
  }

  std::string operator()(const JointVelocityCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return a.error;
    if (std::abs(c.velocity) > a.actuator->maxVelocity) {
      const std::string unit = angular(*a.joint) ? " deg/s" : " m/s";
      return "velocity " + showInFileUnit(*a.joint, c.velocity) + unit + " exceeds joint '" + c.joint +
             "' max_velocity " + showInFileUnit(*a.joint, a.actuator->maxVelocity) + unit;
    }
    return {};
  }

  std::string operator()(const JointTorqueCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return a.error;
    if (std::abs(c.torque) > a.actuator->maxTorque) {
      const std::string unit = angular(*a.joint) ? " N m" : " N";
      return "torque " + show(c.torque) + unit + " exceeds joint '" + c.joint + "' max_torque " +
             show(a.actuator->maxTorque) + unit;
    }
    return {};
  }

  std::string operator()(const JointModeCmd& c) const {
    const Actuated a = findActuated(robot, c.joint);
    if (!a.error.empty()) return a.error;
    if (c.mode == JointMode::Position && !a.actuator->hasPid) return needsPid(c.joint);
    return {};
  }

  std::string operator()(const WheelsCmd& c) const {
    if (std::string e = needDrive(); !e.empty()) return e;
    for (size_t i = 0; i < 4; ++i) {
      const JointSpec& joint = robot.joints[robot.drive->wheels[i]];
      const int a = robot.findActuator(joint.name);
      if (a < 0) return "wheel joint '" + joint.name + "' has no actuator";
      const double max = robot.actuators[a].maxVelocity;
      if (std::abs(c.omega[i]) > max)
        return std::string(kWheelNames[i]) + " wheel speed " + show(c.omega[i]) + " rad/s exceeds joint '" +
               joint.name + "' max_velocity " + show(max) + " rad/s (" + show(radToDeg(max)) + " deg/s)";
    }
    return {};
  }

  std::string operator()(const DriveCmd& c) const {
    if (std::string e = needDrive(); !e.empty()) return e;
    const JointSpec& j = robot.joints[robot.drive->articulation];
    if (j.limited && (c.articulation < j.lower || c.articulation > j.upper))
      return "articulation " + show(radToDeg(c.articulation)) + " deg is outside joint '" + j.name +
             "' limits [" + show(radToDeg(j.lower)) + ", " + show(radToDeg(j.upper)) + "] deg";
    return {};
  }

  std::string operator()(const StopCmd&) const { return {}; }

  std::string operator()(const TurnCmd&) const { return needDrive(); }

  std::string operator()(const GaitCmd&) const {
    if (std::string e = needDrive(); !e.empty()) return e;
    const auto legs = findLegs(robot);
    if (!legs) return "robot '" + robot.name + "' has no hip-knee-wheel legs for gaits";
    for (const LegJoints& leg : *legs)
      for (int j : {leg.hip, leg.knee}) {
        const int a = robot.findActuator(robot.joints[j].name);
        if (a < 0 || !robot.actuators[a].hasPid) return needsPid(robot.joints[j].name);
      }
    return {};
  }

  // The robot's <drive>, with joint indices checked so that the checks above
  // cannot index out of range on a hand-built model.
  std::string needDrive() const {
    if (!robot.drive) return "robot '" + robot.name + "' has no <drive>";
    const auto valid = [&](int j) { return j >= 0 && static_cast<size_t>(j) < robot.joints.size(); };
    bool ok = valid(robot.drive->articulation);
    for (int w : robot.drive->wheels) ok = ok && valid(w);
    return ok ? std::string() : "robot '" + robot.name + "' has a <drive> with unknown joints";
  }
};

}  // namespace

std::optional<Command> parseCommand(std::string_view text, std::string& error, const RobotModel* robot) {
  const std::vector<std::string_view> words = splitWords(text);
  if (words.empty()) {
    error = "empty command";
    return std::nullopt;
  }
  for (const Syntax& s : kSyntax) {
    if (words[0] != s.name) continue;
    ArgReader reader{s.name, {words.begin() + 1, words.end()}, {}, robot};
    if (reader.args.size() != s.arity) {
      const std::string got = ", got " + std::to_string(reader.args.size());
      error = std::string(s.name) +
              (s.arity == 0 ? ": expected no arguments" + got
                            : ": expected " + std::to_string(s.arity) + " arguments (" + std::string(s.help) +
                                  ")" + got);
      return std::nullopt;
    }
    Command command = s.build(reader);
    if (!reader.error.empty()) {
      error = reader.error;
      return std::nullopt;
    }
    return command;
  }
  error = "unknown command '" + std::string(words[0]) + "'";
  return std::nullopt;
}

std::optional<std::vector<TimedCommand>> parseCommandSequence(std::string_view text, std::string_view file,
                                                              Diagnostics& diag, const RobotModel* robot) {
  std::vector<TimedCommand> commands;
  bool ok = true;
  std::optional<double> previousTime;
  int line = 0;
  for (size_t pos = 0; pos <= text.size();) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view content = text.substr(pos, end - pos);
    pos = end + 1;
    ++line;
    content = trim(content.substr(0, content.find('#')));
    if (content.empty()) continue;

    const size_t split = std::min(content.find_first_of(" \t\r\v\f"), content.size());
    const std::string_view timeText = content.substr(0, split);
    const std::string_view rest = trim(content.substr(split));
    const std::optional<double> time = parseReal(timeText);
    if (!time) {
      diag.error(file, line, "bad time '" + std::string(timeText) + "'");
      ok = false;
      continue;
    }
    if (*time < 0) {
      diag.error(file, line, "time must be >= 0");
      ok = false;
      continue;
    }
    if (previousTime && *time < *previousTime) {
      diag.error(file, line, "time " + shortestText(*time) + " is before the previous command's time " +
                                 shortestText(*previousTime));
      ok = false;
      continue;
    }
    previousTime = time;
    if (rest.empty()) {
      diag.error(file, line, "expected a command after the time");
      ok = false;
      continue;
    }
    std::string error;
    std::optional<Command> command = parseCommand(rest, error, robot);
    if (!command) {
      diag.error(file, line, error);
      ok = false;
      continue;
    }
    commands.push_back({*time, std::move(*command), line});
  }
  if (!ok) return std::nullopt;
  return commands;
}

std::optional<std::vector<TimedCommand>> loadCommandSequence(const std::string& path, Diagnostics& diag,
                                                             const RobotModel* robot) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    diag.error(path, 0, "cannot open command sequence file");
    return std::nullopt;
  }
  std::string text;
  char chunk[4096];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) text.append(chunk, static_cast<size_t>(in.gcount()));
  if (in.bad()) {  // a directory, say
    diag.error(path, 0, "cannot read command sequence file");
    return std::nullopt;
  }
  return parseCommandSequence(text, path, diag, robot);
}

bool checkCommands(const std::vector<TimedCommand>& commands, const RobotModel& robot, std::string_view file,
                   Diagnostics& diag) {
  bool ok = true;
  for (const TimedCommand& c : commands) {
    std::string error = checkCommand(c.command, robot);
    if (!error.empty()) {
      diag.error(file, c.line, std::move(error));
      ok = false;
    }
  }
  return ok;
}

std::string checkCommand(const Command& command, const RobotModel& robot) {
  return std::visit(Checker{robot}, command);
}

}  // namespace sp
