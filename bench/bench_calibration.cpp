// Benchmark of calibration from telemetry (issue 28, docs/performance.md):
// robots that are not their twin (20 perturbation seeds), driven and turned
// for 30 s while the console's fitter runs as it does live (8 s windows every
// 3 s, two steps each from the last values), then judged over the next 30 s
// and on a rehearsed sequence. Prints a table; asserts nothing.
//
//   build/bench/bench_calibration [--seeds N] [--worlds flat,bumpy,track] [--jobs J] [--seed S] [--iterations N] [--window S] [--horizon S] [--weak-motor WHEEL=F]
//
// Per world and seed:
//   ghost error   the ghost's prediction over a 1 s each way link is 2 s
//                 ahead of the newest telemetry: a twin anchored on a frame
//                 (the ghost's profile and hold) predicts 2 s under the
//                 commands at their arrival, every 0.5 s over 30-60 s; the
//                 median horizontal and heading errors for the files' twin,
//                 the calibrated twin, the oracle (the fitted parameters at the
//                 hidden values: the floor this parameter set allows) and the
//                 matched twin (the robot's own physics and delay: the floor
//                 the ghost's coarse profile sets);
//   fitted        wheel radius against the hidden mean of the four wheels,
//                 total mass against the hidden total, the centre of mass
//                 against the hidden one (centreShift over the drive's poses);
//   rehearsal     a 30 s sequence rehearsed (app/rehearse) with the files' and
//                 with the calibrated parameters, from rest, against the
//                 perturbed robot running it: end position errors; and
//                 with the oracle's (the floor of the parameter set: a
//                 robot whose rehearsal with the hidden values ends off by
//                 more than 25 % of the files' error cannot meet the
//                 issue's 25 % by calibrating these parameters); and in
//                 the robot's own physics and delay (the floor of any
//                 calibration: what starting the rehearsal from the
//                 world's settled start instead of the robot's run, and
//                 the joints held rigid, leave);
//   fit cost      wall time of each online fit (on this thread);
//   motors        each wheel motor's torque limit: as the ghost gets it (the
//                 fused estimate where significant), the estimate itself
//                 +- its deviation, and as the rehearsals get it (after the
//                 full physics' check, fullPhysicsValues).
// Seed 0 is the control: the robot is its twin. --seed S runs seed S alone;
// --window and --horizon measure a fit other than the console's (8 s, 2 s);
// with SP_BENCH_VALUES set, each case's estimates, deviations and the hidden
// values go to stderr.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "app/calibration/calibration.h"
#include "app/calibration/live_calibrator.h"
#include "app/calibration/recorded_drive.h"
#include "app/ghost/ghost.h"
#include "app/rehearse/rehearsal.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/perturbation.h"

using namespace sp;

