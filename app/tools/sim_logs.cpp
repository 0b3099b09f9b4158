// simpartner-sim resim and export: a session log re-simulated, exported.

#include "app/tools/sim_tool.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "app/log/log_export.h"

#include "app/log/resimulation.h"

namespace sp::simtool {

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

}  // namespace sp::simtool
