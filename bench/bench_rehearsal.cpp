// Benchmark of rehearsals (issue 14): how long a 60 s sequence takes to
// rehearse with the flight rules checked every step (goal: <= 10 s on this
// 2-core machine), against the bare step loop in the same process (the
// rules' cost), and robustness runs on one and on two threads. Prints
// figures, asserts nothing.
//
//   build/bench/bench_rehearsal [--quick]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "app/rehearse/rehearsal.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/runner.h"
#include "sim/world.h"

using namespace sp;
using Clock = std::chrono::steady_clock;

namespace {

// 60 s of work on flat ground: drive, turn both ways, move the arms and the
// waist while rolling, a caterpillar stretch, stop.
constexpr const char* kFlat =
    "1 drive 0.8 0\n"
    "6 drive 0.8 20\n"
    "12 drive 0.8 -20\n"
    "18 target shoulder_pitch_l -30\n"
    "18 target shoulder_pitch_r -30\n"
    "20 target waist_yaw 20\n"
    "24 turn 0.5 10\n"
    "32 stop\n"
    "34 gait caterpillar\n"
    "46 gait off\n"
    "48 drive 0.5 0\n"
    "55 target waist_yaw 0\n"
    "60 stop\n";
// 60 s along the test track's bumps, slowly enough to stay on it.
constexpr const char* kTrack =
    "1 drive 0.3 0\n"
    "20 target shoulder_pitch_l -20\n"
    "30 target shoulder_pitch_l 0\n"
    "40 drive 0.2 0\n"
    "60 stop\n";

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int rounds = quick ? 1 : 3;
  const std::string root = SP_SOURCE_DIR;
  std::printf("SimPartner rehearsal benchmark: median of %d, the machine's %u hardware threads\n", rounds,
              std::thread::hardware_concurrency());
  std::printf("%-11s %10s %12s %12s %10s %14s %8s %22s\n", "world", "simulated", "rehearse [s]", "bare run [s]",
              "rules cost", "held rigid [s]", "speed-up", "held vs full at the end");
  for (const auto& [name, file, text] :
       {std::tuple{"flat", root + "/terrains/flat.world.xml", kFlat},
        std::tuple{"test track", root + "/terrains/test_track.world.xml", kTrack}}) {
    Diagnostics diag;
    const std::optional<WorldModel> world = loadWorld(file, diag);
    const auto commands = world ? parseCommandSequence(text, "bench.seq", diag, &world->robots[0].model) : std::nullopt;
    if (!commands) {
      std::fprintf(stderr, "%s", diag.format().c_str());
      return 1;
    }
    RehearsalPlan plan{*world, {}, {}, *commands, std::nullopt};
    RehearsalPlan heldPlan = plan;
    plan.holdUnmoved = false;
    std::vector<double> rehearsal, bare, heldTimes;
    RehearsalResult last, held;
    for (int r = 0; r < rounds; ++r) {
      last = rehearse(plan);
      rehearsal.push_back(last.wallSeconds);
      held = rehearse(heldPlan);
      heldTimes.push_back(held.wallSeconds);
      // The same steps without rules or samples: World and Runner alone.
      const auto t0 = Clock::now();
      auto w = World::create(plan.world, plan.params, diag);
      Runner runner(*w);
      runner.schedule(plan.commands);
      runner.advanceToTime(last.duration);
      bare.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
    const double a = median(rehearsal), b = median(bare), h = median(heldTimes);
    const Pose& pa = last.path.back().base;
    const Pose& ph = held.path.back().base;
    const double dyaw = radToDeg(std::abs(std::remainder(heading(pa.q) - heading(ph.q), 2 * kPi)));
    std::printf("%-11s %8.0f s %12.2f %12.2f %9.2fx %14.2f %7.2fx %8.1f mm, %5.2f deg  %s (%d held)\n", name, last.duration,
                a, b, a / b, h, a / h, 1000 * std::hypot(pa.p.x - ph.p.x, pa.p.y - ph.p.y), dyaw,
                last.passed == held.passed ? (last.passed ? "both passed" : "both failed") : "VERDICTS DIFFER",
                held.heldJoints);
    if (!last.passed) std::printf("            %s\n", last.summary().c_str());
  }

  // Robustness of the test-track sequence: 8 samples on one thread, then on two.
  Diagnostics diag;
  const std::optional<WorldModel> track = loadWorld(root + "/terrains/test_track.world.xml", diag);
  RehearsalPlan plan{*track, {}, {}, *parseCommandSequence(kTrack, "bench.seq", diag, &track->robots[0].model),
                     std::nullopt};
  plan.rules.robustSamples = quick ? 4 : 8;
  const RobustnessResult one = robustness(plan, 1, 1);
  const RobustnessResult two = robustness(plan, 1, 2);
  std::printf("robustness, %d samples of the test-track sequence: 1 thread %.2f s, 2 threads %.2f s (%.2fx); "
              "%d passed, end spread %.3f m (both runs %s)\n",
              plan.rules.robustSamples, one.wallSeconds, two.wallSeconds, one.wallSeconds / two.wallSeconds, two.passed,
              two.spread, one.endPoses.size() == two.endPoses.size() && std::equal(one.endPoses.begin(), one.endPoses.end(), two.endPoses.begin(), [](const Pose& x, const Pose& y) { return x.p == y.p; }) ? "equal" : "DIFFER");
  return 0;
}
