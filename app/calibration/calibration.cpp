// Calibration from telemetry (app/calibration/calibration.h): the segments,
// the candidate twins, Levenberg-Marquardt, the checks of what was fitted
// (the parameters in calibration_params.cpp, the load fits in calibration_loads.cpp).
#include "app/calibration/calibration.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <tuple>

#include "app/calibration/usable_frames.h"
#include "app/state/parallel_for.h"
#include "app/state/robot_shapes.h"
#include "app/ghost/hold_policy.h"
#include "app/log/resimulation.h"
#include "app/log/session_log.h"
#include "sim/command_file.h"
#include "sim/kinematics.h"
#include "sim/perturbation.h"
#include "sim/rigid.h"
#include "sim/runner.h"
#include "sim/text.h"
#include "sim/world.h"

namespace sp {

using calibration_detail::usableFrames;

namespace {

constexpr int kMass = static_cast<int>(CalParam::Mass);
constexpr int kFitted = kMass;  // the parameters fitted through the twin: all before the mass
// A parameter is unobserved when its deviation is above this share of its
// scale. The first step of a fit takes only those pinned to kFirstStep:
// from the start values the residuals are far from linear, and a step in a
// weakly pinned direction (the tyres' front-rear split) can stall the rest;
// later steps, near the fit, take all within kUnobserved, so that windows
// each too short to pin the split alone pin it fused (docs/performance.md).
constexpr double kUnobserved = 0.5;
constexpr double kFirstStep = 0.25;

/// A duration for the operator: one decimal ("4.0", not "4.000000000000001").
std::string tenths(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", seconds);
  return text;
}

// What one scaled residual is: a deviation of this size counts 1.
struct ResidualScale {
  double position = 0.01;   // [m]
  double heading = 0.01;    // [rad]
  double wheelTurn = 0.2;   // [rad] a wheel's turn since the anchor (contacts make it chatter by ~0.05)
  double articulation = 0.01;  // [rad]
};
constexpr ResidualScale kResidualScale;
constexpr int kPerCheckpoint = 8;  // x, y, heading, 4 wheel rates, articulation

double wrapAngle(double a) { return std::remainder(a, 2 * M_PI); }

// One stretch of telemetry the twin predicts from its first frame.
struct Segment {
  size_t anchor = 0;                // frame index
  std::vector<size_t> checkpoints;  // frame indices compared
};

struct Problem {
  const WorldModel* files = nullptr;
  SimParams profile;
  const std::vector<RobotFrame>* frames = nullptr;
  std::vector<TimedCommand> commands;  // arrival times, in order
  std::vector<Segment> segments;
  std::vector<int> held;     // the full robot's joints held rigid
  std::vector<double> weld;  // where (full robot's joint positions)
  std::array<int, 4> wheels{-1, -1, -1, -1};
  int articulation = -1;
};

// The frame nearest robot time `t`, if one lies within `tolerance`.
std::optional<size_t> frameAt(const std::vector<RobotFrame>& f, double t, double tolerance) {
  const auto it = std::lower_bound(f.begin(), f.end(), t, [](const RobotFrame& r, double x) { return r.time < x; });
  std::optional<size_t> best;
  for (auto c : {it, it == f.begin() ? it : it - 1})
    if (c != f.end() && std::abs(c->time - t) <= tolerance &&
        (!best || std::abs(c->time - t) < std::abs(f[*best].time - t)))
      best = static_cast<size_t>(c - f.begin());
  return best;
}

// Cuts the frames into driving segments whose held joints stay at the weld.
std::vector<Segment> cutSegments(const Problem& pb, const CalibrationOptions& o) {
  const std::vector<RobotFrame>& f = *pb.frames;
  std::vector<Segment> out;
  if (f.size() < 2) return out;
  const double tolerance = 0.6 * std::min(o.checkpoint, 0.05);
  for (double a = f.front().time; a + o.horizon <= f.back().time + 1e-9; a += o.spacing) {
    const std::optional<size_t> anchor = frameAt(f, a, o.spacing / 2);
    if (!anchor) continue;
    Segment s;
    s.anchor = *anchor;
    const double t0 = f[*anchor].time;
    bool ok = true;
    double turning = 0;
    for (double t = t0 + o.checkpoint; t <= t0 + o.horizon + 1e-9; t += o.checkpoint) {
      const std::optional<size_t> c = frameAt(f, t, tolerance);
      if (c) s.checkpoints.push_back(*c);
    }
    for (size_t i = s.anchor; i < f.size() && f[i].time <= t0 + o.horizon + 1e-9 && ok; ++i) {
      for (int j : pb.held)
        if (std::abs(f[i].jointPositions[static_cast<size_t>(j)] - pb.weld[static_cast<size_t>(j)]) > 0.03) ok = false;
      for (int w : pb.wheels)
        if (w >= 0) turning = std::max(turning, std::abs(f[i].jointRates[static_cast<size_t>(w)]));
    }
    // A segment where the wheels stand still teaches nothing of wheels.
    if (ok && turning > 0.2 && s.checkpoints.size() >= 2) out.push_back(std::move(s));
  }
  return out;
}

// The model joint index (in `rigid`'s robot, or the full one) of the full robot's joint `full`.
int modelJoint(const std::optional<RigidRobot>& rigid, int full) {
  if (!rigid || full < 0) return full;
  const auto it = std::find(rigid->jointOf.begin(), rigid->jointOf.end(), full);
  return it == rigid->jointOf.end() ? -1 : static_cast<int>(it - rigid->jointOf.begin());
}

// The scaled residuals of the twin calibrated by `v` over every segment, or
// nullopt and `why` when the twin cannot be built or diverges.
// `turns`, when given, receives each checkpoint's wheel turns since its
// anchor, (twin, robot), for the motor gain's closed form. `jitter` [m]
// lifts every anchor by that much: a run from anchors a micrometre off
// differs from the plain one by the contacts' chaos alone (the noise probe).
std::optional<std::vector<double>> residuals(const Problem& pb, const CalValues& v, std::string& why,
                                             std::vector<std::pair<double, double>>* turns = nullptr,
                                             double jitter = 0) {
  WorldModel model = calibratedWorld(*pb.files, withCalValues(pb.profile, v));
  std::optional<RigidRobot> rigid;
  if (!pb.held.empty()) {
    rigid = holdRigid(model.robots[0].model, pb.weld, pb.held, why);
    if (!rigid) return std::nullopt;
    model.robots[0].model = rigid->model;
  }
  WorldOptions options;
  options.sensors = false;
  Diagnostics diag;
  std::unique_ptr<World> world = World::create(model, pb.profile, diag, options);
  if (!world) {
    why = "the twin cannot be built: " + diag.format();
    return std::nullopt;
  }
  const Snapshot pristine = world->snapshot();
  const RobotModel& robot = world->robotModel(0);
  std::array<int, 4> wheels{};
  for (size_t w = 0; w < 4; ++w) wheels[w] = modelJoint(rigid, pb.wheels[w]);
  const int articulation = modelJoint(rigid, pb.articulation);
  const double delay = v[static_cast<size_t>(CalParam::Delay)];
  const double h = pb.profile.step;
  const std::vector<RobotFrame>& f = *pb.frames;
  std::vector<double> r;
  for (const Segment& s : pb.segments) {
    world->restore(pristine);
    const RobotFrame& a = f[s.anchor];
    // The commands in effect by the anchor set the controllers; the rest
    // fall due during the segment.
    size_t next = 0;
    bool submitted = false;
    for (; next < pb.commands.size() && pb.commands[next].time + delay <= a.time; ++next)
      submitted |= world->submit(pb.commands[next].command).empty();
    if (submitted && !world->step()) {
      why = "the twin diverged applying the commands in effect at " + shortestText(a.time) + " s";
      return std::nullopt;
    }
    const std::vector<double> positions = rigid ? rigidJoints(*rigid, a.jointPositions) : a.jointPositions;
    const std::vector<double> rates = rigid ? rigidJoints(*rigid, a.jointRates) : a.jointRates;
    Pose lifted = a.base;
    lifted.p.z += jitter;
    why = world->setRobotMotion(0, linkMotions(robot, lifted, a.baseLinearVelocity, a.baseAngularVelocity, positions, rates));
    if (!why.empty()) return std::nullopt;
    Runner runner(*world);
    const int64_t start = world->stepCount();
    for (size_t i = next; i < pb.commands.size(); ++i) {
      const double due = pb.commands[i].time + delay - a.time;
      if (due > f[s.checkpoints.back()].time - a.time) break;  // after the segment
      runner.schedule(ScheduledCommand{pb.commands[i].command, 0, start + static_cast<int64_t>(std::ceil(due / h - 1e-9))});
    }
    // How far each wheel turned since the anchor, by the twin and by the
    // robot: rates chatter with the contacts, turns are their integral.
    // Hinge angles wrap: increments between checkpoints (< pi) are summed.
    std::array<double, 4> twinTurn{}, robotTurn{}, twinLast{}, robotLast{};
    for (size_t w = 0; w < 4; ++w)
      if (wheels[w] >= 0) twinLast[w] = robotLast[w] = a.jointPositions[static_cast<size_t>(pb.wheels[w])];
    for (size_t c : s.checkpoints) {
      const int64_t target = start + static_cast<int64_t>(std::floor((f[c].time - a.time) / h + 0.5));
      if (target > world->stepCount() && runner.advanceBy(target - world->stepCount()).stop != RunOutcome::Stop::Reached) {
        why = "the twin diverged at " + shortestText(f[c].time) + " s: " + world->health().message();
        return std::nullopt;
      }
      const Pose base = world->linkPose(0, 0);
      r.push_back((base.p.x - f[c].base.p.x) / kResidualScale.position);
      r.push_back((base.p.y - f[c].base.p.y) / kResidualScale.position);
      r.push_back(wrapAngle(heading(base.q) - heading(f[c].base.q)) / kResidualScale.heading);
      for (size_t w = 0; w < 4; ++w) {
        if (wheels[w] < 0) {
          r.push_back(0);
          continue;
        }
        const double twinNow = world->jointPosition(0, wheels[w]);
        const double robotNow = f[c].jointPositions[static_cast<size_t>(pb.wheels[w])];
        twinTurn[w] += wrapAngle(twinNow - twinLast[w]);
        robotTurn[w] += wrapAngle(robotNow - robotLast[w]);
        twinLast[w] = twinNow;
        robotLast[w] = robotNow;
        r.push_back((twinTurn[w] - robotTurn[w]) / kResidualScale.wheelTurn);
        if (turns) turns->emplace_back(twinTurn[w], robotTurn[w]);
      }
      r.push_back(articulation < 0 ? 0
                                   : (world->jointPosition(0, articulation) -
                                      f[c].jointPositions[static_cast<size_t>(pb.articulation)]) /
                                         kResidualScale.articulation);
    }
  }
  for (double x : r)
    if (!std::isfinite(x)) {
      why = "the twin's prediction is not finite";
      return std::nullopt;
    }
  return r;
}

double meanSquare(const std::vector<double>& r) {
  double s = 0;
  for (double x : r) s += x * x;
  return r.empty() ? 0 : s / static_cast<double>(r.size());
}

// Runs the candidates on up to `threads` threads; a failed one is nullopt.
// A candidate twin: its values, and the noise probe's jitter (residuals()).
struct Candidate {
  CalValues values;
  double jitter = 0;
};

std::vector<std::optional<std::vector<double>>> runAll(const Problem& pb, const std::vector<Candidate>& candidates,
                                                       int threads, std::string& why,
                                                       const std::function<bool()>& abort = {}) {
  std::vector<std::optional<std::vector<double>>> out(candidates.size());
  std::vector<std::string> whys(candidates.size());
  std::mutex asking;  // `abort` is asked from one thread at a time
  parallelFor(candidates.size(), threads, [&](size_t i) {
    if (abort) {
      std::lock_guard lock(asking);
      if (abort()) {
        whys[i] = "cancelled";
        return true;  // every candidate gets its why
      }
    }
    // The candidate fails, not the fit: a twin that throws is a bad candidate.
    try {
      out[i] = residuals(pb, candidates[i].values, whys[i], nullptr, candidates[i].jitter);
    } catch (const std::exception& e) {
      out[i].reset();
      whys[i] = std::string("its twin failed: ") + e.what();
    }
    return true;
  });
  for (size_t i = 0; i < out.size(); ++i)
    if (!out[i]) {
      why = whys[i];
      break;
    }
  return out;
}

// Solves A x = b (n <= kFitted) by Gaussian elimination with partial
// pivoting; false when A is singular.
bool solve(std::vector<std::vector<double>> a, std::vector<double> b, std::vector<double>& x) {
  const size_t n = b.size();
  for (size_t c = 0; c < n; ++c) {
    size_t p = c;
    for (size_t r = c + 1; r < n; ++r)
      if (std::abs(a[r][c]) > std::abs(a[p][c])) p = r;
    if (std::abs(a[p][c]) < 1e-12) return false;
    std::swap(a[p], a[c]);
    std::swap(b[p], b[c]);
    for (size_t r = c + 1; r < n; ++r) {
      const double k = a[r][c] / a[c][c];
      for (size_t k2 = c; k2 < n; ++k2) a[r][k2] -= k * a[c][k2];
      b[r] -= k * b[c];
    }
  }
  x.assign(n, 0);
  for (size_t c = n; c-- > 0;) {
    double s = b[c];
    for (size_t k = c + 1; k < n; ++k) s -= a[c][k] * x[k];
    x[c] = s / a[c][c];
  }
  return true;
}

// The normal matrix J'J and J'r over the parameters `on` (indices into J's columns).
struct Normal {
  std::vector<std::vector<double>> h;
  std::vector<double> g;
};
Normal normalEquations(const std::vector<std::vector<double>>& jac, const std::vector<double>& r, const std::vector<int>& on) {
  Normal n{std::vector<std::vector<double>>(on.size(), std::vector<double>(on.size(), 0)), std::vector<double>(on.size(), 0)};
  for (size_t a = 0; a < on.size(); ++a) {
    const std::vector<double>& ja = jac[static_cast<size_t>(on[a])];
    for (size_t i = 0; i < r.size(); ++i) n.g[a] += ja[i] * r[i];
    for (size_t b = 0; b < on.size(); ++b) {
      const std::vector<double>& jb = jac[static_cast<size_t>(on[b])];
      for (size_t i = 0; i < r.size(); ++i) n.h[a][b] += ja[i] * jb[i];
    }
  }
  return n;
}

// Each parameter's standard deviation (in its own units) given the scaled
// Jacobian columns `jac` (d residual / d (value / scale)); parameters the
// data cannot pin are dropped from `on` one at a time, worst first.
// Observability is judged on the residuals' scales as given (far from the
// fit they are large for want of fitting, not noise): a parameter is
// observed when its deviation is at most `threshold` of its scale. The
// deviations reported are the residuals' own scatter's, grown by
// `correlated`, the residuals that move together (a segment's checkpoints
// share its anchor's error: they count as one), so that fusing fits
// (fuse()) weighs each window for what it is worth: a window the twin
// follows closely counts more than one it follows loosely (a fit that has
// not yet converged). They were floored at the residuals' scales, which
// made every window's about 1.5-2 % on the radius where the fits' errors
// were 0.2-0.3 %, and the fusion weighed the first windows (fitted before
// the splits were pinned) as much as the rest (docs/performance.md).
std::vector<int> observable(const std::vector<std::vector<double>>& jac, const std::vector<double>& r,
                            std::vector<int> on, CalValues& sigma, double correlated, double threshold) {
  const double dof = std::max<double>(1, static_cast<double>(r.size()) - static_cast<double>(on.size()));
  const double inflate = correlated * meanSquare(r) * static_cast<double>(r.size()) / dof;
  while (!on.empty()) {
    const Normal n = normalEquations(jac, r, on);
    // The covariance's diagonal: one solve per unit vector.
    std::vector<double> var(on.size(), INFINITY);
    bool singular = false;
    for (size_t k = 0; k < on.size() && !singular; ++k) {
      std::vector<double> e(on.size(), 0), x;
      e[k] = 1;
      if (!solve(n.h, e, x)) singular = true;
      else var[k] = x[k];
    }
    size_t worst = 0;
    for (size_t k = 0; k < on.size(); ++k)
      if (singular ? n.h[k][k] < n.h[worst][worst] : var[k] > var[worst]) worst = k;
    if (!singular && std::sqrt(var[worst]) <= threshold) {
      for (size_t k = 0; k < on.size(); ++k)
        sigma[static_cast<size_t>(on[k])] = std::sqrt(var[k] * inflate) * calParams()[static_cast<size_t>(on[k])].scale;
      return on;
    }
    on.erase(on.begin() + static_cast<long>(worst));
  }
  return on;
}

// Total mass from the load cells: the mean of sum N / (g cos roll cos pitch)
// over the frames against the files' mass; nullopt without loads.
std::optional<std::pair<double, double>> massFromLoads(const WorldModel& files, const std::vector<RobotFrame>& f) {
  double filesMass = 0;
  for (const LinkSpec& l : files.robots[0].model.links) filesMass += l.mass;
  const double g = norm(files.gravity);
  std::vector<double> x;
  for (const RobotFrame& r : f) {
    const double sum = r.wheelNormal[0] + r.wheelNormal[1] + r.wheelNormal[2] + r.wheelNormal[3];
    if (sum > 0) x.push_back(sum / (g * std::cos(r.roll) * std::cos(r.pitch)) / filesMass);
  }
  if (x.size() < 50 || filesMass <= 0 || g <= 0) return std::nullopt;
  double mean = 0, var = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  for (double v : x) var += (v - mean) * (v - mean);
  var /= static_cast<double>(x.size() - 1);
  // Neighbouring frames are not independent (the body rocks over ~0.2 s):
  // count one sample per 10 frames.
  return std::make_pair(mean, std::sqrt(var / (static_cast<double>(x.size()) / 10)));
}

}  // namespace

namespace {

// The fit's problem over `frames` (usable, oldest first): the twin's
// weld, the commands in order, the driving segments. "" or why not.
std::string makeProblem(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                        const std::vector<TimedCommand>& commands, const CalibrationOptions& o, Problem& pb) {
  const RobotModel& robot = files.robots[0].model;
  pb.files = &files;
  pb.profile = profile;
  pb.frames = &frames;
  std::string why;
  const std::optional<std::vector<int>> held = holdableJoints(robot, profile.ghostHold, "ghost.hold", why);
  if (!held) return why;
  pb.held = *held;
  pb.weld = frames.back().jointPositions;
  pb.wheels = robot.drive->wheels;
  pb.articulation = robot.drive->articulation;
  pb.commands = commands;
  std::stable_sort(pb.commands.begin(), pb.commands.end(), [](const TimedCommand& a, const TimedCommand& b) { return a.time < b.time; });
  pb.segments = cutSegments(pb, o);
  return {};
}

}  // namespace

CalibrationFit fitCalibration(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                              const std::vector<TimedCommand>& commands, const CalEstimate& from, CalibrationOptions options,
                              const std::function<bool()>& abort) {
  options.startSigma = from.sigma;
  return fitCalibration(files, profile, frames, commands, from.value, options, abort);
}

std::vector<double> consideredVariance(const std::vector<std::vector<double>>& jac, const std::vector<int>& on,
                                       const std::vector<int>& held, const CalValues& heldVariance) {
  std::vector<double> add(on.size(), 0);
  if (on.empty() || held.empty()) return add;
  // One normal matrix over both: its `on` block is H_oo, each held one's
  // column below it H_ou.
  std::vector<int> both = on;
  both.insert(both.end(), held.begin(), held.end());
  const Normal n = normalEquations(jac, std::vector<double>(jac[static_cast<size_t>(on[0])].size(), 0), both);
  std::vector<std::vector<double>> hoo(on.size());
  for (size_t k = 0; k < on.size(); ++k) hoo[k].assign(n.h[k].begin(), n.h[k].begin() + static_cast<long>(on.size()));
  for (size_t u = 0; u < held.size(); ++u) {
    std::vector<double> b(on.size()), x;
    for (size_t k = 0; k < on.size(); ++k) b[k] = n.h[k][on.size() + u];
    if (!solve(hoo, b, x)) return std::vector<double>(on.size(), INFINITY);
    for (size_t k = 0; k < on.size(); ++k) add[k] += x[k] * x[k] * heldVariance[static_cast<size_t>(held[u])];
  }
  return add;
}

CalibrationFit fitCalibration(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& in,
                              const std::vector<TimedCommand>& commands, const CalValues& start,
                              const CalibrationOptions& o, const std::function<bool()>& abort) {
  const auto began = std::chrono::steady_clock::now();
  CalibrationFit fit;
  fit.value = start;
  const auto done = [&](std::string refused) {
    if (!refused.empty()) {
      fit.value = start;
      fit.sigma = {};
      fit.observed = {};
    }
    fit.refused = std::move(refused);
    fit.wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - began).count();
    return fit;
  };
  if (files.robots.empty() || !files.robots[0].model.drive) return done("the world has no robot with a drive to calibrate");
  const RobotModel& robot = files.robots[0].model;
  const std::vector<RobotFrame> frames = usableFrames(in, o.window);
  for (const RobotFrame& r : frames)
    if (r.jointPositions.size() != robot.joints.size() || r.jointRates.size() != robot.joints.size())
      return done("telemetry at " + shortestText(r.time) + " s has " + std::to_string(r.jointPositions.size()) +
                  " joints; the robot has " + std::to_string(robot.joints.size()));
  if (frames.size() < 2) return done("not enough telemetry: " + std::to_string(frames.size()) + " usable frames");
  fit.from = frames.front().time;
  fit.to = frames.back().time;

