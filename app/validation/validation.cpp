#include "app/validation/validation.h"

#include <algorithm>
#include <chrono>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "sim/command_file.h"
#include "sim/hash.h"
#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/runner.h"
#include "sim/text.h"
#include "sim/world.h"

namespace sp {
namespace {

using Clock = std::chrono::steady_clock;

std::string num(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

WorldModel loadModel(const ValidationOptions& o, const std::string& relative) {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(o.sourceDir + "/" + relative, diag);
  if (!model) throw std::runtime_error(diag.format());
  return *model;
}

std::unique_ptr<World> makeWorld(const WorldModel& model, const SimParams& params) {
  Diagnostics diag;
  std::unique_ptr<World> w = World::create(model, params, diag);
  if (!w) throw std::runtime_error(diag.format());
  return w;
}

void stepFor(World& w, double seconds) { Runner(w).advanceBy(std::llround(seconds / w.params().step)); }

void requireHealthy(const World& w, const std::string& experiment) {
  if (!w.health().healthy())
    throw std::runtime_error(experiment + ": the twin diverged: " + w.health().message());
}

/// The articulation hinge's position in the world (the robot's centre).
Vec3 hingePoint(const World& w) {
  const RobotModel& robot = w.robotModel(0);
  const JointSpec& hinge = robot.joints[robot.drive->articulation];
  const Pose parent = w.linkPose(0, hinge.parent) * inverse(robot.links[hinge.parent].pose);
  return transformPoint(parent, hinge.anchor);
}

/// Mean normal forces of the four wheel_force sensors (FL, FR, RL, RR).
std::array<double, 4> wheelNormals(const World& w) { return readRobot(w).wheelNormal; }

/// Least-squares circle through points (Kasa): centre and radius.
std::pair<Vec3, double> fitCircle(const std::vector<Vec3>& p) {
  double n = static_cast<double>(p.size()), mx = 0, my = 0;
  for (const Vec3& q : p) {
    mx += q.x / n;
    my += q.y / n;
  }
  double suu = 0, svv = 0, suv = 0, suuu = 0, svvv = 0, suvv = 0, svuu = 0;
  for (const Vec3& q : p) {
    const double u = q.x - mx, v = q.y - my;
    suu += u * u, svv += v * v, suv += u * v;
    suuu += u * u * u, svvv += v * v * v, suvv += u * v * v, svuu += v * u * u;
  }
  const double det = suu * svv - suv * suv, b0 = (suuu + suvv) / 2, b1 = (svvv + svuu) / 2;
  const double uc = (b0 * svv - b1 * suv) / det, vc = (suu * b1 - suv * b0) / det;
  return {{uc + mx, vc + my, 0}, std::sqrt(uc * uc + vc * vc + (suu + svv) / n)};
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}

/// Centred moving average over `window` samples (the plots show trends;
/// the quick solver's contact forces jitter from step to step).
std::vector<double> smooth(const std::vector<double>& v, size_t window) {
  std::vector<double> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    const size_t lo = i >= window / 2 ? i - window / 2 : 0, hi = std::min(v.size(), i + window / 2 + 1);
    double sum = 0;
    for (size_t k = lo; k < hi; ++k) sum += v[k];
    out[i] = sum / static_cast<double>(hi - lo);
  }
  return out;
}

/// Slope of y over x by least squares.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double mx = mean(x), my = mean(y);
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxx > 0 ? sxy / sxx : 0;
}

}  // namespace

LinearFit linearFit(const std::vector<double>& x, const std::vector<double>& y) {
  LinearFit f;
  if (x.size() < 2 || x.size() != y.size()) return f;
  f.slope = slope(x, y);
  f.intercept = mean(y) - f.slope * mean(x);
  const double my = mean(y);
  double residual = 0, total = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double e = y[i] - (f.intercept + f.slope * x[i]);
    residual += e * e;
    total += (y[i] - my) * (y[i] - my);
  }
  f.r2 = total > 0 ? 1 - residual / total : 0;
  return f;
}

double proportionalityMismatch(const ErrorSeries& a, const ErrorSeries& b, double floor) {
  std::vector<double> mismatch;
  // The instants both have (a beam out of range gives no sample).
  for (size_t i = 0, j = 0; i < a.times.size() && j < b.times.size();) {
    if (a.times[i] < b.times[j] - 1e-9) {
      ++i;
    } else if (b.times[j] < a.times[i] - 1e-9) {
      ++j;
    } else {
      if (std::abs(b.errors[j]) >= floor && a.ranges[i] > 0 && b.ranges[j] > 0) {
        const double perMetreA = a.errors[i] / a.ranges[i], perMetreB = b.errors[j] / b.ranges[j];
        mismatch.push_back(std::abs(perMetreB - perMetreA) / std::abs(perMetreB));
      }
      ++i, ++j;
    }
  }
  if (mismatch.empty()) return std::numeric_limits<double>::infinity();
  std::sort(mismatch.begin(), mismatch.end());
  return mismatch[mismatch.size() / 2];
}

namespace {

std::string solverText(const SimParams& p) {
  return "step " + num(p.step * 1000, 1) + " ms, " +
         (p.solver == Solver::Quick ? "quick solver " + std::to_string(p.iterations) + " iterations"
                                    : std::string("exact solver")) +
         ", ERP " + num(p.erp, 2) + ", CFM " + num(p.cfm * 1e6, 1) + "e-6";
}

}  // namespace

namespace {

// "Validation: 2 criteria against the paper (1 failed); verification: ..."
std::string checkedAgainst(const ExperimentResult& r) {
  std::string out;
  for (Basis b : {Basis::Paper, Basis::Mathematics, Basis::Solver, Basis::Control}) {
    int judged = 0, failed = 0;
    for (const Metric& m : r.metrics)
      if (m.judged && m.basis == b) ++judged, failed += !m.pass;
    if (judged == 0) continue;
    std::string text = basisText(b);
    text[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[0])));
    out += (out.empty() ? "" : "; ") + text + ", " + std::to_string(judged) + (judged == 1 ? " criterion" : " criteria") +
           (failed ? " (" + std::to_string(failed) + " failed)" : "");
  }
  return (out.empty() ? "Nothing judged" : out) + ".";
}

}  // namespace

const char* basisText(Basis b) {
  switch (b) {
    case Basis::Paper: return "validation: the paper";
    case Basis::Mathematics: return "verification: mathematics";
    case Basis::Solver: return "numerics: the solver";
    case Basis::Control: return "control";
  }
  return "";
}

bool ExperimentResult::pass() const {
  return std::all_of(metrics.begin(), metrics.end(), [](const Metric& m) { return !m.judged || m.pass; });
}

// The circular errors [%] are near zero: converged means within a tenth of
// a percentage point, a fifth of the 0.5 % the paper's error allows.
constexpr double kCircularConverged = 0.1;

// 1. Articulation hinge held at several angles, wheel speeds from the
// articulated-steering kinematics; the hinge's path against the model circle.
ExperimentResult circularDrive(const ValidationOptions& o) {
  ExperimentResult r;
  r.number = 1;
  r.title = "Circular drive";
  const WorldModel model = loadModel(o, "terrains/flat.world.xml");
  // The quick suite records as long as the full one: over 8 s the arc at
  // 10 deg is 36 degrees of the circle and the fitted radius moved the
  // commanded-angle verdict (-1.1 % against -0.31 % over 20 s), and the
  // quick suite must give the full one's verdicts (issue 29). 3 s of wall time.
  const double speed = 0.5, settle = 3, record = 20;
  r.conditions = "terrains/flat.world.xml (rubber on ground, mu 1.0); drive " + num(speed, 1) +
                 " m/s at the hinge; " + num(settle, 0) + " s to settle, then the hinge point's path over " +
                 num(record, 0) + " s is fitted with a circle";
  PlotSpec paths{"Circular drive: path of the articulation hinge", "x [m]", "y [m]", {}, 900, 900, {}, {}};
  // The quick suite checks every angle the full one does.
  const std::vector<double> angles = {10, 20, 30};
  double worst = 0;
  for (double gammaDeg : angles) {
    auto w = makeWorld(model, o.params);
    w->submit(DriveCmd{speed, degToRad(gammaDeg)});
    stepFor(*w, settle);
    std::vector<Vec3> points;
    DriveGeometry mean{};
    int n = 0;
    const auto samples = std::llround(record / 0.02);
    for (int64_t i = 0; i < samples; ++i) {
      stepFor(*w, 0.02);
      points.push_back(hingePoint(*w));
      const DriveGeometry g = *w->driveGeometry(0);
      mean.frontLength += g.frontLength, mean.rearLength += g.rearLength, mean.articulation += g.articulation;
      ++n;
    }
    requireHealthy(*w, r.title);
    mean.frontLength /= n, mean.rearLength /= n, mean.articulation /= n;
    const auto [centre, radius] = fitCircle(points);
    // The kinematic radius for a hinge angle (workpartner-facts.md §3).
    const auto kinematic = [&](double gamma) {
      const double rRear = (mean.frontLength + mean.rearLength * std::cos(gamma)) / std::sin(gamma);
      return std::hypot(mean.rearLength, rRear);
    };
    const double expected = kinematic(mean.articulation), nominal = kinematic(degToRad(gammaDeg));
    const double error = 100 * (radius - expected) / expected;
    const double nominalError = 100 * (radius - nominal) / nominal;
    worst = std::max(worst, std::abs(error));
    r.metrics.push_back({"hinge path radius at " + num(gammaDeg, 0) + " deg, measured hinge angle " +
                             num(radToDeg(mean.articulation), 3) + " deg: model " + num(expected, 3) +
                             " m, simulated " + num(radius, 3) + " m; error",
                         "about 0.5", error, "%", "|error| <= 0.5 %", std::abs(error) <= 0.5, true, Basis::Mathematics,
                         kCircularConverged});
    r.metrics.push_back({"the same against the commanded (nominal) hinge angle: model " + num(nominal, 3) + " m; error",
                         "about 0.5", nominalError, "%", "|error| <= 0.5 %", std::abs(nominalError) <= 0.5, true,
                         Basis::Paper, kCircularConverged});
    PlotSeries path{"simulated, " + num(gammaDeg, 0) + " deg", {}, {}, PlotSeries::Style::Line};
    for (const Vec3& p : points) {
      path.x.push_back(p.x);
      path.y.push_back(p.y);
    }
    PlotSeries circle{"kinematic circle, " + num(gammaDeg, 0) + " deg", {}, {}, PlotSeries::Style::Points};
    for (int k = 0; k < 72; ++k) {
      const double a = 2 * kPi * k / 72;
      circle.x.push_back(centre.x + expected * std::cos(a));
      circle.y.push_back(centre.y + expected * std::sin(a));
    }
    paths.series.push_back(std::move(path));
    paths.series.push_back(std::move(circle));
    r.simSeconds += settle + record;
  }
  r.plots.push_back({"circular_paths", paths});
  r.discussion =
      "With the hinge held at gamma, both axle lines meet in one instantaneous centre, and the hinge runs on "
      "a circle of radius R_H = sqrt(L_r^2 + R_r^2), R_r = (L_f + L_r cos gamma) / sin gamma "
      "(workpartner-facts.md §3), with L_f, L_r and gamma measured on the twin during the run (they move "
      "slightly with the legs). The wheel speeds come from the same kinematics, recomputed every step. The "
      "criterion uses the measured hinge angle, as an experimenter with an encoder on the hinge would; the "
      "largest deviation is " + num(worst, 2) + " %, the compliance of the contacts and joints under the "
      "tyres' side forces (at ERP 0.2 it was about 0.5 %, see config/defaults.params). The paper's 0.5 % is "
      "judged against the commanded geometry too, as an operator would see it: there the error also holds "
      "the hinge controller's error under the steering load and the legs' give.";
  return r;
}

