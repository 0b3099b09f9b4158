// Benchmark of the twin: prints figures, asserts nothing.
//
//   build/bench/bench_twin [--quick]
//
// For the WorkPartner model on flat ground and on the test track it prints:
// - us per step of the bare ODE world (same model, no sensors or
//   controllers) and of the full twin, and their ratio (goal >= 0.9);
// - the cost of one 181-beam laser scan;
// - snapshot and restore costs;
// - how many seconds of prediction a forked ghost computes per wall-clock
//   second while the main twin keeps real time, at the normal step and at
//   coarser ones, with the ghost's position error after 5 s against the
//   fine-step prediction.
// Runs alternate between the variants so that machine load hits them alike.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "sim/model_loader.h"
#include "sim/world.h"

using namespace sp;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

WorldModel load(const std::string& file) {
  Diagnostics diag;
  auto model = loadWorld(file, diag);
  if (!model) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    std::exit(1);
  }
  return *model;
}

std::unique_ptr<World> build(const WorldModel& model, SimParams params = {}, WorldOptions options = {}) {
  Diagnostics diag;
  auto world = World::create(model, params, diag, options);
  if (!world) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    std::exit(1);
  }
  return world;
}

/// Mean us per step over `steps` steps.
double timeSteps(World& w, int steps) {
  const auto t0 = Clock::now();
  for (int i = 0; i < steps; ++i) w.step();
  return seconds(t0, Clock::now()) * 1e6 / steps;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void stepCost(const char* name, const WorldModel& model, int rounds, int steps) {
  auto bare = build(model, {}, {false, false});
  auto full = build(model);
  full->submit(DriveCmd{0.6, degToRad(8)});
  // Warm up: settle both, fill caches.
  timeSteps(*bare, 500);
  timeSteps(*full, 500);
  std::vector<double> b, f;
  for (int r = 0; r < rounds; ++r) {
    b.push_back(timeSteps(*bare, steps));
    f.push_back(timeSteps(*full, steps));
  }
  const double mb = median(b), mf = median(f);
  std::printf("%-11s step: bare ODE world %7.1f us, full twin %7.1f us, ratio bare/full %.3f (goal >= 0.9); "
              "%.1fx real time\n",
              name, mb, mf, mb / mf, 1000.0 / mf);
}

void laserCost(const char* name, const WorldModel& model, int scans) {
  auto w = build(model);
  timeSteps(*w, 200);
  const RobotModel& robot = w->robotModel(0);
  const SensorSpec& laser = robot.sensors[robot.findSensor("laser")];
  const Pose pose = w->linkPose(0, laser.link) * laser.pose;
  // Also tilt the fan down 10 degrees so beams reach the ground.
  const Pose tilted = pose * Pose{{}, quatFromRpy({0, degToRad(10), 0})};
  int hits = 0;
  for (int k = 0; k < 2; ++k) {
    const Pose& p = k == 0 ? pose : tilted;
    std::vector<double> ranges(static_cast<size_t>(laser.beams));
    const auto t0 = Clock::now();
    for (int s = 0; s < scans; ++s) {
      // Through the robot's own bodies too (exclude_self="false"): the
      // costlier case, every link a candidate.
      w->castFan(p, -laser.fov / 2, laser.fov / (laser.beams - 1), laser.maxRange, 0, laser.link, ranges);
      for (double r : ranges) hits += std::isfinite(r);
    }
    std::printf("%-11s laser: %d beams x %.0f m, %s: %6.1f us per scan (%d of %d beams hit)\n", name, laser.beams,
                laser.maxRange, k == 0 ? "level        " : "tilted 10 deg", seconds(t0, Clock::now()) * 1e6 / scans,
                hits / scans, laser.beams);
    hits = 0;
  }
}

void snapshotCost(const char* name, const WorldModel& model, int n) {
  auto w = build(model);
  timeSteps(*w, 300);
  auto t0 = Clock::now();
  Snapshot s;
  for (int i = 0; i < n; ++i) s = w->snapshot();
  const double take = seconds(t0, Clock::now()) * 1e6 / n;
  auto other = build(model);
  t0 = Clock::now();
  for (int i = 0; i < n; ++i) other->restore(s);
  const double restore = seconds(t0, Clock::now()) * 1e6 / n;
  std::printf("%-11s snapshot %.1f us, restore %.1f us (%zu bodies)\n", name, take, restore, s.bodies.size());
}

/// The ghost: a second world restored from the main twin's snapshot runs
/// `horizon` s ahead as fast as it can in another thread, while the main
/// twin keeps real time in this one. Returns predicted seconds per wall
/// second and the base position at the horizon.
struct GhostResult {
  double rate = 0;
  Vec3 base;
  bool healthy = true;
};

GhostResult runGhost(const WorldModel& model, const Snapshot& start, double step, double horizon,
                     World& main) {
  SimParams params;
  params.step = step;
  GhostResult result;
  std::atomic<bool> done{false};
  std::thread ghost([&] {
    auto g = build(model, params, {true, true});
    if (!g->restore(start).empty()) std::abort();
    const int64_t steps = std::llround(horizon / step);
    const auto t0 = Clock::now();
    for (int64_t i = 0; i < steps && g->step(); ++i) {
    }
    result.rate = horizon / seconds(t0, Clock::now());
    result.base = g->linkPose(0, 0).p;
    result.healthy = g->health().healthy();
    done = true;
  });
  // The main twin in real time meanwhile.
  const auto t0 = Clock::now();
  int64_t mainSteps = 0;
  while (!done) {
    const double due = seconds(t0, Clock::now()) / main.params().step;
    while (static_cast<double>(mainSteps) < due) {
      main.step();
      ++mainSteps;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  ghost.join();
  return result;
}

void ghostCost(const WorldModel& model, double horizon) {
  auto main = build(model);
  main->submit(DriveCmd{1.0, degToRad(10)});
  timeSteps(*main, 1000);
  const Snapshot start = main->snapshot();
  GhostResult fine;
  for (const double step : {0.001, 0.002, 0.004}) {
    const GhostResult r = runGhost(model, start, step, horizon, *main);
    if (step == 0.001) fine = r;
    std::printf("ghost       step %.0f ms: %5.1f s of prediction per wall second while the twin runs in real time; "
                "position error after %.0f s vs the 1 ms prediction: %.4f m%s\n",
                step * 1000, r.rate, horizon, norm(r.base - fine.base), r.healthy ? "" : " (DIVERGED)");
  }
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const std::string root = SP_SOURCE_DIR;
  const WorldModel flat = load(root + "/terrains/flat.world.xml");
  const WorldModel track = load(root + "/terrains/test_track.world.xml");
  std::printf("SimPartner twin benchmark (%s); WorkPartner, 1 ms step, quick solver\n", quick ? "quick" : "full");
  const int rounds = quick ? 3 : 9, steps = quick ? 300 : 1000;
  stepCost("flat", flat, rounds, steps);
  stepCost("test track", track, rounds, steps);
  laserCost("flat", flat, quick ? 20 : 200);
  laserCost("test track", track, quick ? 20 : 200);
  snapshotCost("flat", flat, quick ? 100 : 2000);
  snapshotCost("test track", track, quick ? 100 : 2000);
  ghostCost(flat, 5.0);
  return 0;
}
