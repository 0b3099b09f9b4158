// simpartner-sim: the headless twin. `check` validates files, `run` runs a
// world paced against the monotonic clock.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "app/calibration/calibration.h"
#include "app/data/data_files.h"
#include "app/ghost/ghost.h"
#include "app/tools/headless_runner.h"
#include "app/log/log_export.h"
#include "app/validation/plot_svg.h"
#include "app/rehearse/rehearsal.h"
#include "app/log/resimulation.h"
#include "app/sweep/sweep.h"
#include "app/validation/validation.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/params.h"
#include "sim/terrain_file.h"
#include "sim/text.h"
#include "sim/urdf.h"

namespace {

constexpr const char* kUsage = R"(usage:
  simpartner-sim --version
      Prints the version.
  simpartner-sim check FILE...
      Validates robot (.xml), world (.world.xml), parameter (.params) and
      command sequence (.seq) files; sequences are also checked against the
      first robot or world given. Prints every problem as file:line: error:
      and exits 0 only when all files are clean.
  simpartner-sim run --world FILE [options]
      Runs the twin headless, paced by a monotonic clock.
      --params FILE     parameters (default: built-in, see config/defaults.params)
      --set KEY=VALUE   override one parameter (repeatable)
      --commands FILE   command sequence to apply (see docs/formats.md)
      --duration S      sim seconds to run (default 10)
      --rtf X|max       real-time factor (default: realtime.factor)
      --csv FILE        write link poses and joint states (rate.csv Hz)
      --log FILE        write a session log (SQLite; samples at rate.log Hz)
      --quiet           no progress lines
      Exits 0 when the run completed, 1 on bad input (a file, or a sequence
      command the twin refused when due: each is printed and logged as a
      "refused" event), 3 if the twin diverged
      (the report names what, where and when), 4 if the CSV could not be
      written whole (a full disk).
  simpartner-sim validate [--out DIR] [--quick] [--params FILE] [--set KEY=VALUE]...
                          [--convergence STEP/IT,...,STEP/exact]
      Runs the founding paper's five validation experiments headless and
      writes DIR/report.md (default DIR: validation), an SVG plot and the CSV
      data behind each. --quick runs short versions. Exits 0 when every
      experiment passes its target, 4 when some fail. --convergence runs
      the suite at each physics setting (step in seconds / quick solver
      iterations, or /exact), the last the reference, and writes
      DIR/convergence.md: every judged figure per setting against the
      reference, and the cheapest setting within 10 % of it on all.
  simpartner-sim params
      Prints every parameter key with its default and meaning.
  simpartner-sim resim LOG [--from S]
      Re-simulates a session log from the files it stores: restores the
      latest snapshot at or before S sim seconds (default 0), applies the
      logged commands and compares every logged state hash. Exits 0 when all
      match, 5 at the first divergence (printed), 1 if the log is unusable.
  simpartner-sim rehearse --world FILE --commands SEQ [options]
      Rehearses a command sequence on the twin from the world's start, as
      fast as it goes, checking the flight rules after every step, and prints
      each rule's verdict (first violation, or closest approach). The robot
      first settles from where the world places it (until its base stays
      within 3 mm for 0.5 s, at most 5 s: it says how long); t = 0 is then.
      One that does not settle is refused (exit 1, saying why).
      --rules FILE      flight rules (default: built-in, see config/flight.rules)
      --params FILE, --set KEY=VALUE   as for run
      --fast            in the fast profile (rehearsal.fast_step and
                        .fast_iterations): about 2x faster, a preview
      --robust N        also N perturbed rehearsals (ranges robust.* of the
                        rules), each in the fast profile and stopped at its
                        first failed rule
      Exits 0 when the sequence passed, 6 when a rule failed, 1 on bad input.
  simpartner-sim sweep --world FILE --commands SEQ --samples N --out DIR [options]
      Many rehearsals of one sequence, each with its own parameters and
      seed: writes DIR/manifest.txt (a line of --set arguments and a seed per
      sample) and runs it, on all cores or as a Slurm job array.
      --vary KEY=LO:HI  draw KEY uniformly in [LO, HI] per sample (repeatable)
      --seed S          the sweep's seed (default 1)
      --no-perturb      do not perturb friction, masses, terrain and start
      --rules FILE, --params FILE, --set KEY=VALUE   as for rehearse
      --jobs J          local threads (default: every core)
      --slurm           submit a job array with sbatch instead of running
      --sbatch ARG      pass ARG to sbatch (repeatable), e.g. --partition=sim
  simpartner-sim sweep --resume DIR [--jobs J] [--slurm] [--sbatch ARG]...
      Runs (or submits) only the tasks of DIR that have not run or failed.
  simpartner-sim sweep-task DIR [INDEX]
      Runs one sample (INDEX, or $SLURM_ARRAY_TASK_ID): what a job array runs.
  simpartner-sim collect DIR
      Gathers DIR's results into results.csv and report.md (pass/fail, end
      pose, minimum stability margin, health, end hash per sample), naming
      failed and missing tasks. Exits 0 when every task ran, 4 otherwise.
  simpartner-sim calibrate LOG [--out FILE] [--robot-out FILE] [--window S] [--profile ghost|robot]
      Fits the twin to the robot that made LOG (a robot's own log or a
      console's telemetry log): wheel radius and its front-rear, left-right
      and diagonal splits, tyre friction, wheel motor gain, command delay
      (fitting the twin's predictions) and total mass (from the wheel loads). Prints each with
      its deviation, or "unobserved" when the motion cannot tell, and writes
      the calibration.* keys to FILE (a parameters file; default: none).
      Fitted in the ghost's physics, the tyre radius splits are checked in
      the log's own over its last 16 s: a split the full physics predicts
      worse with is printed and written as the files' value.
      --robot-out FILE  also the log's robot file with the fitted masses,
                        tyre radii and wheel motor gain written in (friction
                        and delay stay parameters: a comment says so)
      --window S        fit the last S seconds (default: the whole log)
      --profile P       the twin fitted: ghost (the console's ghost's
                        physics, default) or robot (the log's own physics)
      Exits 0 with a fit, 1 when the log is unusable, 7 when the fit was
      refused (not enough motion, a diverging fit; the reason is printed).
  simpartner-sim export LOG --csv DIR
      Writes one CSV per stream of a session log into DIR (samples.csv,
      laser.csv, commands.csv, events.csv), headers naming columns and units.
  simpartner-sim export LOG --bag FILE
      Writes the session log as a ROS bag (/odom, /joint_states, /scan, /tf,
      /simpartner/commands, /simpartner/events; robot time), whole or not at
      all, with simpartner-ros-export (the ROS component, docs/ros.md).
  simpartner-sim urdf FILE [--out URDF]
      Writes the robot of FILE (a robot file, or a world's first robot) as
      URDF for ROS tools (RViz, check_urdf): links with the twin's inertia,
      visual and collision geometry, joints with limits, efforts and
      damping (docs/formats.md, "URDF"). To stdout, or to URDF whole or not
      at all. Exits 1 on a bad file or a robot URDF cannot describe.
)";

std::atomic<bool> gStop{false};

double monotonicSeconds() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

void sleepUntilSeconds(double t) {
  using namespace std::chrono;
  std::this_thread::sleep_until(steady_clock::time_point(duration_cast<steady_clock::duration>(duration<double>(t))));
}

bool endsWith(const std::string& s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

int check(const std::vector<std::string>& files) {
  sp::Diagnostics diag;
  std::optional<sp::RobotModel> robot;
  std::optional<sp::WorldModel> world;  // when the robot came from a world: its terrain checks terrain edits
  std::vector<std::string> sequences;
  for (const std::string& f : files) {
    if (endsWith(f, ".params")) {
      sp::SimParams p;
      sp::loadParams(f, p, diag);
    } else if (endsWith(f, ".seq")) {
      sequences.push_back(f);
    } else if (endsWith(f, ".xml")) {
      const std::string root = sp::xmlRootName(f);
      if (root == "world") {
        auto w = sp::loadWorld(f, diag);
        if (w && !w->robots.empty() && !robot) {
          robot = w->robots[0].model;
          world = std::move(w);
        }
      } else if (root == "robot" || root.empty()) {
        // Not well-formed XML (root "") is reported by the robot loader.
        auto r = sp::loadRobot(f, diag);
        if (r && !robot) robot = std::move(r);
      } else {
        diag.error(f, 0, "root element <" + root + "> is neither <robot> nor <world>");
      }
    } else if (!std::filesystem::exists(f)) {
      diag.error(f, 0, "no such file");
    } else {
      diag.error(f, 0, "unknown kind of file (expected .xml, .params or .seq)");
    }
  }
  for (const std::string& f : sequences) {
    auto seq = sp::loadCommandSequence(f, diag, robot ? &*robot : nullptr);
    if (seq && world)
      sp::checkCommands(*seq, *world, f, diag);
    else if (seq && robot)
      sp::checkCommands(*seq, *robot, f, diag);
  }
  std::cerr << diag.format();
  const int errors = diag.errorCount();
  const int warnings = static_cast<int>(diag.items().size()) - errors;
  std::cout << files.size() << " file(s) checked: " << errors << " error(s), " << warnings << " warning(s)\n";
  return errors == 0 ? 0 : 1;
}

int validate(const std::vector<std::string>& args) {
  sp::ValidationOptions o;
  std::string out = "validation", paramsFile, convergence;
  std::vector<std::string> overrides;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--quick") {
      o.quick = true;
    } else if (a == "--convergence" && i + 1 < args.size()) {
      convergence = args[++i];
    } else if ((a == "--out" || a == "--params" || a == "--set") && i + 1 < args.size()) {
      (a == "--out" ? out : a == "--params" ? paramsFile : overrides.emplace_back()) = args[++i];
    } else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  sp::Diagnostics diag;
  auto params = sp::loadRunParams(paramsFile, overrides, diag);
  std::cerr << diag.format();
  if (!params) return 2;
  o.params = *params;
  // The shipped robots/ and terrains/: from the working directory or the
  // data folder (app/data/data_files.h).
  namespace fs = std::filesystem;
  std::string dataError;
  const std::string flat = sp::findDataFile("terrains/flat.world.xml", dataError);
  if (flat.empty()) {
    std::cerr << dataError << "\n";
    return 1;
  }
  o.sourceDir = fs::path(flat).parent_path().parent_path().string();
  if (o.sourceDir.empty()) o.sourceDir = ".";
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) {
    std::cerr << out << ": error: cannot create the output folder: " << ec.message() << "\n";
    return 1;
  }
  if (!convergence.empty()) {
    std::string error;
    const auto settings = sp::parsePhysicsSettings(convergence, error);
    if (!settings) {
      std::cerr << "<command line>: error: " << error << "\n";
      return 2;
    }
    std::string report;
    try {
      report = sp::convergenceReport(sp::convergenceStudy(o, *settings, std::cout), o);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 1;
    }
    std::ofstream(out + "/convergence.md") << report;
    std::cout << report << "written to " << out << "/convergence.md\n";
    return 0;
  }
  std::cout << "SimPartner validation" << (o.quick ? " (quick)" : "") << ": the founding paper's five experiments\n";
  std::vector<sp::ExperimentResult> results;
  try {
    results = sp::runValidation(o, std::cout);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  for (const sp::ExperimentResult& r : results)
    for (const sp::ExperimentPlot& p : r.plots) {
      std::ofstream(out + "/" + p.file + ".csv") << sp::toCsv(p.spec);
      std::string error;
      if (!sp::writePlotSvg(p.spec, out + "/" + p.file + ".svg", error)) {
        std::cerr << "error: " << error << "\n";
        return 1;
      }
    }
  std::ofstream(out + "/report.md") << sp::validationReport(results, o);
  int passed = 0;
  for (const sp::ExperimentResult& r : results) passed += r.pass();
  std::cout << passed << " of " << results.size() << " experiments pass; report: " << out << "/report.md\n";
  return passed == static_cast<int>(results.size()) ? 0 : 4;
}

int printParams() {
  for (const sp::ParamInfo& p : sp::paramTable())
    std::cout << p.key << " = " << p.defaultValue << "\n    " << p.description << "\n";
  return 0;
}

int run(const std::vector<std::string>& args) {
  sp::RunOptions o;
  auto needValue = [&](size_t& i) -> const std::string* {
    if (i + 1 >= args.size()) {
      std::cerr << "<command line>: error: " << args[i] << " needs a value\n";
      return nullptr;
    }
    return &args[++i];
  };
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const std::string* v = nullptr;
    if (a == "--quiet") {
      o.progressInterval = 0;
      continue;
    }
    if (a != "--world" && a != "--params" && a != "--set" && a != "--commands" && a != "--duration" &&
        a != "--rtf" && a != "--csv" && a != "--log") {
      std::cerr << "<command line>: error: unknown option '" << a << "'\n" << kUsage;
      return 2;
    }
    if (!(v = needValue(i))) return 2;
    if (a == "--world") o.worldFile = *v;
    else if (a == "--params") o.paramsFile = *v;
    else if (a == "--set") o.overrides.push_back(*v);
    else if (a == "--commands") o.commandsFile = *v;
    else if (a == "--csv") o.csvFile = *v;
    else if (a == "--log") o.logFile = *v;
    else if (a == "--duration" || a == "--rtf") {
      if (a == "--rtf" && *v == "max") {
        o.realTimeFactor = 0;
        continue;
      }
      char* end = nullptr;
      const double x = std::strtod(v->c_str(), &end);
      if (end == v->c_str() || *end != '\0' || !(x > 0) || !std::isfinite(x)) {
        std::cerr << "<command line>: error: " << a << ": expected a finite positive number, got '" << *v << "'\n";
        return 2;
      }
      if (a == "--duration") o.duration = x;
      else o.realTimeFactor = x;
    }
  }
  if (o.worldFile.empty()) {
    std::cerr << "<command line>: error: run needs --world FILE\n" << kUsage;
    return 2;
  }
  std::signal(SIGINT, [](int) { gStop = true; });
  std::signal(SIGTERM, [](int) { gStop = true; });
  const auto report = sp::runHeadless(o, std::cout, std::cerr, monotonicSeconds, sleepUntilSeconds, &gStop);
  if (!report) return 1;
  if (!report->health.healthy()) return 3;
  if (report->commandsRefused > 0) return 1;
  return report->csvError.empty() ? 0 : 4;
}

// Whether args[i] is one of `options` and has a value after it; says why
// not on stderr.
bool knownWithValue(const std::vector<std::string>& args, size_t i, std::initializer_list<std::string_view> options) {
  const std::string& a = args[i];
  if (std::find(options.begin(), options.end(), a) == options.end()) {
    std::cerr << "<command line>: error: unknown option '" << a << "'\n" << kUsage;
    return false;
  }
  if (i + 1 >= args.size()) {
    std::cerr << "<command line>: error: " << a << " needs a value\n";
    return false;
  }
  return true;
}

int rehearseCommand(const std::vector<std::string>& args) {
  std::string worldFile, commandsFile, rulesFile, paramsFile;
  std::vector<std::string> overrides;
  int robust = 0;
  bool fast = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--fast") {
      fast = true;
      continue;
    }
    if (!knownWithValue(args, i, {"--world", "--commands", "--rules", "--params", "--set", "--robust"})) return 2;
    const std::string& v = args[++i];
    if (a == "--world") worldFile = v;
    else if (a == "--commands") commandsFile = v;
    else if (a == "--rules") rulesFile = v;
    else if (a == "--params") paramsFile = v;
    else if (a == "--set") overrides.push_back(v);
    else {
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end != '\0' || n < 1 || n > 100000) {
        std::cerr << "<command line>: error: --robust: expected a count 1..100000, got '" << v << "'\n";
        return 2;
      }
      robust = static_cast<int>(n);
    }
  }
  if (worldFile.empty() || commandsFile.empty()) {
    std::cerr << "<command line>: error: rehearse needs --world FILE and --commands FILE\n";
    return 2;
  }
  sp::Diagnostics diag;
  std::optional<sp::WorldModel> world = sp::loadWorld(worldFile, diag);
  sp::SimParams params;
  if (world && world->robots.empty()) diag.error(worldFile, 0, "the world has no robot to rehearse");
  if (!paramsFile.empty()) sp::loadParams(paramsFile, params, diag);
  for (const std::string& o : overrides) sp::applyOverride(params, o, diag);
  sp::FlightRules rules;
  if (!rulesFile.empty()) sp::loadFlightRules(rulesFile, rules, diag);
  std::optional<std::vector<sp::TimedCommand>> commands;
  if (world && !world->robots.empty()) {
    commands = sp::loadCommandSequence(commandsFile, diag, &world->robots[0].model);
    if (commands) sp::checkCommands(*commands, *world, commandsFile, diag);
  }
  if (diag.hasErrors() || !commands) {
    std::cerr << diag.format();
    return 1;
  }
  if (robust > 0) rules.robustSamples = robust;
  sp::RehearsalPlan plan{*world, params, rules, *commands, std::nullopt};
  plan.fast = fast;
  const sp::RehearsalResult r = sp::rehearse(plan);
  if (!r.error.empty()) {
    std::cerr << "error: " << r.error << "\n";
    return 1;
  }
  std::cout << "rehearsal of " << commandsFile << " (hash " << sp::sequenceHash(sp::sequenceText(*commands, &world->robots[0].model))
            << ") on " << worldFile << ": " << r.duration << " s simulated in " << r.wallSeconds << " s, after "
            << r.settled << " s for the robot to settle from the world's start"
            << (!r.refined.empty() ? " (fast profile, run again at full fidelity: " + r.refined + "; not sendable)"
                : fast ? " (fast profile: step " + sp::shortestText(params.rehearsalFastStep * 1000) + " ms, " +
                             std::to_string(params.rehearsalFastIterations) + " iterations; a preview, not sendable)"
                       : std::string())
            << "\n";
  for (const sp::RuleVerdict& v : r.verdicts) std::cout << "  " << (v.passed ? "pass  " : "FAIL  ") << v.message() << "\n";
  for (const std::string& why : r.refused) std::cerr << commandsFile << ": error: refused: " << why << "\n";
  std::cout << (r.passed ? "passed" : "failed: " + r.summary()) << "\n";
  if (robust > 0) {
    sp::RehearsalPlan samples = plan;
    samples.fast = samples.stopAtFirstFailure = true;
    const sp::RobustnessResult rob = sp::robustness(samples, 1, 2);
    std::cout << "robustness: " << rob.passed << " of " << rob.samples << " passed (" << 100 * rob.probability()
              << " %), end positions within " << rob.spread << " m of their mean, " << rob.wallSeconds << " s; "
              << rob.refined << " run again at full fidelity (failed or near a limit)\n";
    for (int i = 0; i < rob.samples; ++i)
      if (!rob.samplePassed[i]) std::cout << "  sample " << i << ": " << rob.failures[i] << "\n";
  }
  return r.passed ? 0 : 6;
}

