// Calibration from telemetry (app/calibration/calibration.h): a fit's
// steps, from the loads, the rolling, the motor gain's closed form and
// Levenberg-Marquardt through the twin, and the checks of what was fitted
// (the twins in calibration_twin.cpp, the linear algebra in
// calibration_solver.cpp, the parameters in calibration_params.cpp, the
// load fits in calibration_loads.cpp).
#include "app/calibration/calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <tuple>

#include "app/calibration/calibration_solver.h"
#include "app/calibration/calibration_twin.h"
#include "app/calibration/usable_frames.h"
#include "app/log/resimulation.h"
#include "app/log/session_log.h"
#include "app/state/robot_shapes.h"
#include "sim/command_file.h"
#include "sim/text.h"

namespace sp {

using namespace calibration_detail;

namespace {

constexpr int kMass = static_cast<int>(CalParam::Mass);
constexpr int kFitted = kMass;  // the parameters fitted through the twin: all before the mass
constexpr size_t kRadius = static_cast<size_t>(CalParam::WheelRadius);
constexpr size_t kGain = static_cast<size_t>(CalParam::MotorGain);
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

bool contains(const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); }

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

// The mass and the centre of mass from the loads, whatever the motion:
// into `fit` where the loads pin them; "" or why the fit is refused.
std::string fitFromLoads(const WorldModel& files, const std::vector<RobotFrame>& frames, const CalibrationOptions& o,
                         CalibrationFit& fit) {
  if (!o.fixed[kMass])
    if (const auto mass = massFromLoads(files, frames); mass && mass->second / calParam(CalParam::Mass).scale <= kUnobserved) {
      if (mass->first < calParam(CalParam::Mass).lower || mass->first > calParam(CalParam::Mass).upper)
        return "the loads say the mass is " + shortestText(mass->first) + " x the files', outside [" +
               shortestText(calParam(CalParam::Mass).lower) + ", " + shortestText(calParam(CalParam::Mass).upper) + "]";
      fit.value[kMass] = mass->first;
      fit.sigma[kMass] = mass->second;
      fit.observed[kMass] = true;
    }
  if (const auto com = comFromLoads(files, frames))
    for (const auto& [param, value, scatter] : {std::tuple{CalParam::ComX, com->forward, com->sigmaForward},
                                                std::tuple{CalParam::ComY, com->left, com->sigmaLeft}}) {
      const size_t i = static_cast<size_t>(param);
      const CalParamInfo& info = calParams()[i];
      const double sigma = std::hypot(scatter, info.floor);
      if (o.fixed[i] || sigma / info.scale > kUnobserved) continue;
      if (value < info.lower || value > info.upper)
        return "the loads say " + std::string(info.key) + " = " + shortestText(value) + " m, outside [" +
               shortestText(info.lower) + ", " + shortestText(info.upper) + "]";
      fit.value[i] = value;
      fit.sigma[i] = sigma;
      fit.observed[i] = true;
    }
  return {};
}

// The tyres' radii: from rolling without slip, through the kinematics
// alone. Through the twin they were pinned to 0.3-0.7 % at best, and a
// weakly pinned split soaked up the ghost profile's own bias; rolling
// pins each wheel to about 0.1 % (docs/performance.md). A window in which
// a wheel skids leaves them to the twin, which reproduces the skid.
// Into `fit`, `rolled` marking them; "" or why the fit is refused.
std::string fitFromRolling(const WorldModel& files, const std::vector<RobotFrame>& frames, const CalibrationOptions& o,
                           CalibrationFit& fit, CalFlags& rolled) {
  const RollingRadii rr = radiiFromRolling(files, frames);
  if (!rr.rolled()) return {};
  const double sum = rr.factor[0] + rr.factor[1] + rr.factor[2] + rr.factor[3];
  const double spread = std::sqrt(rr.sigma[0] * rr.sigma[0] + rr.sigma[1] * rr.sigma[1] + rr.sigma[2] * rr.sigma[2] +
                                  rr.sigma[3] * rr.sigma[3]);
  const std::array<double, 4> radii = radiusValues(rr.factor);
  for (size_t i = kRadius; i < kRadius + radii.size(); ++i) {
    const double value = radii[i - kRadius];
    if (o.fixed[i]) continue;
    const CalParamInfo& info = calParams()[i];
    if (!std::isfinite(value) || value < info.lower || value > info.upper)
      return "the wheels' rolling says " + std::string(info.key) + " = " + shortestText(value) + ", outside [" +
             shortestText(info.lower) + ", " + shortestText(info.upper) + "]";
    fit.value[i] = value;
    fit.sigma[i] = i == kRadius ? spread / 4 : 2 * spread / sum;
    fit.observed[i] = rolled[i] = true;
  }
  return {};
}

// Where a fit through the twin stands: the values, their residuals, the
// Jacobian's columns and which parameters did what.
struct TwinFit {
  CalValues v{};
  std::optional<std::vector<double>> r;
  Columns jac = Columns(kFitted);
  std::vector<int> free;        // fitted through the twin (not fixed, rolled or the gain)
  std::vector<int> on;          // pinned at the last judgement
  std::vector<int> everSmooth;  // moved the twin more than its noise at some iteration
  std::vector<int> fitted;      // in some step's parameters: the fit sought their best values
};

// The motor gain in closed form: the wheels' turns are the motors' own
// output, so the robot's over the twin's is the gain (least squares through
// the origin). Left in the fit it shares a valley with the radius (their
// product sets the speed) that the contacts' noise keeps the finite
// differences from finding. "" or why the fit is refused.
std::string fitMotorGain(const Problem& pb, const CalibrationOptions& o, const CalFlags& rolled,
                         const std::vector<std::pair<double, double>>& turns, TwinFit& t, CalibrationFit& fit) {
  double tr = 0, tt = 0;
  for (const auto& [twin, real] : turns) {
    tr += twin * real;
    tt += twin * twin;
  }
  if (!(tt > 0)) return {};
  const double k = tr / tt;
  double e2 = 0;
  for (const auto& [twin, real] : turns) e2 += (real - k * twin) * (real - k * twin);
  // The four wheels at the checkpoints of one segment move together:
  // count one sample per segment.
  const double perSegment = 4 * std::max(1.0, o.horizon / o.checkpoint);
  const double n = static_cast<double>(turns.size());
  fit.sigma[kGain] = t.v[kGain] * k * std::sqrt(e2 / std::max(1.0, n - 1) / tt * perSegment);
  fit.observed[kGain] = fit.sigma[kGain] <= kUnobserved * calParams()[kGain].scale;
  if (!fit.observed[kGain]) return {};
  t.v[kGain] *= k;
  // The ground speed goes as radius x gain: when the start had found it (a
  // refinement) it is kept by moving the radius with the gain; when not (a
  // first fit) the radius stays. Whichever predicts the window better.
  std::vector<Candidate> both{{t.v, 0}};
  if (!o.fixed[kRadius] && !rolled[kRadius]) {
    both.push_back({t.v, 0});
    both.back().values[kRadius] /= k;
  }
  std::string why;
  const auto runs = runAll(pb, both, o.threads, why);
  fit.twinRuns += static_cast<int>(both.size());
  size_t best = 0;
  for (size_t b = 0; b < runs.size(); ++b)
    if (runs[b] && (!runs[best] || meanSquare(*runs[b]) < meanSquare(*runs[best]))) best = b;
  if (!runs[best]) return "the twin diverged with the motor gain fitted: " + why;
  t.v = both[best].values;
  t.r = runs[best];
  fit.costAfter = meanSquare(*t.r);
  return {};
}

// The Jacobian's columns of the free parameters by central differences,
// two candidates per parameter, and the noise probe, in parallel. Contacts
// make a twin's response partly chaotic: a parameter whose difference moves
// the residuals less than anchors a micrometre off do only stirs noise and
// is left out of `smooth` (friction on grip). "" or why the fit is refused.
std::string probeJacobian(const Problem& pb, const CalibrationOptions& o, TwinFit& t, std::vector<int>& smooth,
                          CalibrationFit& fit) {
  std::vector<Candidate> probes;
  for (int p : t.free)
    for (double sign : {1.0, -1.0}) {
      CalValues c = t.v;
      c[static_cast<size_t>(p)] += sign * calParams()[static_cast<size_t>(p)].probe;
      probes.push_back({c, 0});
    }
  probes.push_back({t.v, 1e-6});
  std::string why;
  const auto runs = runAll(pb, probes, o.threads, why);
  fit.twinRuns += static_cast<int>(probes.size());
  if (!runs.back()) return "the twin diverged from anchors a micrometre off: " + why;
  const std::vector<double>& r = *t.r;
  double noise = 0;
  for (size_t i = 0; i < r.size(); ++i) noise += ((*runs.back())[i] - r[i]) * ((*runs.back())[i] - r[i]);
  for (size_t k = 0; k < t.free.size(); ++k) {
    const CalParamInfo& info = calParams()[static_cast<size_t>(t.free[k])];
    const auto& up = runs[2 * k];
    const auto& down = runs[2 * k + 1];
    if (!up || !down) return "the twin diverged probing " + std::string(info.key) + ": " + why;
    std::vector<double>& col = t.jac[static_cast<size_t>(t.free[k])];
    col.resize(r.size());
    double move = 0;  // the two probes apart, against two noise realisations
    for (size_t i = 0; i < r.size(); ++i) {
      const double apart = (*up)[i] - (*down)[i];
      col[i] = apart / 2 / info.probe * info.scale;
      move += apart * apart;
    }
    if (move > 4 * noise) {
      smooth.push_back(t.free[k]);
      if (!contains(t.everSmooth, t.free[k])) t.everSmooth.push_back(t.free[k]);
    }
  }
  return {};
}

// Levenberg-Marquardt over the free parameters the data pins, up to
// o.iterations steps or o.budgetMs. "" or why the fit is refused.
std::string levenbergMarquardt(const Problem& pb, const CalibrationOptions& o, TwinFit& t, CalibrationFit& fit,
                               const std::function<double()>& elapsedMs, const std::function<bool()>& abort) {
  double lambda = 1e-3;
  for (int it = 0; it < o.iterations && !t.free.empty(); ++it) {
    const double iterationBegan = elapsedMs();
    if (abort && abort()) return "cancelled";
    std::vector<int> smooth;
    if (std::string why = probeJacobian(pb, o, t, smooth, fit); !why.empty()) return why;
    CalValues sigma{};
    t.on = observable(t.jac, *t.r, smooth, sigma, 1, it == 0 ? kFirstStep : kUnobserved);
    for (int p : t.free) fit.sigma[static_cast<size_t>(p)] = sigma[static_cast<size_t>(p)];
    if (t.on.empty()) break;
    for (int p : t.on)
      if (!contains(t.fitted, p)) t.fitted.push_back(p);
    const Normal n = normalEquations(t.jac, *t.r, t.on);
    bool stepped = false;
    for (int attempt = 0; attempt < 4 && !stepped; ++attempt) {
      const std::optional<Eigen::VectorXd> dx = levenbergMarquardtStep(n, lambda);
      if (!dx) break;
      CalValues c = t.v;
      for (size_t k = 0; k < t.on.size(); ++k)
        c[static_cast<size_t>(t.on[k])] += (*dx)(static_cast<Eigen::Index>(k)) * calParams()[static_cast<size_t>(t.on[k])].scale;
      if (abort && abort()) return "cancelled";
      std::string cwhy;
      std::optional<std::vector<double>> cr = residuals(pb, c, cwhy);
      ++fit.twinRuns;
      if (cr && meanSquare(*cr) < fit.costAfter) {
        t.v = c;
        t.r = std::move(cr);
        const double gain = (fit.costAfter - meanSquare(*t.r)) / fit.costAfter;
        fit.costAfter = meanSquare(*t.r);
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
  return {};
}

// The deviations at the fit, from the residuals' own scatter; what the
// window moved with but could not pin stays at the start, and the fitted
// ones carry its uncertainty.
void deviationsAtTheFit(const CalibrationOptions& o, TwinFit& t, CalibrationFit& fit) {
  std::sort(t.everSmooth.begin(), t.everSmooth.end());
  if (t.everSmooth.empty()) return;
  CalValues sigma{};
  t.on = observable(t.jac, *t.r, t.everSmooth, sigma, std::max(1.0, o.horizon / o.checkpoint), kUnobserved);
  for (int p : t.free) fit.sigma[static_cast<size_t>(p)] = sigma[static_cast<size_t>(p)];
  std::vector<int> held;
  CalValues heldVariance{};
  for (int p : t.everSmooth)
    if (!contains(t.on, p)) {
      const size_t i = static_cast<size_t>(p);
      held.push_back(p);
      const double s = (o.startSigma[i] > 0 ? o.startSigma[i] : calParams()[i].scale) / calParams()[i].scale;
      heldVariance[i] = s * s;
    }
  const std::vector<double> add = consideredVariance(t.jac, t.on, held, heldVariance);
  for (size_t k = 0; k < t.on.size(); ++k) {
    const size_t i = static_cast<size_t>(t.on[k]);
    fit.sigma[i] = std::sqrt(fit.sigma[i] * fit.sigma[i] + add[k] * calParams()[i].scale * calParams()[i].scale);
  }
}

// What the fit through the twin keeps: observed is pinned by the data and
// fitted to it, within the physical bounds; the rest keeps `start`.
// "" or why the fit is refused.
std::string settle(const CalValues& start, const CalFlags& rolled, TwinFit& t, CalibrationFit& fit) {
  for (int p : t.on) fit.observed[static_cast<size_t>(p)] = true;
  for (int p = 0; p < kFitted; ++p) {
    const size_t i = static_cast<size_t>(p);
    if (rolled[i]) continue;  // measured, not fitted
    // One pinned only at the last check, never in a step, still has its start value.
    if (i != kGain && (!contains(t.on, p) || !contains(t.fitted, p))) fit.observed[i] = false;
    if (!fit.observed[i]) {
      fit.sigma[i] = 0;
      t.v[i] = start[i];  // unobserved: left alone
      continue;
    }
    // Beyond a bound by less than three deviations, or by less than half
    // the parameter's scale (what the fit calls unobserved), is the bound:
    // the ghost's coarser profile can pull a value a little way out (a
    // robot without delay fitted -19 +- 5 ms in a window on flat ground);
    // further is a fit the physics refuses (tyres 1.3x the files').
    const CalParamInfo& info = calParams()[i];
    const double bounded = std::clamp(t.v[i], info.lower, info.upper);
    if (!std::isfinite(t.v[i]) || std::abs(t.v[i] - bounded) > std::max(3 * fit.sigma[i], kUnobserved * info.scale))
      return boundsRefusal(info, t.v[i]);
    t.v[i] = bounded;
  }
  for (int p = 0; p < kFitted; ++p) fit.value[static_cast<size_t>(p)] = t.v[static_cast<size_t>(p)];
  return {};
}

}  // namespace

CalibrationFit fitCalibration(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                              const std::vector<TimedCommand>& commands, const CalEstimate& from, CalibrationOptions options,
                              const std::function<bool()>& abort) {
  options.startSigma = from.sigma;
  return fitCalibration(files, profile, frames, commands, from.value, options, abort);
}

CalibrationFit fitCalibration(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& in,
                              const std::vector<TimedCommand>& commands, const CalValues& start,
                              const CalibrationOptions& o, const std::function<bool()>& abort) {
  const auto began = std::chrono::steady_clock::now();
  const auto elapsedMs = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - began).count();
  };
  CalibrationFit fit;
  fit.value = start;
  const auto done = [&](std::string refused) {
    if (!refused.empty()) {
      fit.value = start;
      fit.sigma = {};
      fit.observed = {};
    }
    fit.refused = std::move(refused);
    fit.wallMs = elapsedMs();
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

  if (std::string why = fitFromLoads(files, frames, o, fit); !why.empty()) return done(why);
  CalFlags rolled{};
  if (std::string why = fitFromRolling(files, frames, o, fit, rolled); !why.empty()) return done(why);

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

  // The motor gain in closed form, the rest by Levenberg-Marquardt.
  TwinFit t;
  for (int p = 0; p < kFitted; ++p)
    if (!o.fixed[static_cast<size_t>(p)] && !rolled[static_cast<size_t>(p)] && p != static_cast<int>(kGain)) t.free.push_back(p);
  t.v = fit.value;
  std::vector<std::pair<double, double>> turns;
  t.r = residuals(pb, t.v, why, &turns);
  ++fit.twinRuns;
  if (!t.r) return done("the twin cannot follow the telemetry with the current values: " + why);
  fit.residuals = static_cast<int>(t.r->size());
  fit.costBefore = fit.costAfter = meanSquare(*t.r);
  if (!o.fixed[kGain])
    if (std::string refused = fitMotorGain(pb, o, rolled, turns, t, fit); !refused.empty()) return done(refused);
  if (std::string refused = levenbergMarquardt(pb, o, t, fit, elapsedMs, abort); !refused.empty()) return done(refused);
  // A fit that predicts the window worse than its start (the contacts'
  // noise can defeat a step) keeps the start's values: nothing learnt.
  if (fit.costAfter > fit.costBefore) {
    for (int p = 0; p < kFitted; ++p)
      if (!rolled[static_cast<size_t>(p)]) t.v[static_cast<size_t>(p)] = start[static_cast<size_t>(p)];
    fit.costAfter = fit.costBefore;
  }
  deviationsAtTheFit(o, t, fit);
  if (std::string refused = settle(start, rolled, t, fit); !refused.empty()) return done(refused);
  // The motors' torque limits last, the rest as fitted: the forces depend on them all.
  CalValues v = fit.value;
  return done(fitMotorTorques(pb, o, v, fit, elapsedMs, abort));
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
  // Each split against the files', one at a time, on the motion, with the
  // motors' limits at the files' (a limit fitted to the forces of wheels
  // that a spurious split makes fight would hold that split up:
  // tst_calibration liveCalibratorChecksSplitsInTheFullPhysics); then the
  // limits on the wheels' forces with the splits as judged (the motion
  // hardly shows a limit).
  // Every candidate's residuals, or nullopt (and out.problem) when one
  // failed: diverged or cancelled, nothing is judged on a part.
  const auto run = [&](const std::vector<Candidate>& candidates) -> std::optional<std::vector<std::vector<double>>> {
    auto runs = runAll(pb, candidates, threads, out.problem, abort);
    std::vector<std::vector<double>> all;
    for (auto& r : runs) {
      if (!r) {
        if (out.problem.empty()) out.problem = "a full-physics twin failed";
        return std::nullopt;
      }
      all.push_back(std::move(*r));
    }
    out.problem.clear();
    return all;
  };
  const auto judge = [&](const CalValues& with, const std::vector<size_t>& checked, double& cost) {
    if (checked.empty()) return true;
    std::vector<Candidate> candidates{{with, 0}};
    for (size_t i : checked) {
      candidates.push_back({with, 0});
      candidates.back().values[i] = calParams()[i].files;
    }
    const auto runs = run(candidates);
    if (!runs) return false;
    cost = meanSquare((*runs)[0]);
    for (size_t k = 0; k < checked.size(); ++k) {
      const double without = meanSquare((*runs)[k + 1]);
      out.costWithout[checked[k]] = without;
      if (without <= cost) out.values[checked[k]] = calParams()[checked[k]].files;
    }
    return true;
  };
  std::vector<size_t> splits, limits;
  CalValues unlimited = applied;
  for (CalParam p : kFullPhysicsChecked) {
    const size_t i = static_cast<size_t>(p);
    const bool limit = isTorqueLimit(p);
    if (limit) unlimited[i] = calParams()[i].files;
    if (applied[i] != calParams()[i].files) (limit ? limits : splits).push_back(i);
  }
  if (!judge(unlimited, splits, out.cost)) {
    out.values = applied;
    return out;
  }
  // Each applied limit L at L, two thirds and one third of the way to the
  // files' and at the files' (a line search, the others as applied): the
  // fits' value, taken from the forces in the ghost's coarser physics, can
  // be right that a motor is weak and wrong by how much (0.15 for a hidden
  // 0.46 on the bumpy field), and a verdict between two values only would
  // then keep the wrong one.
  if (!limits.empty()) {
    const CalValues judged = out.values;  // the splits as judged, the limits as applied
    std::vector<Candidate> candidates{{judged, 0, true}};
    for (size_t i : limits)
      for (int k = 1; k <= kLimitSteps; ++k) {
        candidates.push_back({judged, 0, true});
        candidates.back().values[i] = applied[i] + (calParams()[i].files - applied[i]) * k / kLimitSteps;
      }
    const auto runs = run(candidates);
    if (!runs) {
      out.values = applied;
      return out;
    }
    out.forceCost = meanSquare((*runs)[0]);
    for (size_t l = 0; l < limits.size(); ++l) {
      const size_t i = limits[l];
      double best = out.forceCost;
      for (int k = 1; k <= kLimitSteps; ++k) {
        const size_t c = 1 + l * kLimitSteps + static_cast<size_t>(k - 1);
        const double cost = meanSquare((*runs)[c]);
        if (k == kLimitSteps) out.costWithout[i] = cost;
        if (cost <= best) {  // a tie goes to the files'
          best = cost;
          out.values[i] = candidates[c].values[i];
        }
      }
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
