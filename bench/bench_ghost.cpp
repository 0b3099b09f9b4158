// Benchmark of the predictive ghost's physics (issue 13): how long a 5 s
// prediction takes and how far it lands from the full-fidelity twin, for
// ghost profiles (physics step, solver iterations). Prints a table, asserts
// nothing.
//
//   build/bench/bench_ghost [--quick] [--track-turning] [--anchor S] [--profile MS/IT[/rigid|/legs]]...
//
// --track-turning runs only the hardest case; each --profile replaces the
// default list (e.g. --profile 1/20/rigid --profile 2/30); /legs holds the
// hips and knees rigid as well as the upper body.
//
// For each world (flat ground, test track) and motion (straight, turning):
// the "robot" (1 ms step, 50 iterations: the defaults) drives for 2 s; its
// read-out (what telemetry carries) anchors a ghost built with the profile
// (linkMotions + World::setRobotMotion, the same commands submitted); the
// ghost runs 5 s alone on this thread and the robot 5 s too. Profiles marked
// "rigid" hold the upper body (waist and below) welded at the read-out's pose
// (sim/rigid.h); "legs rigid" the hips and knees too, as the console's ghost
// does by default (ghost.hold). Reported: the
// ghost's wall time for the 5 s (median of the runs) and its base position
// and heading error against the robot at the end. Profiles alternate so that
// machine load hits them alike.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/rigid.h"
#include "sim/world.h"

using namespace sp;
using Clock = std::chrono::steady_clock;

namespace {

struct Profile {
  double step;
  int iterations;
  bool rigid = false;  ///< the upper body (waist and below) held rigid at the anchor's pose
  bool legs = false;   ///< the hips and knees held too (the wheels still turn)
};

struct Outcome {
  double wallMs = 0, position = 0, headingDeg = 0;
  bool healthy = true;
};

std::unique_ptr<World> build(const WorldModel& model, SimParams params = {}, WorldOptions options = {}) {
  Diagnostics diag;
  auto w = World::create(model, params, diag, options);
  if (!w) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    std::exit(1);
  }
  return w;
}

void run(World& w, double seconds) {
  const auto n = std::llround(seconds / w.params().step);
  for (int64_t i = 0; i < n && w.step(); ++i) {
  }
}

Outcome predict(const WorldModel& model, const Command& drive, const Profile& p, double anchor, double horizon) {
  auto robot = build(model);
  robot->submit(drive);
  run(*robot, anchor);
  const RobotReadout r = readRobot(*robot);
  SimParams params;
  params.step = p.step;
  params.iterations = p.iterations;
  WorldModel ghostModel = model;
  std::vector<double> positions = r.jointPositions, rates = r.jointRates;
  if (p.rigid) {
    const RobotModel& full = model.robots[0].model;
    std::string why;
    std::vector<int> held = subtreeJoints(full, "waist_yaw");
    if (p.legs)
      for (const char* leg : {"fl", "fr", "rl", "rr"})
        for (const char* joint : {"hip_", "knee_"}) held.push_back(full.findJoint(std::string(joint) + leg));
    const auto rigid = holdRigid(full, r.jointPositions, held, why);
    if (!rigid) {
      std::fprintf(stderr, "hold rigid: %s\n", why.c_str());
      std::exit(1);
    }
    ghostModel.robots[0].model = rigid->model;
    positions = rigidJoints(*rigid, r.jointPositions);
    rates = rigidJoints(*rigid, r.jointRates);
  }
  WorldOptions options;
  options.sensors = false;  // as the console's ghost (app/ghost/ghost.cpp): it draws, it does not scan
  auto ghost = build(ghostModel, params, options);
  ghost->submit(drive);
  ghost->step();  // the command takes effect; then the state is the robot's
  std::vector<std::pair<std::string, Pose>> objects;
  for (const ObjectReadout& o : r.objects) objects.emplace_back(o.name, o.pose);
  const std::string error = ghost->setRobotMotion(
      0, linkMotions(ghost->robotModel(0), r.base, r.baseLinearVelocity, r.baseAngularVelocity, positions, rates),
      objects);
  if (!error.empty()) {
    std::fprintf(stderr, "anchor: %s\n", error.c_str());
    std::exit(1);
  }
  const auto t0 = Clock::now();
  run(*ghost, horizon);
  Outcome o;
  o.wallMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  o.healthy = ghost->health().healthy();
  if (!o.healthy) std::fprintf(stderr, "ghost: %s\n", ghost->health().message().c_str());
  run(*robot, horizon);
  const Pose a = robot->linkPose(0, 0), b = ghost->linkPose(0, 0);
  o.position = std::hypot(a.p.x - b.p.x, a.p.y - b.p.y);
  double dyaw = heading(a.q) - heading(b.q);
  dyaw = std::remainder(dyaw, 2 * kPi);
  o.headingDeg = std::abs(radToDeg(dyaw));
  return o;
}