int resim(const std::vector<std::string>& args) {
  std::string log;
  sp::ResimOptions options;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--from" && i + 1 < args.size()) {
      char* end = nullptr;
      options.from = std::strtod(args[++i].c_str(), &end);
      if (*end != '\0' || !(options.from >= 0)) {
        std::cerr << "<command line>: error: --from: expected seconds >= 0, got '" << args[i] << "'\n";
        return 2;
      }
    } else if (log.empty() && !args[i].empty() && args[i][0] != '-') {
      log = args[i];
    } else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << args[i] << "'\n" << kUsage;
      return 2;
    }
  }
  if (log.empty()) {
    std::cerr << "<command line>: error: resim needs a LOG file\n";
    return 2;
  }
  // Progress on a terminal only (a long log takes minutes): "\r 37 %".
  if (isatty(STDERR_FILENO))
    options.progress = [](double f) {
      std::fprintf(stderr, "\rre-simulating: %3d %%", static_cast<int>(f * 100));
      return true;
    };
  std::string error;
  const auto report = sp::resimulate(log, options, error);
  if (options.progress) std::fprintf(stderr, "\r                    \r");
  if (!report) {
    std::cerr << error << "\n";
    return 1;
  }
  std::cout << "re-simulated steps " << report->startStep << " to " << report->endStep << ", "
            << report->commandsApplied << " commands applied, " << report->hashesCompared << " hashes compared\n";
  if (!report->healthMessage.empty()) std::cout << "the twin diverged: " << report->healthMessage << "\n";
  if (const auto& d = report->divergence) {
    std::cout << "divergence at step " << d->step << " (t = " << d->time << " s): expected hash "
              << sp::hashHex(d->expected) << ", got " << sp::hashHex(d->actual) << "\n";
    return 5;
  }
  std::cout << "no divergence\n";
  return 0;
}