  // The mass: from the loads, whatever the motion.
  if (!o.fixed[kMass])
    if (const auto mass = massFromLoads(files, frames); mass && mass->second / calParam(CalParam::Mass).scale <= kUnobserved) {
      if (mass->first < calParam(CalParam::Mass).lower || mass->first > calParam(CalParam::Mass).upper)
        return done("the loads say the mass is " + shortestText(mass->first) + " x the files', outside [" +
                    shortestText(calParam(CalParam::Mass).lower) + ", " + shortestText(calParam(CalParam::Mass).upper) + "]");
      fit.value[kMass] = mass->first;
      fit.sigma[kMass] = mass->second;
      fit.observed[kMass] = true;
    }
  // The centre of mass: from the same loads.
  if (const auto com = comFromLoads(files, frames))
    for (const auto& [param, value, scatter] : {std::tuple{CalParam::ComX, com->forward, com->sigmaForward},
                                                std::tuple{CalParam::ComY, com->left, com->sigmaLeft}}) {
      const size_t i = static_cast<size_t>(param);
      const CalParamInfo& info = calParams()[i];
      const double sigma = std::hypot(scatter, info.floor);
      if (o.fixed[i] || sigma / info.scale > kUnobserved) continue;
      if (value < info.lower || value > info.upper)
        return done("the loads say " + std::string(info.key) + " = " + shortestText(value) + " m, outside [" +
                    shortestText(info.lower) + ", " + shortestText(info.upper) + "]");
      fit.value[i] = value;
      fit.sigma[i] = sigma;
      fit.observed[i] = true;
    }

