#pragma once
// A console session driven headless, as the console's window drives it: a
// client on the session's robot, the lease taken, commands sent at their
// times (and handed to the ghost), every telemetry frame through the
// session as it arrives (its tap: log, ghost, calibration), then the
// calibration taken. For benchmarks and tests of what the ghost and the
// calibration make of a robot (bench/bench_region, tests/app/tst_ghost_trust).
//
//   sp::ConsoleSession session(options);   // the stand-in, its link's delay
//   session.start();
//   sp::driveSession(session, token, {{0, DriveCmd{0.5, 0}}, {10, StopCmd{}}}, 12,
//                    [](const net::TelemetryMsg& t, const std::optional<GhostError>& e) { ... });
//
// Thread: the caller's; the client's callbacks only queue the frames.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "app/ghost/prediction_record.h"
#include "net/message.h"
#include "sim/command.h"

namespace sp {

class ConsoleSession;

/// A command sent `at` seconds (wall clock) after the drive starts.
struct DrivePhase {
  double at = 0;
  Command command;
};

/// Connects to `session`'s robot with `token`, takes the lease, waits for
/// the ghost's first view (when it has a ghost), then sends `phases` at
/// their times and hands each telemetry frame to the session, calling
/// `each` with it and the session's prediction for it, for `seconds` after
/// the first phase. "" or why it could not drive (no connection, no lease).
std::string driveSession(ConsoleSession& session, const std::string& token, const std::vector<DrivePhase>& phases,
                         double seconds,
                         const std::function<void(const net::TelemetryMsg&, const std::optional<GhostError>&)>& each);

}  // namespace sp