int exportLog(const std::vector<std::string>& args, const char* argv0) {
  std::string log, dir, bag;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--csv" && i + 1 < args.size()) dir = args[++i];
    else if (args[i] == "--bag" && i + 1 < args.size()) bag = args[++i];
    else if (log.empty() && !args[i].empty() && args[i][0] != '-') log = args[i];
    else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << args[i] << "'\n" << kUsage;
      return 2;
    }
  }
  if (log.empty() || dir.empty() == bag.empty()) {
    std::cerr << "<command line>: error: export needs LOG and one of --csv DIR, --bag FILE\n";
    return 2;
  }
  if (!bag.empty()) {
    // ROS bags come from the ROS component (ros/), built only with ROS's
    // packages: its exporter sits beside this program, which links no ROS.
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    const fs::path exporter = (ec ? fs::path(argv0) : self).parent_path() / "simpartner-ros-export";
    if (!fs::exists(exporter)) {
      std::cerr << "error: --bag needs the ROS component (" << exporter.string()
                << " is missing): install Debian's ROS 1 packages (scripts/install-deps.sh) and build again\n";
      return 1;
    }
    const std::string path = exporter.string();
    execl(path.c_str(), path.c_str(), log.c_str(), "--bag", bag.c_str(), static_cast<char*>(nullptr));
    std::cerr << "error: cannot run " << path << ": " << std::strerror(errno) << "\n";
    return 1;
  }
  std::string error;
  std::vector<std::string> written;
  if (!sp::exportLogCsv(log, dir, error, &written)) {
    std::cerr << error << "\n";
    return 1;
  }
  for (const std::string& f : written) std::cout << "wrote " << f << "\n";
  return 0;
}

