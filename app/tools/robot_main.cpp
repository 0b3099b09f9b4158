// simpartner-robot: the stand-in robot. Runs the twin headless and speaks
// the robot's side of the link protocol (docs/protocol.md) on TCP, exactly as
// a real robot's adapter would, so that everything can be tested without
// hardware.

#include <signal.h>
#include <unistd.h>

#include <iostream>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "app/data/data_files.h"
#include "app/robot/line_writer.h"
#include "app/robot/stand_in.h"
#include "sim/model_loader.h"
#include "sim/perturbation.h"

namespace {

constexpr const char* kUsage = R"(usage:
  simpartner-robot [--world FILE] [options]
      Runs the twin as a robot on the link protocol (docs/protocol.md).
      --world FILE      world to run (default terrains/flat.world.xml); a
                        relative name not found from the working directory
                        is taken from the data folder (installed with the
                        program; $SIMPARTNER_DATA overrides)
      --ground FILE     stand on FILE's terrain instead of the world's, which
                        is still announced and logged as the robot's files:
                        ground its map lacks (terrains/rough_unmapped.world.xml)
      --port N          TCP port (default: port.robot of the parameters; 0 = any free port)
      --bind ADDRESS    address to listen on (default 127.0.0.1); any other
                        address needs --token
      --token HEX       shared secret, >= 32 hex digits; without it on
                        loopback a random one is made and printed
      --params FILE     parameters file; --set KEY=VALUE overrides (repeatable)
      --rtf X|max       real-time factor (default: realtime.factor)
      --delay S         emulate a slow link: one-way delay [s] in both directions
      --jitter S        and +- this much jitter [s]
      --loss P          and lose each frame with probability P
      --log FILE        write the session log to FILE (must not exist)
      --log-dir DIR     write it to a new DIR/session-YYYYMMDD-HHMMSS.splog
                        (default: sessions/ under the current directory)
      --no-log          write no session log
      --no-terrain-edits  refuse terrain edits as a real robot does (the
                        stand-in, a simulator, takes them by default)
      --perturb SEED    a robot that is not its twin: hidden deviations from
                        the files drawn from SEED (wheel radius +-3 %, link
                        masses +-15 % and centres of mass +-2 cm, friction
                        +-30 %, wheel torque limit and speed gain +-20 %,
                        actuator delay 0-60 ms, IMU roll/pitch bias +-1 deg);
                        WELCOME and telemetry do not tell them, the log does
      --weak-motor WHEEL=F  that wheel motor's torque limit times F (fl, fr, rl
                        or rr; F in (0, 2]; repeatable): a weak motor, with or
                        without --perturb; the log records it
      --change T,F,D    at robot time T s the contacts' friction times F and
                        the actuator delay D s longer (30,0.7,0.1): a robot
                        that changes while it runs; the log notes it, a
                        replay does not re-apply it
      --perturb-report  print the deviations (with --perturb) and exit
  Prints `world PATH`, `logging to PATH`, then `listening on ADDRESS:PORT`
  when ready;
  connections, lease changes and e-stops go to stderr. On SIGINT or SIGTERM
  it stops every motor (as an e-stop), tells every client why and closes
  them, waits for the robot to come to rest (at most 3 s), then exits; the
  log ends with the stop and the robot at rest. The session log (docs/session-format.md) re-simulates with
  `simpartner-sim resim PATH`.
)";