namespace {

// 60 s of driving and turning at varied speeds: the first half calibrates,
// the second judges. Each world's drive stays on its terrain: the open
// plane takes anything; the bumpy field (20 x 20 m, the robot at its
// centre) is driven in loops; the test track (its 22 m profile, extruded
// 12 m wide here: see main) straight along, weaving a little.
const char* const kDriveOpen =
    "0.5 drive 0.5 0\n"
    "5 drive 0.7 12\n"
    "10 drive 0.6 -15\n"
    "15 drive 0.8 0\n"
    "20 drive 0.5 20\n"
    "25 drive 0.7 -10\n"
    "30 drive 0.6 0\n"
    "35 drive 0.8 15\n"
    "40 drive 0.5 -20\n"
    "45 drive 0.7 0\n"
    "50 drive 0.6 10\n"
    "55 drive 0.8 -12\n";
const char* const kDriveLoops =
    "0.5 drive 0.5 20\n"
    "6 drive 0.6 12\n"
    "12 drive 0.4 25\n"
    "18 drive 0.6 15\n"
    "24 drive 0.5 22\n"
    "30 drive 0.6 12\n"
    "36 drive 0.4 25\n"
    "42 drive 0.6 15\n"
    "48 drive 0.5 20\n"
    "54 drive 0.6 12\n";
const char* const kDriveAlong =
    "0.5 drive 0.25 0\n"
    "6 drive 0.3 6\n"
    "12 drive 0.25 -6\n"
    "18 drive 0.3 0\n"
    "24 drive 0.25 6\n"
    "30 drive 0.3 -6\n"
    "36 drive 0.25 0\n"
    "42 drive 0.3 6\n"
    "48 drive 0.25 -6\n"
    "54 drive 0.3 0\n";
// The rehearsed sequences: 30 s, stopping at the end, on the same ground.
const char* const kRehearsedOpen =
    "0.5 drive 0.6 0\n"
    "8 drive 0.6 15\n"
    "16 drive 0.7 -10\n"
    "24 drive 0.5 0\n"
    "30 stop\n";
const char* const kRehearsedLoops =
    "0.5 drive 0.5 18\n"
    "10 drive 0.6 12\n"
    "20 drive 0.4 22\n"
    "30 stop\n";
const char* const kRehearsedAlong =
    "0.5 drive 0.3 0\n"
    "10 drive 0.35 5\n"
    "20 drive 0.3 -5\n"
    "30 stop\n";

// The console's fit (app/calibration/live_calibrator.h), whose settings the
// bench measures unless told otherwise.
const CalibrationOptions kLive = LiveCalibrator::Options{}.fit;
// Levenberg-Marquardt steps per online fit: the console's (it takes a
// further one while the last left time within its period); --iterations 1
// measures the loaded case.
int gIterations = kLive.iterations;
// The fit's window and each segment's horizon [s]: the console's (8, 2)
// unless --window / --horizon measure others.
double gWindow = kLive.window, gHorizon = kLive.horizon;
// --weak-motor WHEEL=F: every robot's motor at that wheel has F x its torque
// limit on top of its seed's deviations (the seed-0 control too).
std::array<double, 4> gWheelTorque{1, 1, 1, 1};

struct Case {
  std::string world;
  uint64_t seed = 0;
  double filesPos = 0, calPos = 0, matchedPos = 0;      // medians [m]
  double oraclePos = 0, oracleHead = 0;                  // the hidden values of the fitted parameters
  double filesHead = 0, calHead = 0, matchedHead = 0;   // [rad]
  double radiusFit = 0, radiusTrue = 0, massFit = 0, massTrue = 0;
  Vec3 comFit, comTrue;  // [m] forward, left of the files' (calibration.com_x, com_y)
  double rehearseFiles = 0, rehearseCal = 0, rehearseGhostValues = 0, rehearseOracle = 0, rehearseOwn = 0;  // [m] end position errors
  std::array<double, 4> torqueFit{}, torqueTrue{};  // each wheel motor's torque limit, factor
  std::array<double, 4> torqueEstimate{}, torqueSigma{};  // the fused estimate before the significance gate; sigma 0: unobserved
  std::array<double, 4> torqueRehearsal{};  // as the full-physics check leaves it for the rehearsals (fullPhysicsValues)
  std::array<double, 4> tyreError{};                // |fitted / hidden - 1| per tyre (rolling radius)
  double checkMs = 0;
  double fitMsMax = 0, fitMsMedian = 0;
  int fits = 0, refused = 0;
  std::string problem;
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::vector<TimedCommand> parse(const WorldModel& w, const char* text) {
  Diagnostics diag;
  auto seq = parseCommandSequence(text, "<bench>", diag, &w.robots[0].model);
  if (!seq) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    std::exit(1);
  }
  return *seq;
}

Perturbation identity(const WorldModel& w) {
  Perturbation p;
  p.linkMass.assign(w.robots[0].model.links.size(), 1.0);
  p.centreOfMass.assign(w.robots[0].model.links.size(), Vec3{});
  return p;
}

Case run(const std::string& name, const WorldModel& world, uint64_t seed) {
  const bool loops = name == "bumpy", along = name == "track";
  const char* const kDrive = loops ? kDriveLoops : along ? kDriveAlong : kDriveOpen;
  const char* const kRehearsed = loops ? kRehearsedLoops : along ? kRehearsedAlong : kRehearsedOpen;
  Case c;
  c.world = name;
  c.seed = seed;
  const RobotModel& robot = world.robots[0].model;
  Perturbation p = seed == 0 ? identity(world) : drawPerturbation(seed, robot);
  p.wheelTorque = gWheelTorque;
  const std::vector<TimedCommand> drive = parse(world, kDrive);
  const RecordedDrive d = recordDrive(world, SimParams{}, p, drive, 60.0);
  if (!d.problem.empty()) {
    c.problem = d.problem;
    return c;
  }
  const SimParams profile = Ghost::profile(SimParams{});

  // The console's fitter over the first 30 s, as it runs live.
  CalEstimate estimate = filesEstimate();
  CalibrationOptions o;
  o.window = gWindow;
  o.horizon = gHorizon;
  o.iterations = gIterations;
  std::vector<double> fitMs;
  const auto framesUpTo = [&](double end) {  // the telemetry the console has at robot time `end`
    std::vector<RobotFrame> out;
    for (const RobotFrame& f : d.frames)
      if (f.time <= end) out.push_back(f);
    return out;
  };
  for (double end = gWindow; end <= 30 + 1e-9; end += 3) {
    const CalibrationFit fit = fitCalibration(world, profile, framesUpTo(end), d.commands, estimate, o);
    fitMs.push_back(fit.wallMs);
    ++c.fits;
    if (!fit.refused.empty()) ++c.refused;
    else estimate = fuse(estimate, fit, o.window / 3);
  }
  const CalValues values = significantValues(estimate);
  c.fitMsMax = *std::max_element(fitMs.begin(), fitMs.end());
  c.fitMsMedian = median(fitMs);
  double radius = 0;
  for (double r : p.wheelRadius) radius += r / 4;
  c.radiusTrue = radius;
  c.radiusFit = values[static_cast<size_t>(CalParam::WheelRadius)];
  double files = 0, perturbed = 0;
  for (size_t i = 0; i < robot.links.size(); ++i) {
    files += robot.links[i].mass;
    perturbed += robot.links[i].mass * p.linkMass[i];
  }
  c.massTrue = perturbed / files;
  c.massFit = values[static_cast<size_t>(CalParam::Mass)];
  // The robot's centre of mass against the files', as calibration.com_x,
  // com_y would move it over the poses the robot drove through (comFromLoads'
  // meaning: bent legs turn their links' parts of a shift).
  if (const auto truth = centreShift(robot, perturbWorld(world, p).robots[0].model, framesUpTo(30)))
    c.comTrue = {truth->forward, truth->left, 0};
  c.comFit = {values[static_cast<size_t>(CalParam::ComX)], values[static_cast<size_t>(CalParam::ComY)], 0};

  // The ghost's error over 30-60 s, 2 s ahead.
  std::vector<RobotFrame> judged;
  for (const RobotFrame& f : d.frames)
    if (f.time >= 30) judged.push_back(f);
  const auto check = [&](const WorldModel& twin, const CalValues& v, double& pos, double& head) {
    const PredictionCheck k = checkPredictions(twin, profile, judged, d.commands, v, 2.0, 0.5);
    if (!k.problem.empty()) c.problem = k.problem;
    pos = median(k.position);
    head = median(k.heading);
  };
  check(world, filesCalValues(), c.filesPos, c.filesHead);
  check(world, values, c.calPos, c.calHead);
  // The oracle: the fitted parameters at the hidden values (what a perfect
  // fit of this parameter set would give; the rest of the robot's deviations
  // - each link's mass and centre, torque limits, IMU bias - left out).
  CalValues oracle = filesCalValues();
  const auto& radii = p.wheelRadius;  // FL FR RL RR
  const std::array<double, 4> radiusOracle = radiusValues(radii);
  std::copy(radiusOracle.begin(), radiusOracle.end(), oracle.begin() + static_cast<long>(CalParam::WheelRadius));
  oracle[static_cast<size_t>(CalParam::Friction)] = p.friction;
  oracle[static_cast<size_t>(CalParam::MotorGain)] = p.velocityGain;
  oracle[static_cast<size_t>(CalParam::Delay)] = p.delay;
  oracle[static_cast<size_t>(CalParam::Mass)] = c.massTrue;
  oracle[static_cast<size_t>(CalParam::ComX)] = c.comTrue.x;
  oracle[static_cast<size_t>(CalParam::ComY)] = c.comTrue.y;
  for (size_t w = 0; w < 4; ++w) {
    const size_t i = static_cast<size_t>(CalParam::TorqueFL) + w;
    oracle[i] = c.torqueTrue[w] = p.torqueLimit * p.wheelTorque[w];
    c.torqueFit[w] = values[i];
    c.torqueEstimate[w] = estimate.value[i];
    c.torqueSigma[w] = estimate.observed[i] ? estimate.sigma[i] : 0;
  }
  {
    // Each tyre as the twins build it from the fitted mean and splits
    // (calibratedWorld) against the hidden one.
    SimParams fitted = withCalValues(SimParams{}, values);
    const WorldModel tw = calibratedWorld(world, fitted);
    for (size_t w = 0; w < 4; ++w) {
      const auto& geoms = [&](const WorldModel& m) -> const std::vector<GeomSpec>& {
        const RobotModel& rm = m.robots[0].model;
        return rm.links[static_cast<size_t>(rm.joints[static_cast<size_t>(rm.drive->wheels[w])].child)].geoms;
      };
      for (size_t g = 0; g < geoms(world).size(); ++g)
        if (geoms(world)[g].type == GeomType::Cylinder || geoms(world)[g].type == GeomType::Sphere) {
          c.tyreError[w] = std::abs(geoms(tw)[g].radius / (geoms(world)[g].radius * radii[w]) - 1);
          break;
        }
    }
  }
  check(world, oracle, c.oraclePos, c.oracleHead);
  if (std::getenv("SP_BENCH_VALUES")) {  // each parameter: estimate +- sigma [applied] (hidden)
    std::string text;
    for (size_t i = 0; i < kCalParams; ++i)
      text += std::string(" ") + (calParams()[i].key + 12) + " " + std::to_string(estimate.value[i]) + "+-" +
              std::to_string(estimate.sigma[i]) + (values[i] == estimate.value[i] ? "" : " [files]") + " (" +
              std::to_string(oracle[i]) + ")";
    std::fprintf(stderr, "%s %llu:%s\n", name.c_str(), static_cast<unsigned long long>(seed), text.c_str());
    const RollingRadii rr = radiiFromRolling(world, framesUpTo(30));
    std::fprintf(stderr, "%s %llu rolling:", name.c_str(), static_cast<unsigned long long>(seed));
    for (size_t w = 0; w < 4; ++w)
      std::fprintf(stderr, " %.5f+-%.5f (%.5f, %d, %.3f)", rr.factor[w], rr.sigma[w], radii[w], rr.frames[w], rr.slipping[w]);
    std::fprintf(stderr, "\n");
  }
  CalValues matchedDelay = filesCalValues();
  matchedDelay[static_cast<size_t>(CalParam::Delay)] = p.delay;
  check(perturbWorld(world, p), matchedDelay, c.matchedPos, c.matchedHead);

  // A rehearsed 30 s sequence against the robot running it.
  const std::vector<TimedCommand> seq = parse(world, kRehearsed);
  const RecordedDrive truth = recordDrive(world, SimParams{}, p, seq, 32.0);
  const auto rehearsedEnd = [&](const SimParams& params, const WorldModel& in) {
    RehearsalPlan plan{in, params, FlightRules{}, seq, std::nullopt, true};
    plan.rules.settle = 32.0 - seq.back().time - params.calDelay;
    const RehearsalResult r = rehearse(plan);
    return r.path.empty() ? Vec3{NAN, NAN, NAN} : r.path.back().base.p;
  };
  const Vec3 end = truth.frames.back().base.p;
  const Vec3 a = rehearsedEnd(SimParams{}, world);
  const FullPhysicsCheck full = fullPhysicsValues(world, SimParams{}, framesUpTo(30), d.commands, values, gWindow);
  c.checkMs = full.wallMs;
  for (size_t w = 0; w < 4; ++w) c.torqueRehearsal[w] = full.values[static_cast<size_t>(CalParam::TorqueFL) + w];
  if (std::getenv("SP_BENCH_VALUES")) {
    std::string text;
    for (CalParam q : kFullPhysicsChecked) {
      const size_t i = static_cast<size_t>(q);
      text += std::string(" ") + (calParams()[i].key + 12) + " " + std::to_string(values[i]) + " -> " + std::to_string(full.values[i]) +
              " (cost " + std::to_string(full.cost) + " vs " + std::to_string(full.costWithout[i]) + ")";
    }
    std::fprintf(stderr, "%s %llu full physics:%s %.0f ms %s\n", name.c_str(), static_cast<unsigned long long>(seed), text.c_str(),
                 full.wallMs, full.problem.c_str());
  }
  const Vec3 b = rehearsedEnd(withCalValues(SimParams{}, full.values), world);
  const Vec3 g = rehearsedEnd(withCalValues(SimParams{}, values), world);
  c.rehearseFiles = std::hypot(a.x - end.x, a.y - end.y);
  c.rehearseCal = std::hypot(b.x - end.x, b.y - end.y);
  c.rehearseGhostValues = std::hypot(g.x - end.x, g.y - end.y);
  const Vec3 q = rehearsedEnd(withCalValues(SimParams{}, oracle), world);
  c.rehearseOracle = std::hypot(q.x - end.x, q.y - end.y);
  const Vec3 own = rehearsedEnd(withCalValues(SimParams{}, matchedDelay), perturbWorld(world, p));
  c.rehearseOwn = std::hypot(own.x - end.x, own.y - end.y);
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 20, jobs = 2, only = -1;
  std::string worlds = "flat,bumpy,track";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seeds" && i + 1 < argc) seeds = std::atoi(argv[++i]);
    else if (a == "--jobs" && i + 1 < argc) jobs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--worlds" && i + 1 < argc) worlds = argv[++i];
    else if (a == "--iterations" && i + 1 < argc) gIterations = std::clamp(std::atoi(argv[++i]), 1, 10);
    else if (a == "--seed" && i + 1 < argc) seeds = only = std::max(0, std::atoi(argv[++i]));
    else if (a == "--window" && i + 1 < argc) gWindow = std::clamp(std::atof(argv[++i]), 3.0, 30.0);
    else if (a == "--horizon" && i + 1 < argc) gHorizon = std::clamp(std::atof(argv[++i]), 0.5, 8.0);
    else if (a == "--weak-motor" && i + 1 < argc) {
      Perturbation p;
      p.wheelTorque = gWheelTorque;
      if (const std::string why = parseWeakMotor(argv[++i], p); !why.empty()) {
        std::fprintf(stderr, "bench_calibration: --weak-motor: %s\n", why.c_str());
        return 2;
      }
      gWheelTorque = p.wheelTorque;
    }
    else {
      std::fprintf(stderr, "usage: bench_calibration [--seeds N] [--worlds flat,bumpy,track] [--jobs J] [--seed S] [--iterations N] [--window S] [--horizon S] [--weak-motor WHEEL=F]\n");
      return 2;
    }
  }
  const std::pair<const char*, const char*> files[] = {
      {"flat", "terrains/flat.world.xml"}, {"bumpy", "terrains/bumpy.world.xml"}, {"track", "terrains/test_track.world.xml"}};
  std::vector<std::pair<std::string, WorldModel>> loaded;
  for (const auto& [name, path] : files) {
    if (worlds.find(name) == std::string::npos) continue;
    Diagnostics diag;
    const std::string file = std::string(SP_SOURCE_DIR) + "/" + path;
    std::optional<WorldModel> w;
    if (std::string(name) == "track") {
      // The test track's profile extruded 12 m sideways instead of 4: a
      // perturbed robot (one side's tyres larger) drifts up to 2 m across
      // over the minute's open-loop drive, and 4 m put seeds 2 and 13's
      // wheels off the heightfield's edge (the robot "diverged" there).
      std::ifstream in(file);
      std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const size_t at = text.find("depth=\"4\"");
      if (at == std::string::npos) {
        std::fprintf(stderr, "%s: error: no depth=\"4\" to widen\n", file.c_str());
        return 1;
      }
      text.replace(at, 9, "depth=\"12\"");
      w = parseWorld(text, file, std::string(SP_SOURCE_DIR) + "/terrains", diag);
    } else {
      w = loadWorld(file, diag);
    }
    if (!w) {
      std::fprintf(stderr, "%s", diag.format().c_str());
      return 1;
    }
    loaded.emplace_back(name, std::move(*w));
  }
  std::vector<std::pair<size_t, uint64_t>> work;
  for (size_t w = 0; w < loaded.size(); ++w)
    for (int s = 0; s <= seeds; ++s)
      if (only < 0 || s == only) work.emplace_back(w, static_cast<uint64_t>(s));
  std::vector<Case> cases(work.size());
  std::atomic<size_t> next{0};
  std::mutex print;
  std::printf("world  seed | ghost pos [cm] files  calib  oracle matched | heading [deg] files calib oracle matched | radius fit/true  "
              "mass fit/true | com x, y fit/true [mm] | rehearsal end [m] files calib (ghost's values) oracle own | fits (refused) fit ms med/max, check ms\n");
  const auto worker = [&] {
    for (size_t i; (i = next++) < work.size();) {
      const auto& [w, seed] = work[i];
      Case c = run(loaded[w].first, loaded[w].second, seed);
      std::lock_guard lock(print);
      std::printf("%-6s %4llu | %6.2f %6.2f %6.2f %6.2f | %5.2f %5.2f %5.2f %5.2f | %.4f/%.4f %.3f/%.3f | %5.1f/%5.1f %5.1f/%5.1f | %6.3f %6.3f (%6.3f) %6.3f %6.3f | %d (%d) %4.0f/%4.0f %5.0f %s\n",
                  c.world.c_str(), static_cast<unsigned long long>(c.seed), c.filesPos * 100, c.calPos * 100,
                  c.oraclePos * 100, c.matchedPos * 100, c.filesHead * 57.2958, c.calHead * 57.2958, c.oracleHead * 57.2958,
                  c.matchedHead * 57.2958, c.radiusFit,
                  c.radiusTrue, c.massFit, c.massTrue, c.comFit.x * 1000, c.comTrue.x * 1000, c.comFit.y * 1000, c.comTrue.y * 1000,
                  c.rehearseFiles, c.rehearseCal, c.rehearseGhostValues, c.rehearseOracle, c.rehearseOwn, c.fits, c.refused, c.fitMsMedian,
                  c.fitMsMax, c.checkMs, c.problem.c_str());
      std::printf("       torque fit/true FL %.3f/%.3f FR %.3f/%.3f RL %.3f/%.3f RR %.3f/%.3f | tyre |err| FL %.2f FR %.2f RL %.2f RR %.2f %%\n",
                  c.torqueFit[0], c.torqueTrue[0], c.torqueFit[1], c.torqueTrue[1], c.torqueFit[2], c.torqueTrue[2],
                  c.torqueFit[3], c.torqueTrue[3], c.tyreError[0] * 100, c.tyreError[1] * 100, c.tyreError[2] * 100,
                  c.tyreError[3] * 100);
      std::printf("       torque estimate FL %.3f+-%.3f FR %.3f+-%.3f RL %.3f+-%.3f RR %.3f+-%.3f (+-0: unobserved); "
                  "rehearsals' FL %.3f FR %.3f RL %.3f RR %.3f\n",
                  c.torqueEstimate[0], c.torqueSigma[0], c.torqueEstimate[1], c.torqueSigma[1], c.torqueEstimate[2],
                  c.torqueSigma[2], c.torqueEstimate[3], c.torqueSigma[3], c.torqueRehearsal[0], c.torqueRehearsal[1],
                  c.torqueRehearsal[2], c.torqueRehearsal[3]);
      std::fflush(stdout);
      cases[i] = std::move(c);
    }
  };
  std::vector<std::thread> pool;
  for (int j = 1; j < jobs; ++j) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();