  // The tyres' radii: from rolling without slip, through the kinematics
  // alone. Through the twin they were pinned to 0.3-0.7 % at best, and a
  // weakly pinned split soaked up the ghost profile's own bias; rolling
  // pins each wheel to about 0.1 % (docs/performance.md). A window in which
  // a wheel skids leaves them to the twin, which reproduces the skid.
  constexpr size_t kRadius = static_cast<size_t>(CalParam::WheelRadius);
  CalFlags rolled{};
  if (const RollingRadii rr = radiiFromRolling(files, frames); rr.rolled()) {
    const double sum = rr.factor[0] + rr.factor[1] + rr.factor[2] + rr.factor[3];
    const double spread = std::sqrt(rr.sigma[0] * rr.sigma[0] + rr.sigma[1] * rr.sigma[1] + rr.sigma[2] * rr.sigma[2] +
                                    rr.sigma[3] * rr.sigma[3]);
    const std::array<double, 4> radii = radiusValues(rr.factor);
    for (size_t i = kRadius; i < kRadius + radii.size(); ++i) {
      const double value = radii[i - kRadius];
      if (o.fixed[i]) continue;
      const CalParamInfo& info = calParams()[i];
      if (!std::isfinite(value) || value < info.lower || value > info.upper)
        return done("the wheels' rolling says " + std::string(info.key) + " = " + shortestText(value) + ", outside [" +
                    shortestText(info.lower) + ", " + shortestText(info.upper) + "]");
      fit.value[i] = value;
      fit.sigma[i] = i == kRadius ? spread / 4 : 2 * spread / sum;
      fit.observed[i] = rolled[i] = true;
    }
  }