// Reads the command line into `options`; an exit code when it is done
// (--help, --version) or wrong.
std::optional<int> parseArgs(const std::vector<std::string>& args, sp::StandInOptions& options, bool& perturbReport) {
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      std::cout << kUsage;
      return 0;
    }
    if (a == "--version") {
      std::cout << "simpartner-robot " << SP_VERSION << "\n";
      return 0;
    }
    if (a == "--no-log") {
      options.log = false;
      continue;
    }
    if (a == "--no-terrain-edits") {
      options.terrainEdits = false;
      continue;
    }
    if (a == "--perturb-report") {
      perturbReport = true;
      continue;
    }
    if (i + 1 >= args.size()) {
      std::cerr << "<command line>: error: unknown option or missing value '" << a << "'\n" << kUsage;
      return 2;
    }
    const std::string& v = args[++i];
    if (a == "--world") options.worldFile = v;
    else if (a == "--ground") options.groundFile = v;
    else if (a == "--params") options.paramsFile = v;
    else if (a == "--set") options.overrides.push_back(v);
    else if (a == "--bind") options.bind = v;
    else if (a == "--token") options.token = v;
    else if (a == "--port") options.port = static_cast<uint16_t>(std::atoi(v.c_str()));
    else if (a == "--rtf") options.realTimeFactor = v == "max" ? 0.0 : std::atof(v.c_str());
    else if (a == "--log") options.logPath = v;
    else if (a == "--log-dir") options.logDir = v;
    else if (a == "--perturb") {
      char* end = nullptr;
      const unsigned long long seed = std::strtoull(v.c_str(), &end, 10);
      if (v.empty() || v[0] == '-' || end == v.c_str() || *end != '\0') {
        std::cerr << "<command line>: error: --perturb: expected a seed (an unsigned integer), got '" << v << "'\n";
        return 2;
      }
      options.perturbSeed = seed;
    }
    else if (a == "--change") {
      sp::SuddenChange c;
      if (const std::string why = sp::parseSuddenChange(v, c); !why.empty()) {
        std::cerr << "<command line>: error: --change: " << why << "\n";
        return 2;
      }
      options.change = c;
    }
    else if (a == "--weak-motor") {
      sp::Perturbation p;
      p.wheelTorque = options.wheelTorque;
      if (const std::string why = sp::parseWeakMotor(v, p); !why.empty()) {
        std::cerr << "<command line>: error: --weak-motor: " << why << "\n";
        return 2;
      }
      options.wheelTorque = p.wheelTorque;
    }
    else if (a == "--delay" || a == "--jitter" || a == "--loss") {
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(x >= 0) || (a == "--loss" && x > 1)) {
        std::cerr << "<command line>: error: " << a << ": expected a number " << (a == "--loss" ? "in [0, 1]" : ">= 0")
                  << ", got '" << v << "'\n";
        return 2;
      }
      sp::net::LinkEmulatorConfig& e = options.emulation;
      (a == "--delay" ? e.delay : a == "--jitter" ? e.jitter : e.loss) = x;
    }
    else {
      std::cerr << "<command line>: error: unknown option '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  return std::nullopt;
}

int perturbationReport(const sp::StandInOptions& options);

// The files found in the data folder, --perturb-report answered, and the
// options that contradict each other refused; an exit code when done or
// something is wrong.
std::optional<int> checkOptions(sp::StandInOptions& options, bool perturbReport) {
  if (options.worldFile.empty()) options.worldFile = "terrains/flat.world.xml";
  for (std::string* file : {&options.worldFile, &options.paramsFile, &options.groundFile}) {
    std::string error;
    *file = sp::findDataFile(*file, error);
    if (!error.empty()) {
      std::cerr << error << "\n";
      return 1;
    }
  }
  if (perturbReport) return perturbationReport(options);
  const std::string& bind = options.bind;
  if (options.token.empty() && !(bind == "127.0.0.1" || bind == "::1" || bind == "localhost")) {
    std::cerr << "<command line>: error: refusing to listen on " << bind
              << " without --token: only loopback may run with a generated token\n";
    return 2;
  }
  if (!options.log && (!options.logPath.empty() || options.logDir != sp::StandInOptions{}.logDir)) {
    std::cerr << "<command line>: error: --no-log contradicts --log and --log-dir\n";
    return 2;
  }
  return std::nullopt;
}

