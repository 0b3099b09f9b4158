#include "sim/perturbation.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <tinyxml2.h>

#include "sim/random.h"
#include "sim/text.h"

namespace sp {

namespace {

// The wheels' short names, FL FR RL RR: the report's keys and --weak-motor's.
constexpr const char* kWheels[] = {"fl", "fr", "rl", "rr"};

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
          a.maxTorque *= p.torqueLimit * p.wheelTorque[w];
          a.velocityScale *= p.velocityGain;
        }
    }
  world.defaultContact.mu *= p.friction;
  for (ContactSpec& c : world.contacts) c.mu *= p.friction;
  return world;
}

namespace {

// The calibration as a perturbation of the files' robot: what both the
// twins (calibratedWorld) and a saved robot file apply.
Perturbation calibrationPerturbation(const SimParams& params, const RobotModel& robot) {
  const size_t links = robot.links.size();
  Perturbation p;
  const double front = params.calWheelRadius * (1 + params.calWheelRadiusSplit / 2);
  const double rear = params.calWheelRadius * (1 - params.calWheelRadiusSplit / 2);
  const double left = 1 + params.calWheelRadiusSide / 2, right = 1 - params.calWheelRadiusSide / 2;
  const double diag = 1 + params.calWheelRadiusDiag / 2, antiDiag = 1 - params.calWheelRadiusDiag / 2;
  p.wheelRadius = {front * left * diag, front * right * antiDiag, rear * left * antiDiag, rear * right * diag};  // FL FR RL RR
  p.linkMass.assign(links, params.calMass);
  // Every link's centre moved by the same shift in the robot frame: at zero
  // pose the robot's centre moves by exactly that, whatever the masses.
  p.centreOfMass.resize(links);
  for (size_t i = 0; i < links; ++i)
    p.centreOfMass[i] = rotate(conjugate(robot.links[i].pose.q), Vec3{params.calComX, params.calComY, 0});
  p.friction = params.calFriction;
  p.velocityGain = params.calMotorGain;
  p.wheelTorque = {params.calTorqueFL, params.calTorqueFR, params.calTorqueRL, params.calTorqueRR};
  return p;
}

}  // namespace

WorldModel calibratedWorld(const WorldModel& world, const SimParams& params) {
  if (!params.calibrated() || world.robots.empty()) return world;
  return perturbWorld(world, calibrationPerturbation(params, world.robots[0].model));
}

std::optional<std::string> calibratedRobotText(const std::string& text, const RobotModel& robot, const SimParams& params,
                                               std::string& error) {
  using namespace tinyxml2;
  const std::string where = robot.file.empty() ? std::string("robot file") : robot.file;
  XMLDocument doc;
  if (doc.Parse(text.data(), text.size()) != XML_SUCCESS || !doc.RootElement()) {
    error = where + ": error: not a robot file: " + (doc.ErrorStr() ? doc.ErrorStr() : "no root element");
    return std::nullopt;
  }
  const Perturbation p = calibrationPerturbation(params, robot);
  const auto scale = [](XMLElement* e, const char* attr, double factor, double fallback) {
    e->SetAttribute(attr, shortestText(e->DoubleAttribute(attr, fallback) * factor).c_str());
  };
  std::vector<bool> seen(robot.links.size(), false);
  for (XMLElement* e = doc.RootElement()->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const char* name = e->Attribute("name");
    if (!name) continue;
    if (std::string_view(e->Name()) == "link") {
      const int i = robot.findLink(name);
      if (i < 0) continue;
      seen[static_cast<size_t>(i)] = true;
      scale(e, "mass", p.linkMass[static_cast<size_t>(i)], 0);
      if (!robot.drive) continue;
      for (size_t w = 0; w < 4; ++w) {
        const int joint = robot.drive->wheels[w];
        if (joint < 0 || robot.joints[static_cast<size_t>(joint)].child != i) continue;
        // The tyre: the wheel link's round geoms, as perturbWorld scales them.
        for (XMLElement* g = e->FirstChildElement("geom"); g; g = g->NextSiblingElement("geom")) {
          const std::string type = g->Attribute("type") ? g->Attribute("type") : "";
          if (type == "cylinder" || type == "sphere") scale(g, "radius", p.wheelRadius[w], 0);
        }
      }
    } else if (std::string_view(e->Name()) == "actuator" && robot.drive && e->Attribute("joint")) {
      const int joint = robot.findJoint(e->Attribute("joint"));
      for (size_t w = 0; w < 4; ++w)
        if (joint >= 0 && joint == robot.drive->wheels[w]) {
          scale(e, "velocity_scale", p.velocityGain, 1);
          if (p.wheelTorque[w] != 1) scale(e, "max_torque", p.wheelTorque[w], 0);
        }
    }
  }
  for (size_t i = 0; i < seen.size(); ++i)
    if (!seen[i]) {
      error = where + ": error: link '" + robot.links[i].name + "' is not in the file's text (a file other than the one loaded?)";
      return std::nullopt;
    }
  const std::string note = " Calibrated from telemetry (SimPartner, app/calibration/): link masses x " +
                           shortestText(params.calMass) + ", tyre radii and wheel motors' velocity_scale and max_torque written in. " +
                           "Not in a robot file, keep them in the parameters: calibration.friction = " +
                           shortestText(params.calFriction) + " (the ground's contact), calibration.delay = " +
                           shortestText(params.calDelay) + " s (the link's)" +
                           (params.calComX != 0 || params.calComY != 0
                                ? ", calibration.com_x = " + shortestText(params.calComX) + ", calibration.com_y = " +
                                      shortestText(params.calComY) + " m (a robot file places no centre of mass). "
                                : std::string(". "));
  XMLComment* comment = doc.NewComment(note.c_str());
  if (doc.FirstChild() && doc.FirstChild()->ToDeclaration()) doc.InsertAfterChild(doc.FirstChild(), comment);
  else doc.InsertFirstChild(comment);
  XMLPrinter printer;
  doc.Print(&printer);
  return std::string(printer.CStr(), static_cast<size_t>(printer.CStrSize() > 0 ? printer.CStrSize() - 1 : 0));
}