// 2. The torso turns at a constant rate in front of a wall; the laser's
// range error against time and distance, with the wall at three distances.
namespace {

struct LaserSweep {
  std::vector<double> times, distances, trueError, commandError, angleError;
  double simSeconds = 0;
};

// The waist turns from `from` degrees at `rateDeg` deg/s for `seconds` with
// the wall's face `face` metres ahead of the hinge; the beam along the
// torso's heading, every scan.
LaserSweep sweepWall(WorldModel m, const SimParams& params, int wall, double face, double from, double rateDeg,
                     double seconds, const std::string& experiment) {
  m.objects[static_cast<size_t>(wall)].pose.p.x += face - 6;
  auto w = makeWorld(m, params);
  const RobotModel& robot = w->robotModel(0);
  const int laser = robot.findSensor("laser");
  const int waist = robot.findJoint("waist_yaw");
  w->submit(JointTargetCmd{"waist_yaw", degToRad(from)});
  stepFor(*w, 4);
  w->submit(JointVelocityCmd{"waist_yaw", degToRad(rateDeg)});
  const double t0 = w->time(), angle0 = w->jointPosition(0, waist);
  LaserSweep sw;
  int64_t lastStep = -1;
  Runner runner(*w);
  while (w->time() < t0 + seconds - 1e-9) {
    runner.advanceBy(1);
    const SensorSample& s = w->sensorSample(0, laser);
    if (s.step == lastStep) continue;
    lastStep = s.step;
    const auto& scan = std::get<LaserReading>(s.value);
    const double measured = scan.ranges[scan.ranges.size() / 2];
    const Vec3 dir = rotate(scan.sensorPose.q, {1, 0, 0});
    const Vec3 p = scan.sensorPose.p;
    const double truth = (face - p.x) / dir.x;
    // What the paper's experimenters compared with: the pose the commanded
    // rate implies, integrated from the start of the sweep.
    const double heading = std::atan2(dir.y, dir.x);
    const double actualAngle = w->jointPosition(0, waist);
    const double commanded = angle0 + degToRad(rateDeg) * (s.time - t0);
    const double expectedFromCommand = (face - p.x) / std::cos(heading + (commanded - actualAngle));
    if (!std::isfinite(measured)) continue;
    sw.times.push_back(s.time - t0);
    sw.distances.push_back(measured);
    sw.trueError.push_back(measured - truth);
    sw.commandError.push_back(measured - expectedFromCommand);
    sw.angleError.push_back(radToDeg(actualAngle - commanded));
  }
  requireHealthy(*w, experiment);
  sw.simSeconds = w->time();
  return sw;
}

// The largest difference between two sweeps' range errors against the
// commanded pose over a's samples from `after` on, b interpolated linearly
// at a's times (the two runs' scans need not fall on the same
// instants at different steps).
double largestRangeDifference(const LaserSweep& a, const LaserSweep& b, double after) {
  double worst = 0;
  for (size_t i = 0; i < a.times.size(); ++i) {
    if (a.times[i] < after) continue;
    const auto next = std::lower_bound(b.times.begin(), b.times.end(), a.times[i]);
    if (next == b.times.begin() || next == b.times.end()) continue;
    const size_t k = static_cast<size_t>(next - b.times.begin());
    const double f = (a.times[i] - b.times[k - 1]) / (b.times[k] - b.times[k - 1]);
    const double other = b.commandError[k - 1] + f * (b.commandError[k] - b.commandError[k - 1]);
    worst = std::max(worst, std::abs(a.commandError[i] - other));
  }
  return worst;
}

}  // namespace

