// simpartner-sim run: the twin headless, paced by the monotonic clock.

#include "app/tools/sim_tool.h"

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "app/run/headless_runner.h"

namespace sp::simtool {

namespace {

std::atomic<bool> gStop{false};

}  // namespace

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

}  // namespace sp::simtool
