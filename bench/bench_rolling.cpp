// The twin's wheels rolling without slip in a turn, per physics setting: a
// verification figure the validation suite does not judge. A robot that is
// its twin drives the calibration tests' 10 s drive on flat ground (0.6 m/s
// straight, then 15 deg left and right), recorded as telemetry at 50 Hz; per
// wheel, the share of turning frames whose rolling ratio (hub speed across
// the axle / spin) is 5 % or more off the wheel's median ratio: what the
// calibration's radiiFromRolling leaves out as slipping (above
// RollingRadii::kSlipping, 5 %, the wheel counts as skidding). The spin-up
// at 0.5 s leaves about 1.2 % out at any setting; a solver that has not
// converged leaves more. The same share from the wheel bodies' own
// velocities in the world (the same drive, the same band, spin-up
// excluded) tells the two apart: a wheel that slips shows in both, a
// joint whose rate telemetry reports inconsistently with the bodies'
// motion (the chain base velocity + joint rates, which the console
// rebuilds the wheels' motion from) only in the first.
//
//   build/bench/bench_rolling [--settings 0.001/40,0.001/60,0.002/100,...]
//
// Prints one row per setting: per wheel the radius factor it measured from
// telemetry and the share left out; the worst wheel's share from the
// bodies; the wall time of the recorded drive.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "app/calibration/calibration.h"
#include "app/calibration/recorded_drive.h"
#include "app/validation/validation.h"
#include "sim/command_file.h"
#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/runner.h"
#include "sim/world.h"

using namespace sp;

namespace {

// From the wheel bodies' velocities in the world, 20 ms samples from 1 s on
// (past the spin-up): the worst wheel's share whose rolling ratio
// |across| / |spin| is 5 % or more off its median, and the largest
// difference between a wheel's hub velocity across its axle and the same
// rebuilt as the console does, from the base's twist and the joint rates
// (what the iterative solver's joint error leaves out of the rates).
struct Bodies {
  double off = std::nan("");
  double chain = std::nan("");  ///< [m/s]
};
Bodies bodies(const WorldModel& model, const SimParams& params, const std::vector<TimedCommand>& drive) {
  Diagnostics diag;
  std::unique_ptr<World> w = World::create(model, params, diag);
  if (!w) return {};
  const RobotModel& robot = w->robotModel(0);
  Runner runner(*w);
  runner.schedule(drive);
  std::array<std::vector<double>, 4> ratio;
  Bodies out;
  out.chain = 0;
  for (double t = 1.0; t <= 10.0 + 1e-9; t += 0.02) {
    runner.advanceToTime(t);
    const RobotReadout now = readRobot(*w);
    const std::vector<LinkMotion> rebuilt = linkMotions(robot, now.base, now.baseLinearVelocity,
                                                        now.baseAngularVelocity, now.jointPositions, now.jointRates);
    for (size_t k = 0; k < 4; ++k) {
      const JointSpec& j = robot.joints[static_cast<size_t>(robot.drive->wheels[k])];
      const WheelRolling r = wheelRolling(
          robot, j, {w->linkPose(0, j.child), w->linkLinearVelocity(0, j.child), w->linkAngularVelocity(0, j.child)});
      const WheelRolling c = wheelRolling(robot, j, rebuilt[static_cast<size_t>(j.child)]);
      out.chain = std::max(out.chain, norm(c.across - r.across));
      if (std::abs(r.spin) >= 0.5) ratio[k].push_back(norm(r.across) / std::abs(r.spin));
    }
  }
  out.off = 0;
  for (std::vector<double>& v : ratio) {
    if (v.empty()) continue;
    std::vector<double> sorted = v;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
    const double med = sorted[sorted.size() / 2];
    const auto off = std::count_if(v.begin(), v.end(), [&](double x) { return std::abs(x - med) >= 0.05 * med; });
    out.off = std::max(out.off, static_cast<double>(off) / static_cast<double>(v.size()));
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string settings = "0.001/40,0.001/60,0.001/80,0.001/100,0.0005/40,0.002/100,0.002/150,0.002/200";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--settings" && i + 1 < argc) {
      settings = argv[++i];
    } else {
      std::fprintf(stderr, "usage: bench_rolling [--settings STEP/IT,...]\n");
      return 2;
    }
  }
  std::string error;
  const std::optional<std::vector<PhysicsSetting>> list = parsePhysicsSettings(settings, error);
  if (!list) {
    std::fprintf(stderr, "--settings: %s\n", error.c_str());
    return 2;
  }
  Diagnostics diag;
  const std::optional<WorldModel> world = loadWorld(SP_SOURCE_DIR "/terrains/flat.world.xml", diag);
  if (!world) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    return 1;
  }
  const std::optional<std::vector<TimedCommand>> drive = parseCommandSequence(
      "0.5 drive 0.6 0\n3.5 drive 0.6 15\n6.5 drive 0.6 -15\n", "<bench_rolling>", diag, &world->robots[0].model);
  if (!drive) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    return 1;
  }
  Perturbation twin;  // none: the robot is its twin
  twin.linkMass.assign(world->robots[0].model.links.size(), 1.0);
  twin.centreOfMass.assign(world->robots[0].model.links.size(), Vec3{});
  std::printf("%-16s %-34s %-30s %-8s %-11s %s\n", "physics", "radius factor FL FR RL RR",
              "frames left out FL FR RL RR", "bodies", "chain [m/s]", "drive [s]");
  for (const PhysicsSetting& s : *list) {
    SimParams params;
    params.step = s.step;
    params.iterations = s.iterations;
    params.solver = s.exact ? Solver::Exact : Solver::Quick;
    const auto t0 = std::chrono::steady_clock::now();
    const RecordedDrive d = recordDrive(*world, params, twin, *drive, 10.0);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!d.problem.empty()) {
      std::printf("%-16s %s\n", s.label().c_str(), d.problem.c_str());
      continue;
    }
    const RollingRadii r = radiiFromRolling(*world, d.frames);
    char factors[64], left[64];
    std::snprintf(factors, sizeof factors, "%.4f %.4f %.4f %.4f", r.factor[0], r.factor[1], r.factor[2], r.factor[3]);
    std::snprintf(left, sizeof left, "%4.1f %4.1f %4.1f %4.1f %%", 100 * r.slipping[0], 100 * r.slipping[1],
                  100 * r.slipping[2], 100 * r.slipping[3]);
    const Bodies b = bodies(*world, params, *drive);
    std::printf("%-16s %-34s %-30s %5.1f %%  %-11.3f %.2f%s\n", s.label().c_str(), factors, left, 100 * b.off, b.chain,
                wall,
                r.rolled() ? "" : "  (a wheel counted as skidding)");
  }
  return 0;
}