ExperimentResult laserSweep(const ValidationOptions& o) {
  ExperimentResult r;
  r.number = 2;
  r.title = "Laser scanner";
  WorldModel model = loadModel(o, "terrains/laser_wall.world.xml");
  const RobotModel& robot = model.robots[0].model;
  const int scanner = robot.findSensor("laser");
  if (scanner < 0) throw std::runtime_error("laser_wall.world.xml: the robot has no sensor named 'laser'");
  const double noise = robot.sensors[static_cast<size_t>(scanner)].noise;  // the scanner's, one deviation [m]
  for (SensorSpec& s : model.robots[0].model.sensors) s.noise = 0;  // the error of the model, not of noise
  int wall = -1;
  for (size_t i = 0; i < model.objects.size(); ++i)
    if (model.objects[i].name == "wall") wall = static_cast<int>(i);
  if (wall < 0) throw std::runtime_error("laser_wall.world.xml has no object named 'wall'");
  const double rateDeg = 15, from = -45, sweep = 90 / rateDeg, jitter = 0.5;
  const double walls[] = {3, 6, 9};  // [m] the wall's face ahead of the hinge; 6 m is the paper's
  SimParams converged = o.params, ghost = o.params;
  // Nearer convergence in both the step and the iterations, whatever the
  // suite's own setting (its share of error is what is judged).
  converged.step = std::min(o.params.step, 0.001);
  converged.iterations = 200;
  const std::string nearerPhysics = num(converged.step * 1000, 1) + " ms, " + std::to_string(converged.iterations) +
                                    " iterations";
  ghost.solver = Solver::Quick;  // the ghost's physics, whatever the suite runs
  ghost.step = o.params.ghostStep;
  ghost.iterations = o.params.ghostIterations;
  r.conditions = "terrains/laser_wall.world.xml, the wall's face moved to 3, 6 and 9 m ahead of the hinge (6 m in "
                 "the paper); laser noise off; the waist turns from " + num(from, 0) + " deg at " + num(rateDeg, 0) +
                 " deg/s (velocity mode) for " + num(sweep, 0) + " s; the beam along the torso's heading is compared "
                 "with the wall; fits start " + num(jitter, 1) + " s into the sweep (after the start-up jitter). "
                 "The 6 m sweep again at " + nearerPhysics + " (nearer "
                 "convergence, the reference) and in the ghost's physics (" + num(ghost.step * 1000, 0) + " ms, " +
                 std::to_string(ghost.iterations) + " iterations; the control)";
  std::vector<LaserSweep> sweeps;
  for (double face : walls) sweeps.push_back(sweepWall(model, o.params, wall, face, from, rateDeg, sweep, r.title));
  const LaserSweep reference = sweepWall(model, converged, wall, 6, from, rateDeg, sweep, r.title);
  const LaserSweep coarse = sweepWall(model, ghost, wall, 6, from, rateDeg, sweep, r.title);
  for (const LaserSweep& sw : sweeps) r.simSeconds += sw.simSeconds;
  r.simSeconds += reference.simSeconds + coarse.simSeconds;
  const LaserSweep& paper = sweeps[1];
  double worstTrue = 0;
  for (const LaserSweep& sw : sweeps)
    for (double e : sw.trueError) worstTrue = std::max(worstTrue, std::abs(e));
  // A line through a sweep's samples after the start-up jitter.
  const auto fit = [&](const LaserSweep& sw, const std::vector<double> LaserSweep::*series) {
    std::vector<double> t, y;
    for (size_t i = 0; i < sw.times.size(); ++i)
      if (sw.times[i] >= jitter) {
        t.push_back(sw.times[i]);
        y.push_back((sw.*series)[i]);
      }
    return linearFit(t, y);
  };
  const LinearFit angleFit = fit(paper, &LaserSweep::angleError);
  const LinearFit rangeFit = fit(paper, &LaserSweep::commandError);
  const LinearFit angleConverged = fit(reference, &LaserSweep::angleError);
  const LinearFit rangeConverged = fit(reference, &LaserSweep::commandError);
  const double solverShare = largestRangeDifference(paper, reference, jitter);
  const double ghostShare = largestRangeDifference(coarse, reference, jitter);
  const double proportional =
      proportionalityMismatch({sweeps[0].times, sweeps[0].distances, sweeps[0].commandError},
                              {sweeps[2].times, sweeps[2].distances, sweeps[2].commandError}, 0.5e-3);
  // Judged only what can fail, and what does not rest on solver error.
  // Ranges against the true pose are exact by construction (analytic ray
  // casting, tst_sensors tests it) and the per-metre agreement of the walls
  // is an identity (d tan(phi) dphi): both for the record. The paper's
  // linear growth is, by its own account, its integrator's error: a
  // converged twin has none, so the line through our range error is for
  // the record too (at the default it is the solver's drift plus the
  // geometry of a constant offset, converged the geometry alone). What is
  // judged is how much of the scan is our solver's error.
  r.metrics.push_back({"for the record: largest range error against the scanner's true pose, all three walls (exact "
                       "ray casting, tested in tst_sensors)",
                       "", worstTrue * 1000, "mm", "", false, false});
  r.metrics.push_back({"for the record: torso angle drift against the commanded rate after the start-up, linear fit "
                       "over time (" + num(angleConverged.slope * 1000, 3) + " mdeg/s at " +
                           nearerPhysics + ": the drift shrinks as the solver converges)",
                       "the integrator error grew linearly", angleFit.slope * 1000, "mdeg/s", "", false, false});
  r.metrics.push_back({"for the record: range error against the commanded pose, 6 m wall: linear fit over time, R^2 (" +
                           num(rangeConverged.r2, 3) + " at " + nearerPhysics + ": the geometry of a constant angle offset)",
                       "grew linearly with time", rangeFit.r2, "", "", false, false});
  Metric share{"range error against the commanded pose, 6 m wall: largest difference from the run at " +
                   nearerPhysics + " (nearer convergence) after the start-up: the "
                   "solver's share",
               "", solverShare * 1000, "mm", "<= " + num(noise * 1000, 0) + " mm (the scanner's noise, robot file)",
               solverShare <= noise};
  share.basis = Basis::Solver;
  r.metrics.push_back(share);
  r.metrics.push_back({"control: the same in the ghost's physics (" + num(ghost.step * 1000, 0) + " ms, " +
                           std::to_string(ghost.iterations) + " iterations; must fail the test)",
                       "", ghostShare * 1000, "mm", "> " + num(noise * 1000, 0) + " mm", ghostShare > noise, true,
                       Basis::Control});
  r.metrics.push_back({"for the record: range error per metre of range, 9 m wall against 3 m wall at the same "
                       "instants, median relative difference (an identity: d tan(phi) dphi)",
                       "proportional to the distance", proportional * 100, "%", "", false, false});
  const std::string nearer = "the same, " + nearerPhysics + " (nearer convergence)";
  PlotSpec vsTime{"Laser: range error against time (6 m wall)", "time since the sweep started [s]",
                  "range error [mm]", {}, 960, 540, {}, {}};
  const auto errors = [](const std::string& name, const LaserSweep& sw, const std::vector<double> LaserSweep::*series) {
    PlotSeries out{name, sw.times, {}, PlotSeries::Style::Line};
    for (double e : sw.*series) out.y.push_back(e * 1000);
    return out;
  };
  vsTime.series = {errors("against the true scanner pose", paper, &LaserSweep::trueError),
                   errors("against the pose the commanded rate implies", paper, &LaserSweep::commandError),
                   errors(nearer, reference, &LaserSweep::commandError)};
  PlotSpec vsDistance{"Laser: range error against the commanded pose, by distance", "measured range [m]",
                      "range error [mm]", {}, 960, 540, {}, {}};
  for (size_t k = 0; k < sweeps.size(); ++k) {
    PlotSeries d{"wall at " + num(walls[k], 0) + " m", sweeps[k].distances, {}, PlotSeries::Style::Points};
    for (double e : sweeps[k].commandError) d.y.push_back(e * 1000);
    vsDistance.series.push_back(std::move(d));
  }
  PlotSpec angle{"Laser: torso angle error against the commanded rotation", "time since the sweep started [s]",
                 "angle error [deg]", {}, 960, 400, {}, {}};
  PlotSeries fitted{"linear fit from " + num(jitter, 1) + " s", {}, {}, PlotSeries::Style::Line};
  for (double x : paper.times)
    if (x >= jitter) {
      fitted.x.push_back(x);
      fitted.y.push_back(angleFit.intercept + angleFit.slope * x);
    }
  angle.series = {{"torso (waist) angle - commanded", paper.times, paper.angleError, PlotSeries::Style::Line},
                  {nearer, reference.times, reference.angleError, PlotSeries::Style::Line},
                  fitted};
  r.plots.push_back({"laser_error_time", vsTime});
  r.plots.push_back({"laser_error_distance", vsDistance});
  r.plots.push_back({"laser_angle_error", angle});
  const auto last = [](const std::vector<double>& v) { return v.empty() ? 0.0 : v.back(); };
  r.discussion =
      "What the paper saw is, by its own account, its integrator's error: after an initial jitter the torso's "
      "angle fell behind the commanded rotation at a steady rate, so the range error against the commanded pose "
      "grew with time and with the distance. Our twin shows the same at its default physics: after the start-up "
      "the torso drifts at " + num(angleFit.slope * 1000, 2) + " mdeg/s against the commanded rate (the quick "
      "solver leaves the waist's velocity motor a little short of its set-point each step). Closer to convergence (" +
      nearerPhysics + ") it drifts at " + num(angleConverged.slope * 1000, 3) +
      " mdeg/s, and the angle keeps nearly the offset the start-up left (" + num(last(reference.angleError), 4) +
      " deg at the end), as an ideal velocity loop would. So the paper's linear growth is not a property of the robot that "
      "a twin should reproduce, and it is not judged: it would judge our solver's error. The line through our "
      "range error (R^2 " + num(rangeFit.r2, 3) + " at the default, " + num(rangeConverged.r2, 3) +
      " at " + nearerPhysics + ") is mostly geometry: a constant angle offset "
      "dphi moves a beam meeting the wall at angle phi by d tan(phi) dphi, which runs from one sign to the other as the beam sweeps across the wall's normal, so "
      "it is for the record, as are the exact ranges against the true pose (largest error " +
      num(worstTrue * 1e9, 3) + " nm: analytic ray casting) and the error's proportionality to the distance (per "
      "metre the 3 m and 9 m walls agree within " + num(proportional * 100, 3) + " %, an identity). What is "
      "judged is numerics: how much of the scan an operator sees is our solver's error. At the 6 m wall the "
      "range error against the commanded pose differs from the run at " + nearerPhysics +
      " by at most " +
      num(solverShare * 1000, 2) + " mm after the start-up (its own runs from " +
      num(paper.commandError.empty() ? 0 : paper.commandError.front() * 1000, 1) + " to " +
      num(last(paper.commandError) * 1000, 1) + " mm), within the scanner's noise of " + num(noise * 1000, 0) +
      " mm (one deviation, robot file), so the solver's drift does not show in a scan; in the ghost's coarser "
      "physics the same difference is " + num(ghostShare * 1000, 1) + " mm (the control, which must fail).";
  return r;
}

// 3. Pick and place: drive to a pole across two cubes, lift it, carry it to
// a second pair and lay it down; the wheel forces on the way. The pole's
// effect on the axles is measured in one pose: the same sequence run again
// without the pole gives the robot's own loads in every pose.
namespace {

struct PickPlaceRun {
  std::vector<double> t, fl, fr, rl, rr, poleZ;
  Pose poleEnd;
  double seconds = 0;
  // Mean axle loads (front pair, rear pair) over a time window.
  std::pair<double, double> axles(double from, double to) const {
    std::vector<double> front, rear;
    for (size_t i = 0; i < t.size(); ++i)
      if (t[i] >= from && t[i] < to) {
        front.push_back(fl[i] + fr[i]);
        rear.push_back(rl[i] + rr[i]);
      }
    return {mean(front), mean(rear)};
  }
};

PickPlaceRun runPickPlace(const WorldModel& model, const SimParams& params, const std::vector<TimedCommand>& seq,
                          int pole, double end, const std::string& experiment) {
  auto w = makeWorld(model, params);
  PickPlaceRun run;
  Runner runner(*w);
  runner.schedule(seq);
  const int64_t sampleSteps = std::llround(0.01 / w->params().step);
  while (w->time() < end - 1e-9 && w->health().healthy()) {
    runner.advanceBy(sampleSteps);
    const std::array<double, 4> f = wheelNormals(*w);
    run.t.push_back(w->time());
    run.fl.push_back(f[0]), run.fr.push_back(f[1]), run.rl.push_back(f[2]), run.rr.push_back(f[3]);
    run.poleZ.push_back(pole >= 0 ? w->objectPose(pole).p.z : 0);
  }
  requireHealthy(*w, experiment);
  if (pole >= 0) run.poleEnd = w->objectPose(pole);
  run.seconds = w->time();
  return run;
}

}  // namespace