int urdfCommand(const std::vector<std::string>& args) {
  std::string file, out;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--out" && i + 1 < args.size()) out = args[++i];
    else if (file.empty() && !args[i].empty() && args[i][0] != '-') file = args[i];
    else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << args[i] << "'\n" << kUsage;
      return 2;
    }
  }
  if (file.empty()) {
    std::cerr << "<command line>: error: urdf needs a robot or world file\n";
    return 2;
  }
  // A robot file, or a world's first robot.
  sp::Diagnostics diag;
  std::optional<sp::RobotModel> robot;
  if (endsWith(file, ".world.xml")) {
    if (std::optional<sp::WorldModel> world = sp::loadWorld(file, diag); world && !world->robots.empty())
      robot = world->robots.front().model;
    else if (world) diag.error(file, 0, "the world has no robot");
  } else {
    robot = sp::loadRobot(file, diag);
  }
  std::cerr << diag.format();
  if (!robot) return 1;
  std::string error;
  const std::optional<std::string> urdf = sp::robotUrdf(*robot, error);
  if (!urdf) {
    std::cerr << file << ": error: " << error << "\n";
    return 1;
  }
  if (out.empty()) {
    std::cout << *urdf;
    return 0;
  }
  if (!sp::writeFileAtomically(out, *urdf, error)) {  // nothing half-written
    std::cerr << error << "\n";
    return 1;
  }
  std::cout << "wrote " << out << " (" << robot->links.size() << " links, " << robot->joints.size() << " joints)\n";
  return 0;
}

