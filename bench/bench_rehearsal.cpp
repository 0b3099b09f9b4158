// Benchmark of rehearsals (issue 14): how long a 60 s sequence takes to
// rehearse with the flight rules checked every step (goal: <= 10 s on this
// 2-core machine), against the bare step loop in the same process (the
// rules' cost), and robustness runs on one and on two threads. Issue 32:
// the fast profile against the full one (time, and the verdicts and
// margins it gives over the shipped sequences and 20 random ones), and 16
// robustness samples of the demo sequence (goal: <= 3 s) against the same
// 16 in the full profile run to their end. Prints figures, asserts nothing.
//
//   build/bench/bench_rehearsal [--quick] [--profile-only] [--margins] [--fast STEP ITERATIONS]
//                               [--random SEED COUNT]
//
// --profile-only: only the fast-profile comparison and robustness; --fast:
// another fast profile than the defaults' (rehearsal.fast_*) to compare (a
// finer one too: 0.0005 60 measures the full profile's own step error);
// --margins: each rule's closest approach in both profiles; --random: only
// the profile comparison, over COUNT random sequences drawn from SEED (the
// table's 20 are seed 32's: other seeds are sequences nothing was tuned on).

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "app/rehearse/rehearsal.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/random.h"
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

// A random sequence of 8 to 14 s: drives and turns within what the rules
// allow, arm and waist targets within their joints' limits, a stop.
std::string randomSequence(Random& random) {
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * random.uniform(); };
  const char* joints[][3] = {{"shoulder_pitch_l", "-60", "30"}, {"shoulder_pitch_r", "-60", "30"},
                             {"elbow_l", "-60", "0"},           {"waist_yaw", "-40", "40"}};
  std::string text;
  char line[96];
  double t = 0.5;
  const int n = 4 + static_cast<int>(random.uniform() * 4);
  for (int k = 0; k < n; ++k, t += uniform(1.0, 2.5)) {
    const double pick = random.uniform();
    if (pick < 0.45)
      std::snprintf(line, sizeof line, "%.2f drive %.2f %.1f\n", t, uniform(0.2, 1.2), uniform(-25, 25));
    else if (pick < 0.6)
      std::snprintf(line, sizeof line, "%.2f turn %.2f %.1f\n", t, uniform(0.2, 0.8), uniform(-20, 20));
    else {
      const auto& j = joints[static_cast<int>(random.uniform() * 4) % 4];
      std::snprintf(line, sizeof line, "%.2f target %s %.1f\n", t, j[0], uniform(std::atof(j[1]), std::atof(j[2])));
    }
    text += line;
  }
  std::snprintf(line, sizeof line, "%.2f stop\n", t);
  return text + line;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, profileOnly = false, margins = false;
  uint64_t randomSeed = 32;
  int randomOnly = 0;  // > 0: only that many random sequences (--random)
  SimParams defaults;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) quick = true;
    else if (std::strcmp(argv[i], "--profile-only") == 0) profileOnly = true;
    else if (std::strcmp(argv[i], "--margins") == 0) margins = true;
    else if (std::strcmp(argv[i], "--fast") == 0 && i + 2 < argc) {
      defaults.rehearsalFastStep = std::atof(argv[++i]);
      defaults.rehearsalFastIterations = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--random") == 0 && i + 2 < argc) {
      randomSeed = std::strtoull(argv[++i], nullptr, 10);
      randomOnly = std::atoi(argv[++i]);
      profileOnly = true;
    } else {
      std::fprintf(stderr, "usage: bench_rehearsal [--quick] [--profile-only] [--margins] [--fast STEP ITERATIONS] [--random SEED COUNT]\n");
      return 2;
    }
  }
  const int rounds = quick ? 1 : 3;
  const std::string root = SP_SOURCE_DIR;
  std::printf("SimPartner rehearsal benchmark: median of %d, the machine's %u hardware threads\n", rounds,
              std::thread::hardware_concurrency());
  if (!profileOnly) {
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

  }

  // Issue 32: the fast profile against the full one.
  std::printf("\nfast profile (step %.1f ms, %d iterations) against the full one (%.1f ms, %d): each rule's verdict, "
              "and its margin (closest approach to the limit) relative to the full run's\n",
              defaults.rehearsalFastStep * 1000, defaults.rehearsalFastIterations, defaults.step * 1000,
              defaults.iterations);
  std::printf("%-26s %8s %8s %7s %-8s %-9s %s\n", "sequence on world", "full [s]", "fast [s]", "speed-up", "verdict",
              "verdicts", "largest margin change");
  struct Case {
    std::string name, world, text;
  };
  std::vector<Case> cases = {{"demo on flat", root + "/terrains/flat.world.xml", ""},
                             {"pick_place on its world", root + "/terrains/pick_place.world.xml", ""},
                             {"60 s with arms, flat", root + "/terrains/flat.world.xml", kFlat},
                             {"60 s on the test track", root + "/terrains/test_track.world.xml", kTrack}};
  const auto readFile = [](const std::string& path) {
    std::string text;
    if (FILE* f = std::fopen(path.c_str(), "r")) {
      char buffer[4096];
      for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) text.append(buffer, n);
      std::fclose(f);
    }
    return text;
  };
  cases[0].text = readFile(root + "/terrains/demo.seq");
  cases[1].text = readFile(root + "/terrains/pick_place.seq");
  if (randomOnly > 0) cases.clear();
  Random random(randomSeed);
  const int randomCount = randomOnly > 0 ? randomOnly : quick ? 6 : 20;
  for (int k = 0; k < randomCount; ++k)
    cases.push_back({"random " + std::to_string(k + 1) + (k % 2 ? " on bumpy" : " on flat"),
                     root + (k % 2 ? "/terrains/bumpy.world.xml" : "/terrains/flat.world.xml"), randomSequence(random)});
  // Each fast run is run once without refinement (the fast profile's own
  // verdicts and margins); where untrusted() would refine it, the refined
  // result is the full run's (the same plan at full fidelity: deterministic,
  // tst_rehearsal checks the hashes agree) and its time both runs'.
  int same = 0, within = 0, failedFull = 0, refinedCount = 0, sameRefined = 0, withinRefined = 0;
  double fullTotal = 0, fastTotal = 0, refinedTotal = 0, largest = 0;
  // The largest |margin change| per rule over the runs the fast profile
  // passed (a failed one is refined whatever its margins): what the bands
  // must cover.
  std::array<double, kRuleCount> error{};
  std::array<std::string, kRuleCount> errorCase;
  for (const Case& c : cases) {
    Diagnostics d;
    const std::optional<WorldModel> w = loadWorld(c.world, d);
    const auto commands = w ? parseCommandSequence(c.text, c.name, d, &w->robots[0].model) : std::nullopt;
    if (!commands) {
      std::fprintf(stderr, "%s: %s", c.name.c_str(), d.format().c_str());
      return 1;
    }
    RehearsalPlan casePlan{*w, defaults, {}, *commands, std::nullopt};
    const RehearsalResult full = rehearse(casePlan);
    casePlan.fast = true;
    casePlan.refine = false;
    const RehearsalResult fast = rehearse(casePlan);
    const std::string why = untrusted(fast, defaults);
    const ProfileAgreement a = compareProfiles(full, fast);
    const ProfileAgreement b = why.empty() ? a : compareProfiles(full, full);
    same += a.sameVerdicts;
    within += a.within(0.1);
    sameRefined += b.sameVerdicts;
    withinRefined += b.within(0.1);
    refinedCount += !why.empty();
    failedFull += !full.passed;
    largest = std::max(largest, a.largestChange);
    fullTotal += full.wallSeconds;
    fastTotal += fast.wallSeconds;
    refinedTotal += fast.wallSeconds + (why.empty() ? 0 : full.wallSeconds);
    for (size_t r = 0; r < full.verdicts.size() && r < fast.verdicts.size(); ++r) {
      const RuleVerdict &u = full.verdicts[r], &v = fast.verdicts[r];
      const double e = std::abs(ruleMargin(u) - ruleMargin(v));
      if (fast.passed && u.rule == v.rule && v.rule != Rule::Health && e > error[static_cast<int>(v.rule)]) {
        error[static_cast<int>(v.rule)] = e;
        errorCase[static_cast<int>(v.rule)] = c.name;
      }
    }
    std::printf("%-26s %8.2f %8.2f %6.2fx %-8s %-9s %5.1f %% (%s)%s%s%s%s\n", c.name.c_str(), full.wallSeconds,
                fast.wallSeconds, full.wallSeconds / fast.wallSeconds, full.passed ? "passed" : "failed",
                a.sameVerdicts ? "same" : "DIFFER", 100 * a.largestChange, a.largestRule.c_str(),
                a.differ.empty() ? "" : "  ", a.differ.c_str(), why.empty() ? "" : "; refined: ", why.c_str());
    if (margins)
      for (size_t r = 0; r < full.verdicts.size() && r < fast.verdicts.size(); ++r) {
        const RuleVerdict &u = full.verdicts[r], &v = fast.verdicts[r];
        std::printf("    %-13s limit %8.3f  full worst %8.3f (margin %8.3f)  fast worst %8.3f (margin %8.3f)\n",
                    toString(u.rule), u.limit, u.worst, ruleMargin(u), v.worst, ruleMargin(v));
      }
  }
  std::printf("%zu sequences (%d failing in the full profile): verdicts the same in %d, every margin within 10 %% in %d; "
              "largest margin change %.1f %%; all together %.1f s full, %.1f s fast (%.2fx)\n",
              cases.size(), failedFull, same, within, 100 * largest, fullTotal, fastTotal, fullTotal / fastTotal);
  std::printf("refined where untrusted (rehearsal.refine.*): %d of %zu run again at full fidelity; verdicts the same in "
              "%d, every margin within 10 %% in %d; %.1f s (%.2fx faster than full)\n",
              refinedCount, cases.size(), sameRefined, withinRefined, refinedTotal, fullTotal / refinedTotal);
  std::printf("the fast profile's largest margin error per rule (runs it passed), against its refine band:\n");
  for (int r = 0; r < kRuleCount; ++r)
    if (static_cast<Rule>(r) != Rule::Health)
      std::printf("    %-15s %9.4f  x11 = %9.4f   band %9.4f  (%s)\n", toString(static_cast<Rule>(r)), error[r],
                  11 * error[r], refineBand(static_cast<Rule>(r), defaults), errorCase[r].c_str());

  if (randomOnly > 0) return 0;
  // 16 robustness samples of the demo sequence on flat ground: as
  // robustness() runs them (fast, stopped at a failure) against the same 16
  // in the full profile run to their end, both on two threads.
  {
    Diagnostics d;
    const std::optional<WorldModel> flat = loadWorld(root + "/terrains/flat.world.xml", d);
    RehearsalPlan demo{*flat, defaults, {}, *parseCommandSequence(cases[0].text, "demo.seq", d, &flat->robots[0].model),
                       std::nullopt};
    demo.rules.robustSamples = 16;
    demo.fast = demo.stopAtFirstFailure = true;
    std::vector<double> fastTimes, fullTimes;
    RobustnessResult r;
    for (int round = 0; round < rounds; ++round) {
      r = robustness(demo, 1, 2);
      fastTimes.push_back(r.wallSeconds);
      const auto t0 = Clock::now();
      std::atomic<int> next{0};
      auto work = [&] {
        for (int i; (i = next++) < 16;) {
          RehearsalPlan sample = perturbed(demo, 1 + static_cast<uint64_t>(i));
          sample.fast = sample.stopAtFirstFailure = false;
          (void)rehearse(sample);
        }
      };
      std::thread other(work);
      work();
      other.join();
      fullTimes.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
    std::printf("robustness, 16 samples of demo.seq on flat ground, 2 threads: %.2f s (fast profile, stopped at a "
                "failure; %d passed, %d refined) against %.2f s in the full profile (%.2fx)\n",
                median(fastTimes), r.passed, r.refined, median(fullTimes), median(fullTimes) / median(fastTimes));
  }
  return 0;
}