ExperimentResult pickAndPlace(const ValidationOptions& o) {
  ExperimentResult r;
  r.number = 3;
  r.title = "Pick and place";
  const WorldModel model = loadModel(o, "terrains/pick_place.world.xml");
  Diagnostics diag;
  const std::string seqFile = o.sourceDir + "/terrains/pick_place.seq";
  auto seq = loadCommandSequence(seqFile, diag, &model.robots[0].model);
  if (!seq || !checkCommands(*seq, model, seqFile, diag)) throw std::runtime_error(diag.format());
  int pole = -1;
  for (size_t i = 0; i < model.objects.size(); ++i)
    if (!model.objects[i].isStatic) pole = static_cast<int>(i);
  if (pole < 0) throw std::runtime_error("pick_place.world.xml has no dynamic object (the pole)");
  const double poleWeight = model.objects[static_cast<size_t>(pole)].mass * 9.81;
  const double end = seq->back().time + 4;
  // The windows terrains/pick_place.seq names: standing in the stance pose
  // before anything moves, and standing still holding the pole up.
  const double standFrom = 1, standTo = 2, holdFrom = 11, holdTo = 12.5;
  r.conditions = "terrains/pick_place.world.xml and terrains/pick_place.seq (" + std::to_string(seq->size()) +
                 " commands, " + num(end, 0) + " s); pole " + num(poleWeight / 9.81, 1) +
                 " kg; wheel forces from the 100 Hz wheel_force sensors, averaged over " + num(standFrom, 0) + "-" +
                 num(standTo, 0) + " s (standing) and " + num(holdFrom, 1) + "-" + num(holdTo, 1) +
                 " s (holding the pole up, standing still); control run: the same sequence with the pole removed";
  const PickPlaceRun with = runPickPlace(model, o.params, *seq, pole, end, r.title);
  WorldModel bare = model;
  bare.objects.erase(bare.objects.begin() + pole);
  const PickPlaceRun without = runPickPlace(bare, o.params, *seq, -1, end, r.title);
  r.simSeconds = with.seconds + without.seconds;
  const double z0 = model.objects[static_cast<size_t>(pole)].pose.p.z;
  const auto [frontStand, rearStand] = with.axles(standFrom, standTo);
  const auto [frontHold, rearHold] = with.axles(holdFrom, holdTo);
  const auto [frontBare, rearBare] = without.axles(holdFrom, holdTo);
  const double dFront = frontHold - frontBare, dRear = rearHold - rearBare;
  // Criteria, stated before the run.
  r.metrics.push_back({"front share of the wheel load, standing", "front clearly heavier",
                       100 * frontStand / (frontStand + rearStand), "%", "> 52 %",
                       frontStand / (frontStand + rearStand) > 0.52});
  r.metrics.push_back({"front axle load from the pole (same pose with and without it), share of its weight",
                       "most of the pole's weight", 100 * dFront / poleWeight, "%", "> 50 %", dFront > 0.5 * poleWeight});
  r.metrics.push_back({"rear axle load from the pole (same pose with and without it)", "falls slightly", dRear, "N",
                       "< 0", dRear < 0});
  r.metrics.push_back({"both axles together from the pole, share of its weight (statics: 100 %)", "",
                       100 * (dFront + dRear) / poleWeight, "%", "within 10 % of 100 %",
                       std::abs((dFront + dRear) / poleWeight - 1) <= 0.1});
  r.metrics.push_back({"pole height after release, against its start on the first cubes", "stays on the cubes",
                       (with.poleEnd.p.z - z0) * 1000, "mm", "within 20 mm (cubes of equal height)",
                       std::abs(with.poleEnd.p.z - z0) < 0.02, true, Basis::Mathematics,
                       2.0 /* mm: a tenth of the target; the height is near zero */});
  r.metrics.push_back({"for the record: front axle load change from standing to holding (the poses differ)", "",
                       frontHold - frontStand, "N", "", false, false});
  PlotSpec forces{"Pick and place: wheel normal forces (0.25 s moving average)", "time [s]", "normal force [N]", {},
                  960, 540, {}, {}};
  forces.series = {{"front left", with.t, smooth(with.fl, 25), PlotSeries::Style::Line},
                   {"front right", with.t, smooth(with.fr, 25), PlotSeries::Style::Line},
                   {"rear left", with.t, smooth(with.rl, 25), PlotSeries::Style::Line},
                   {"rear right", with.t, smooth(with.rr, 25), PlotSeries::Style::Line}};
  PlotSpec lift{"Pick and place: pole height", "time [s]", "pole centre height [m]", {}, 960, 400, {}, {}};
  lift.series = {{"pole", with.t, with.poleZ, PlotSeries::Style::Line}};
  r.plots.push_back({"pick_place_wheel_forces", forces});
  r.plots.push_back({"pick_place_pole_height", lift});
  r.discussion = "Standing, the front axle carries " + num(frontStand, 0) + " N and the rear " + num(rearStand, 0) +
                 " N: the torso and arms sit on the front half, the engine and batteries at the rear only partly "
                 "balance them. The pole's own effect is measured in one pose, holding it up and standing still, "
                 "against the same moment of the same sequence run without the pole (the robot's loads differ "
                 "between its poses by as much as the pole's effect, so standing-before against holding would mix "
                 "the two: " + num(frontHold - frontStand, 0) + " N at the front). The " + num(poleWeight, 0) +
                 " N pole adds " + num(dFront, 0) + " N to the front and changes the rear by " + num(dRear, 0) +
                 " N, together " + num(100 * (dFront + dRear) / poleWeight, 1) + " % of its weight, as statics "
                 "requires: held ahead of the front axle, its moment lifts weight off the rear, as the paper "
                 "observed. (Our readings include the legs' and wheels' weight, about 200 N per axle pair, which "
                 "the real robot's sensors did not measure.)";
  return r;
}

// 4. Slippery surface, mu 0.025 with the motion resistance of snow: plain
// rolling, caterpillar and rolking.
namespace {

struct SlipperyModes {
  double speed[3] = {0, 0, 0};  // rolling, caterpillar, rolking [m/s]
  PlotSpec progress;
  double seconds = 0;
};

const char* const kModeNames[3] = {"wheels at 1 rad/s", "caterpillar", "rolking"};

const Command kModeCommands[3] = {WheelsCmd{{1, 1, 1, 1}}, GaitCmd{Gait::Caterpillar}, GaitCmd{Gait::Rolking}};

// One mode (index into kModeNames) on `model` from rest: starts at `start`,
// runs to `duration`; the hinge's mean speed, its progress into `progress`.
double runMode(const WorldModel& model, const SimParams& params, int mode, double start, double duration,
               const std::string& experiment, PlotSeries* progress) {
  auto w = makeWorld(model, params);
  stepFor(*w, start);
  const double x0 = hingePoint(*w).x;
  w->submit(kModeCommands[mode]);
  while (w->time() < duration - 1e-9 && w->health().healthy()) {
    stepFor(*w, 0.05);
    if (!progress) continue;
    progress->x.push_back(w->time());
    progress->y.push_back(hingePoint(*w).x - x0);
  }
  requireHealthy(*w, experiment);
  return (hingePoint(*w).x - x0) / (duration - start);
}

// The three modes on `model`, each from rest.
SlipperyModes runModes(const WorldModel& model, const SimParams& params, double start, double duration,
                       const std::string& experiment) {
  SlipperyModes out;
  out.progress = {"Slippery surface (mu 0.025): distance travelled", "time [s]", "hinge x [m]", {}, 960, 540, {}, {}};
  for (int m = 0; m < 3; ++m) {
    PlotSeries s{kModeNames[m], {}, {}, PlotSeries::Style::Line};
    out.speed[m] = runMode(model, params, m, start, duration, experiment, &s);
    out.progress.series.push_back(std::move(s));
    out.seconds += duration;
  }
  return out;
}

// How far `ours` is from `paper`, as a factor >= 1 (infinite when not moving forward).
double paperFactor(double ours, double paper) { return ours > 0 ? std::max(ours / paper, paper / ours) : INFINITY; }

// `model` with every contact's motion resistance set to `c` (sliding as given).
WorldModel withResistance(WorldModel model, double c, bool sliding) {
  model.defaultContact.motionResistance = c;
  model.defaultContact.motionResistanceSliding = sliding;
  for (ContactSpec& contact : model.contacts) {
    contact.motionResistance = c;
    contact.motionResistanceSliding = sliding;
  }
  return model;
}

}  // namespace