  Problem pb;
  std::string why = makeProblem(files, profile, frames, commands, o, pb);
  if (!why.empty()) return done(why);
  fit.segments = static_cast<int>(pb.segments.size());
  if (fit.segments < o.minSegments) {
    fit.wantsDriving = true;
    return done("not enough driving: " + std::to_string(fit.segments) + " segments of " + shortestText(o.horizon) +
                " s with the wheels turning and the legs still in " + tenths(fit.to - fit.from) +
                " s of telemetry (need " + std::to_string(o.minSegments) + ")");
  }

  // The motor gain in closed form, the rest by Levenberg-Marquardt: the
  // wheels' turns are the motors' own output, so the robot's over the
  // twin's is the gain (least squares through the origin). Left in the fit
  // it shares a valley with the radius (their product sets the speed) that
  // the contacts' noise keeps the finite differences from finding.
  constexpr size_t kGain = static_cast<size_t>(CalParam::MotorGain);
  std::vector<int> free;
  for (int p = 0; p < kFitted; ++p)
    if (!o.fixed[static_cast<size_t>(p)] && !rolled[static_cast<size_t>(p)] && p != static_cast<int>(kGain)) free.push_back(p);
  CalValues v = fit.value;
  std::vector<std::pair<double, double>> turns;
  std::optional<std::vector<double>> r = residuals(pb, v, why, &turns);
  ++fit.twinRuns;
  if (!r) return done("the twin cannot follow the telemetry with the current values: " + why);
  fit.residuals = static_cast<int>(r->size());
  fit.costBefore = fit.costAfter = meanSquare(*r);
  if (!o.fixed[kGain]) {
    double tr = 0, tt = 0;
    for (const auto& [twin, real] : turns) {
      tr += twin * real;
      tt += twin * twin;
    }
    if (tt > 0) {
      const double k = tr / tt;
      double e2 = 0;
      for (const auto& [twin, real] : turns) e2 += (real - k * twin) * (real - k * twin);
      // The four wheels at the checkpoints of one segment move together:
      // count one sample per segment.
      const double perSegment = 4 * std::max(1.0, o.horizon / o.checkpoint);
      const double n = static_cast<double>(turns.size());
      fit.sigma[kGain] = v[kGain] * k * std::sqrt(e2 / std::max(1.0, n - 1) / tt * perSegment);
      fit.observed[kGain] = fit.sigma[kGain] <= kUnobserved * calParams()[kGain].scale;
      if (fit.observed[kGain]) {
        v[kGain] *= k;
        // The ground speed goes as radius x gain: when the start had found
        // it (a refinement) it is kept by moving the radius with the gain;
        // when not (a first fit) the radius stays. Whichever predicts the
        // window better.
        std::vector<Candidate> both{{v, 0}};
        if (!o.fixed[kRadius] && !rolled[kRadius]) {
          both.push_back({v, 0});
          both.back().values[kRadius] /= k;
        }
        const auto runs = runAll(pb, both, o.threads, why);
        fit.twinRuns += static_cast<int>(both.size());
        size_t best = 0;
        for (size_t b = 0; b < runs.size(); ++b)
          if (runs[b] && (!runs[best] || meanSquare(*runs[b]) < meanSquare(*runs[best]))) best = b;
        if (!runs[best]) return done("the twin diverged with the motor gain fitted: " + why);
        v = both[best].values;
        r = runs[best];
        fit.costAfter = meanSquare(*r);
      }
    }
  }
  double lambda = 1e-3;
  std::vector<std::vector<double>> jac(kFitted);
  std::vector<int> on, everSmooth;  // everSmooth: moved the twin more than its noise at some iteration
  std::vector<int> fitted;          // in some step's parameters: the fit sought their best values
  const auto elapsedMs = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - began).count();
  };
  for (int it = 0; it < o.iterations && !free.empty(); ++it) {
    const double iterationBegan = elapsedMs();
    // Central differences, two candidates per free parameter, and the
    // noise probe, in parallel. Contacts make a twin's response partly
    // chaotic: a parameter whose difference moves the residuals less than
    // anchors a micrometre off do only stirs noise and is left out
    // (friction on grip).
    std::vector<Candidate> probes;
    for (int p : free)
      for (double sign : {1.0, -1.0}) {
        CalValues c = v;
        c[static_cast<size_t>(p)] += sign * calParams()[static_cast<size_t>(p)].probe;
        probes.push_back({c, 0});
      }
    probes.push_back({v, 1e-6});
    if (abort && abort()) return done("cancelled");
    const auto runs = runAll(pb, probes, o.threads, why);
    fit.twinRuns += static_cast<int>(probes.size());
    std::vector<int> smooth;
    if (!probes.empty() && !runs.back()) return done("the twin diverged from anchors a micrometre off: " + why);
    double noise = 0;
    for (size_t i = 0; i < r->size(); ++i) noise += ((*runs.back())[i] - (*r)[i]) * ((*runs.back())[i] - (*r)[i]);
    for (size_t k = 0; k < free.size(); ++k) {
      const CalParamInfo& info = calParams()[static_cast<size_t>(free[k])];
      const auto& up = runs[2 * k];
      const auto& down = runs[2 * k + 1];
      if (!up || !down) return done("the twin diverged probing " + std::string(info.key) + ": " + why);
      std::vector<double>& col = jac[static_cast<size_t>(free[k])];
      col.resize(r->size());
      double move = 0;  // the two probes apart, against two noise realisations
      for (size_t i = 0; i < r->size(); ++i) {
        const double apart = (*up)[i] - (*down)[i];
        col[i] = apart / 2 / info.probe * info.scale;
        move += apart * apart;
      }
      if (move > 4 * noise) {
        smooth.push_back(free[k]);
        if (std::find(everSmooth.begin(), everSmooth.end(), free[k]) == everSmooth.end()) everSmooth.push_back(free[k]);
      }
    }
    CalValues sigma{};
    on = observable(jac, *r, smooth, sigma, 1, it == 0 ? kFirstStep : kUnobserved);
    for (int p : free) fit.sigma[static_cast<size_t>(p)] = sigma[static_cast<size_t>(p)];
    if (on.empty()) break;
    for (int p : on)
      if (std::find(fitted.begin(), fitted.end(), p) == fitted.end()) fitted.push_back(p);
    const Normal n = normalEquations(jac, *r, on);
    bool stepped = false;
    for (int attempt = 0; attempt < 4 && !stepped; ++attempt) {
      std::vector<std::vector<double>> a = n.h;
      for (size_t k = 0; k < on.size(); ++k) a[k][k] *= 1 + lambda;
      std::vector<double> minusG(n.g.size()), dx;
      for (size_t k = 0; k < n.g.size(); ++k) minusG[k] = -n.g[k];
      if (!solve(a, minusG, dx)) break;
      CalValues c = v;
      for (size_t k = 0; k < on.size(); ++k)
        c[static_cast<size_t>(on[k])] += dx[k] * calParams()[static_cast<size_t>(on[k])].scale;
      if (abort && abort()) return done("cancelled");
      std::string cwhy;
      std::optional<std::vector<double>> cr = residuals(pb, c, cwhy);
      ++fit.twinRuns;
      if (cr && meanSquare(*cr) < fit.costAfter) {
        v = c;
        r = std::move(cr);
        const double gain = (fit.costAfter - meanSquare(*r)) / fit.costAfter;
        fit.costAfter = meanSquare(*r);
        lambda = std::max(1e-6, lambda / 3);
        stepped = true;
        ++fit.iterations;
        if (gain < 1e-3) it = o.iterations;  // converged
      } else {
        lambda *= 8;
      }
    }
    if (!stepped) break;
    const double now = elapsedMs();
    if (o.budgetMs > 0 && now + (now - iterationBegan) > o.budgetMs) break;  // the next would overrun
  }
  // A fit that predicts the window worse than its start (the contacts'
  // noise can defeat a step) keeps the start's values: nothing learnt.
  if (fit.costAfter > fit.costBefore) {
    for (int p = 0; p < kFitted; ++p)
      if (!rolled[static_cast<size_t>(p)]) v[static_cast<size_t>(p)] = start[static_cast<size_t>(p)];
    fit.costAfter = fit.costBefore;
  }
  // The deviations at the fit, from the residuals' own scatter.
  std::sort(everSmooth.begin(), everSmooth.end());
  if (!everSmooth.empty()) {
    CalValues sigma{};
    on = observable(jac, *r, everSmooth, sigma, std::max(1.0, o.horizon / o.checkpoint), kUnobserved);
    for (int p : free) fit.sigma[static_cast<size_t>(p)] = sigma[static_cast<size_t>(p)];
    // What the window moved with but could not pin stays at the start:
    // the fitted ones carry its uncertainty.
    std::vector<int> held;
    CalValues heldVariance{};
    for (int p : everSmooth)
      if (std::find(on.begin(), on.end(), p) == on.end()) {
        const size_t i = static_cast<size_t>(p);
        held.push_back(p);
        const double s = (o.startSigma[i] > 0 ? o.startSigma[i] : calParams()[i].scale) / calParams()[i].scale;
        heldVariance[i] = s * s;
      }
    const std::vector<double> add = consideredVariance(jac, on, held, heldVariance);
    for (size_t k = 0; k < on.size(); ++k) {
      const size_t i = static_cast<size_t>(on[k]);
      fit.sigma[i] = std::sqrt(fit.sigma[i] * fit.sigma[i] + add[k] * calParams()[i].scale * calParams()[i].scale);
    }
  }
  for (int p : on) fit.observed[static_cast<size_t>(p)] = true;
  for (int p = 0; p < kFitted; ++p) {
    const size_t i = static_cast<size_t>(p);
    if (rolled[i]) continue;  // measured, not fitted
    // Observed is pinned by the data and fitted to it: one pinned only at
    // the last check, never in a step, still has its start value.
    if (i != kGain && (std::find(on.begin(), on.end(), p) == on.end() ||
                       std::find(fitted.begin(), fitted.end(), p) == fitted.end()))
      fit.observed[i] = false;
    if (!fit.observed[i]) {
      fit.sigma[i] = 0;
      v[i] = start[i];  // unobserved: left alone
      continue;
    }
    // Beyond a bound by less than three deviations, or by less than half
    // the parameter's scale (what the fit calls unobserved), is the bound:
    // the ghost's coarser profile can pull a value a little way out (a
    // robot without delay fitted -19 +- 5 ms in a window on flat ground);
    // further is a fit the physics refuses (tyres 1.3x the files').
    const CalParamInfo& info = calParams()[i];
    const double bounded = std::clamp(v[i], info.lower, info.upper);
    if (!std::isfinite(v[i]) || std::abs(v[i] - bounded) > std::max(3 * fit.sigma[i], kUnobserved * info.scale))
      return done(boundsRefusal(info, v[i]));
    v[i] = bounded;
  }
  for (int p = 0; p < kFitted; ++p) fit.value[static_cast<size_t>(p)] = v[static_cast<size_t>(p)];
  return done("");
}

