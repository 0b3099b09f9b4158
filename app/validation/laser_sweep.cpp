// Experiment 2: the laser against a wall while the torso turns (validation.h).

#include "app/validation/experiment.h"

namespace sp {

using namespace experiment;

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

// The report's plots: the 6 m sweep's range error against time, every
// wall's by distance, and the torso's angle error with its fitted line.
void addLaserPlots(ExperimentResult& r, const std::vector<LaserSweep>& sweeps, const double (&walls)[3],
                   const LaserSweep& reference, const LinearFit& angleFit, double jitter, const std::string& nearerPhysics) {
  const std::string nearer = "the same, " + nearerPhysics + " (nearer convergence)";
  const LaserSweep& paper = sweeps[1];
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
}

// A line through a sweep's samples from `jitter` s on (after the start-up).
LinearFit fitAfter(const LaserSweep& sw, const std::vector<double> LaserSweep::*series, double jitter) {
  std::vector<double> t, y;
  for (size_t i = 0; i < sw.times.size(); ++i)
    if (sw.times[i] >= jitter) {
      t.push_back(sw.times[i]);
      y.push_back((sw.*series)[i]);
    }
  return linearFit(t, y);
}

// The index of the world's object named "wall".
int wallObject(const WorldModel& model) {
  for (size_t i = 0; i < model.objects.size(); ++i)
    if (model.objects[i].name == "wall") return static_cast<int>(i);
  throw std::runtime_error("laser_wall.world.xml has no object named 'wall'");
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
  const int wall = wallObject(model);
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
  const auto fit = [&](const LaserSweep& sw, const std::vector<double> LaserSweep::*series) {
    return fitAfter(sw, series, jitter);
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
  addLaserPlots(r, sweeps, walls, reference, angleFit, jitter, nearerPhysics);
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

}  // namespace sp
