#include "app/rehearse/rehearsal.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <mutex>

#include "app/state/parallel_for.h"
#include "sim/hash.h"
#include "sim/kinematics.h"
#include "sim/perturbation.h"
#include "sim/random.h"
#include "sim/readout.h"
#include "sim/rigid.h"
#include "sim/runner.h"
#include "sim/text.h"
#include "sim/world.h"

namespace sp {
namespace {

using Clock = std::chrono::steady_clock;

// `rigid` (may be null): the held robot the world runs; joints are reported
// as the full robot's.
RehearsalSample sampleOf(const World& world, double margin, const RigidRobot* rigid) {
  RehearsalSample s;
  s.time = world.time();
  s.base = world.linkPose(0, 0);
  const RobotModel& robot = world.robotModel(0);
  s.jointPositions.resize(robot.joints.size());
  for (size_t j = 0; j < robot.joints.size(); ++j) s.jointPositions[j] = world.jointPosition(0, static_cast<int>(j));
  if (rigid) s.jointPositions = fullJoints(*rigid, s.jointPositions);
  const Vec3 tilted = tilt(s.base.q);
  s.roll = tilted.x;
  s.pitch = tilted.y;
  s.margin = margin;
  const Vec3 v = world.linkLinearVelocity(0, 0);
  s.speed = std::hypot(v.x, v.y);
  return s;
}

double lerp(double a, double b, double f) { return a + (b - a) * f; }

}  // namespace

std::string RehearsalResult::summary() const {
  if (!error.empty()) return error;
  if (cancelled) return "cancelled";
  if (!refused.empty()) return "refused: " + refused.front();
  for (const RuleVerdict& v : verdicts)
    if (!v.passed) return v.message();
  return "passed";
}

std::optional<RehearsalSample> RehearsalResult::at(double time) const {
  if (path.empty() || time < path.front().time || time > path.back().time) return std::nullopt;
  const auto it = std::lower_bound(path.begin(), path.end(), time,
                                   [](const RehearsalSample& s, double t) { return s.time < t; });
  if (it == path.begin()) return *it;
  const RehearsalSample& a = *(it - 1);
  const RehearsalSample& b = *it;
  const double f = b.time > a.time ? (time - a.time) / (b.time - a.time) : 0;
  RehearsalSample s = f < 0.5 ? a : b;  // joints and the rest from the nearer sample
  s.time = time;
  s.base.p = {lerp(a.base.p.x, b.base.p.x, f), lerp(a.base.p.y, b.base.p.y, f), lerp(a.base.p.z, b.base.p.z, f)};
  const double ha = heading(a.base.q);
  const double h = ha + f * std::remainder(heading(b.base.q) - ha, 2 * kPi);
  s.base.q = quatFromAxisAngle({0, 0, 1}, h - heading(s.base.q)) * s.base.q;
  for (size_t j = 0; j < s.jointPositions.size() && j < a.jointPositions.size(); ++j)
    s.jointPositions[j] = lerp(a.jointPositions[j], b.jointPositions[j], f);
  return s;
}

std::vector<int> unmovedJoints(const RobotModel& robot, const std::vector<TimedCommand>& commands) {
  std::vector<bool> moved(robot.joints.size(), false);
  auto mark = [&](const std::string& name) {
    if (const int j = robot.findJoint(name); j >= 0) moved[static_cast<size_t>(j)] = true;
  };
  for (const TimedCommand& c : commands)
    std::visit(
        [&](const auto& cmd) {
          if constexpr (requires { cmd.joint; }) mark(cmd.joint);
        },
        c.command);
  if (robot.drive) {
    if (robot.drive->articulation >= 0) moved[static_cast<size_t>(robot.drive->articulation)] = true;
    for (int w : robot.drive->wheels)
      if (w >= 0) moved[static_cast<size_t>(w)] = true;
  }
  return unmovedSubtrees(robot, moved);
}


namespace {

// The state rehearsals start from, read off `w` (robot 0, its dynamic objects).
RehearsalStart stateOf(const World& w) {
  RobotReadout r = readRobot(w);
  RehearsalStart s{r.base, r.baseLinearVelocity, r.baseAngularVelocity, std::move(r.jointPositions),
                   std::move(r.jointRates), {}};
  for (ObjectReadout& o : r.objects) s.objects.emplace_back(std::move(o.name), o.pose);
  return s;
}

}  // namespace

std::optional<SettledStart> settleWorldStart(const WorldModel& model, const SimParams& params, std::string& why) {
  Diagnostics diag;
  std::unique_ptr<World> w = World::create(model, params, diag);
  if (!w) {
    why = "cannot build the twin: " + diag.format();
    return std::nullopt;
  }
  // Still: the base stays within kSettleDrift of where it was kSettleStill
  // ago (its velocity alone chatters by a centimetre a second on rough
  // ground while it goes nowhere).
  const size_t window = static_cast<size_t>(std::max<int64_t>(1, std::llround(kSettleStill / params.step)));
  std::deque<Vec3> recent;
  std::string last = "it never touched the ground";
  while (w->time() < kSettleLimit) {
    if (!w->step()) {
      why = "the twin diverged while the robot settled: " + w->health().message();
      return std::nullopt;
    }
    bool grounded = false;
    for (const LinkContact& c : w->linkContacts()) grounded = grounded || (c.robot == 0 && (c.terrain || c.object >= 0));
    recent.push_back(w->linkPose(0, 0).p);
    if (recent.size() > window + 1) recent.pop_front();
    if (!grounded) {
      recent.clear();
      continue;
    }
    double drift = 0;
    for (const Vec3& p : recent) drift = std::max(drift, norm(p - recent.front()));
    if (recent.size() > window && drift <= kSettleDrift) return SettledStart{stateOf(*w), w->time()};
    char text[120];
    std::snprintf(text, sizeof text, "its base still moved %.1f mm in the last %.1f s", drift * 1000, kSettleStill);
    last = text;
  }
  char text[80];
  std::snprintf(text, sizeof text, "the robot did not settle within %.0f s of the world's start: ", kSettleLimit);
  why = text + last;
  return std::nullopt;
}

namespace {

// One run in the plan's profile.
RehearsalResult rehearseOnce(const RehearsalPlan& plan, const std::function<bool(double)>& progress) {
  const auto t0 = Clock::now();
  RehearsalResult result;
  result.fast = plan.fast;
  SimParams params = plan.params;
  if (plan.fast) {
    params.step = params.rehearsalFastStep;
    params.iterations = params.rehearsalFastIterations;
  }
  if (plan.world.robots.empty()) {
    result.error = "the world has no robot";
    return result;
  }
  // A twin calibrated to the robot (calibration.* keys) has its physics
  // and acts on each command its delay after it is due, as the robot does.
  const WorldModel calibrated = calibratedWorld(plan.world, params);
  const RobotModel& full = calibrated.robots[0].model;
  std::optional<RehearsalStart> start = plan.start;
  if (!start) {
    // A world places its robot above the ground: judged there, before it
    // has landed, every sequence failed at t = 0. It settles first.
    std::string why;
    const std::optional<SettledStart> settled = settleWorldStart(calibrated, params, why);
    if (!settled) {
      result.error = why;
      return result;
    }
    start = settled->state;
    result.settled = settled->seconds;
  }
  if (start->jointPositions.size() != full.joints.size() || start->jointRates.size() != full.joints.size()) {
    result.error = "the start state has " + std::to_string(start->jointPositions.size()) + " joints, the robot " +
                   std::to_string(full.joints.size());
    return result;
  }
  result.duration = (plan.commands.empty() ? 0.0 : plan.commands.back().time) + params.calDelay + plan.rules.settle;
  std::vector<TimedCommand> acting = plan.commands;
  for (TimedCommand& c : acting) c.time += params.calDelay;
  // The joints no command is moving welded (app/rehearse/held_twin.h),
  // in the fast profile the legs too.
  std::vector<int> legs;
  if (plan.fast && plan.holdUnmoved) {
    std::string why;
    const std::optional<std::vector<int>> named = holdableJoints(full, params.rehearsalFastHold, "rehearsal.fast_hold", why);
    if (!named) {
      result.error = why;
      return result;
    }
    legs = *named;
  }
  HeldTwin twin(calibrated, params, acting, plan.holdUnmoved, legs);
  if (std::string why = twin.start(*start); !why.empty()) {
    result.error = why;
    return result;
  }
  RuleMonitor monitor(plan.rules, twin.world().robotModel(0));
  twin.setSwitchHook([&](const World& w) { monitor.rebind(w.robotModel(0)); });
  twin.setSubmitHook([&](const ScheduledCommand& c, const std::string& why) {
    if (!why.empty())
      result.refused.push_back("line " + std::to_string(c.line) + " at " + shortestText(twin.world().time()) +
                               " s: " + why);
  });
  const int64_t total = std::max<int64_t>(1, std::llround(result.duration / params.step));
  const int64_t sampleEvery = std::max<int64_t>(1, std::llround(RehearsalResult::kSampleInterval / params.step));
  const int64_t progressEvery = std::max<int64_t>(1, total / 100);
  result.path.push_back(sampleOf(twin.world(), 0, twin.rigid()));
  twin.setMonitor([&](const World& w) {
    monitor.check(w);
    if (plan.stopAtFirstFailure && !monitor.passed()) {
      result.stoppedEarly = true;
      return false;
    }
    const int64_t n = w.stepCount();
    if (n % sampleEvery == 0) result.path.push_back(sampleOf(w, monitor.margin(), twin.rigid()));
    if (progress && n % progressEvery == 0 && !progress(static_cast<double>(n) / static_cast<double>(total))) {
      result.cancelled = true;
      return false;
    }
    return true;
  });
  const RunOutcome out = twin.advanceTo(total);
  const World* world = &twin.world();
  result.switches = twin.switches();
  result.heldJoints = twin.heldThroughout();
  if (out.stop == RunOutcome::Stop::Diverged) monitor.check(*world);  // the health verdict
  result.verdicts = monitor.verdicts();
  result.passed = !result.cancelled && monitor.passed() && world->health().healthy() && result.refused.empty();
  result.endHash = world->stateHash();
  result.wallSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

}  // namespace

double refineBand(Rule rule, const SimParams& p) {
  switch (rule) {
    case Rule::Stability: return p.refineStability;
    case Rule::Roll: return p.refineRoll;
    case Rule::Pitch: return p.refinePitch;
    case Rule::JointLimit: return p.refineJointLimit;
    case Rule::WheelLiftoff: return p.refineLiftoff;
    case Rule::WheelForce: return p.refineWheelForce;
    case Rule::Speed: return p.refineSpeed;
    case Rule::YawRate: return p.refineYawRate;
    case Rule::Collision:  // touching or not: a failure refines
    case Rule::Health: return 0;
  }
  return 0;
}

std::string untrusted(const RehearsalResult& fast, const SimParams& params) {
  if (!fast.refused.empty()) return "a command was refused";
  for (const RuleVerdict& v : fast.verdicts) {
    if (!v.passed) return std::string(toString(v.rule)) + " failed";
    // Stopped early, the rules not yet failed have partial margins: the
    // failure above decides.
    const double band = refineBand(v.rule, params);
    if (!fast.stoppedEarly && ruleMargin(v) < band) {
      char text[120];
      std::snprintf(text, sizeof text, "%s %.3g from its limit, within the fast profile's %.3g", toString(v.rule),
                    ruleMargin(v), band);
      return text;
    }
  }
  return fast.passed ? "" : "it did not pass";
}

RehearsalResult rehearse(const RehearsalPlan& plan, const std::function<bool(double)>& progress) {
  RehearsalResult first = rehearseOnce(plan, progress);
  if (!plan.fast || !plan.refine || first.cancelled || !first.error.empty()) return first;
  std::string why = untrusted(first, plan.params);
  if (why.empty()) return first;
  // Near a limit (or past it) the fast profile's error could change the
  // verdict or move the margin by more than 10 %: the full profile decides.
  RehearsalPlan full = plan;
  full.fast = false;
  RehearsalResult r = rehearseOnce(full, progress);
  r.refined = std::move(why);
  r.wallSeconds += first.wallSeconds;
  return r;
}

double ruleMargin(const RuleVerdict& v) {
  // Lower bounds (the stability margin, a joint's distance from its stop):
  // how far above. Upper bounds on a magnitude (roll, pitch, yaw rate are
  // signed: -21.5 deg/s is as near the 60 deg/s limit as +21.5): how far
  // below. Negative once the rule failed, so a run 3 cm outside its
  // support polygon is not as good as one 3 cm inside the limit.
  if (v.rule == Rule::Stability || v.rule == Rule::JointLimit) return v.worst - v.limit;
  return std::abs(v.limit) - std::abs(v.worst);
}

ProfileAgreement compareProfiles(const RehearsalResult& reference, const RehearsalResult& other) {
  ProfileAgreement a;
  const bool margins = !reference.stoppedEarly && !other.stoppedEarly;
  for (const RuleVerdict& r : reference.verdicts)
    for (const RuleVerdict& o : other.verdicts) {
      if (o.rule != r.rule) continue;
      if (o.passed != r.passed) {
        a.sameVerdicts = false;
        a.differ += std::string(a.differ.empty() ? "" : "; ") + toString(r.rule) + ": " +
                    (r.passed ? "passed" : "failed") + ", " + (o.passed ? "passed" : "failed");
      }
      if (!margins) continue;
      const double ref = ruleMargin(r), oth = ruleMargin(o);
      const double change = std::abs(oth - ref) / std::max({std::abs(ref), 0.01 * std::abs(r.limit), 1e-9});
      if (change > a.largestChange) {
        a.largestChange = change;
        a.largestRule = toString(r.rule);
      }
    }
  return a;
}

std::string sequenceText(const std::vector<TimedCommand>& commands, const RobotModel* robot) {
  std::string out;
  for (const TimedCommand& c : commands) out += shortestText(c.time) + " " + toText(c.command, robot) + "\n";
  return out;
}

std::string sequenceHash(const std::string& canonicalText) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(canonicalText)));
  return hex;
}

