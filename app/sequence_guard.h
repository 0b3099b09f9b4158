#pragma once
// The guard of a relayed sequence, shared between the link client's worker
// thread (which feeds it every telemetry frame and SEQUENCE_STATE as they
// arrive, and sends ABORT itself when it trips) and the GUI thread (which
// arms it and reads its state): a SequenceRelay behind a mutex. The abort
// thus never waits for the window: a stalled GUI does not stall the guard.
//
// Thread: every method from any thread; each holds the lock for a few
// microseconds (no I/O inside).

#include <mutex>
#include <optional>

#include "app/sequence_relay.h"

namespace sp {

class SequenceGuard {
 public:
  /// Arms the guard for a SEQUENCE about to go out.
  void relayed(const net::SequenceMsg& message, RehearsalResult result, const FlightRules& rules,
               const RobotModel& robot) {
    std::lock_guard lock(mutex_);
    relay_.relayed(message, std::move(result), rules, robot);
  }
  void state(const net::SequenceStateMsg& state) {
    std::lock_guard lock(mutex_);
    relay_.state(state);
  }
  /// The first departure beyond the thresholds, once (SequenceRelay::guard).
  std::optional<GuardDeparture> telemetry(const net::TelemetryMsg& telemetry) {
    std::lock_guard lock(mutex_);
    return relay_.guard(telemetry);
  }
  /// A copy of where the relay stands.
  SequenceRelay snapshot() const {
    std::lock_guard lock(mutex_);
    return relay_;
  }

 private:
  mutable std::mutex mutex_;
  SequenceRelay relay_;
};

}  // namespace sp