PredictionCheck checkPredictions(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& in,
                                 const std::vector<TimedCommand>& commands, const CalValues& values, double horizon,
                                 double spacing) {
  PredictionCheck out;
  if (files.robots.empty() || !files.robots[0].model.drive) {
    out.problem = "the world has no robot with a drive";
    return out;
  }
  const std::vector<RobotFrame> frames = usableFrames(in, 0);
  if (frames.size() < 2) {
    out.problem = "not enough telemetry";
    return out;
  }
  CalibrationOptions o;
  o.spacing = spacing;
  o.horizon = horizon;
  o.checkpoint = horizon / 2;  // two per segment: the last is the one judged
  Problem pb;
  out.problem = makeProblem(files, profile, frames, commands, o, pb);
  if (!out.problem.empty()) return out;
  const std::optional<std::vector<double>> r = residuals(pb, values, out.problem);
  if (!r) return out;
  size_t at = 0;
  for (const Segment& seg : pb.segments) {
    const size_t last = at + (seg.checkpoints.size() - 1) * kPerCheckpoint;
    out.time.push_back(frames[seg.anchor].time);
    out.position.push_back(std::hypot((*r)[last], (*r)[last + 1]) * kResidualScale.position);
    out.heading.push_back(std::abs((*r)[last + 2]) * kResidualScale.heading);
    at += seg.checkpoints.size() * kPerCheckpoint;
  }
  return out;
}

