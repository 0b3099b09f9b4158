#pragma once
// Logging a short headless run for the session-log tests.

#include <QtGlobal>

#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "app/run/headless_runner.h"

namespace sp::test {

inline std::string sourcePath(const std::string& relative) { return std::string(SP_SOURCE_DIR) + "/" + relative; }

/// Runs `commandsFile` on `worldFile` (absolute paths) for `duration` s,
/// unpaced on a fake clock, logging to `path`; the run's report, or nullopt
/// (with the runner's errors as a warning) if it could not run.
inline std::optional<RunReport> logRun(const std::string& path, const std::string& worldFile,
                                       const std::string& commandsFile, double duration,
                                       std::vector<std::string> overrides = {}) {
  RunOptions o;
  o.worldFile = worldFile;
  o.commandsFile = commandsFile;
  o.duration = duration;
  o.realTimeFactor = 0;
  o.progressInterval = 0;
  o.logFile = path;
  o.overrides = std::move(overrides);
  std::ostringstream out, err;
  double fakeClock = 0;
  auto report = runHeadless(o, out, err, [&] { return fakeClock += 1e-4; }, [](double) {});
  if (!report) qWarning("%s", err.str().c_str());
  return report;
}

/// The demo sequence on flat ground, logged as logRun() does.
inline std::optional<RunReport> logDemoRun(const std::string& path, double duration,
                                           std::vector<std::string> overrides = {}) {
  return logRun(path, sourcePath("terrains/flat.world.xml"), sourcePath("terrains/demo.seq"), duration,
                std::move(overrides));
}

}  // namespace sp::test
