#include "app/run/headless_runner.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "app/log/session_recorder.h"
#include "app/state/run_params.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/pacer.h"
#include "sim/perturbation.h"
#include "sim/runner.h"

namespace sp {
namespace {

/// Writes one row per sample of the first robot: link poses, joint states.
class CsvWriter {
 public:
  CsvWriter(std::ostream& out, const World& world) : out_(out) {
    const RobotModel& robot = world.robotModel(0);
    out_ << "time_s";
    for (const LinkSpec& l : robot.links)
      for (const char* c : {"x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"}) out_ << ',' << l.name << '.' << c;
    for (const JointSpec& j : robot.joints) {
      const bool slider = j.type == JointType::Slider;
      out_ << ',' << j.name << (slider ? ".pos_m" : ".pos_rad") << ',' << j.name
           << (slider ? ".vel_m_s" : ".vel_rad_s");
    }
    out_ << '\n' << std::setprecision(9);
  }

  void sample(const World& world) {
    const RobotModel& robot = world.robotModel(0);
    out_ << world.time();
    for (size_t l = 0; l < robot.links.size(); ++l) {
      const Pose p = world.linkPose(0, static_cast<int>(l));
      out_ << ',' << p.p.x << ',' << p.p.y << ',' << p.p.z << ',' << p.q.w << ',' << p.q.x << ',' << p.q.y
           << ',' << p.q.z;
    }
    for (size_t j = 0; j < robot.joints.size(); ++j)
      out_ << ',' << world.jointPosition(0, static_cast<int>(j)) << ','
           << world.jointRate(0, static_cast<int>(j));
    out_ << '\n';
  }

