#pragma once
// The headless runner behind `simpartner-sim run`: builds the twin from a
// world file, feeds it a command sequence, paces it against a monotonic clock
// and writes decimated CSV and, optionally, a session log.

#include <atomic>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/command.h"
#include "sim/diagnostics.h"
#include "sim/params.h"
#include "sim/world.h"

namespace sp {

struct RunOptions {
  std::string worldFile;
  std::string paramsFile;              ///< "" = built-in defaults
  std::vector<std::string> overrides;  ///< key=value
  std::string commandsFile;            ///< "" = none
  double duration = 10;                ///< sim seconds
  std::optional<double> realTimeFactor;  ///< overrides realtime.factor; 0 = max
  std::string csvFile;                 ///< "" = none
  std::string logFile;                 ///< session log (app/log/session_log.h); "" = none
  double progressInterval = 1.0;       ///< wall seconds between progress lines; 0 = none
};

/// Monotonic seconds since an arbitrary origin.
using ClockFn = std::function<double()>;
/// Sleeps until the given clock time.
using SleepUntilFn = std::function<void(double)>;

struct RunReport {
  double simTime = 0;        ///< [s]
  double wallTime = 0;       ///< [s]
  double achievedFactor = 0; ///< sim s per wall s
  double requestedFactor = 0;  ///< 0 = as fast as possible
  double maxLag = 0;         ///< worst sim-behind-wall x factor seen after a pass [s]
  double finalError = 0;     ///< sim time - wall x factor at the end [s]
  int64_t resyncs = 0;       ///< times the pacer gave up catching up
  double slipped = 0;        ///< sim time not run in real time [s]
  int64_t steps = 0;
  int commandsApplied = 0;
  int commandsRefused = 0;   ///< sequence commands the twin refused when due (each printed and logged)
  bool interrupted = false;
  uint64_t stateHash = 0;    ///< World::stateHash() at the end
  HealthReport health;       ///< why the run stopped early, if it diverged
  int64_t logDropped = 0;    ///< session log items dropped (full queue, failed disk)
  std::string logError;      ///< why the session log failed, "" if it did not
  std::string csvError;      ///< why the CSV file is incomplete (a full disk), "" if it is whole
};

/// Loads files and runs. Writes the narrative to `out` and diagnostics to
/// `err`. Returns nullopt when the files have errors (all of them printed).
/// Thread: the calling thread owns the world for the whole run.
std::optional<RunReport> runHeadless(const RunOptions& options, std::ostream& out, std::ostream& err,
                                     const ClockFn& clock, const SleepUntilFn& sleepUntil,
                                     const std::atomic<bool>* stop = nullptr);

}  // namespace sp
