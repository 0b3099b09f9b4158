#pragma once
// The console's side of relaying a rehearsed sequence: the SEQUENCE for a
// rehearsal that passed (unchanged: the hash names its commands on both
// ends), the robot's SEQUENCE_STATE as it comes, and the guard: while the
// sequence runs, each telemetry frame is compared with the rehearsed
// trajectory at the same sequence time; a departure beyond the rules'
// guard thresholds is reported once, for the caller to send ABORT (the robot
// stops) and tell the operator where and why.
//
//   auto msg = sp::sequenceMessage(plan, result, why);     // nullopt: not passed
//   client.sendSequence(*msg); relay.relayed(*msg, result, plan.rules, robot);
//   on SEQUENCE_STATE: relay.state(s);
//   on TELEMETRY:  if (auto d = relay.guard(t)) client.abortSequence(relay.hash(), d->message());
//
// Thread: one (the console's GUI thread); plain logic, no I/O.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "app/rehearse/rehearsal.h"
#include "net/message.h"

namespace sp {

/// The SEQUENCE for `plan` rehearsed as `result`; nullopt and `why` when
/// the rehearsal did not pass (or did not run), or ran in the fast profile.
std::optional<net::SequenceMsg> sequenceMessage(const RehearsalPlan& plan, const RehearsalResult& result,
                                                std::string& why);

/// The rehearsal's start from a telemetry frame (joints by name into the
/// model's order); nullopt and `why` when a joint of the model is missing.
std::optional<RehearsalStart> startFromTelemetry(const net::TelemetryMsg& telemetry, const RobotModel& robot,
                                                 std::string& why);

/// Where telemetry left the rehearsed trajectory.
struct GuardDeparture {
  double time = 0;      ///< [s] sequence time
  std::string what;     ///< "position", "heading" or "joint 'knee_fl'"
  double value = 0;     ///< [m] or [deg]
  double limit = 0;
  Pose reported, rehearsed;  ///< the base, both
  /// Not "" when the guard tripped on telemetry it could not judge (refused
  /// by the link's checks: net/link_check.h): why.
  std::string unjudged;
  /// e.g. "position 0.41 m from the rehearsal at t = 3.20 s (guard 0.3 m)".
  std::string message() const;
};

class SequenceRelay {
 public:
  enum class Phase { Idle, Sent, Running, Done, Aborted, Refused };

  /// A SEQUENCE went out for this rehearsal.
  void relayed(const net::SequenceMsg& message, RehearsalResult result, const FlightRules& rules,
               const RobotModel& robot);
  /// The robot's word on it (others' hashes are ignored).
  void state(const net::SequenceStateMsg& state);
  /// Compares a telemetry frame with the rehearsal while the sequence runs
  /// (and while the rehearsal's settling time lasts after it is done); the
  /// first departure beyond a guard threshold is returned, once.
  std::optional<GuardDeparture> guard(const net::TelemetryMsg& telemetry);
  /// A telemetry frame was refused as unbelievable (`why`): while a
  /// sequence is sent or running, the guard trips on it, once.
  std::optional<GuardDeparture> cannotJudge(const std::string& why);

  Phase phase() const { return phase_; }
  const std::string& hash() const { return hash_; }
  uint64_t index() const { return index_; }
  uint64_t count() const { return count_; }
  const std::string& reason() const { return reason_; }  ///< refused or aborted: why
  /// The largest position and heading departures seen so far [m], [deg].
  double worstPosition() const { return worstPosition_; }
  double worstHeading() const { return worstHeading_; }
  /// Frames compared so far.
  int compared() const { return compared_; }

 private:
  Phase phase_ = Phase::Idle;
  std::string hash_, reason_;
  uint64_t index_ = 0, count_ = 0;
  double startTime_ = 0;
  bool tripped_ = false;
  RehearsalResult result_;
  FlightRules rules_;
  std::vector<std::string> jointNames_;  // model order
  std::vector<bool> guarded_;            // per joint: compared
  double worstPosition_ = 0, worstHeading_ = 0;
  int compared_ = 0;
};

const char* toString(SequenceRelay::Phase phase);  ///< "idle", "sent", ...

}  // namespace sp
