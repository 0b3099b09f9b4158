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

#include "app/rehearse/sequence_relay.h"

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
  /// Forgets the sequence relayed: a new connection is another robot, or
  /// the same one restarted, which runs nothing the console relayed before
  /// (issue 59: a branch's stand-in was "aborted by the guard" against the
  /// old robot's sequence).
  void reset() {
    std::lock_guard lock(mutex_);
    relay_ = SequenceRelay{};
  }
  /// Telemetry refused by the link's checks (SequenceRelay::cannotJudge).
  std::optional<GuardDeparture> cannotJudge(const std::string& why) {
    std::lock_guard lock(mutex_);
    return relay_.cannotJudge(why);
  }
  /// Where the relay stands, without the rehearsal it carries (the GUI
  /// asks on every key and state; the rehearsal's path is large).
  class Status {
   public:
    SequenceRelay::Phase phase() const { return phase_; }
    const std::string& hash() const { return hash_; }
    const std::string& reason() const { return reason_; }
    uint64_t index() const { return index_; }
    uint64_t count() const { return count_; }
    double worstPosition() const { return worstPosition_; }
    double worstHeading() const { return worstHeading_; }
    int compared() const { return compared_; }

   private:
    friend class SequenceGuard;
    SequenceRelay::Phase phase_ = SequenceRelay::Phase::Idle;
    std::string hash_, reason_;
    uint64_t index_ = 0, count_ = 0;
    double worstPosition_ = 0, worstHeading_ = 0;
    int compared_ = 0;
  };
  Status status() const {
    std::lock_guard lock(mutex_);
    Status s;
    s.phase_ = relay_.phase();
    s.hash_ = relay_.hash();
    s.reason_ = relay_.reason();
    s.index_ = relay_.index();
    s.count_ = relay_.count();
    s.worstPosition_ = relay_.worstPosition();
    s.worstHeading_ = relay_.worstHeading();
    s.compared_ = relay_.compared();
    return s;
  }

 private:
  mutable std::mutex mutex_;
  SequenceRelay relay_;
};

}  // namespace sp