FullPhysicsCheck fullPhysicsValues(const WorldModel& files, const SimParams& full, const std::vector<RobotFrame>& in,
                                   const std::vector<TimedCommand>& commands, const CalValues& applied, double window,
                                   int threads, const std::function<bool()>& abort) {
  const auto began = std::chrono::steady_clock::now();
  FullPhysicsCheck out;
  out.values = applied;
  if (files.robots.empty() || !files.robots[0].model.drive) {
    out.problem = "the world has no robot with a drive";
    return out;
  }
  const std::vector<RobotFrame> frames = usableFrames(in, window);
  SimParams physics = full;
  physics.ghostHold = "none";  // the full robot: nothing held
  CalibrationOptions o;
  Problem pb;
  out.problem = makeProblem(files, physics, frames, commands, o, pb);
  if (!out.problem.empty()) return out;
  if (pb.segments.size() < static_cast<size_t>(o.minSegments)) {
    out.problem = "not enough driving";
    return out;
  }
  std::vector<Candidate> candidates{{applied, 0}};
  std::vector<size_t> tried;
  for (CalParam p : kFullPhysicsChecked) {
    const size_t i = static_cast<size_t>(p);
    if (applied[i] == calParams()[i].files) continue;
    Candidate c{applied, 0};
    c.values[i] = calParams()[i].files;
    candidates.push_back(c);
    tried.push_back(i);
  }
  if (!tried.empty()) {
    const auto runs = runAll(pb, candidates, threads, out.problem, abort);
    for (const auto& run : runs)
      if (!run) {  // diverged or cancelled: nothing is judged on a part
        if (out.problem.empty()) out.problem = "a full-physics twin failed";
        return out;
      }
    out.problem.clear();
    out.cost = meanSquare(*runs[0]);
    for (size_t k = 0; k < tried.size(); ++k) {
      const double without = meanSquare(*runs[k + 1]);
      out.costWithout[tried[k]] = without;
      if (without <= out.cost) out.values[tried[k]] = calParams()[tried[k]].files;
    }
  }
  out.wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - began).count();
  return out;
}