ExperimentResult slipperySurface(const ValidationOptions& o) {
  ExperimentResult r;
  r.number = 4;
  r.title = "Slippery surface";
  const WorldModel model = loadModel(o, "terrains/ice.world.xml");
  const double duration = o.quick ? 10 : 30, start = 1;
  const double wheelRadius = model.robots[0].model.drive ? model.robots[0].model.drive->wheelRadius : 0.2;
  double c = 0;
  bool sliding = true;
  for (const ContactSpec& contact : model.contacts)
    if (contact.motionResistance > c) c = contact.motionResistance, sliding = contact.motionResistanceSliding;
  r.conditions = "terrains/ice.world.xml (mu 0.025, Coulomb friction pyramid; motion resistance of the tyres on "
                 "snow C = " + num(c, 3) + (sliding ? ", braced wheels included" : ", rolling wheels only") +
                 "); each mode starts at t = " + num(start, 0) + " s and runs " + num(duration - start, 0) +
                 " s; speed = distance of the hinge / time. Gait parameters: config/defaults.params (gait.*)";
  const double paper[3] = {0.0038, 0.057, 0.048};
  const SlipperyModes modes = runModes(model, o.params, start, duration, r.title);
  r.simSeconds += modes.seconds;
  const double* v = modes.speed;
  // Criteria, stated before the run (issue 29): the paper's own speeds,
  // each within a factor of 1.5, and in its order (caterpillar > rolking >
  // rolling). The slip and the ratios follow from the speeds: for the record.
  const double slip = 1 - v[0] / (1.0 * wheelRadius);
  // Near zero a relative tolerance means nothing: the rolling speed is
  // converged when within a tenth of the paper's figure of the reference.
  const double rollingFloor = 0.1 * paper[0];
  for (int m = 0; m < 3; ++m) {
    r.metrics.push_back({std::string("mean speed, ") + kModeNames[m] + " (ours / paper's: " + num(v[m] / paper[m], 2) +
                             " x)",
                         num(paper[m], 4), v[m], "m/s", "within a factor of 1.5", paperFactor(v[m], paper[m]) <= 1.5,
                         true, Basis::Paper, m == 0 ? rollingFloor : 0});
  }
  r.metrics.push_back({"order: caterpillar > rolking > rolling", "0.057 > 0.048 > 0.0038", v[1] > v[2] && v[2] > v[0] ? 1.0 : 0.0,
                       "", "1 (in order)", v[1] > v[2] && v[2] > v[0]});
  // Converged: the rolling speed must be the surface's, not the iterative
  // solver's creep (with C above mu the ideal model gives zero): within
  // 10 % of the 200-iteration figure, or, the two near zero, within a
  // tenth of the paper's (the resistance posed as a constraint crept at
  // 0.0059 m/s against 0.0006: it fails this).
  SimParams converged = o.params;
  converged.iterations = 200;
  const double rolling200 = runMode(model, converged, 0, start, duration, r.title, nullptr);
  r.simSeconds += duration;
  const double creep = std::abs(v[0] - rolling200);
  const bool settled = creep <= std::max(0.1 * std::abs(rolling200), rollingFloor);
  r.metrics.push_back({"rolling speed at 200 solver iterations (" + num(rolling200, 5) +
                           " m/s) against the default's (" + num(v[0], 5) + " m/s): difference",
                       "", creep, "m/s", "<= 10 % of it or <= " + num(rollingFloor, 5) + " m/s (not the solver's creep)",
                       settled, true, Basis::Solver});
  r.metrics.push_back({"for the record: rolling at 1 rad/s, slip (1 - speed / wheel surface speed)", "98 %", slip * 100,
                       "%", "", false, false});
  r.metrics.push_back({"for the record: caterpillar against rolling", num(paper[1] / paper[0], 0) + " x", v[1] / v[0],
                       "x", "", false, false});
  r.metrics.push_back({"for the record: rolking against rolling", num(paper[2] / paper[0], 0) + " x", v[2] / v[0], "x",
                       "", false, false});

  // Sensitivity (full runs only): C over the range the literature gives
  // for shallow snow, and braced wheels without it.
  std::string sensitivity;
  if (!o.quick) {
    PlotSpec table{"Slippery surface: speed against the motion resistance C", "C", "speed [m/s]", {}, 960, 540, {}, {}};
    PlotSeries curves[3] = {{kModeNames[0], {}, {}, PlotSeries::Style::Line},
                            {kModeNames[1], {}, {}, PlotSeries::Style::Line},
                            {kModeNames[2], {}, {}, PlotSeries::Style::Line}};
    sensitivity = " Sensitivity (the same runs, C changed in every contact): ";
    const auto criteria = [&](const double* s) {
      bool ok = s[1] > s[2] && s[2] > s[0];
      for (int m = 0; m < 3; ++m) ok = ok && paperFactor(s[m], paper[m]) <= 1.5;
      return ok;
    };
    for (double ci : {0.0, 0.02, 0.03, 0.06, 0.12}) {
      const SlipperyModes m = runModes(withResistance(model, ci, true), o.params, start, duration, r.title);
      r.simSeconds += m.seconds;
      for (int k = 0; k < 3; ++k) {
        curves[k].x.push_back(ci);
        curves[k].y.push_back(m.speed[k]);
      }
      sensitivity += "C = " + num(ci, 2) + ": rolling " + num(m.speed[0], 4) + ", caterpillar " + num(m.speed[1], 3) +
                     ", rolking " + num(m.speed[2], 3) + " m/s (criteria " + (criteria(m.speed) ? "met" : "missed") +
                     "); ";
    }
    const SlipperyModes rollingOnly = runModes(withResistance(model, c, false), o.params, start, duration, r.title);
    r.simSeconds += rollingOnly.seconds;
    sensitivity += "and C = " + num(c, 2) + " on rolling wheels only (braced wheels slide with mu alone): rolling " +
                   num(rollingOnly.speed[0], 4) + ", caterpillar " + num(rollingOnly.speed[1], 3) + ", rolking " +
                   num(rollingOnly.speed[2], 3) + " m/s (criteria " + (criteria(rollingOnly.speed) ? "met" : "missed") +
                   ").";
    table.series = {curves[0], curves[1], curves[2]};
    r.plots.push_back({"slippery_sensitivity", table});
  }
  r.plots.insert(r.plots.begin(), {"slippery_distance", modes.progress});
  const double traction = 0.025 * model.robots[0].model.totalMass() * 9.81;
  r.discussion =
      "Which surface: the paper gives only mu = 0.025, an ice-like friction (workpartner-facts.md). On ice "
      "alone (Coulomb friction, nothing resisting the wheels' travel) the four tyres push with up to " +
      num(traction, 0) + " N and the robot rolls at the wheels' surface speed, 0.2 m/s at 1 rad/s (the "
      "control in tst_validation: 50 x the paper's), faster than either gait: the paper's order cannot come "
      "from ice. It comes from snow over the ice: the tyres reach the ice (mu 0.025) and push snow "
      "ahead of them, a motion resistance C N against each hub's travel (CRREL TR-01-16: C 0.02-0.03 for very "
      "light snow with 10-17 cm sinkage; C = " + num(c, 2) + " was taken from it before the run, not fitted). "
      "A braced wheel sliding meets it too, as friction mu + C. Below C N the snow holds the wheel (it gives way "
      "by at most 0.5 mm, a reset-integrator friction model; docs/architecture.md), so a robot that pushes with "
      "less stands still. That is what plain rolling does: C exceeds mu, the wheels spin (" +
      num(slip * 100, 1) + " % slip) and the robot stands, at " + num(v[0], 5) + " m/s (" +
      num(rolling200, 5) + " m/s at 200 iterations: converged, not the solver's creep, which set it to "
      "0.0059 m/s before the hold). The paper's 0.0038 m/s (98 % slip) is therefore not reproduced: with the "
      "resistance above the traction the converged model does not move, and below it the robot rolls off at "
      "nearly full speed (C 0.02: the sensitivity below); no surface between gives 98 % slip without being fitted "
      "to it. The other candidates were measured and do no better (docs/validation/wheel-ground.md): ODE's "
      "force-dependent slip reaches the paper's rolling speed only where both gaits lose their grip, Wong's "
      "published snows sink this wheel deeper than its radius with 16-24 times the paper's friction, and a "
      "Janosi-Hanamoto slip on the ice gives 98 % only at a resistance fitted to half a percent. The paper's "
      "figure is most likely its own solver's creep, which ours showed at the same order "
      "(0.0059 m/s at 40 iterations). The gaits move by bracing wheels and pushing with the legs: caterpillar " +
      num(v[1], 3) + " m/s, rolking " + num(v[2], 3) + " m/s, the paper's ordering; their speeds follow from the "
      "gait timing and hip swing, which the paper does not give (ours are estimates in config/defaults.params). "
      "Judged against the paper's own speeds: rolling " + num(v[0] / paper[0], 2) + " x, caterpillar " +
      num(v[1] / paper[1], 2) + " x, rolking " + num(v[2] / paper[2], 2) + " x the paper's." +
      sensitivity;
  return r;
}

