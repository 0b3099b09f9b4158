// Benchmark of session logging's cost to the twin: prints figures, asserts
// nothing (issue 6 goal: at most 5 % slower).
//
//   build/bench/bench_log [--quick]
//
// Two WorkPartner twins on flat ground, built alike, driving alike, step at
// the model's 1 kHz. One feeds a SessionLogWriter as runHeadless does
// (app/headless_runner.cpp RunLog) with the logging rate raised to 1 kHz: a
// full-state sample every step, every laser scan (20 Hz), a snapshot and a
// state hash every sim second. The other logs nothing. Rounds alternate
// between the two so that machine load hits them alike; the figures are
// medians over rounds of us per step, the writer thread's cost included
// only as far as it competes with the physics thread for a core.

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "app/session_log.h"
#include "sim/model_loader.h"
#include "sim/world.h"

using namespace sp;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

std::unique_ptr<World> build(const WorldModel& model, const SimParams& params) {
  Diagnostics diag;
  auto world = World::create(model, params, diag);
  if (!world) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    std::exit(1);
  }
  return world;
}

// Logs what runHeadless logs after each step.
void logStep(SessionLogWriter& writer, const World& world, int64_t sampleEvery, int64_t snapshotEvery) {
  const int64_t step = world.stepCount();
  if (step % sampleEvery == 0) writer.logSample(makeLogSample(world));
  for (auto [robot, sensor] : world.sampledLastStep())
    if (robot == 0)
      if (auto scan = makeLogLaser(world.sensorSample(robot, sensor))) writer.logLaser(std::move(*scan));
  if (step % snapshotEvery == 0) {
    writer.logSnapshot(world.snapshot(), world.time(), world.stateHash());
    writer.logHash(step, world.stateHash());
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int rounds = quick ? 5 : 21;
  const int steps = quick ? 1000 : 3000;

  Diagnostics diag;
  auto model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
  if (!model) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    return 1;
  }
  SimParams params;
  params.logRate = 1.0 / params.step;  // full state every step
  auto logged = build(*model, params);
  auto plain = build(*model, params);
  logged->submit(DriveCmd{0.6, degToRad(8)});
  plain->submit(DriveCmd{0.6, degToRad(8)});

  char dir[] = "/tmp/bench_log.XXXXXX";
  if (!mkdtemp(dir)) {
    std::perror("mkdtemp");
    return 1;
  }
  const std::string path = std::string(dir) + "/bench.splog";
  std::string error;
  SessionInfo info;
  info.programVersion = "bench";
  auto writer = SessionLogWriter::open(path, info, error);
  if (!writer) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  const int64_t sampleEvery = std::max<int64_t>(1, std::llround(1.0 / (params.logRate * params.step)));
  const int64_t snapshotEvery = std::max<int64_t>(1, std::llround(1.0 / params.step));

  auto runLogged = [&](int n) {
    const auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) {
      logged->step();
      logStep(*writer, *logged, sampleEvery, snapshotEvery);
    }
    return seconds(t0, Clock::now()) * 1e6 / n;
  };
  auto runPlain = [&](int n) {
    const auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) plain->step();
    return seconds(t0, Clock::now()) * 1e6 / n;
  };
  // Warm up: settle both, fill caches, start the log's WAL.
  runLogged(500);
  runPlain(500);
  std::vector<double> with, without;
  for (int r = 0; r < rounds; ++r) {
    with.push_back(runLogged(steps));
    without.push_back(runPlain(steps));
  }
  writer->close();
  struct stat st {};
  const long long bytes = stat(path.c_str(), &st) == 0 ? static_cast<long long>(st.st_size) : -1;
  const double mw = median(with), mo = median(without);
  std::printf("WorkPartner twin, flat ground, %d rounds x %d steps at %.0f Hz, logging samples at %.0f Hz + laser "
              "%s\n",
              rounds, steps, 1.0 / params.step, params.logRate, "20 Hz + snapshot/hash 1 Hz");
  std::printf("  without logging %7.2f us/step\n  with logging    %7.2f us/step\n  slowdown %+.1f %% (goal <= 5 %%)\n",
              mo, mw, 100.0 * (mw - mo) / mo);
  std::printf("  log: %lld bytes for %.1f sim s, %lld items dropped%s%s\n", bytes,
              static_cast<double>(logged->stepCount()) * params.step, static_cast<long long>(writer->dropped()),
              writer->failed() ? ", failed: " : "", writer->errorMessage().c_str());
  std::remove(path.c_str());
  rmdir(dir);
  return 0;
}