// --perturb-report: the deviations a seed draws, and nothing run.
int perturbationReport(const sp::StandInOptions& options) {
  if (!options.perturbSeed) {
    std::cerr << "<command line>: error: --perturb-report needs --perturb SEED\n";
    return 2;
  }
  sp::Diagnostics diag;
  const std::optional<sp::WorldModel> world = sp::loadWorld(options.worldFile, diag);
  std::cerr << diag.format();
  if (!world || world->robots.empty()) return 1;
  std::cout << sp::drawPerturbation(*options.perturbSeed, world->robots[0].model).report(world->robots[0].model);
  return 0;
}

// Waits for a stop signal, looking at the log's health meanwhile; then
// stops the robot and says how the run went.
int serveUntilSignalled(sp::StandInRobot& robot, const sigset_t& stopSignals, sp::LineWriter& lines) {
  // A failed log is told once and the twin runs on.
  bool toldLogFailure = false;
  const timespec poll{0, 200'000'000};
  int signal = -1;
  while ((signal = sigtimedwait(&stopSignals, nullptr, &poll)) < 0) {
    if (!toldLogFailure && robot.logFailed()) {
      toldLogFailure = true;
      lines.write("error: " + robot.logError() + "; the twin runs on without logging");
    }
  }
  // A signal stops the robot before the program ends: every motor first
  // (as an e-stop), the clients told why, the log ending with the robot at rest.
  const std::string reason = std::string("robot shutting down (") + (signal == SIGINT ? "SIGINT" : "SIGTERM") + ")";
  lines.write(reason + ": stopping every motor");
  if (!robot.shutdown(reason)) lines.write("warning: the robot was still moving 3 s after the stop");
  const sp::StandInStats stats = robot.stats();
  std::cout << "stopped: " << stats.clientsAccepted << " clients, " << stats.framesIn << " frames in, "
            << stats.badFrames << " closed for bad frames, " << stats.telemetryDropped
            << " telemetry frames dropped for slow clients\n";
  if (!robot.logPath().empty()) {
    if (robot.logDropped() > 0)
      std::cerr << "simpartner-robot: warning: " << robot.logPath() << ": " << robot.logDropped()
                << " log items dropped\n";
    std::cout << "session log " << robot.logPath() << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  sp::StandInOptions options;
  bool perturbReport = false;
  // The link's lines go through their own thread: the link thread (which
  // runs the deadman) never waits for a stderr nobody reads.
  sp::LineWriter lines(STDERR_FILENO, "simpartner-robot: ");
  options.lineLog = [&lines](const std::string& line) { lines.write(line); };
  if (const std::optional<int> exit = parseArgs(args, options, perturbReport)) return *exit;
  if (const std::optional<int> exit = checkOptions(options, perturbReport)) return *exit;

  sp::Diagnostics diag;
  std::unique_ptr<sp::StandInRobot> robot = sp::StandInRobot::create(options, diag);
  std::cerr << diag.format();
  if (!robot) return 1;

  // SIGINT and SIGTERM are taken by sigtimedwait below: blocked before
  // start() so that the threads it starts inherit the mask.
  sigset_t stopSignals;
  sigemptyset(&stopSignals);
  sigaddset(&stopSignals, SIGINT);
  sigaddset(&stopSignals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);

  if (const std::string error = robot->start(); !error.empty()) {
    std::cerr << "error: " << error << "\n";
    return 1;
  }
  if (options.token.empty()) std::cout << "token " << robot->token() << "\n";
  std::cout << "world " << options.worldFile << "\n";
  const sp::net::LinkEmulatorConfig& emulation = options.emulation;
  if (emulation.active())
    std::cout << "emulating a link with " << emulation.delay << " s delay, +-" << emulation.jitter << " s jitter, "
              << emulation.loss * 100 << " % loss\n";
  if (!robot->logPath().empty()) std::cout << "logging to " << robot->logPath() << "\n";
  std::cout << "listening on " << options.bind << ":" << robot->port() << std::endl;

  return serveUntilSignalled(*robot, stopSignals, lines);
}