int calibrate(const std::vector<std::string>& args) {
  std::string log, out, robotOut, profileName = "ghost";
  double window = 0;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if ((a == "--out" || a == "--robot-out" || a == "--window" || a == "--profile") && i + 1 < args.size()) {
      const std::string& v = args[++i];
      if (a == "--out") out = v;
      else if (a == "--robot-out") robotOut = v;
      else if (a == "--profile") profileName = v;
      else {
        char* end = nullptr;
        window = std::strtod(v.c_str(), &end);
        if (end == v.c_str() || *end != '\0' || !(window > 0)) {
          std::cerr << "<command line>: error: --window: expected seconds > 0, got '" << v << "'\n";
          return 2;
        }
      }
    } else if (log.empty() && !a.empty() && a[0] != '-') {
      log = a;
    } else {
      std::cerr << "<command line>: error: unknown or incomplete option '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  if (log.empty() || (profileName != "ghost" && profileName != "robot")) {
    std::cerr << "<command line>: error: calibrate needs a LOG file (and --profile ghost or robot)\n";
    return 2;
  }
  std::string error;
  std::optional<sp::CalibrationInput> in = sp::calibrationInput(log, error);
  if (!in) {
    std::cerr << error << "\n";
    return 1;
  }
  const sp::SimParams profile = profileName == "ghost" ? sp::Ghost::profile(in->params) : in->params;
  sp::CalibrationOptions options;
  options.window = window;
  options.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  options.iterations = 5;
  const sp::CalibrationFit fit =
      sp::fitCalibration(in->world, profile, in->frames, in->commands, sp::calValues(in->params), options);
  if (!fit.refused.empty()) {
    std::cerr << log << ": calibration refused: " << fit.refused << "\n";
    return 7;
  }
  std::printf("%s: %d segments over %.1f - %.1f s, %d twin runs, %.0f ms; cost %.3g -> %.3g\n", log.c_str(),
              fit.segments, fit.from, fit.to, fit.twinRuns, fit.wallMs, fit.costBefore, fit.costAfter);
  // Fitted in the ghost's profile: the radius splits are checked in the
  // log's own physics before a file gets them, as the console does for its
  // rehearsals (calibration.h, fullPhysicsValues), over the newest 16 s.
  sp::CalibrationFit written = fit;
  if (profileName == "ghost") {
    const sp::FullPhysicsCheck check =
        sp::fullPhysicsValues(in->world, in->params, in->frames, in->commands, fit.value, 16, options.threads);
    if (!check.problem.empty()) {
      std::printf("full physics: not checked (%s): the splits are written as fitted\n", check.problem.c_str());
    } else {
      for (sp::CalParam q : sp::kFullPhysicsChecked) {
        const size_t i = static_cast<size_t>(q);
        if (check.values[i] == fit.value[i]) continue;
        std::printf("full physics: %s %.5f put back to the files' %.5f (it predicts the robot better without it: cost %.4g "
                    "against %.4g)\n",
                    sp::calParams()[i].key, fit.value[i], check.values[i], check.costWithout[i], check.cost);
        written.value[i] = check.values[i];
        written.observed[i] = false;
      }
    }
  }
  for (size_t i = 0; i < sp::kCalParams; ++i) {
    const sp::CalParamInfo& p = sp::calParams()[i];
    if (fit.observed[i])
      std::printf("%-32s %.5f +- %.5f%s\n", p.key, fit.value[i], fit.sigma[i], *p.unit ? (std::string(" ") + p.unit).c_str() : "");
    else
      std::printf("%-32s %.5f unobserved\n", p.key, fit.value[i]);
  }
  if (!out.empty()) {
    std::ofstream f(out);
    f << sp::calibrationParamsText(written);
    if (!f.flush()) {
      std::cerr << out << ": error: cannot write the parameters file\n";
      return 1;
    }
    std::printf("wrote %s\n", out.c_str());
  }
  if (!robotOut.empty()) {
    const std::optional<std::string> text = sp::calibratedRobotText(
        in->robotText, in->world.robots[0].model, sp::withCalValues(in->params, written.value), error);
    std::ofstream f;
    if (text) f.open(robotOut);
    if (!text || !(f << *text).flush()) {
      std::cerr << (text ? robotOut + ": error: cannot write the robot file" : error) << "\n";
      return 1;
    }
    std::printf("wrote %s\n", robotOut.c_str());
  }
  return 0;
}