RehearsalPlan perturbed(const RehearsalPlan& plan, uint64_t seed) {
  RehearsalPlan p = plan;
  Random random(seed);
  auto spread = [&](double range) { return range * (2 * random.uniform() - 1); };
  const FlightRules& r = plan.rules;
  if (plan.estimate) {
    // The robot as the console knows it: the calibration's own parameters
    // (friction and mass among them), which rehearse() applies.
    for (size_t i = 0; i < kCalParams; ++i) {
      const CalParamInfo& info = calParams()[i];
      double& value = p.params.*info.field;
      const double drawn = plan.estimate->observed[i] ? value + plan.estimate->sigma[i] * random.normal()
                                                      : value + spread(info.scale);
      value = std::clamp(drawn, info.lower, info.upper);
    }
  } else {
    p.world.defaultContact.mu *= 1 + spread(r.robustFriction);
    for (ContactSpec& c : p.world.contacts) c.mu *= 1 + spread(r.robustFriction);
    for (LinkSpec& link : p.world.robots[0].model.links) {
      const double f = 1 + spread(r.robustMass);
      link.mass *= f;
      for (GeomSpec& g : link.geoms) g.mass *= f;
    }
  }
  if (p.world.terrain.kind == TerrainSpec::Kind::Heightfield && r.robustTerrain > 0) {
    // A smooth random field: offsets drawn every kTerrainCell metres and
    // interpolated between, so the ground is uncertain the way a survey is,
    // not jagged (independent noise per 5 cm sample makes 40 % slopes).
    constexpr double kTerrainCell = 1.0;
    HeightGrid& g = p.world.terrain.grid;
    const int nx = static_cast<int>(std::ceil(g.width / kTerrainCell)) + 1;
    const int ny = static_cast<int>(std::ceil(g.depth / kTerrainCell)) + 1;
    std::vector<double> coarse(static_cast<size_t>(nx) * ny);
    for (double& c : coarse) c = spread(r.robustTerrain);
    for (int j = 0; j < g.rows; ++j)
      for (int i = 0; i < g.columns; ++i) {
        const double x = i * g.spacingX() / kTerrainCell, y = j * g.spacingY() / kTerrainCell;
        const int x0 = std::min(static_cast<int>(x), nx - 2), y0 = std::min(static_cast<int>(y), ny - 2);
        const double fx = x - x0, fy = y - y0;
        auto at = [&](int a, int b) { return coarse[static_cast<size_t>(b) * nx + a]; };
        g.at(i, j) += (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
                      fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
      }
  }
  const double dx = spread(r.robustStartPosition), dy = spread(r.robustStartPosition);
  const double dyaw = degToRad(spread(r.robustStartHeading));
  Pose& base = p.start ? p.start->base : p.world.robots[0].pose;
  base.p.x += dx;
  base.p.y += dy;
  base.q = quatFromAxisAngle({0, 0, 1}, dyaw) * base.q;
  return p;
}

std::string RobustnessResult::verdict() const {
  char within[64];
  const double w = within90.value_or(0);
  if (w < 0.01) std::snprintf(within, sizeof within, "%.0f mm", w * 1000);
  else std::snprintf(within, sizeof within, "%.0f cm", w * 100);
  return std::string(passed == samples ? "passes" : "fails") + " in " + std::to_string(passed == samples ? passed : samples - passed) +
         " of " + std::to_string(samples) +
         (fromEstimate ? " draws of what the console knows of the robot" : " perturbed rehearsals") +
         (within90 ? std::string("; 90 % of the ends within ") + within : std::string());
}

RobustnessResult robustness(const RehearsalPlan& plan, uint64_t seed, int threads,
                            const std::function<bool(int, int)>& progress) {
  const auto t0 = Clock::now();
  const int n = plan.rules.robustSamples;
  RobustnessResult out;
  out.samples = n;
  out.endPoses.resize(n);
  out.endHashes.resize(n);
  out.failures.resize(n);
  out.paths.resize(n);
  // Per sample, written by the worker threads: chars, not vector<bool>'s
  // shared bits, so two threads never write one word.
  std::vector<char> passed(static_cast<size_t>(n), 0), ranToTheEnd(static_cast<size_t>(n), 0);
  std::atomic<int> done{0}, refined{0};
  std::mutex progressMutex;
  parallelFor(static_cast<size_t>(n), threads, [&](size_t s) {
    const int i = static_cast<int>(s);
    const RehearsalResult r = rehearse(perturbed(plan, seed + static_cast<uint64_t>(i)));
    passed[s] = r.passed;
    out.failures[s] = r.summary();
    if (!r.path.empty()) out.endPoses[s] = r.path.back().base;
    for (const RehearsalSample& q : r.path) out.paths[s].push_back(q.base.p);
    out.endHashes[s] = r.endHash;
    ranToTheEnd[s] = !r.stoppedEarly;
    refined += !r.refined.empty();
    const int d = ++done;
    if (!progress) return true;
    std::lock_guard lock(progressMutex);
    return progress(d, n);  // false: cancelled
  });
  out.samplePassed.assign(passed.begin(), passed.end());
  out.passed = static_cast<int>(std::count(passed.begin(), passed.end(), 1));
  out.refined = refined;
  Vec3 mean;
  const auto ended = std::count(ranToTheEnd.begin(), ranToTheEnd.end(), 1);
  for (size_t k = 0; k < out.endPoses.size(); ++k)
    if (ranToTheEnd[k]) mean = mean + (1.0 / static_cast<double>(ended)) * out.endPoses[k].p;
  std::vector<double> distances;
  for (size_t k = 0; k < out.endPoses.size(); ++k)
    if (ranToTheEnd[k]) {
      distances.push_back(std::hypot(out.endPoses[k].p.x - mean.x, out.endPoses[k].p.y - mean.y));
      out.spread = std::max(out.spread, distances.back());
    }
  if (distances.size() >= 2) {
    std::sort(distances.begin(), distances.end());
    out.within90 = distances[std::min(distances.size() - 1, static_cast<size_t>(std::ceil(0.9 * static_cast<double>(distances.size()))) - 1)];
  }
  out.fromEstimate = plan.estimate.has_value();
  out.wallSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return out;
}

}  // namespace sp
