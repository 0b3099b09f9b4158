#include "app/log/resimulation.h"

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <vector>

#include "app/log/session_log.h"
#include "sim/command_file.h"
#include "sim/text.h"
#include "sim/file_set.h"
#include "sim/model_loader.h"
#include "sim/params.h"
#include "sim/runner.h"
#include "sim/world.h"

namespace sp {
namespace {

std::string get(const std::map<std::string, std::string>& meta, const std::string& key) {
  auto it = meta.find(key);
  return it == meta.end() ? std::string() : it->second;
}

}  // namespace

std::string hashHex(uint64_t hash) {
  char text[32];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

std::optional<LoggedWorld> loggedWorld(const SessionLogReader& reader, const std::string& path, std::string& error) {
  const std::map<std::string, std::string> meta = reader.meta();
  const std::string worldName = get(meta, "world_file");
  const std::string robotName = get(meta, "robot_file");
  if (worldName.empty() || !meta.count("world_contents") || robotName.empty() || !meta.count("robot_contents")) {
    error = path + ": the log holds no world or robot file to re-simulate from";
    return std::nullopt;
  }

  // The logged files, held in memory where they were recorded: the robot
  // where the world file's reference to it leads (a robot opened in place
  // of the world's own goes where the world looks). Nothing is written.
  const std::string replaced = get(meta, "replaced_robot_file");
  FileSet files;
  files.add(worldName, get(meta, "world_contents"));
  files.add(replaced.empty() ? robotName : replaced, get(meta, "robot_contents"));

  // A heightfield's data file, where the log stores it (logs written before
  // it was stored read it from the disk, beside the recorded world file).
  if (meta.count("terrain_contents")) files.add(get(meta, "terrain_file"), get(meta, "terrain_contents"));
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(worldName, diag, &files);
  if (!model || model->robots.empty()) {
    error = path + ": cannot rebuild the logged world:\n" + diag.format();
    return std::nullopt;
  }

  SimParams params;
  if (meta.count("params_contents") &&
      !parseParams(get(meta, "params_contents"), get(meta, "params_file"), params, diag)) {
    error = path + ": cannot load the logged parameters:\n" + diag.format();
    return std::nullopt;
  }
  for (const LogEvent& e : reader.events())
    if (e.kind == "param_override" && !applyOverride(params, e.text, diag)) {
      error = path + ": cannot apply the logged override '" + e.text + "':\n" + diag.format();
      return std::nullopt;
    }
  LoggedWorld logged{std::move(*model), params, std::nullopt};
  if (const std::string seed = get(meta, "perturbation_seed"); !seed.empty()) {
    char* end = nullptr;
    const unsigned long long value = std::strtoull(seed.c_str(), &end, 10);
    if (end == seed.c_str() || *end != '\0') {
      error = path + ": meta perturbation_seed: expected an unsigned integer, got '" + seed + "'";
      return std::nullopt;
    }
    logged.perturbation = drawPerturbation(value, logged.world.robots[0].model);
  }
  if (const std::string torque = get(meta, "perturbation_wheel_torque"); !torque.empty()) {
    const std::vector<std::string_view> words = splitWords(torque);
    std::array<double, 4> factor{};
    for (size_t w = 0; w < 4; ++w) {
      const std::optional<double> x = w < words.size() ? parseReal(words[w]) : std::nullopt;
      if (words.size() != 4 || !x || !(*x > 0)) {
        error = path + ": meta perturbation_wheel_torque: expected four positive factors (FL FR RL RR), got '" + torque + "'";
        return std::nullopt;
      }
      factor[w] = *x;
    }
    if (!logged.perturbation) logged.perturbation = Perturbation{};
    logged.perturbation->wheelTorque = factor;
  }
  return logged;
}

namespace {

// A log's world at its latest snapshot at or before `from`, with the logged
// commands scheduled at their steps: what re-simulation and branching start from.
struct Replay {
  std::unique_ptr<SessionLogReader> reader;
  LoggedWorld logged;
  std::unique_ptr<World> world;
  std::unique_ptr<Runner> runner;
  int64_t start = 0;
  int64_t lastSnapshot = 0;  // the log's last snapshot step
};

std::optional<Replay> openReplay(const std::string& path, double from, std::string& error) {
  Replay r;
  r.reader = SessionLogReader::open(path, error);
  if (!r.reader) return std::nullopt;
  std::optional<LoggedWorld> logged = loggedWorld(*r.reader, path, error);
  if (!logged) return std::nullopt;
  r.logged = std::move(*logged);
  Diagnostics diag;
  r.world = World::create(r.logged.physicsWorld(), r.logged.params, diag);
  if (!r.world) {
    error = path + ": cannot build the logged world:\n" + diag.format();
    return std::nullopt;
  }
  const RobotModel& robot = r.logged.world.robots[0].model;

  // The commands as applied, parsed back against the robot, each due at
  // the step it was logged at.
  r.runner = std::make_unique<Runner>(*r.world);
  for (const LogCommand& c : r.reader->commands()) {
    std::string why;
    std::optional<Command> command = parseCommand(c.text, why, &robot);
    if (!command) {
      error = path + ": logged command at step " + std::to_string(c.step) + " ('" + c.text + "'): " + why;
      return std::nullopt;
    }
    if (c.step >= 0) r.runner->schedule(ScheduledCommand{std::move(*command), 0, c.step});
  }

  // The latest snapshot at or before `from`.
  const std::vector<int64_t> snapshotSteps = r.reader->snapshotSteps();
  if (snapshotSteps.empty()) {
    error = path + ": the log holds no snapshot to start from";
    return std::nullopt;
  }
  r.start = snapshotSteps.front();
  r.lastSnapshot = snapshotSteps.back();
  for (int64_t s : snapshotSteps)
    if (static_cast<double>(s) * r.logged.params.step <= from + 1e-9) r.start = s;
  std::optional<std::pair<Snapshot, uint64_t>> snapshot = r.reader->snapshot(r.start, &error);
  if (!snapshot) {
    error = path + ": the snapshot at step " + std::to_string(r.start) + ": " + error;
    return std::nullopt;
  }
  if (std::string why = r.world->restore(snapshot->first); !why.empty()) {
    error = path + ": cannot restore the snapshot at step " + std::to_string(r.start) + ": " + why;
    return std::nullopt;
  }
  // A command logged at step s was submitted before the step from s; those
  // before the snapshot are in it (applied, or pending in its queue).
  r.runner->skipBefore(r.start);
  return r;
}

// A Runner monitor that reports the fraction of [from, to] done about every
// 1 % of the steps; false (stop) when `progress` says so.
std::function<bool(const World&)> progressMonitor(const std::function<bool(double)>& progress, int64_t from,
                                                 int64_t to, bool& cancelled) {
  const int64_t every = std::max<int64_t>(1, (to - from) / 100);
  return [&progress, &cancelled, from, to, every](const World& w) {
    const int64_t done = w.stepCount() - from;
    if (!progress || done % every != 0) return true;
    cancelled = !progress(static_cast<double>(done) / static_cast<double>(std::max<int64_t>(1, to - from)));
    return !cancelled;
  };
}

}  // namespace

std::optional<BranchPoint> branchAt(const std::string& path, double time, std::string& error,
                                    const std::function<bool(double)>& progress) {
  std::optional<Replay> r = openReplay(path, time, error);
  if (!r) return std::nullopt;
  const int64_t step = std::llround(time / r->logged.params.step);
  if (step < r->start) {
    error = path + ": no snapshot at or before t = " + std::to_string(time) + " s";
    return std::nullopt;
  }
  bool cancelled = false;
  r->runner->setMonitor(progressMonitor(progress, r->start, step, cancelled));
  const RunOutcome::Stop stop = r->runner->advanceTo(step).stop;
  if (cancelled) {
    error = path + ": cancelled re-simulating to t = " + std::to_string(time) + " s";
    return std::nullopt;
  }
  if (stop == RunOutcome::Stop::Diverged) {
    error = path + ": the twin diverged re-simulating to t = " + std::to_string(time) + " s: " +
            r->world->health().message();
    return std::nullopt;
  }
  BranchPoint b;
  b.logged = std::move(r->logged);
  b.state = r->world->snapshot();
  b.hash = r->world->stateHash();
  b.step = step;
  b.fromSnapshot = r->start;
  for (const auto& [s, h] : r->reader->hashes())
    if (s == step) b.loggedHash = h;
  b.meta = r->reader->meta();
  return b;
}

std::optional<ResimReport> resimulate(const std::string& path, const ResimOptions& options, std::string& error) {
  std::optional<Replay> replay = openReplay(path, options.from, error);
  if (!replay) return std::nullopt;
  SessionLogReader* reader = replay->reader.get();
  World* world = replay->world.get();
  Runner& runner = *replay->runner;
  const int64_t start = replay->start;

  ResimReport report;
  report.startStep = start;
  const std::vector<std::pair<int64_t, uint64_t>> hashes = reader->hashes();
  // Untrusted logs: nothing to compare is no verdict, and a hash far beyond
  // the log's last snapshot (a writer logs one every sim second and at the
  // end) would have the re-simulation run for ages.
  const int64_t lastSnapshot = replay->lastSnapshot;
  const int64_t slack = std::llround(2.0 / replay->logged.params.step);
  int64_t end = start;
  for (const auto& h : hashes) {
    if (h.first > lastSnapshot + slack) {
      error = path + ": a state hash at step " + std::to_string(h.first) + " lies beyond the log's last snapshot (step " +
              std::to_string(lastSnapshot) + "): a damaged or altered log";
      return std::nullopt;
    }
    end = std::max(end, h.first);
  }
  if (std::none_of(hashes.begin(), hashes.end(), [&](const auto& h) { return h.first >= start; })) {
    error = path + ": the log holds no state hash at or after step " + std::to_string(start) +
            ": there is nothing to compare the re-simulation with";
    return std::nullopt;
  }

  size_t nextHash = 0;
  while (nextHash < hashes.size() && hashes[nextHash].first < start) ++nextHash;

  // Compares the hash logged at the current step, if any; true to go on.
  auto compare = [&]() {
    while (nextHash < hashes.size() && hashes[nextHash].first <= world->stepCount()) {
      const auto [step, expected] = hashes[nextHash++];
      if (step != world->stepCount()) continue;  // a step the re-simulation skipped cannot happen
      ++report.hashesCompared;
      const uint64_t actual = world->stateHash();
      if (actual != expected) {
        report.divergence = ResimDivergence{step, world->time(), expected, actual};
        return false;
      }
    }
    return true;
  };

  const auto progress = progressMonitor(options.progress, start, end, report.cancelled);
  runner.setMonitor([&](const World& w) { return compare() && progress(w); });
  if (compare() && runner.advanceTo(end).stop == RunOutcome::Stop::Diverged)
    report.healthMessage = world->health().message();
  report.commandsApplied = runner.commandsApplied();
  // A physical divergence before the end is a divergence from the log too.
  if (!report.divergence && !report.healthMessage.empty() && nextHash < hashes.size()) {
    const auto [step, expected] = hashes[nextHash];
    report.divergence = ResimDivergence{step, static_cast<double>(step) * replay->logged.params.step, expected, world->stateHash()};
  }
  report.endStep = world->stepCount();
  return report;
}

}  // namespace sp
