// Experiment 4: the slippery surface, rolling against walking gaits (validation.h).

#include "app/validation/experiment.h"

namespace sp {

using namespace experiment;

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

// The same runs with C changed in every contact, and with braced wheels
// free of it: a plot into `r`, and the figures said.
std::string addSensitivity(ExperimentResult& r, const WorldModel& model, const SimParams& params, double c, double start,
                           double duration, const double (&paper)[3]) {
  PlotSpec table{"Slippery surface: speed against the motion resistance C", "C", "speed [m/s]", {}, 960, 540, {}, {}};
  PlotSeries curves[3] = {{kModeNames[0], {}, {}, PlotSeries::Style::Line},
                          {kModeNames[1], {}, {}, PlotSeries::Style::Line},
                          {kModeNames[2], {}, {}, PlotSeries::Style::Line}};
  std::string sensitivity = " Sensitivity (the same runs, C changed in every contact): ";
  const auto criteria = [&](const double* s) {
    bool ok = s[1] > s[2] && s[2] > s[0];
    for (int m = 0; m < 3; ++m) ok = ok && paperFactor(s[m], paper[m]) <= 1.5;
    return ok;
  };
  for (double ci : {0.0, 0.02, 0.03, 0.06, 0.12}) {
    const SlipperyModes m = runModes(withResistance(model, ci, true), params, start, duration, r.title);
    r.simSeconds += m.seconds;
    for (int k = 0; k < 3; ++k) {
      curves[k].x.push_back(ci);
      curves[k].y.push_back(m.speed[k]);
    }
    sensitivity += "C = " + num(ci, 2) + ": rolling " + num(m.speed[0], 4) + ", caterpillar " + num(m.speed[1], 3) +
                   ", rolking " + num(m.speed[2], 3) + " m/s (criteria " + (criteria(m.speed) ? "met" : "missed") +
                   "); ";
  }
  const SlipperyModes rollingOnly = runModes(withResistance(model, c, false), params, start, duration, r.title);
  r.simSeconds += rollingOnly.seconds;
  sensitivity += "and C = " + num(c, 2) + " on rolling wheels only (braced wheels slide with mu alone): rolling " +
                 num(rollingOnly.speed[0], 4) + ", caterpillar " + num(rollingOnly.speed[1], 3) + ", rolking " +
                 num(rollingOnly.speed[2], 3) + " m/s (criteria " + (criteria(rollingOnly.speed) ? "met" : "missed") +
                 ").";
  table.series = {curves[0], curves[1], curves[2]};
  r.plots.push_back({"slippery_sensitivity", table});
  return sensitivity;
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
  const std::string sensitivity = o.quick ? std::string() : addSensitivity(r, model, o.params, c, start, duration, paper);
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

}  // namespace sp
