#include "sim/command.h"

#include "sim/robot_model.h"

#include <charconv>
#include <system_error>

#include "sim/math.h"

namespace sp {
namespace {

std::string formatShortest(double value) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value);
  return ec == std::errc() ? std::string(buf, end) : std::string("?");
}

// An angle [rad] as degrees, with the fewest significant digits that read
// back (through degToRad) to exactly `rad`: degToRad(10) prints as "10", not
// as "10.000000000000002". If no decimal does, the closest one is printed.
std::string formatDegrees(double rad) {
  const double deg = radToDeg(rad);
  char buf[40];
  for (int digits = 1; digits < 17; ++digits) {
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, deg, std::chars_format::scientific, digits - 1);
    double rounded = 0;
    if (ec != std::errc() || std::from_chars(buf, end, rounded).ec != std::errc()) break;
    if (degToRad(rounded) == rad) return formatShortest(rounded);
  }
  return formatShortest(deg);
}

}  // namespace

const char* toString(Gait gait) {
  switch (gait) {
    case Gait::Off: return "off";
    case Gait::Caterpillar: return "caterpillar";
    case Gait::Rolking: return "rolking";
  }
  return "?";
}

std::string toText(const Command& command, const RobotModel* robot) {
  struct Writer {
    const RobotModel* robot;
    // Degrees for hinges, metres for sliders (as parseCommand reads them).
    std::string jointValue(const std::string& joint, double value) const {
      const int j = robot ? robot->findJoint(joint) : -1;
      if (j >= 0 && robot->joints[j].type == JointType::Slider) return formatShortest(value);
      return formatDegrees(value);
    }
    std::string operator()(const JointVelocityCmd& c) const {
      return "velocity " + c.joint + " " + jointValue(c.joint, c.velocity);
    }
    std::string operator()(const JointTargetCmd& c) const {
      return "target " + c.joint + " " + jointValue(c.joint, c.position);
    }
    std::string operator()(const JointTorqueCmd& c) const {
      return "torque " + c.joint + " " + formatShortest(c.torque);
    }
    std::string operator()(const JointModeCmd& c) const {
      return "mode " + c.joint + " " + toString(c.mode);
    }
    std::string operator()(const WheelsCmd& c) const {
      std::string out = "wheels";
      for (double omega : c.omega) out += " " + formatShortest(omega);
      return out;
    }
    std::string operator()(const DriveCmd& c) const {
      return "drive " + formatShortest(c.speed) + " " + formatDegrees(c.articulation);
    }
    std::string operator()(const StopCmd&) const { return "stop"; }
    std::string operator()(const GaitCmd& c) const { return std::string("gait ") + toString(c.gait); }
    std::string operator()(const TurnCmd& c) const {
      return "turn " + formatShortest(c.speed) + " " + formatDegrees(c.yawRate);
    }
    // Heights in their shortest exact form, so the text reads back to the
    // same bits (a logged edit re-simulates exactly).
    std::string operator()(const TerrainPatchCmd& c) const {
      std::string out = "terrain " + std::to_string(c.column) + " " + std::to_string(c.row) + " " +
                        std::to_string(c.columns) + " " + std::to_string(c.rows);
      for (double h : c.heights) out += " " + formatShortest(h);
      return out;
    }
  };
  return std::visit(Writer{robot}, command);
}

}  // namespace sp