// 5. The test track: the robot's centre slows and speeds up over each bump
// (the body pitches under a hinge high above the axles), and the front axle
// unloads on the climb (nose up); the same tests at places without bumps
// must fail.
namespace {

// A bump of the track's profile, from the terrain alone: foot, crest and
// end along x [m].
struct Bump {
  double foot, crest, end;
};

// Bumps: crests (local maxima above 8 cm); each bump runs from where the
// profile last rose 2 cm above the lowest point since the previous crest to
// where it falls back within 2 cm of the lowest point before the next one.
std::vector<Bump> findBumps(const HeightGrid& grid, int row, double x0) {
  std::vector<int> crests;
  for (int i = 1; i + 1 < grid.columns; ++i) {
    const double h = grid.at(i, row);
    if (h > 0.08 && h >= grid.at(i - 1, row) && h > grid.at(i + 1, row)) crests.push_back(i);
  }
  const auto x = [&](int i) { return x0 + i * grid.spacingX(); };
  std::vector<Bump> bumps;
  for (size_t k = 0; k < crests.size(); ++k) {
    const int c = crests[k];
    const int before = k == 0 ? 0 : crests[k - 1], after = k + 1 < crests.size() ? crests[k + 1] : grid.columns - 1;
    double low = 1e9;
    for (int i = before; i <= c; ++i) low = std::min(low, grid.at(i, row));
    int foot = c;
    while (foot > before && grid.at(foot - 1, row) > low + 0.02) --foot;
    low = 1e9;
    for (int i = c; i <= after; ++i) low = std::min(low, grid.at(i, row));
    int end = c;
    while (end < after && grid.at(end + 1, row) > low + 0.02) ++end;
    bumps.push_back({x(foot), x(c), x(end)});
  }
  return bumps;
}

// Mean of `v` over the samples whose position is in [a, b).
double meanOver(const std::vector<double>& at, const std::vector<double>& v, double a, double b) {
  std::vector<double> in;
  for (size_t i = 0; i < at.size(); ++i)
    if (at[i] >= a && at[i] < b) in.push_back(v[i]);
  return in.empty() ? std::numeric_limits<double>::quiet_NaN() : mean(in);
}

struct TrackRun {
  std::vector<double> axle, v, front, rear;
  std::vector<double> rolling;    ///< the four wheels' mean rolling speed, |spin| x radius [m/s]
  std::vector<double> pitchRate;  ///< the body's, nose down positive [rad/s]
  std::vector<double> slip;       ///< the largest |1 - rolling / hub speed| of a wheel whose hub moves > 0.3 m/s
  double seconds = 0;
};

// Drives straight at `speed` until the front axle is `until` metres along x,
// sampling the hinge speed, the axle loads, the wheels' rolling and the
// body's pitch rate every 20 ms.
TrackRun driveStraight(const WorldModel& model, const SimParams& params, double speed, double until,
                       const std::string& experiment) {
  auto w = makeWorld(model, params);
  w->submit(DriveCmd{speed, 0});
  TrackRun run;
  Vec3 previous = hingePoint(*w);
  const RobotModel& robot = w->robotModel(0);
  const DriveSpec& d = *robot.drive;
  auto frontAxleX = [&] {
    return (w->linkPose(0, robot.joints[d.wheels[0]].child).p.x + w->linkPose(0, robot.joints[d.wheels[1]].child).p.x) / 2;
  };
  while (frontAxleX() < until && w->time() < 80 && w->health().healthy()) {
    stepFor(*w, 0.02);
    const Vec3 p = hingePoint(*w);
    const std::array<double, 4> f = wheelNormals(*w);
    run.axle.push_back(frontAxleX());
    run.v.push_back(norm(p - previous) / 0.02);
    run.front.push_back(f[0] + f[1]);
    run.rear.push_back(f[2] + f[3]);
    previous = p;
    // Each wheel's rolling speed (its spin about the axle in the world,
    // which holds the leg's and the body's rotation) against its hub's
    // speed across the axle: equal when it rolls without slip.
    double rolling = 0, slip = 0;
    for (int k = 0; k < 4; ++k) {
      const JointSpec& j = robot.joints[static_cast<size_t>(d.wheels[static_cast<size_t>(k)])];
      const WheelRolling roll = wheelRolling(
          robot, j, {w->linkPose(0, j.child), w->linkLinearVelocity(0, j.child), w->linkAngularVelocity(0, j.child)});
      const double surface = std::abs(roll.spin) * d.wheelRadius;
      const double across = norm(roll.across);
      rolling += surface / 4;
      if (across > 0.3) slip = std::max(slip, std::abs(1 - surface / across));
    }
    run.rolling.push_back(rolling);
    run.slip.push_back(slip);
    const Pose body = w->linkPose(0, 0);
    // About the body's left axis: positive turns the nose down.
    run.pitchRate.push_back(dot(w->linkAngularVelocity(0, 0), rotate(body.q, {0, 1, 0})));
  }
  requireHealthy(*w, experiment);
  run.seconds = w->time();
  return run;
}

}  // namespace