std::optional<Profile> parseProfile(const std::string& text) {
  double ms = 0;
  int iterations = 0;
  char rigid[8] = "";
  const int n = std::sscanf(text.c_str(), "%lf/%d/%7s", &ms, &iterations, rigid);
  const bool legs = n == 3 && std::strcmp(rigid, "legs") == 0;
  if (n < 2 || !(ms > 0) || iterations < 1 || (n == 3 && !legs && std::strcmp(rigid, "rigid") != 0)) return std::nullopt;
  return Profile{ms / 1000, iterations, n == 3, legs};
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, trackTurningOnly = false;
  double anchor = 2.0;
  std::vector<Profile> chosen;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      quick = true;
    } else if (arg == "--anchor" && i + 1 < argc) {
      anchor = std::atof(argv[++i]);
      if (!(anchor > 0 && anchor < 60)) {
        std::fprintf(stderr, "bench_ghost: --anchor %s: expected seconds in (0, 60)\n", argv[i]);
        return 2;
      }
    } else if (arg == "--track-turning") {
      trackTurningOnly = true;
    } else if (arg == "--profile" && i + 1 < argc) {
      const auto p = parseProfile(argv[++i]);
      if (!p) {
        std::fprintf(stderr, "bench_ghost: --profile %s: expected MS/ITERATIONS[/rigid|/legs], e.g. 2/20/rigid\n", argv[i]);
        return 2;
      }
      chosen.push_back(*p);
    } else {
      std::fprintf(stderr, "usage: bench_ghost [--quick] [--track-turning] [--anchor S] [--profile MS/IT[/rigid|/legs]]...\n");
      return 2;
    }
  }
  const std::string root = SP_SOURCE_DIR;
  const std::vector<std::pair<const char*, std::string>> worlds = {{"flat", root + "/terrains/flat.world.xml"},
                                                                   {"test track", root + "/terrains/test_track.world.xml"}};
  const std::vector<std::pair<const char*, Command>> motions = {{"straight 0.5 m/s", DriveCmd{0.5, 0}},
                                                                {"turning 0.5 m/s, 12 deg", DriveCmd{0.5, degToRad(12)}}};
  // The full robot at the twin's default, then held profiles: the upper
  // body alone (rigid) and with the legs (the console's default, ghost.hold).
  std::vector<Profile> profiles = {{0.001, 50},
                                   {0.001, 50, true, true},
                                   {0.002, 20, true, true},
                                   {0.003, 20, true, true},
                                   {0.004, 20, true},
                                   {0.004, 20, true, true},
                                   {0.004, 15, true, true},
                                   {0.005, 20, true, true}};
  if (!chosen.empty()) profiles = chosen;
  const int rounds = quick ? 1 : 3;
  const double horizon = 5.0;
  std::printf("SimPartner ghost benchmark: %.0f s predictions anchored from the robot's read-out at %.1f s; "
              "errors against the 1 ms / 50-iteration robot; wall time of the ghost alone, median of %d\n",
              horizon, anchor, rounds);
  std::printf("%-11s %-24s %-22s %10s %12s %12s\n", "world", "motion", "profile", "wall [ms]", "position [m]",
              "heading [deg]");
  for (const auto& [worldName, file] : worlds) {
    Diagnostics diag;
    const std::optional<WorldModel> model = loadWorld(file, diag);
    if (!model) {
      std::fprintf(stderr, "%s", diag.format().c_str());
      return 1;
    }
    for (const auto& [motionName, drive] : motions) {
      if (trackTurningOnly && (worldName != worlds[1].first || motionName != motions[1].first)) continue;
      std::vector<std::vector<Outcome>> results(profiles.size());
      for (int r = 0; r < rounds; ++r)
        for (size_t p = 0; p < profiles.size(); ++p) results[p].push_back(predict(*model, drive, profiles[p], anchor, horizon));
      for (size_t p = 0; p < profiles.size(); ++p) {
        std::vector<double> walls;
        for (const Outcome& o : results[p]) walls.push_back(o.wallMs);
        std::sort(walls.begin(), walls.end());
        const Outcome& last = results[p].back();  // deterministic: every round lands the same
        char profile[32];
        std::snprintf(profile, sizeof profile, "%.0f ms / %d it%s", profiles[p].step * 1000, profiles[p].iterations,
                      profiles[p].legs ? ", legs rigid" : profiles[p].rigid ? ", rigid" : "");
        std::printf("%-11s %-24s %-22s %10.0f %12.4f %12.2f%s\n", worldName, motionName, profile,
                    walls[walls.size() / 2], last.position, last.headingDeg, last.healthy ? "" : "  DIVERGED");
      }
    }
  }
  return 0;
}