int collectCommand(const std::vector<std::string>& args);

int sweepCommand(const std::vector<std::string>& args, const char* argv0) {
  sp::SweepSpec spec;
  std::string out, resume;
  std::vector<std::string> sbatchArgs;
  bool slurm = false;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool haveSamples = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--no-perturb") {
      spec.perturb = false;
      continue;
    }
    if (a == "--slurm") {
      slurm = true;
      continue;
    }
    if (!knownWithValue(args, i,
                        {"--world", "--commands", "--rules", "--params", "--set", "--vary", "--samples", "--seed",
                         "--out", "--jobs", "--resume", "--sbatch"}))
      return 2;
    const std::string& v = args[++i];
    const auto count = [&](long lo, long hi, long& n) {
      char* end = nullptr;
      n = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end != '\0' || n < lo || n > hi) {
        std::cerr << "<command line>: error: " << a << ": expected " << lo << ".." << hi << ", got '" << v << "'\n";
        return false;
      }
      return true;
    };
    long n = 0;
    if (a == "--world") spec.world = v;
    else if (a == "--commands") spec.commands = v;
    else if (a == "--rules") spec.rules = v;
    else if (a == "--params") spec.params = v;
    else if (a == "--set") spec.overrides.push_back(v);
    else if (a == "--out") out = v;
    else if (a == "--resume") resume = v;
    else if (a == "--sbatch") sbatchArgs.push_back(v);
    else if (a == "--vary") {
      sp::SweepVary vary;
      if (const std::string why = sp::parseVary(v, vary); !why.empty()) {
        std::cerr << "<command line>: error: " << why << "\n";
        return 2;
      }
      spec.vary.push_back(vary);
    } else if (a == "--samples") {
      if (!count(1, 100000, n)) return 2;
      spec.samples = static_cast<int>(n);
      haveSamples = true;
    } else if (a == "--seed") {
      if (!count(0, std::numeric_limits<long>::max(), n)) return 2;
      spec.seed = static_cast<uint64_t>(n);
    } else if (a == "--jobs") {
      if (!count(1, 256, n)) return 2;
      jobs = static_cast<int>(n);
    }
  }
  std::string error;
  std::string dir = resume;
  if (resume.empty()) {
    if (spec.world.empty() || spec.commands.empty() || !haveSamples || out.empty()) {
      std::cerr << "<command line>: error: sweep needs --world FILE, --commands SEQ, --samples N and --out DIR "
                   "(or --resume DIR)\n";
      return 2;
    }
    if (!sp::createSweep(out, spec, error)) {
      std::cerr << error << "\n";
      return 1;
    }
    dir = out;
  }
  if (slurm) {
    // The tasks run this very binary: its full path, however it was started.
    std::error_code ec;
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
    const std::string job = sp::submitSlurm(dir, {}, ec ? std::string(argv0) : self.string(), sbatchArgs, error);
    if (job.empty()) {
      std::cerr << error << "\n";
      return 1;
    }
    std::cout << "submitted job array " << job << " for " << dir << "; when it is done: simpartner-sim collect " << dir
              << "\n";
    return 0;
  }
  if (!sp::runSweepLocal(dir, {}, jobs, error)) {
    std::cerr << error << "\n";
    return 1;
  }
  return collectCommand({dir});
}

