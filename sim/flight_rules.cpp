#include "sim/flight_rules.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>

#include "sim/file_set.h"
#include "sim/params.h"
#include "sim/properties.h"
#include "sim/robot_model.h"
#include "sim/text.h"
#include "sim/world.h"

namespace sp {
namespace {

// One key of the rules file: parses its text into the rules ("" or why not)
// and writes it back.
struct RuleKey {
  const char* key;
  std::function<std::string(FlightRules&, std::string_view)> set;
  std::function<std::string(const FlightRules&)> get;
};

RuleKey number(const char* key, double FlightRules::*field, double lo, double hi) {
  return {key,
          [field, lo, hi](FlightRules& r, std::string_view text) -> std::string {
            const std::optional<double> v = parseReal(text);
            if (!v) return "expected a number, got '" + std::string(text.substr(0, 80)) + "'";
            if (*v < lo || *v > hi)
              return "must be in [" + shortestText(lo) + ", " + shortestText(hi) + "], got " + std::string(text);
            r.*field = *v;
            return {};
          },
          [field](const FlightRules& r) { return shortestText(r.*field); }};
}

RuleKey count(const char* key, int FlightRules::*field, int lo, int hi) {
  return {key,
          [field, lo, hi](FlightRules& r, std::string_view text) -> std::string {
            const std::optional<double> v = parseReal(text);
            if (!v || *v != std::floor(*v)) return "expected an integer, got '" + std::string(text.substr(0, 80)) + "'";
            if (*v < lo || *v > hi)
              return "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::string(text);
            r.*field = static_cast<int>(*v);
            return {};
          },
          [field](const FlightRules& r) { return std::to_string(r.*field); }};
}

RuleKey names(const char* key, std::string FlightRules::*field) {
  return {key,
          [field](FlightRules& r, std::string_view text) -> std::string {
            for (const std::string& n : splitNames(text))
              if (n.empty() || !std::all_of(n.begin(), n.end(), [](char c) {
                    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
                  }))
                return "expected names separated by commas, or 'none', got '" +
                       std::string(text.substr(0, 80)) + "'";
            r.*field = std::string(text);
            return {};
          },
          [field](const FlightRules& r) { return r.*field; }};
}

constexpr double kHuge = 1e6;

// In the order of config/flight.rules.
const std::vector<RuleKey>& keys() {
  using R = FlightRules;
  static const std::vector<RuleKey> table = {
      number("stability.min_margin", &R::minStabilityMargin, -1, 10),
      number("stability.support_gap", &R::supportGap, 0, 1),
      number("attitude.max_roll", &R::maxRoll, 0, 180),
      number("attitude.max_pitch", &R::maxPitch, 0, 180),
      number("joints.limit_margin", &R::jointLimitMargin, 0, 90),
      names("joints.exempt", &R::jointLimitExempt),
      number("wheels.max_liftoff", &R::maxLiftoff, 0, kHuge),
      number("wheels.max_force", &R::maxWheelForce, 0, kHuge),
      names("collision.allowed", &R::collisionAllowed),
      number("speed.max", &R::maxSpeed, 0, kHuge),
      number("speed.max_yaw_rate", &R::maxYawRate, 0, kHuge),
      number("rehearsal.settle", &R::settle, 0, 3600),
      number("start.position", &R::startPosition, 0, kHuge),
      number("start.heading", &R::startHeading, 0, 180),
      number("guard.position", &R::guardPosition, 0, kHuge),
      number("guard.heading", &R::guardHeading, 0, 180),
      number("guard.joint", &R::guardJoint, 0, 360),
      count("robust.samples", &R::robustSamples, 1, 100000),
      number("robust.friction", &R::robustFriction, 0, 0.99),
      number("robust.mass", &R::robustMass, 0, 0.99),
      number("robust.terrain", &R::robustTerrain, 0, 10),
      number("robust.start_position", &R::robustStartPosition, 0, 100),
      number("robust.start_heading", &R::robustStartHeading, 0, 180),
  };
  return table;
}

const RuleKey* findKey(std::string_view key) {
  for (const RuleKey& k : keys())
    if (key == k.key) return &k;
  return nullptr;
}

const char* unitOf(Rule rule) {
  switch (rule) {
    case Rule::Stability: return "m";
    case Rule::Roll:
    case Rule::Pitch: return "deg";
    case Rule::JointLimit: return "deg or cm";
    case Rule::WheelLiftoff: return "s";
    case Rule::WheelForce: return "N";
    case Rule::Collision: return "m deep";
    case Rule::Speed: return "m/s";
    case Rule::YawRate: return "deg/s";
    case Rule::Health: return "";
  }
  return "";
}

}  // namespace

// Andrew's monotone chain.
std::vector<Vec3> convexHullXY(std::vector<Vec3> p) {
  std::sort(p.begin(), p.end(), [](Vec3 a, Vec3 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  if (p.size() < 3) return p;
  auto turn = [](Vec3 o, Vec3 a, Vec3 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); };
  std::vector<Vec3> h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && turn(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && turn(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

namespace {

double segmentDistance(Vec3 p, Vec3 a, Vec3 b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - (a.x + t * dx), p.y - (a.y + t * dy));
}

}  // namespace

const char* toString(Rule rule) {
  switch (rule) {
    case Rule::Stability: return "stability";
    case Rule::Roll: return "roll";
    case Rule::Pitch: return "pitch";
    case Rule::JointLimit: return "joint limit";
    case Rule::WheelLiftoff: return "wheel lift-off";
    case Rule::WheelForce: return "wheel force";
    case Rule::Collision: return "collision";
    case Rule::Speed: return "speed";
    case Rule::YawRate: return "yaw rate";
    case Rule::Health: return "twin health";
  }
  return "?";
}

bool parseFlightRules(std::string_view contents, std::string_view path, FlightRules& rules, Diagnostics& diag) {
  FlightRules staged = rules;
  const bool ok = readProperties(
      contents, path, diag, [](std::string_view key) { return findKey(key) != nullptr; },
      [&](std::string_view key, std::string_view value, int line) {
        const RuleKey* k = findKey(key);
        if (!k) {
          diag.error(path, line, "unknown key '" + std::string(key.substr(0, 80)) + "'");
          return false;
        }
        if (std::string why = k->set(staged, value); !why.empty()) {
          diag.error(path, line, std::string(key) + ": " + why);
          return false;
        }
        return true;
      });
  if (ok) rules = staged;
  return ok;
}

bool loadFlightRules(const std::string& path, FlightRules& rules, Diagnostics& diag) {
  const std::optional<std::string> contents = readSourceFile(path, nullptr);
  if (!contents) {
    diag.error(path, 0, sourceFileExists(path, nullptr) ? "cannot read rules file" : "cannot open rules file");
    return false;
  }
  return parseFlightRules(*contents, path, rules, diag);
}

std::string flightRulesText(const FlightRules& rules) {
  std::string out;
  for (const RuleKey& k : keys()) out += std::string(k.key) + " = " + k.get(rules) + "\n";
  return out;
}

std::string RuleVerdict::message() const {
  char buf[256];
  const std::string at = where.empty() ? "" : " (" + where + ")";
  if (!passed) {
    // With as many digits as it takes for the value and the limit to read
    // differently: "1.94 against 1.94" would read as a pass.
    int digits = 3;
    char v[40], l[40];
    for (;; ++digits) {
      std::snprintf(v, sizeof v, "%.*g", digits, value);
      std::snprintf(l, sizeof l, "%.*g", digits, limit);
      if (std::strcmp(v, l) != 0 || digits >= 12) break;
    }
    std::snprintf(buf, sizeof buf, "%s: %s %s %s its limit %s at t = %.2f s%s", toString(rule), v, unitOf(rule),
                  value > limit ? "exceeded" : "fell below", l, time, at.c_str());
  } else {
    const std::string w = worstWhere.empty() ? "" : ", " + worstWhere;
    std::snprintf(buf, sizeof buf, "%s: ok (closest %.3g %s at t = %.2f s%s; limit %.3g)", toString(rule), worst,
                  unitOf(rule), worstTime, w.c_str(), limit);
  }
  return rule == Rule::Health && !passed ? std::string("twin health: ") + where : std::string(buf);
}

double supportMargin(Vec3 point, const std::vector<Vec3>& support) {
  const std::vector<Vec3> h = convexHullXY(support);
  if (h.empty()) return -std::numeric_limits<double>::infinity();
  if (h.size() == 1) return -std::hypot(point.x - h[0].x, point.y - h[0].y);
  double edge = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < h.size(); ++i) edge = std::min(edge, segmentDistance(point, h[i], h[(i + 1) % h.size()]));
  if (h.size() == 2) return -edge;
  for (size_t i = 0; i < h.size(); ++i) {
    const Vec3 a = h[i], b = h[(i + 1) % h.size()];
    if ((b.x - a.x) * (point.y - a.y) - (b.y - a.y) * (point.x - a.x) < 0) return -edge;  // right of a ccw edge
  }
  return edge;
}

RuleMonitor::RuleMonitor(const FlightRules& rules, const RobotModel& robot, int robotIndex)
    : rules_(rules), robot_(&robot), robotIndex_(robotIndex) {
  bind();
  for (int r = 0; r < kRuleCount; ++r) {
    RuleVerdict v;
    v.rule = static_cast<Rule>(r);
    verdicts_.push_back(v);
  }
  closest_.assign(kRuleCount, -std::numeric_limits<double>::infinity());
}

void RuleMonitor::rebind(const RobotModel& robot) {
  const RobotModel& was = *robot_;
  const std::vector<Wheel> wheels = wheels_;
  std::vector<std::pair<std::string, Limited>> limited;
  for (const Limited& l : limited_) limited.emplace_back(was.joints[static_cast<size_t>(l.joint)].name, l);
  robot_ = &robot;
  bind();
  for (Wheel& w : wheels_)
    for (const Wheel& old : wheels)
      if (old.name == w.name) w.offSince = old.offSince;
  for (Limited& l : limited_)
    for (const auto& [name, old] : limited)
      if (name == robot.joints[static_cast<size_t>(l.joint)].name) {
        l.parked = old.parked;
        l.fresh = old.fresh;
      }
}

void RuleMonitor::bind() {
  const RobotModel& robot = *robot_;
  wheels_.clear();
  if (robot.drive)
    for (int j : robot.drive->wheels) {
      if (j < 0) continue;
      Wheel w;
      w.link = robot.joints[j].child;
      w.name = robot.links[w.link].name;
      for (size_t s = 0; s < robot.sensors.size(); ++s)
        if (robot.sensors[s].type == SensorType::WheelForce && robot.sensors[s].link == w.link)
          w.sensor = static_cast<int>(s);
      wheels_.push_back(w);
    }
  isWheel_.assign(robot.links.size(), false);
  for (const Wheel& w : wheels_) isWheel_[w.link] = true;
  touchAllowed_.assign(robot.links.size(), false);
  for (const std::string& name : splitNames(rules_.collisionAllowed))
    if (const int l = robot.findLink(name); l >= 0) touchAllowed_[l] = true;
  const std::vector<std::string> exempt = splitNames(rules_.jointLimitExempt);
  limited_.clear();
  for (const ActuatorSpec& a : robot.actuators) {
    const JointSpec& j = robot.joints[a.joint];
    if (!j.limited || a.continuous || std::find(exempt.begin(), exempt.end(), j.name) != exempt.end()) continue;
    const double margin = j.type == JointType::Slider ? rules_.jointLimitMargin / 100 : degToRad(rules_.jointLimitMargin);
    limited_.push_back({a.joint, j.lower, j.upper, margin});
  }
}

bool RuleMonitor::passed() const {
  return std::all_of(verdicts_.begin(), verdicts_.end(), [](const RuleVerdict& v) { return v.passed; });
}

void RuleMonitor::record(Rule rule, bool bad, double value, double limit, double closeness, double time,
                         const std::string& where) {
  RuleVerdict& v = verdicts_[static_cast<int>(rule)];
  v.limit = limit;
  if (closeness > closest_[static_cast<int>(rule)]) {
    closest_[static_cast<int>(rule)] = closeness;
    v.worst = value;
    v.worstTime = time;
    v.worstWhere = where;
  }
  if (bad && v.passed) {
    v.passed = false;
    v.time = time;
    v.value = value;
    v.where = where;
  }
}

void RuleMonitor::check(const World& world) {
  const int r = robotIndex_;
  const double t = world.time();
  const Pose base = world.linkPose(r, 0);
  const std::vector<LinkContact> contacts = world.linkContacts();

  // Health first: after a divergence the state means nothing.
  const HealthReport& health = world.health();
  record(Rule::Health, !health.healthy(), health.value, health.limit, health.healthy() ? 0 : 1, t,
         health.healthy() ? std::string() : health.message());
  if (!health.healthy()) return;

  // Collisions; which wheels touch the ground, and where.
  std::vector<Vec3> wheelContactSum(robot_->links.size());
  std::vector<int> wheelContactCount(robot_->links.size(), 0);
  bool collided = false;
  double depth = 0;
  std::string collidedWhere;
  for (const LinkContact& c : contacts) {
    if (c.robot != r) continue;
    const bool ground = c.terrain || c.object >= 0;
    if (isWheel_[c.link] && ground) {
      wheelContactSum[c.link] = wheelContactSum[c.link] + c.position;
      ++wheelContactCount[c.link];
      continue;
    }
    if (c.object >= 0 && touchAllowed_[c.link]) continue;
    if (!collided || c.depth > depth) {
      depth = c.depth;
      std::string with = c.terrain ? "the ground" : c.object >= 0 ? "object " + std::to_string(c.object) : "a robot link";
      if (c.otherRobot == r && c.otherLink >= 0) with = robot_->links[c.otherLink].name;
      collidedWhere = robot_->links[c.link].name + " touches " + with;
    }
    collided = true;
  }
  record(Rule::Collision, collided, depth, 0, collided ? depth : -1, t, collidedWhere);

  // Support polygon: wheels on the ground, or as close to it as rocking takes them.
  std::vector<Vec3> support;
  double radius = robot_->drive ? robot_->drive->wheelRadius : 0;
  double longestOff = 0;
  std::string offWheel;
  double force = 0;
  std::string forceWheel;
  for (Wheel& w : wheels_) {
    const int n = wheelContactCount[w.link];
    const Pose p = world.linkPose(r, w.link);
    if (n > 0) {
      support.push_back((1.0 / n) * wheelContactSum[w.link]);
      w.offSince = -1;
    } else {
      const double ground = world.terrainHeight(p.p.x, p.p.y);
      // Rocking on rough ground leaves a wheel a few millimetres up: it still
      // supports the robot and has not lifted off.
      if (p.p.z - radius - ground < rules_.supportGap) {
        support.push_back({p.p.x, p.p.y, ground});
        w.offSince = -1;
      } else {
        if (w.offSince < 0) w.offSince = t;
        if (t - w.offSince > longestOff) {
          longestOff = t - w.offSince;
          offWheel = w.name;
        }
      }
    }
    if (w.sensor >= 0) {
      const SensorSample& s = world.sensorSample(r, w.sensor);
      if (const auto* f = std::get_if<WheelForceReading>(&s.value); f && f->normal > force) {
        force = f->normal;
        forceWheel = w.name;
      }
    }
  }
  if (!wheels_.empty()) {
    margin_ = supportMargin(world.robotCentreOfMass(r), support);
    record(Rule::Stability, margin_ < rules_.minStabilityMargin, margin_, rules_.minStabilityMargin, -margin_, t, "");
    record(Rule::WheelLiftoff, longestOff > rules_.maxLiftoff, longestOff, rules_.maxLiftoff, longestOff, t,
           offWheel);
    record(Rule::WheelForce, force > rules_.maxWheelForce, force, rules_.maxWheelForce, force, t, forceWheel);
  }

  // Attitude, from where "up" lies in the base's frame.
  const Vec3 tilted = tilt(base.q);
  const double roll = radToDeg(tilted.x);
  const double pitch = radToDeg(tilted.y);
  record(Rule::Roll, std::abs(roll) > rules_.maxRoll, roll, rules_.maxRoll, std::abs(roll), t, "");
  record(Rule::Pitch, std::abs(pitch) > rules_.maxPitch, pitch, rules_.maxPitch, std::abs(pitch), t, "");

  // Joint limits: the closest approach of any limited, actuated joint.
  double nearest = std::numeric_limits<double>::infinity(), nearestMargin = 0;
  std::string nearestJoint;
  bool slider = false;
  for (Limited& l : limited_) {
    const double q = world.jointPosition(r, l.joint);
    const double room = std::min(q - l.lower, l.upper - q);
    if (l.fresh) l.parked = room < l.margin;
    l.fresh = false;
    if (l.parked && room < l.margin) continue;
    l.parked = false;
    if (room - l.margin < nearest - nearestMargin) {
      nearest = room;
      nearestMargin = l.margin;
      nearestJoint = robot_->joints[l.joint].name;
      slider = robot_->joints[l.joint].type == JointType::Slider;
    }
  }
  if (!nearestJoint.empty()) {
    const double shown = slider ? nearest * 100 : radToDeg(nearest);
    record(Rule::JointLimit, nearest < nearestMargin, shown, rules_.jointLimitMargin, -(nearest - nearestMargin), t,
           nearestJoint);
  }

  // Speed and yaw rate of the base.
  const Vec3 v = world.linkLinearVelocity(r, 0);
  const double speed = std::hypot(v.x, v.y);
  const double yawRate = radToDeg(world.linkAngularVelocity(r, 0).z);
  record(Rule::Speed, speed > rules_.maxSpeed, speed, rules_.maxSpeed, speed, t, "");
  record(Rule::YawRate, std::abs(yawRate) > rules_.maxYawRate, yawRate, rules_.maxYawRate, std::abs(yawRate), t, "");
}

}  // namespace sp