ExperimentResult testTrack(const ValidationOptions& o) {
  ExperimentResult r;
  r.number = 5;
  r.title = "Test track";
  const WorldModel model = loadModel(o, "terrains/test_track.world.xml");
  const WorldModel flatModel = loadModel(o, "terrains/flat.world.xml");
  const double speed = 0.8, slow = 0.95, fast = 1.05, unload = 0.95, settled = 1.5;
  const HeightGrid& grid = model.terrain.grid;
  const double x0 = model.terrain.pose.p.x - grid.width / 2;
  const int row = grid.rows / 2;
  const std::vector<Bump> bumps = findBumps(grid, row, x0);
  if (bumps.empty()) throw std::runtime_error("test_track.world.xml: no bump found in the profile");
  const RobotModel& robot = model.robots[0].model;
  if (!robot.drive) throw std::runtime_error("test_track.world.xml: the robot has no <drive>");
  // A bump is behind the robot once its rear axle has left it.
  const auto axleX = [&](size_t wheel) {
    return robot.links[static_cast<size_t>(robot.joints[static_cast<size_t>(robot.drive->wheels[wheel])].child)].pose.p.x;
  };
  const double wheelbase = axleX(0) - axleX(2);
  const double until = bumps.back().end + wheelbase + 0.5;
  r.conditions = "terrains/test_track.world.xml (profile terrains/test_track.csv, packed snow mu 0.3); drive " +
                 num(speed, 1) + " m/s straight until the rear axle is 0.5 m past the last bump. Bumps from the "
                 "profile alone: crests above 8 cm, each from its foot (2 cm above the lowest point before it) to "
                 "its end; a bump's stretch runs from the front axle at its foot until the rear axle (" +
                 num(wheelbase, 2) + " m behind) has left its end. Control runs: the same drive on "
                 "terrains/flat.world.xml, and the track's lead-in before the first bump (the robot at speed, front "
                 "axle past x = " + num(settled, 1) + " m). Speeds are the hinge's, over 20 ms, smoothed over 0.1 s";
  const TrackRun track = driveStraight(model, o.params, speed, until, r.title);
  const TrackRun flat = driveStraight(flatModel, o.params, speed, until, r.title);
  r.simSeconds = track.seconds + flat.seconds;
  const std::vector<double> v = smooth(track.v, 5), vFlat = smooth(flat.v, 5);
  const double steady = meanOver(flat.axle, flat.v, settled, until);  // on flat ground
  // The slowest and fastest of `speeds` over [a, b) of `at`, against the steady speed.
  const auto extremes = [&](const std::vector<double>& at, const std::vector<double>& speeds, double a, double b) {
    double lo = std::numeric_limits<double>::quiet_NaN(), hi = lo;
    for (size_t i = 0; i < at.size(); ++i)
      if (at[i] >= a && at[i] < b) {
        lo = std::isnan(lo) ? speeds[i] : std::min(lo, speeds[i]);
        hi = std::isnan(hi) ? speeds[i] : std::max(hi, speeds[i]);
      }
    return std::make_pair(lo / steady, hi / steady);
  };

  // Flat stretches between bumps (and after the last), at least 0.8 m long:
  // the front axle's loads there are the reference.
  std::vector<std::pair<double, double>> flats;
  double from = settled;
  for (const Bump& b : bumps) {
    if (b.foot - from >= 0.8) flats.emplace_back(from, b.foot);
    from = std::max(from, b.end);
  }
  if (until - from >= 0.8) flats.emplace_back(from, until);
  std::vector<double> flatLoads;
  for (const auto& [a, b] : flats) flatLoads.push_back(meanOver(track.axle, track.front, a, b));
  const double flatLoad = mean(flatLoads);

  // Criteria, stated before the run: over each bump's stretch the hinge
  // runs at most 0.95 x and at least 1.05 x the steady speed on flat ground
  // (it slows and speeds up there), and the front pair's mean load on the
  // climb is at most 0.95 x its mean on the flat stretches.
  int all = 0;
  double flatSlowest = 1e9, flatFastest = 0, flatWorstLoad = 1e9;
  for (size_t k = 0; k < bumps.size(); ++k) {
    const Bump& b = bumps[k];
    const double end = std::min(b.end + wheelbase, k + 1 < bumps.size() ? bumps[k + 1].foot : until);
    const auto [slowest, fastest] = extremes(track.axle, v, b.foot, end);
    const double load = meanOver(track.axle, track.front, b.foot, b.crest) / flatLoad;
    all += slowest <= slow && fastest >= fast && load <= unload;
    const std::string where = "bump " + std::to_string(k + 1) + " (" + num(b.foot, 2) + "-" + num(b.crest, 2) + "-" +
                              num(b.end, 2) + " m)";
    r.metrics.push_back({where + ": slowest hinge speed over its stretch / steady speed on flat ground",
                         "slowed at the same places", slowest, "", "<= " + num(slow, 2), slowest <= slow});
    r.metrics.push_back({where + ": fastest hinge speed over its stretch / steady speed on flat ground",
                         "slowed at the same places", fastest, "", ">= " + num(fast, 2), fastest >= fast});
    r.metrics.push_back({where + ": front load on the climb / on the flat stretches", "force changes at the bumps",
                         load, "", "<= " + num(unload, 2), load <= unload});
    // Control: the same places on flat ground.
    const auto [s, f] = extremes(flat.axle, vFlat, b.foot, end);
    flatSlowest = std::min(flatSlowest, s);
    flatFastest = std::max(flatFastest, f);
    const double flatGroundLoad = meanOver(flat.axle, flat.front, settled, until);
    flatWorstLoad = std::min(flatWorstLoad, meanOver(flat.axle, flat.front, b.foot, b.crest) / flatGroundLoad);
  }
  // Control: the track's lead-in (the speeds) and its flat stretches, each
  // against the others (the loads).
  const auto [leadSlowest, leadFastest] = extremes(track.axle, v, settled, bumps.front().foot);
  double stretchWorstLoad = 1e9;
  for (size_t k = 0; k < flats.size(); ++k) {
    std::vector<double> others;
    for (size_t m = 0; m < flats.size(); ++m)
      if (m != k) others.push_back(flatLoads[m]);
    if (!others.empty()) stretchWorstLoad = std::min(stretchWorstLoad, flatLoads[k] / mean(others));
  }
  const auto control = [&](const std::string& what, double value, const std::string& target, bool fails) {
    r.metrics.push_back({"control: " + what + " (must fail the test)", "", value, "", target, fails, true, Basis::Control});
  };
  control("the same places on flat ground, slowest", flatSlowest, "> " + num(slow, 2), flatSlowest > slow);
  control("the same places on flat ground, fastest", flatFastest, "< " + num(fast, 2), flatFastest < fast);
  control("the track's lead-in before the first bump, slowest", leadSlowest, "> " + num(slow, 2), leadSlowest > slow);
  control("the track's lead-in before the first bump, fastest", leadFastest, "< " + num(fast, 2), leadFastest < fast);
  control("the same places on flat ground, smallest load ratio", flatWorstLoad, "> " + num(unload, 2),
          flatWorstLoad > unload);
  control("the flat stretches' front load against the other stretches', smallest", stretchWorstLoad,
          "> " + num(unload, 2), stretchWorstLoad > unload);

  // The mechanism, for the record: the wheels roll without slipping, and
  // what the hinge gains or loses on them is the body's pitch.
  std::vector<double> rate, gain;
  double worstSlip = 0;
  for (size_t i = 0; i < track.axle.size(); ++i)
    if (track.axle[i] >= settled) {
      rate.push_back(track.pitchRate[i]);
      gain.push_back(track.v[i] - track.rolling[i]);
      worstSlip = std::max(worstSlip, track.slip[i]);
    }
  const LinearFit pitch = linearFit(rate, gain);
  r.metrics.push_back({"for the record: largest slip of a wheel at speed (front axle past " + num(settled, 1) +
                           " m), |1 - rolling speed / hub speed|, any 20 ms sample",
                       "", worstSlip * 100, "%", "", false, false});
  r.metrics.push_back({"for the record: hinge speed less the wheels' rolling speed against the body's pitch rate, "
                       "linear fit, R^2 (slope " + num(pitch.slope, 2) + " m: the hinge's height above the ground)",
                       "", pitch.r2, "", "", false, false});
  // Force spikes, for the record: the largest front load over each bump.
  for (size_t k = 0; k < bumps.size(); ++k) {
    double peak = 0;
    for (size_t i = 0; i < track.axle.size(); ++i)
      if (track.axle[i] >= bumps[k].foot && track.axle[i] < bumps[k].end + 1) peak = std::max(peak, track.front[i]);
    r.metrics.push_back({"bump " + std::to_string(k + 1) + ": largest front load from its foot to 1 m past its end, "
                         "against the flat stretches' mean",
                         "spikes matched the real run's", 100 * (peak / flatLoad - 1), "%", "", false, false});
  }

  PlotSpec speedPlot{"Test track: speed against distance", "front axle position [m]", "speed [m/s]", {}, 960, 400,
                     {}, {}};
  speedPlot.series = {{"hinge speed, test track", track.axle, v, PlotSeries::Style::Line},
                      {"wheels' rolling speed, test track", track.axle, smooth(track.rolling, 5), PlotSeries::Style::Line},
                      {"hinge speed, flat ground (control)", flat.axle, vFlat, PlotSeries::Style::Line}};
  PlotSpec forcePlot{"Test track: axle loads against distance (0.1 s moving average)", "front axle position [m]",
                     "normal force [N]", {}, 960, 400, {}, {}};
  forcePlot.series = {{"front pair", track.axle, smooth(track.front, 5), PlotSeries::Style::Line},
                      {"rear pair", track.axle, smooth(track.rear, 5), PlotSeries::Style::Line}};
  PlotSpec profile{"Test track: profile and the bumps found in it", "distance [m]", "height [m]", {}, 960, 300, {}, {}};
  PlotSeries h{"track middle row", {}, {}, PlotSeries::Style::Line};
  for (int i = 0; i < grid.columns; ++i) {
    h.x.push_back(x0 + i * grid.spacingX());
    h.y.push_back(grid.at(i, row));
  }
  PlotSeries marks{"foot, crest, end", {}, {}, PlotSeries::Style::Points};
  for (const Bump& b : bumps)
    for (double x : {b.foot, b.crest, b.end}) {
      marks.x.push_back(x);
      marks.y.push_back(grid.at(static_cast<int>(std::lround((x - x0) / grid.spacingX())), row));
    }
  profile.series = {h, marks};
  r.plots.push_back({"track_speed", speedPlot});
  r.plots.push_back({"track_forces", forcePlot});
  r.plots.push_back({"track_profile", profile});
  r.discussion =
      "Why the robot slows at the bumps, measured: its wheels roll without slipping (the largest slip of any "
      "wheel in any sample " + num(worstSlip * 100, 1) + " %, on snow of mu 0.3), each turning at the drive's constant rate against "
      "its leg, so they carry the robot at about the commanded speed along the ground. What changes is the body's "
      "pitch: as the front axle meets a climb (and as the rear axle comes off a descent) the nose rises and the "
      "hinge, high above the axles, swings back; over a crest the nose drops and it swings forward. The hinge's "
      "speed less the wheels' rolling speed is the pitch rate times " + num(pitch.slope, 2) + " m (R^2 = " +
      num(pitch.r2, 3) + "), the hinge's height above the ground. So the robot, measured at its centre as an "
      "observer beside the track would, slows where the ground bends up under an axle and speeds up where it "
      "bends down, at every bump. The real robot has the same geometry and velocity-controlled wheels, so the "
      "paper's \"slowed down at the same places\" is judged here, without its run's data, as: slows and speeds up "
      "over every bump, and not where there is none. (An earlier version of this report said gravity "
      "held the climbing robot back: the wheels do not slip, so it does not.) The criteria, stated before the run: "
      "over each bump's stretch the hinge runs at most " + num(slow, 2) + " x and at least " + num(fast, 2) +
      " x the steady " + num(steady, 3) + " m/s of the same drive on flat ground, and the nose-up pitch moves load "
      "from the front axle to the rear (front load on the climb <= " + num(unload, 2) + " x the flat stretches', " +
      num(flatLoad, 0) + " N). " + std::to_string(all) + " of " + std::to_string(bumps.size()) + " bumps show all "
      "three. The same tests where there are no bumps fail, as they must: on flat ground at the bumps' places the "
      "speed stays within " + num(flatSlowest, 3) + "-" + num(flatFastest, 3) + " x the steady speed and the load "
      "ratio at least " + num(flatWorstLoad, 3) + "; on the track's lead-in within " + num(leadSlowest, 3) + "-" +
      num(leadFastest, 3) + " x, and a flat stretch's load against the others' at least " +
      num(stretchWorstLoad, 3) + ". The front-load peaks are listed for the record: the paper compared them with "
      "the real robot's readings, which we do not have.";
  return r;
}

std::vector<ExperimentResult> runValidation(const ValidationOptions& o, std::ostream& log) {
  std::vector<ExperimentResult> results;
  for (auto experiment : {circularDrive, laserSweep, pickAndPlace, slipperySurface, testTrack}) {
    const auto t0 = Clock::now();
    ExperimentResult r = experiment(o);
    r.wallSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
    log << "  " << r.number << ". " << r.title << ": " << (r.pass() ? "pass" : "FAIL") << " (" << num(r.simSeconds, 0)
        << " s simulated in " << num(r.wallSeconds, 1) << " s)\n";
    results.push_back(std::move(r));
  }
  return results;
}

