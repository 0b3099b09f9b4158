// simpartner-sim sweep, sweep-task and collect: sweeps of rehearsals on cores or Slurm.

#include "app/tools/sim_tool.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "app/sweep/sweep.h"

namespace sp::simtool {

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

}  // namespace sp::simtool
