// Experiment 3: pick and place, the load on the wheels (validation.h).

#include "app/validation/experiment.h"

namespace sp {

using namespace experiment;

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

}  // namespace sp