int sweepTaskCommand(const std::vector<std::string>& args) {
  if (args.empty() || args.size() > 2) {
    std::cerr << "<command line>: error: sweep-task needs DIR [INDEX]\n";
    return 2;
  }
  const char* env = std::getenv("SLURM_ARRAY_TASK_ID");
  const std::string text = args.size() == 2 ? args[1] : (env ? env : "");
  char* end = nullptr;
  const long index = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || index < 0 || index >= 100000) {
    std::cerr << "<command line>: error: sweep-task: expected INDEX 0..99999 or SLURM_ARRAY_TASK_ID, got '" << text
              << "'\n";
    return 2;
  }
  std::string error;
  if (!sp::runSweepTask(args[0], static_cast<int>(index), error)) {
    std::cerr << "task " << index << ": " << error << "\n";
    return 1;
  }
  return 0;
}

int collectCommand(const std::vector<std::string>& args) {
  if (args.size() != 1) {
    std::cerr << "<command line>: error: collect needs DIR\n";
    return 2;
  }
  std::string error;
  const sp::SweepSummary s = sp::collectSweep(args[0], error);
  if (!error.empty()) {
    std::cerr << error << "\n";
    return 1;
  }
  std::cout << args[0] << ": " << s.passed << " of " << s.done << " samples passed every rule; " << s.missing.size()
            << " missing, " << s.failed.size() << " failed to run; " << args[0] << "/report.md\n";
  return s.done == s.samples ? 0 : 4;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "--version") {
    std::cout << "simpartner-sim " << SP_VERSION << "\n";
    return 0;
  }
  const std::string cmd = args[0];
  args.erase(args.begin());
  // Files named relative to the data folder (terrains/..., robots/...) are
  // found there from any working directory; one found nowhere stays as
  // given, and its command says it cannot open it.
  const auto dataFile = [](std::string& path) {
    std::string error;
    if (std::string found = sp::findDataFile(path, error); !found.empty()) path = found;
  };
  for (size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == "--world" || args[i] == "--commands" || args[i] == "--rules" || args[i] == "--params")
      dataFile(args[++i]);
  if (cmd == "check")
    for (std::string& file : args) dataFile(file);
  if (cmd == "check") {
    if (args.empty()) {
      std::cerr << "<command line>: error: check needs at least one file\n";
      return 2;
    }
    return check(args);
  }
  if (cmd == "run") return run(args);
  if (cmd == "params") return printParams();
  if (cmd == "validate") return validate(args);
  if (cmd == "resim") return resim(args);
  if (cmd == "rehearse") return rehearseCommand(args);
  if (cmd == "export") return exportLog(args, argv[0]);
  if (cmd == "calibrate") return calibrate(args);
  if (cmd == "urdf") return urdfCommand(args);
  if (cmd == "sweep") return sweepCommand(args, argv[0]);
  if (cmd == "sweep-task") return sweepTaskCommand(args);
  if (cmd == "collect") return collectCommand(args);
  std::cerr << "<command line>: error: unknown command '" << cmd << "'\n" << kUsage;
  return 2;
}
