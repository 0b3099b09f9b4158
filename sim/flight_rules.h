#pragma once
// Flight rules: what a rehearsed command sequence must not do to the robot,
// checked on the twin every step (app/rehearse/rehearsal.h), with their limits, the
// guard's thresholds for the relayed run, and the ranges of the robustness
// rehearsals, all from a rules file (`key = value`, config/flight.rules lists
// every key with its default and where the default comes from; the format in
// docs/formats.md).
//
//   sp::FlightRules rules;                      // defaults
//   if (!sp::loadFlightRules(path, rules, diag)) show(diag.format());
//   sp::RuleMonitor monitor(rules, world.robotModel(0));
//   while (world.step()) monitor.check(world);   // after every step
//   for (const sp::RuleVerdict& v : monitor.verdicts()) ...
//
// Thread: plain values; a RuleMonitor belongs to the thread stepping its World.

#include <string>
#include <string_view>
#include <vector>

#include "sim/diagnostics.h"
#include "sim/math.h"

namespace sp {

class World;
struct RobotModel;

/// Every limit of a rehearsal. Angles in degrees, as in the file.
struct FlightRules {
  // Rules checked every step
  double minStabilityMargin = 0.05;  ///< [m] centre of mass inside the support polygon by at least this
  double supportGap = 0.03;          ///< [m] a wheel this close to the ground still supports (rocking)
  double maxRoll = 25;               ///< [deg] base roll
  double maxPitch = 25;              ///< [deg] base pitch
  double jointLimitMargin = 1;       ///< [deg] (hinges) / [cm] (sliders) closest approach to a joint limit
  /// Joints that may run to their stops (grippers open and close on them);
  /// comma-separated names, or "none".
  std::string jointLimitExempt = "finger_l1,finger_l2,finger_r1,finger_r2";
  double maxLiftoff = 1.5;           ///< [s] longest time a drive wheel may be higher than supportGap
  double maxWheelForce = 4000;       ///< [N] normal force on one wheel
  /// Links that may touch objects (grippers picking up); comma-separated
  /// names, or "none". No link but the drive wheels may touch the ground.
  std::string collisionAllowed = "forearm_l,forearm_r,finger_l1,finger_l2,finger_r1,finger_r2";
  double maxSpeed = 1.94;            ///< [m/s] base speed over ground
  double maxYawRate = 60;            ///< [deg/s] base yaw rate
  // The rehearsal
  double settle = 2;                 ///< [s] simulated after the last command's time
  // The relay (app/rehearse/sequence_relay.h): when the robot refuses to start, when the guard aborts
  double startPosition = 0.10;       ///< [m] robot's base from the rehearsal's start
  double startHeading = 5;           ///< [deg]
  double guardPosition = 0.30;       ///< [m] telemetry's base from the rehearsed one at the same time
  double guardHeading = 10;          ///< [deg]
  double guardJoint = 15;            ///< [deg] any actuated leg or steering joint
  // Robustness: N rehearsals, each with the parameters drawn uniformly in these ranges
  int robustSamples = 16;
  double robustFriction = 0.3;       ///< relative +- on every contact's friction
  double robustMass = 0.1;           ///< relative +- on every link's mass
  double robustTerrain = 0.01;       ///< [m] +- of a smooth random field (1 m cells) added to the heightfield
  double robustStartPosition = 0.05; ///< [m] +- on the start's x and y
  double robustStartHeading = 2;     ///< [deg] +- on the start's heading
};

/// Reads a rules file over `rules` (defaults for keys it leaves out). All
/// problems are reported (`file:line: error: ...`); on any error `rules` is
/// left as it was.
bool loadFlightRules(const std::string& path, FlightRules& rules, Diagnostics& diag);
/// The same for text held in memory; `path` names it in diagnostics.
bool parseFlightRules(std::string_view contents, std::string_view path, FlightRules& rules, Diagnostics& diag);
/// The file that gives `rules` (every key, in order, with its value).
std::string flightRulesText(const FlightRules& rules);

/// The rules checked every step.
enum class Rule { Stability, Roll, Pitch, JointLimit, WheelLiftoff, WheelForce, Collision, Speed, YawRate, Health };
inline constexpr int kRuleCount = 10;
const char* toString(Rule rule);  ///< "stability", "roll", ... (as in the rules file's key prefixes)

/// One rule's outcome over a run.
struct RuleVerdict {
  Rule rule = Rule::Health;
  bool passed = true;
  // The first violation (when !passed)
  double time = 0;      ///< [s] world time
  std::string where;    ///< the link, joint or wheel ("" for the whole robot)
  double value = 0;     ///< in the rule's unit (degrees for angles)
  double limit = 0;
  // The closest approach to the limit over the run, passed or not
  double worst = 0;
  double worstTime = 0;
  std::string worstWhere;
  /// One line, e.g. "stability: margin -0.12 m < 0.05 m at t = 4.31 s" or
  /// "roll: ok (worst 3.2 deg at t = 2.0 s, limit 25)".
  std::string message() const;
};

/// The convex hull of `points` in the xy plane, counter-clockwise (z kept).
std::vector<Vec3> convexHullXY(std::vector<Vec3> points);

/// The support polygon's margin: the distance [m] from `point` (x, y) to
/// the nearest edge of the convex hull of `support` (x, y), positive inside,
/// negative outside; with fewer than three points the distance to the
/// hull (a point or a segment) taken negative.
double supportMargin(Vec3 point, const std::vector<Vec3>& support);

/// Checks the rules on one robot of a World after each step. A joint that
/// the first check finds within the joint-limit margin (parked at its stop,
/// as a closed gripper is) is exempt from that rule until it leaves the margin.
class RuleMonitor {
 public:
  RuleMonitor(const FlightRules& rules, const RobotModel& robot, int robotIndex = 0);
  /// Goes on checking another form of the same robot (`robot` outlives the
  /// monitor): a rehearsal that welds or frees joints mid-run. The verdicts
  /// so far are kept; wheels and joints carry their state by name, and a
  /// joint it did not watch before is judged parked or not at its next check,
  /// as at the first (it was held still meanwhile).
  void rebind(const RobotModel& robot);
  /// Checks the World's state now (after a step).
  void check(const World& world);
  /// One verdict per Rule, in Rule order.
  const std::vector<RuleVerdict>& verdicts() const { return verdicts_; }
  bool passed() const;
  /// The last stability margin [m] (for plots).
  double margin() const { return margin_; }

 private:
  struct Wheel {
    int link = -1;
    int sensor = -1;  // its wheel_force sensor, -1 if none
    std::string name;
    double offSince = -1;  // [s] world time it left the ground; -1 on the ground
  };
  struct Limited {
    int joint;
    double lower, upper, margin;  // margin in the joint's unit
    bool parked = false;  // within the margin at the first check (a closed gripper): exempt until it leaves
    bool fresh = true;    // not checked yet: its first check decides `parked`
  };
  void bind();  // the per-link and per-joint tables for robot_
  // Records one rule's state: `bad` when the limit is broken; `closeness`
  // orders values for "worst" (larger = closer to breaking).
  void record(Rule rule, bool bad, double value, double limit, double closeness, double time,
              const std::string& where);

  FlightRules rules_;
  const RobotModel* robot_;
  int robotIndex_;
  std::vector<Wheel> wheels_;
  std::vector<Limited> limited_;
  std::vector<bool> touchAllowed_;  // per link: may touch objects
  std::vector<bool> isWheel_;       // per link
  std::vector<RuleVerdict> verdicts_;
  std::vector<double> closest_;     // per rule: closeness of `worst`
  double margin_ = 0;
};

}  // namespace sp
