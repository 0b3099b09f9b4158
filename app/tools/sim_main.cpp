// simpartner-sim: the headless twin's command line. Each subcommand is a
// file of its own (app/tools/sim_tool.h); here are the usage and dispatch.

#include <iostream>
#include <string>
#include <vector>

#include "app/data/data_files.h"
#include "app/tools/sim_tool.h"

namespace sp::simtool {

const char* const kUsage = R"(usage:
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

}  // namespace sp::simtool

int main(int argc, char** argv) {
  using namespace sp::simtool;
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