std::optional<CalibrationInput> calibrationInput(const std::string& path, std::string& error) {
  std::unique_ptr<SessionLogReader> reader = SessionLogReader::open(path, error);
  if (!reader) return std::nullopt;
  std::optional<LoggedWorld> logged = loggedWorld(*reader, path, error);
  if (!logged) return std::nullopt;
  CalibrationInput in;
  in.world = std::move(logged->world);
  in.params = logged->params;
  const std::map<std::string, std::string> meta = reader->meta();
  if (const auto it = meta.find("log_source"); it != meta.end()) in.source = it->second;
  if (const auto it = meta.find("robot_contents"); it != meta.end()) in.robotText = it->second;
  const RobotModel& robot = in.world.robots[0].model;
  for (const LogSample& s : reader->samplesBetween(-1e300, 1e300)) in.frames.push_back(frameFromSample(s, robot.joints.size()));
  for (const LogCommand& c : reader->commands()) {
    std::string why;
    std::optional<Command> command = parseCommand(c.text, why, &robot);
    if (!command) {
      error = path + ": command at " + shortestText(c.time) + " s ('" + c.text + "'): " + why;
      return std::nullopt;
    }
    in.commands.push_back(TimedCommand{c.time, std::move(*command), 0});
  }
  return in;
}

}  // namespace sp
