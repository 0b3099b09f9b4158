// Benchmarks of the session log: prints figures, asserts nothing.
//
//   build/bench/bench_log [--quick] [--hour [--keep]] [--seek FILE]
//
// 1. Logging's cost to the twin (issue 6 goal: at most 5 % slower).
// Two WorkPartner twins on flat ground, built alike, driving alike, step at
// the model's 1 kHz. One feeds a SessionLogWriter as runHeadless does
// (app/tools/headless_runner.cpp RunLog) with the logging rate raised to 1 kHz: a
// full-state sample every step, every laser scan (20 Hz), a snapshot and a
// state hash every sim second. The other logs nothing. Rounds alternate
// between the two so that machine load hits them alike; the figures are
// medians over rounds of us per step, the writer thread's cost included
// only as far as it competes with the physics thread for a core.
//
// 2. `--hour`: seeking in a one-hour log at 1 kHz (goal: <= 50 ms). Writes
// 3.6 million samples with the real SessionLogWriter into /tmp (about 2.4
// GB, a few minutes), plus a laser scan every 50 ms and a snapshot and hash
// every second, all copied from a real WorkPartner twin with the step and
// time moved on (and the base moving, so rows differ). Prints the write time,
// then the query plan of a sample seek and the median and worst time of
// SessionLogReader::samplesBetween(t, t + 0.1) and laserBetween(t, t + 0.1)
// at 100 random t, warm (the file in the page cache, as after a session)
// and cold (the file's cached pages dropped before each seek). Removes the
// file unless `--keep`. `--seek FILE` measures the seeks in an existing log.

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "app/log/session_log.h"
#include "app/log/session_recorder.h"
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

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double worst(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

long long fileSize(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0 ? static_cast<long long>(st.st_size) : -1;
}

// A new temporary folder in /tmp, or "" (with a message).
std::string tempDir() {
  char dir[] = "/tmp/bench_log.XXXXXX";
  if (!mkdtemp(dir)) {
    std::perror("mkdtemp");
    return {};
  }
  return dir;
}

// Drops the file's pages from the page cache (written back first), so that
// the next read comes from the disk.
void dropCache(const std::string& path) {
  const int fd = open(path.c_str(), O_RDONLY);
  if (fd < 0) return;
  fdatasync(fd);
  posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
  close(fd);
}

// Removes a log, the -wal and -shm files a read-only reader leaves beside
// it, and its folder.
void removeLog(const std::string& path, const std::string& dir) {
  for (const char* suffix : {"", "-wal", "-shm"}) std::remove((path + suffix).c_str());
  rmdir(dir.c_str());
}

// A new log; nullptr (with a message) if it cannot be created. With
// `model`, its world and robot files are stored, so that the console can
// replay it (bench_replay).
std::unique_ptr<SessionLogWriter> openLog(const std::string& path, const WorldModel* model = nullptr) {
  std::string error;
  SessionInfo info;
  info.programVersion = "bench";
  if (model) {
    info.files.push_back({"world", model->file, readWholeFile(model->file)});
    info.files.push_back({"robot", model->robots[0].model.file, readWholeFile(model->robots[0].model.file)});
  }
  auto writer = SessionLogWriter::open(path, info, error);
  if (!writer) std::fprintf(stderr, "%s\n", error.c_str());
  return writer;
}

// Part 1: the twin's cost of logging at 1 kHz.
int benchOverhead(const WorldModel& model, bool quick) {
  const int rounds = quick ? 5 : 21;
  const int steps = quick ? 1000 : 3000;
  SimParams params;
  params.logRate = 1.0 / params.step;  // full state every step
  auto logged = build(model, params);
  auto plain = build(model, params);
  logged->submit(DriveCmd{0.6, degToRad(8)});
  plain->submit(DriveCmd{0.6, degToRad(8)});

  const std::string dir = tempDir();
  if (dir.empty()) return 1;
  const std::string path = dir + "/bench.splog";
  auto writer = openLog(path);
  if (!writer) return 1;
  // What runHeadless and the stand-in robot log after each step.
  SessionRecorder recorder(std::move(writer), *logged);
  recorder.start(*logged);

  auto runLogged = [&](int n) {
    const auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) {
      logged->step();
      recorder.stepped(*logged);
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
  SessionLogWriter& w = recorder.writer();
  w.close();
  const long long bytes = fileSize(path);
  const double mw = median(with), mo = median(without);
  std::printf("WorkPartner twin, flat ground, %d rounds x %d steps at %.0f Hz, logging samples at %.0f Hz + laser "
              "%s\n",
              rounds, steps, 1.0 / params.step, params.logRate, "20 Hz + snapshot/hash 1 Hz");
  std::printf("  without logging %7.2f us/step\n  with logging    %7.2f us/step\n  slowdown %+.1f %% (goal <= 5 %%)\n",
              mo, mw, 100.0 * (mw - mo) / mo);
  std::printf("  log: %lld bytes for %.1f sim s, %lld items dropped%s%s\n", bytes,
              static_cast<double>(logged->stepCount()) * params.step, static_cast<long long>(w.dropped()),
              w.failed() ? ", failed: " : "", w.errorMessage().c_str());
  removeLog(path, dir);
  return 0;
}

// Queues one item, waiting while the writer's queue is full: this part
// measures how fast the writer drains, not what a full queue drops.
template <typename F>
void pushWaiting(F push, int64_t& waits) {
  while (!push()) {
    ++waits;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

// Part 2a: writes a one-hour log at 1 kHz to `path`; false on failure.
bool writeHour(const WorldModel& model, const std::string& path) {
  SimParams params;
  auto world = build(model, params);
  world->submit(DriveCmd{0.6, degToRad(8)});
  // Step until the laser has a scan to copy (20 Hz: within 50 ms).
  std::optional<LogLaser> scan;
  while (!scan && world->stepCount() < 1000) {
    world->step();
    for (auto [robot, sensor] : world->sampledLastStep())
      if (robot == 0 && !scan) scan = makeLogLaser(world->sensorSample(robot, sensor));
  }
  if (!scan) {
    std::fprintf(stderr, "no laser scan from the twin\n");
    return false;
  }
  const LogSample sample = makeLogSample(*world);
  Snapshot snapshot = world->snapshot();
  const uint64_t hash = world->stateHash();

  auto writer = openLog(path, &model);
  if (!writer) return false;
  const int64_t steps = 3'600'000;  // one hour at 1 kHz
  const double dt = params.step;
  int64_t waits = 0;
  const auto t0 = Clock::now();
  for (int64_t step = 0; step <= steps; ++step) {
    const double t = static_cast<double>(step) * dt;
    LogSample s = sample;
    s.step = step;
    s.time = t;
    s.base[0] += 0.6 * t;
    pushWaiting([&] { return writer->logSample(s); }, waits);
    if (step % 50 == 0) {
      LogLaser l = *scan;
      l.step = step;
      l.time = t;
      pushWaiting([&] { return writer->logLaser(l); }, waits);
    }
    if (step % 1000 == 0) {
      snapshot.step = step;
      pushWaiting([&] { return writer->logSnapshot(snapshot, t, hash + static_cast<uint64_t>(step)); }, waits);
      pushWaiting([&] { return writer->logHash(step, hash + static_cast<uint64_t>(step)); }, waits);
    }
    if (step % 360'000 == 0 && step > 0)
      std::printf("  ... %2lld min of log written after %.0f s\n", static_cast<long long>(step / 60'000),
                  seconds(t0, Clock::now()));
    std::fflush(stdout);
  }
  const auto t1 = Clock::now();
  writer->close();  // the last batches, then the WAL checkpointed into the file
  const auto t2 = Clock::now();
  if (writer->failed()) {
    std::fprintf(stderr, "%s\n", writer->errorMessage().c_str());
    return false;
  }
  std::printf("  wrote %lld samples, %lld laser scans, %lld snapshots in %.1f s (%.0f samples/s, %.1fx real time), "
              "close and checkpoint %.1f s; %lld bytes\n",
              static_cast<long long>(steps + 1), static_cast<long long>(steps / 50 + 1),
              static_cast<long long>(steps / 1000 + 1), seconds(t0, t2),
              static_cast<double>(steps + 1) / seconds(t0, t2), static_cast<double>(steps) * dt / seconds(t0, t2),
              seconds(t1, t2), fileSize(path));
  std::printf("  (the producer waited %lld times for a full queue; items refused then were pushed again)\n",
              static_cast<long long>(waits));
  return true;
}

// EXPLAIN QUERY PLAN of a query, one line per step.
std::string queryPlan(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  std::string plan;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* q = nullptr;
    if (sqlite3_prepare_v2(db, ("EXPLAIN QUERY PLAN " + sql).c_str(), -1, &q, nullptr) == SQLITE_OK)
      while (sqlite3_step(q) == SQLITE_ROW) plan += std::string("    ") + reinterpret_cast<const char*>(sqlite3_column_text(q, 3)) + "\n";
    sqlite3_finalize(q);
  }
  sqlite3_close(db);
  return plan;
}

// Part 2b: seeks to 100 random times in the log at `path`.
int benchSeeks(const std::string& path) {
  std::string error;
  auto reader = SessionLogReader::open(path, error);
  if (!reader) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  const std::vector<int64_t> snaps = reader->snapshotSteps();
  const double end = snaps.empty() ? 0 : static_cast<double>(snaps.back()) * 1e-3;
  std::printf("  query plans (samplesBetween, laserBetween):\n%s%s",
              queryPlan(path, "SELECT * FROM samples INDEXED BY samples_time WHERE time >= 1 AND time <= 2 "
                              "ORDER BY time, step").c_str(),
              queryPlan(path, "SELECT * FROM laser WHERE time >= 1 AND time <= 2 ORDER BY step").c_str());
  std::mt19937 rng(6);  // a fixed seed: the same times every run
  std::uniform_real_distribution<double> at(0, std::max(0.0, end - 0.1));
  std::vector<double> times(100);
  for (double& t : times) t = at(rng);

  struct Figures {
    std::vector<double> samples, laser, replay;
    size_t rows = 0, scans = 0;
  };
  // Cold: the reader opened anew on a file none of whose pages are cached.
  auto coldStart = [&] {
    reader.reset();
    dropCache(path);
    reader = SessionLogReader::open(path, error);
  };
  auto measure = [&](bool cold) {
    Figures f;
    for (double t : times) {
      if (cold) coldStart();
      auto a = Clock::now();
      f.rows += reader->samplesBetween(t, t + 0.1).size();
      f.samples.push_back(seconds(a, Clock::now()) * 1e3);
      if (cold) coldStart();
      a = Clock::now();
      f.scans += reader->laserBetween(t, t + 0.1).size();
      f.laser.push_back(seconds(a, Clock::now()) * 1e3);
      // The console's replay seek (app/log/log_player.h: frameAt, laserAt).
      if (cold) coldStart();
      a = Clock::now();
      const bool found = reader->sampleAt(t).has_value() && reader->laserAt(t).has_value();
      f.replay.push_back(found ? seconds(a, Clock::now()) * 1e3 : 1e9);
    }
    return f;
  };
  reader->samplesBetween(0, 0.1);  // the file in the page cache, as right after writing it
  for (bool cold : {false, true}) {
    const Figures f = measure(cold);
    std::printf("  %s, 100 random t in [0, %.0f s]:\n", cold ? "cold (file pages dropped before each seek)" : "warm",
                end);
    std::printf("    samplesBetween(t, t + 0.1): median %.2f ms, worst %.2f ms, %.1f rows each (goal <= 50 ms)\n",
                median(f.samples), worst(f.samples), static_cast<double>(f.rows) / 100);
    std::printf("    laserBetween(t, t + 0.1):   median %.2f ms, worst %.2f ms, %.1f scans each\n", median(f.laser),
                worst(f.laser), static_cast<double>(f.scans) / 100);
    std::printf("    replay seek (sampleAt(t) + laserAt(t)): median %.2f ms, worst %.2f ms (goal <= 50 ms)\n",
                median(f.replay), worst(f.replay));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, hour = false, keep = false;
  std::string seekFile;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") quick = true;
    else if (a == "--hour") hour = true;
    else if (a == "--keep") keep = true;
    else if (a == "--seek" && i + 1 < argc) seekFile = argv[++i];
    else {
      std::fprintf(stderr, "usage: bench_log [--quick] [--hour [--keep]] [--seek FILE]\n");
      return 2;
    }
  }
  if (!seekFile.empty()) {
    std::printf("Seeks in %s (%lld bytes)\n", seekFile.c_str(), fileSize(seekFile));
    return benchSeeks(seekFile);
  }

  Diagnostics diag;
  auto model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
  if (!model) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    return 1;
  }
  if (int status = benchOverhead(*model, quick); status != 0 || !hour) return status;

  const std::string dir = tempDir();
  if (dir.empty()) return 1;
  const std::string path = dir + "/hour.splog";
  std::printf("One-hour log at 1 kHz: %s\n", path.c_str());
  std::fflush(stdout);
  if (!writeHour(*model, path)) return 1;
  const int status = benchSeeks(path);
  if (keep) {
    std::printf("  kept %s (bench_log --seek FILE measures it again)\n", path.c_str());
  } else {
    removeLog(path, dir);
  }
  return status;
}