  // Summary per world over the perturbed seeds, and the control (seed 0).
  std::printf("\nsummary (perturbed seeds 1..%d):\n", seeds);
  std::printf("world  | ghost pos median of medians: files calib matched, calib/matched | heading calib/matched | "
              "radius |err| max, median | mass |err| max | centre of mass |err| max, median | rehearsal calib/files median, max; within 25 %%: calib, oracle, own physics | control: calib/files pos\n");
  for (const auto& [name, _] : loaded) {
    std::vector<double> fp, cp, mp, ch, mh, rerr, merr, cerr, reh;
    double controlRatio = NAN;
    int failed = 0, within = 0, oracleWithin = 0, ownWithin = 0;
    for (const Case& c : cases) {
      if (c.world != name) continue;
      if (!c.problem.empty()) {  // the robot left the terrain, say: not judged
        ++failed;
        continue;
      }
      if (c.seed == 0) {
        controlRatio = c.calPos / c.filesPos;
        continue;
      }
      fp.push_back(c.filesPos);
      cp.push_back(c.calPos);
      mp.push_back(c.matchedPos);
      ch.push_back(c.calHead);
      mh.push_back(c.matchedHead);
      rerr.push_back(std::abs(c.radiusFit / c.radiusTrue - 1));
      merr.push_back(std::abs(c.massFit / c.massTrue - 1));
      cerr.push_back(std::hypot(c.comFit.x - c.comTrue.x, c.comFit.y - c.comTrue.y));
      reh.push_back(c.rehearseCal / c.rehearseFiles);
      within += c.rehearseCal <= 0.25 * c.rehearseFiles;
      oracleWithin += c.rehearseOracle <= 0.25 * c.rehearseFiles;
      ownWithin += c.rehearseOwn <= 0.25 * c.rehearseFiles;
    }
    if (fp.empty()) continue;
    if (failed) std::printf("%-6s | %d cases not judged (see above)\n", name.c_str(), failed);
    std::printf("%-6s | %.2f %.2f %.2f cm, %.2f | %.2f | %.2f %%, %.2f %% | %.2f %% | %.1f, %.1f mm | %.2f, %.2f; %d, %d, %d of %zu | %.3f\n", name.c_str(),
                median(fp) * 100, median(cp) * 100, median(mp) * 100, median(cp) / median(mp), median(ch) / median(mh),
                *std::max_element(rerr.begin(), rerr.end()) * 100, median(rerr) * 100,
                *std::max_element(merr.begin(), merr.end()) * 100, *std::max_element(cerr.begin(), cerr.end()) * 1000,
                median(cerr) * 1000, median(reh), *std::max_element(reh.begin(), reh.end()),
                within, oracleWithin, ownWithin, reh.size(), controlRatio);
  }
  // The motors and tyres (issue 61): a weak motor (--weak-motor) fitted as
  // the motor within 15 %, the others' fits, and the tyres within 0.5 %.
  std::printf("\nmotors and tyres (every seed, the control too):\n");
  for (const auto& [name, _] : loaded) {
    int weak = 0, weakWithin = 0, weakRehearsed = 0;
    double otherWorst = 0, otherRehearsed = 0, tyreWorst = 0;
    for (const Case& c : cases) {
      if (c.world != name || !c.problem.empty()) continue;
      for (size_t w = 0; w < 4; ++w) {
        const double off = std::abs(c.torqueFit[w] / c.torqueTrue[w] - 1);
        const double rehearsed = std::abs(c.torqueRehearsal[w] / c.torqueTrue[w] - 1);
        if (gWheelTorque[w] < 1) {
          ++weak;
          weakWithin += off <= 0.15;
          weakRehearsed += rehearsed <= 0.15;
        } else {
          otherWorst = std::max(otherWorst, off);
          otherRehearsed = std::max(otherRehearsed, rehearsed);
        }
        tyreWorst = std::max(tyreWorst, c.tyreError[w]);
      }
    }
    std::printf("%-6s | weak motors within 15 %%: %d of %d (the rehearsals' values: %d) | the other motors' |fit/true - 1| max "
                "%.3f (%.3f) | tyres |err| max %.2f %%\n",
                name.c_str(), weakWithin, weak, weakRehearsed, otherWorst, otherRehearsed, tyreWorst * 100);
  }
  return 0;
}