 private:
  std::ostream& out_;
};

// What a run is given, loaded and checked.
struct LoadedRun {
  SimParams params;
  WorldModel model;
  std::vector<TimedCommand> commands;
};

std::optional<LoadedRun> loadRun(const RunOptions& options, std::ostream& err) {
  Diagnostics diag;
  std::optional<SimParams> params = loadRunParams(options.paramsFile, options.overrides, diag);
  std::optional<WorldModel> model = loadWorld(options.worldFile, diag);
  std::vector<TimedCommand> commands;
  if (model && model->robots.empty())
    diag.error(options.worldFile, 0, "the world has no <robot> to run");
  if (!options.commandsFile.empty() && model && !model->robots.empty()) {
    const RobotModel& robot = model->robots[0].model;
    if (auto seq = loadCommandSequence(options.commandsFile, diag, &robot)) {
      if (checkCommands(*seq, *model, options.commandsFile, diag)) commands = std::move(*seq);
    }
  }
  if (options.realTimeFactor && params) params->realTimeFactor = *options.realTimeFactor;
  if (!(options.duration > 0)) diag.error("<command line>", 0, "--duration must be > 0");
  err << diag.format();
  if (diag.hasErrors() || !params || !model) return std::nullopt;
  return LoadedRun{std::move(*params), std::move(*model), std::move(commands)};
}

void printHeader(std::ostream& out, const RunOptions& options, const LoadedRun& run) {
  const SimParams& params = run.params;
  const RobotInstance& robot = run.model.robots[0];
  out << "SimPartner headless twin\n"
      << "  world  '" << run.model.name << "' (" << options.worldFile << "), terrain "
      << (run.model.terrain.kind == TerrainSpec::Kind::Plane ? "plane" : "heightfield " + run.model.terrain.file)
      << "\n  robot  '" << robot.name << "' from " << robot.model.file << ": " << robot.model.links.size()
      << " links, " << robot.model.joints.size() << " joints, " << robot.model.actuators.size()
      << " actuators, " << std::fixed << std::setprecision(1) << robot.model.totalMass() << " kg\n"
      << "  physics step " << params.step * 1000 << " ms, "
      << (params.solver == Solver::Quick ? "quick solver, " + std::to_string(params.iterations) + " iterations"
                                         : std::string("exact solver"))
      << "\n  running " << options.duration << " s of sim time "
      << (params.realTimeFactor > 0 ? "at " + std::to_string(params.realTimeFactor).substr(0, 5) + "x real time"
                                    : std::string("as fast as possible"))
      << (run.commands.empty() ? std::string(", no commands")
                               : ", " + std::to_string(run.commands.size()) + " commands from " + options.commandsFile)
      << "\n";
}

// The run's CSV and session log, where asked for.
struct RunOutputs {
  std::ofstream csvFile;
  std::unique_ptr<CsvWriter> csv;
  std::unique_ptr<SessionRecorder> log;
};

bool openOutputs(const RunOptions& options, const LoadedRun& run, const World& world, std::ostream& out,
                 std::ostream& err, RunOutputs& o) {
  if (!options.csvFile.empty()) {
    o.csvFile.open(options.csvFile);
    if (!o.csvFile) {
      err << options.csvFile << ": error: cannot write CSV file\n";
      return false;
    }
    o.csv = std::make_unique<CsvWriter>(o.csvFile, world);
    out << "  writing CSV at " << run.params.csvRate << " Hz to " << options.csvFile << "\n";
  }
  if (!options.logFile.empty()) {
    std::string error;
    std::unique_ptr<SessionLogWriter> writer = openSessionLog(
        options.logFile,
        {.worldFile = options.worldFile,
         .robotFile = run.model.robots[0].model.file,
         .paramsFile = options.paramsFile,
         .terrainFile = run.model.terrain.file,
         .commandsFile = options.commandsFile,
         .overrides = options.overrides,
         .replacedRobotFile = {}},
        error);
    if (!writer) {
      err << error << "\n";
      return false;
    }
    o.log = std::make_unique<SessionRecorder>(std::move(writer), world);
    out << "  logging the session at " << run.params.logRate << " Hz to " << options.logFile << "\n";
  }
  return true;
}

// Ends the log and the CSV, their troubles into `report`.
void closeOutputs(const RunOptions& options, const World& world, RunReport& report, RunOutputs& o, std::ostream& err) {
  if (o.log) {
    if (!report.health.healthy())
      o.log->writer().logEvent(report.health.step, report.health.time, "health", report.health.message());
    if (report.interrupted) o.log->writer().logEvent(world.stepCount(), world.time(), "interrupted", "");
    o.log->finish(world);
    o.log->writer().close();
    report.logDropped = o.log->writer().dropped();
    report.logError = o.log->writer().errorMessage();
  }
  if (o.csv) {
    // A full disk cuts the file mid-line; the stream only says so when asked.
    o.csvFile.flush();
    o.csvFile.close();
    if (!o.csvFile) {
      report.csvError = options.csvFile + ": error: writing the CSV failed (is the disk full?): the file is incomplete";
      err << report.csvError << "\n";
    }
  }
}

void printSummary(std::ostream& out, std::ostream& err, const RunOptions& options, const RunReport& report,
                  const World& world, bool paced, const RunOutputs& o) {
  const Pose base = world.linkPose(0, 0);
  if (!report.health.healthy()) err << "error: the twin diverged: " << report.health.message() << "\n";
  out << std::setprecision(3)
      << (report.interrupted ? "interrupted" : report.health.healthy() ? "done" : "stopped") << ": "
      << report.simTime
      << " s simulated in " << report.wallTime << " s wall, " << std::setprecision(2) << report.achievedFactor
      << "x real time";
  if (paced)
    out << " (requested " << report.requestedFactor << "x; sim time - wall x factor at the end "
        << std::setprecision(3) << report.finalError * 1000 << " ms, worst lag " << report.maxLag * 1000
        << " ms, " << report.resyncs << " resyncs)";
  char hash[32];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(report.stateHash));
  out << "\n  " << report.commandsApplied << " commands applied"
      << (report.commandsRefused ? ", " + std::to_string(report.commandsRefused) + " refused" : std::string())
      << "; base ended at (" << base.p.x << ", "
      << base.p.y << ", " << base.p.z << ") m; state hash " << hash << "\n";
  if (o.log && !report.logError.empty() && o.log->newlyFailed()) err << "error: " << report.logError << "\n";
  if (o.log && report.logError.empty() && report.logDropped > 0)
    err << "warning: " << options.logFile << ": " << report.logDropped
        << " log items dropped (the writer could not keep up)\n";
  if (paced && report.resyncs > 0)
    out << "warning: this machine cannot keep up with " << report.requestedFactor << "x real time: achieved "
        << std::setprecision(2) << report.achievedFactor << "x, " << std::setprecision(3) << report.slipped
        << " s of sim time ran late\n";
}

}  // namespace