std::string validationReport(const std::vector<ExperimentResult>& results, const ValidationOptions& o) {
  // Table cells: a '|' would end the cell.
  auto cell = [](const std::string& text) {
    std::string out;
    for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
    return out;
  };
  std::ostringstream md;
  int passed = 0;
  for (const ExperimentResult& r : results) passed += r.pass();
  // Model version: a hash of the robot file's bytes, so a report names the
  // exact model it was made with.
  std::ifstream robotFile(o.sourceDir + "/robots/workpartner.xml", std::ios::binary);
  std::ostringstream robotText;
  robotText << robotFile.rdbuf();
  const uint64_t hash = fnv1a64(robotText.str());
  char version[24];
  std::snprintf(version, sizeof version, "%016llx", static_cast<unsigned long long>(hash));
  md << "# SimPartner validation report\n\n"
     << "The founding paper's five validation experiments, run on the twin by `simpartner-sim validate"
     << (o.quick ? " --quick" : "") << "`. Every number below was computed by that run; the paper's figures are "
     << "quoted from ../shared/MISSION.md.\n\n"
     << "**" << passed << " of " << results.size() << " experiments pass.** Conditions common to all: WorkPartner "
     << "model robots/workpartner.xml (FNV-1a 64 of its contents: " << version << "), " << solverText(o.params)
     << ".\n\n"
     << "Each criterion says what it is checked against: **validation** compares with the paper's figures or "
     << "observations (from outside the twin); **verification** with the mathematics the twin must obey "
     << "(kinematics, statics); **numerics** that a figure does not hang on the solver's settings; a **control** is "
     << "a case that must fail the test beside it. Rows marked info are for the record and judge nothing.\n\n"
     << "| # | experiment | quantity | paper | ours | unit | target | checked against | result |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const ExperimentResult& r : results)
    for (const Metric& m : r.metrics)
      md << "| " << r.number << " | " << r.title << " | " << cell(m.quantity) << " | " << cell(m.paper) << " | "
         << num(m.ours, std::abs(m.ours) < 0.1 ? 4 : 2) << " | " << cell(m.unit) << " | " << cell(m.target) << " | "
         << (m.judged ? basisText(m.basis) : "") << " | " << (!m.judged ? "info" : m.pass ? "pass" : "**fail**") << " |\n";
  for (const ExperimentResult& r : results) {
    md << "\n## " << r.number << ". " << r.title << " — " << (r.pass() ? "pass" : "fail") << "\n\n"
       << checkedAgainst(r) << "\n\nConditions: " << r.conditions << ". Simulated " << num(r.simSeconds, 0)
       << " s in " << num(r.wallSeconds, 1) << " s.\n\n"
       << r.discussion << "\n\n";
    for (const ExperimentPlot& p : r.plots)
      md << "![" << p.spec.title << "](" << p.file << ".svg) (data: [" << p.file << ".csv](" << p.file
         << ".csv))\n\n";
  }
  return md.str();
}

std::string PhysicsSetting::label() const {
  return num(step * 1000, step < 0.001 ? 2 : 1) + " ms, " + (exact ? std::string("exact") : std::to_string(iterations) + " it.");
}

std::optional<std::vector<PhysicsSetting>> parsePhysicsSettings(const std::string& text, std::string& error) {
  std::vector<PhysicsSetting> out;
  size_t at = 0;
  while (at <= text.size()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    at = comma + 1;
    const size_t slash = item.find('/');
    PhysicsSetting s;
    char* end = nullptr;
    const std::string step = item.substr(0, slash);
    s.step = std::strtod(step.c_str(), &end);
    const bool stepOk = slash != std::string::npos && !step.empty() && *end == '\0' && std::isfinite(s.step) &&
                        s.step >= 1e-5 && s.step <= 0.01;
    const std::string rest = slash == std::string::npos ? "" : item.substr(slash + 1);
    bool restOk = rest == "exact";
    if (restOk) {
      s.exact = true;
    } else {
      const long n = std::strtol(rest.c_str(), &end, 10);
      restOk = !rest.empty() && *end == '\0' && n >= 1 && n <= 10000;
      s.iterations = static_cast<int>(n);
    }
    if (!stepOk || !restOk) {
      error = "--convergence: '" + item + "': expected STEP/ITERATIONS or STEP/exact, the step in seconds (1e-5 to 0.01), " +
              "iterations 1 to 10000";
      return std::nullopt;
    }
    out.push_back(s);
    if (comma == text.size()) break;
  }
  if (out.size() < 2) {
    error = "--convergence: give at least two settings, the reference (the finest) last";
    return std::nullopt;
  }
  return out;
}

bool ConvergenceStudy::figureWithin(size_t s, size_t f) const {
  const double ref = values.back()[f];
  const double allowed = f < absolute.size() && absolute[f] > 0 ? absolute[f] : tolerance * std::abs(ref);
  return std::abs(values[s][f] - ref) <= allowed;
}

bool ConvergenceStudy::withinTolerance(size_t s) const {
  for (size_t f = 0; f < figures.size(); ++f)
    if (!figureWithin(s, f)) return false;
  return true;
}

ConvergenceStudy convergenceStudy(const ValidationOptions& base, const std::vector<PhysicsSetting>& settings,
                                  std::ostream& log) {
  ConvergenceStudy study;
  study.settings = settings;
  for (const PhysicsSetting& s : settings) {
    ValidationOptions o = base;
    o.params.step = s.step;
    o.params.iterations = s.iterations;
    o.params.solver = s.exact ? Solver::Exact : Solver::Quick;
    log << s.label() << ":\n";
    const auto t0 = Clock::now();
    const std::vector<ExperimentResult> results = runValidation(o, log);
    study.wallSeconds.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    std::vector<std::string> figures;
    std::vector<double>& values = study.values.emplace_back();
    std::vector<bool>& passes = study.passes.emplace_back();
    std::vector<double> absolute;
    for (const ExperimentResult& r : results)
      for (const Metric& m : r.metrics)
        // A numerics criterion measures the solver by design: not a figure to converge.
        if (m.judged && m.basis != Basis::Solver) {
          figures.push_back(std::to_string(r.number) + ". " + r.title + ": " + m.quantity);
          values.push_back(m.ours);
          passes.push_back(m.pass);
          absolute.push_back(m.converged);
        }
    if (study.absolute.empty()) study.absolute = absolute;
    // The quantity texts carry figures measured in the run (a hinge angle,
    // a radius): the first setting's name the rows.
    if (study.figures.empty()) study.figures = figures;
    if (values.size() != study.figures.size())
      throw std::runtime_error("convergence study: " + s.label() + " judged " + std::to_string(values.size()) +
                               " figures, the first setting " + std::to_string(study.figures.size()));
  }
  return study;
}

std::string convergenceReport(const ConvergenceStudy& study, const ValidationOptions& base) {
  std::string out = "# Convergence of the validation figures\n\n";
  out += std::string("Each judged figure of the ") + (base.quick ? "quick" : "full") +
         " suite at each physics setting (the rest as the parameters give: ERP " + num(base.params.erp, 2) +
         ", CFM " + num(base.params.cfm * 1e6, 1) + "e-6), against the last setting, the reference. A setting is "
         "within tolerance when every figure is within " + num(study.tolerance * 100, 0) +
         " % of the reference's, or within the tolerance its criterion states (in brackets after the figure's name, "
         "where a relative one means nothing: a figure near zero). Numerics criteria (they measure the solver) are "
         "not figures here. A value marked * is outside its tolerance. Written by `simpartner-sim validate "
         "--convergence`.\n\n";
  out += "| figure |";
  for (const PhysicsSetting& s : study.settings) out += " " + s.label() + " |";
  out += "\n|---|";
  for (size_t s = 0; s < study.settings.size(); ++s) out += "---|";
  out += "\n";
  const std::vector<double>& ref = study.values.back();
  for (size_t f = 0; f < study.figures.size(); ++f) {
    const bool stated = f < study.absolute.size() && study.absolute[f] > 0;
    out += "| " + study.figures[f] + (stated ? " (within " + shortestText(study.absolute[f]) + ")" : "") + " |";
    for (size_t s = 0; s < study.settings.size(); ++s) {
      const double v = study.values[s][f];
      out += " " + num(v, std::abs(v) < 0.1 ? 4 : 3) + (study.passes[s][f] ? "" : " (fail)") +
             (s + 1 < study.settings.size() && !study.figureWithin(s, f) ? " *" : "");
      if (s + 1 < study.settings.size())
        out += ref[f] != 0 ? " (" + std::string(v - ref[f] >= 0 ? "+" : "") + num(100 * (v - ref[f]) / std::abs(ref[f]), 0) + " %)"
                           : "";
      out += " |";
    }
    out += "\n";
  }
  out += "| within tolerance of the reference |";
  for (size_t s = 0; s + 1 < study.settings.size(); ++s) out += study.withinTolerance(s) ? " yes |" : " no |";
  out += " (reference) |\n| suite wall time |";
  for (double w : study.wallSeconds) out += " " + num(w, 0) + " s |";
  out += "\n\n";
  size_t cheapest = study.settings.size();
  for (size_t s = 0; s + 1 < study.settings.size(); ++s)
    if (study.withinTolerance(s) && (cheapest == study.settings.size() || study.wallSeconds[s] < study.wallSeconds[cheapest]))
      cheapest = s;
  out += cheapest < study.settings.size()
             ? "The cheapest setting within tolerance: **" + study.settings[cheapest].label() + "** (" +
                   num(study.wallSeconds[cheapest], 0) + " s).\n"
             : "No setting but the reference is within tolerance on every figure.\n";
  // A condition outside the suite, stated where the rule's result is.
  out += "\nThe default physics (config/defaults.params) is the cheapest setting within tolerance that also keeps "
         "what the stand-in robot reports consistent with its bodies' motion, which this suite does not judge: "
         "`build/bench/bench_rolling` (docs/performance.md, \"Default physics\").\n";
  return out;
}

}  // namespace sp