std::string SuddenChange::describe() const {
  return "friction x" + shortestText(friction) + ", delay +" + shortestText(delay) + " s at " + shortestText(at) + " s";
}

std::string SuddenChange::check() const {
  if (!std::isfinite(at) || at < 0) return "at " + shortestText(at) + " s: must be >= 0";
  if (!std::isfinite(friction) || friction <= 0) return "friction factor " + shortestText(friction) + ": must be > 0";
  if (!std::isfinite(delay) || delay < 0) return "delay " + shortestText(delay) + " s: must be >= 0";
  return {};
}

std::string parseSuddenChange(const std::string& text, SuddenChange& c) {
  std::array<std::optional<double>, 3> x;
  size_t from = 0;
  for (size_t k = 0; k < 3; ++k) {
    const size_t comma = text.find(',', from);
    if ((k < 2) == (comma == std::string::npos)) return "'" + text + "': a change is T,FRICTION,DELAY (30,0.7,0.1)";
    x[k] = parseReal(std::string_view(text).substr(from, comma == std::string::npos ? std::string::npos : comma - from));
    if (!x[k]) return "'" + text + "': a change is T,FRICTION,DELAY (30,0.7,0.1)";
    from = comma + 1;
  }
  const SuddenChange parsed{*x[0], *x[1], *x[2]};
  if (const std::string why = parsed.check(); !why.empty()) return "'" + text + "': " + why;
  c = parsed;
  return {};
}

std::string parseWeakMotor(const std::string& text, Perturbation& p) {
  const size_t eq = text.find('=');
  const std::string wheel = text.substr(0, eq);
  size_t w = 0;
  while (w < 4 && wheel != kWheels[w]) ++w;
  const auto factor = eq == std::string::npos ? std::nullopt : parseReal(std::string_view(text).substr(eq + 1));
  if (w == 4 || !factor) return "'" + text + "': a weak motor is WHEEL=FACTOR, the wheel fl, fr, rl or rr (rl=0.5)";
  if (!(*factor > 0 && *factor <= 2)) return "'" + text + "': the torque factor must lie in (0, 2]";
  p.wheelTorque[w] = *factor;
  return {};
}

std::string Perturbation::report(const RobotModel& robot) const {
  std::string out = "seed = " + std::to_string(seed) + "\n";
  for (size_t w = 0; w < 4; ++w) out += std::string("wheel_radius.") + kWheels[w] + " = " + number(wheelRadius[w]) + "\n";
  for (size_t i = 0; i < robot.links.size() && i < linkMass.size(); ++i) {
    out += "mass." + robot.links[i].name + " = " + number(linkMass[i]) + "\n";
    const Vec3& c = centreOfMass[i];
    out += "centre_of_mass." + robot.links[i].name + " = " + number(c.x) + " " + number(c.y) + " " + number(c.z) + "\n";
  }
  out += "friction = " + number(friction) + "\n";
  out += "wheel_torque_limit = " + number(torqueLimit) + "\n";
  for (size_t w = 0; w < 4; ++w)
    if (wheelTorque[w] != 1) out += std::string("wheel_torque_limit.") + kWheels[w] + " = " + number(wheelTorque[w]) + "\n";
  out += "wheel_velocity_gain = " + number(velocityGain) + "\n";
  out += "actuator_delay = " + number(delay) + "\n";
  out += "imu_roll_bias = " + number(rollBias) + "\n";
  out += "imu_pitch_bias = " + number(pitchBias) + "\n";
  return out;
}

}  // namespace sp