std::optional<RunReport> runHeadless(const RunOptions& options, std::ostream& out, std::ostream& err,
                                     const ClockFn& clock, const SleepUntilFn& sleepUntil,
                                     const std::atomic<bool>* stop) {
  std::optional<LoadedRun> run = loadRun(options, err);
  if (!run) return std::nullopt;
  const SimParams* params = &run->params;
  Diagnostics diag;
  std::unique_ptr<World> world = World::create(calibratedWorld(run->model, *params), *params, diag);
  if (!world) {
    err << diag.format();
    return std::nullopt;
  }
  const RobotInstance& robot = run->model.robots[0];
  printHeader(out, options, *run);
  RunOutputs o;
  if (!openOutputs(options, *run, *world, out, err, o)) return std::nullopt;
  auto& csv = o.csv;
  auto& log = o.log;
  std::vector<TimedCommand>& commands = run->commands;
  const int64_t csvEvery = std::max<int64_t>(1, std::llround(1.0 / (params->csvRate * params->step)));
  const int64_t totalSteps = std::llround(options.duration / params->step);

  Pacer pacer({params->step, params->realTimeFactor, 0.1, 100});
  RunReport report;
  report.requestedFactor = params->realTimeFactor;
  Runner runner(*world);
  // A calibrated twin acts on each command its delay after it is due.
  for (TimedCommand& c : commands) c.time += params->calDelay;
  runner.schedule(commands);
  runner.setSubmitHook([&](const ScheduledCommand& c, const std::string& why) {
    if (why.empty()) {
      if (log) log->writer().logCommand(world->stepCount(), world->time(), "sequence", c.command, &robot.model);
      return;
    }
    // Refused when due (the checks above catch what they can beforehand):
    // said at once, logged, and the run's exit says so.
    ++report.commandsRefused;
    const std::string where = options.commandsFile + ":" + std::to_string(c.line);
    err << where << ": error: refused at t = " << world->time() << " s: " << why << "\n";
    if (log) log->writer().logEvent(world->stepCount(), world->time(), "refused", where + ": " + why);
  });
  runner.setMonitor([&](const World& w) {
    if (csv && w.stepCount() % csvEvery == 0) csv->sample(w);
    if (log) {
      log->stepped(w);
      if (log->newlyFailed())
        err << "error: " << log->writer().errorMessage() << "; the run goes on without logging\n";
    }
    return true;
  });
  const double wallStart = clock();
  double nextProgress = wallStart + options.progressInterval;
  pacer.start(wallStart);
  if (csv) csv->sample(*world);
  if (log) log->start(*world);
  while (world->stepCount() < totalSteps) {
    if (stop && stop->load()) {
      report.interrupted = true;
      break;
    }
    const int64_t due = std::min(pacer.stepsDue(clock()), totalSteps - world->stepCount());
    runner.advanceBy(due);
    pacer.stepped(due);
    if (!world->health().healthy()) break;
    const double now = clock();
    if (pacer.paced()) report.maxLag = std::max(report.maxLag, -pacer.lead(now));
    if (options.progressInterval > 0 && now >= nextProgress) {
      nextProgress += options.progressInterval;
      const Pose base = world->linkPose(0, 0);
      out << "  t=" << std::setprecision(1) << world->time() << " s  base at (" << std::setprecision(2)
          << base.p.x << ", " << base.p.y << ", " << base.p.z << ") m  " << std::setprecision(2)
          << pacer.achievedFactor(now) << "x real time\n";
    }
    if (due == 0 && pacer.paced()) sleepUntil(pacer.nextDeadline());
  }
  const double wallEnd = clock();
  report.simTime = world->time();
  report.wallTime = wallEnd - wallStart;
  report.achievedFactor = pacer.achievedFactor(wallEnd);
  report.finalError = pacer.paced() ? pacer.lead(wallEnd) : 0;
  report.resyncs = pacer.resyncCount();
  report.slipped = pacer.slippedTime();
  report.steps = world->stepCount();
  report.commandsApplied = runner.commandsApplied();
  report.stateHash = world->stateHash();
  report.health = world->health();
  closeOutputs(options, *world, report, o, err);
  printSummary(out, err, options, report, *world, pacer.paced(), o);
  return report;
}

}  // namespace sp
