#pragma once
// What a client checks of what a robot sends before anything of it is used
// (docs/protocol.md, "What a client refuses"): a robot on the other end of
// the link may be buggy, corrupted or hostile, so every TELEMETRY, WELCOME
// and LIMITS is judged once, where it is decoded, against physical bounds
// and the robot file the console runs. A refused message is not passed on;
// its reason is counted by kind (RefusalTally), so that the operator is told
// once per kind of problem, with a count, not once per frame.
//
// Thread: plain values; their owner's thread (RobotClient's worker).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "net/message.h"

namespace sp {
struct RobotModel;
}

namespace sp::net {

/// What telemetry is judged against. The defaults are physical bounds that
/// fit any robot; `joints` empty accepts any joint names (a client that
/// knows no robot file).
struct TelemetryBounds {
  /// The robot file's joints, in its order; every frame must report these,
  /// and only these, by name.
  std::vector<std::string> joints;
  /// Per joint [rad or m]; -inf / inf where unlimited (a wheel turns on).
  std::vector<double> lower, upper;
  /// Per joint [rad/s or m/s]; 0 where the file gives none.
  std::vector<double> maxVelocity;
  /// [rad or m] a limited joint may be past its limit (ODE's limits are soft).
  double jointSlack = 0.25;
  double extent = 1e5;       ///< [m] |x|, |y|, |z| of the base and objects at most
  double maxSpeed = 30;      ///< [m/s] the base moves at most this fast between two frames (+ 0.5 m)
  double maxForce = 1e6;     ///< [N] wheel forces at most
  double maxRoundTripMs = 600000;  ///< [ms] TELEMETRY `rtt_ms` at most (10 min)
  /// Robot time advances at most this times the wall time between two
  /// frames, plus one second (a twin may run faster than real time; a
  /// backlog arrives in a burst).
  double maxTimeRate = 20;
};

/// The bounds of `robot`'s file: its joints, their limits, the actuators'
/// speed limits.
TelemetryBounds telemetryBounds(const RobotModel& robot);

/// Why a message was refused: `kind` names the problem (one line of the
/// tally per kind), `detail` is this message's instance of it.
struct Refusal {
  std::string kind;    ///< e.g. "telemetry: not finite"
  std::string detail;  ///< e.g. "pose x = inf"
};

/// Telemetry of one connection: each frame against the bounds and against
/// the last frame accepted (time monotonic, no jump in time or place).
class TelemetryCheck {
 public:
  explicit TelemetryCheck(TelemetryBounds bounds = {}) : bounds_(std::move(bounds)) {}
  /// A new connection: nothing accepted yet.
  void reset() { have_ = false; }
  /// Empty kind when `m`, arrived at wall time `wall` [s], may be used
  /// (then it is the last accepted); else why not.
  Refusal check(const TelemetryMsg& m, double wall);
  const TelemetryBounds& bounds() const { return bounds_; }

 private:
  Refusal judge(const TelemetryMsg& m, double wall) const;
  TelemetryBounds bounds_;
  bool have_ = false;
  double lastTime_ = 0, lastWall_ = 0;
  Vec3 lastPosition_;
};

/// "" when `m` can be believed, else why not (the connection is dropped):
/// a telemetry rate in [kMinTelemetryRate, kMaxTelemetryRate] Hz, a
/// deadman 0 (not announced) or in [kMinDeadman, kMaxDeadman] s.
std::string welcomeProblem(const WelcomeMsg& m);
constexpr double kMinTelemetryRate = 0.5, kMaxTelemetryRate = 2000;  ///< [Hz]
constexpr double kMinDeadman = 0.02, kMaxDeadman = 60;               ///< [s]
/// "" when `m` can be believed, else why not (the LIMITS are not taken):
/// one value of each per joint, finite where they must be, lower <= upper,
/// speeds and torques > 0, drive and wheel speeds in physical bounds.
std::string limitsProblem(const LimitsMsg& m);

/// Problems by kind: the first of a kind is to be said at once, more of it
/// in a summary now and then (report()).
class RefusalTally {
 public:
  /// Counts `r`; true when it is the first of its kind (say it now).
  bool add(const Refusal& r);
  /// One line per kind counted since the last report ("telemetry: not
  /// finite: 212 more (last: pose x = inf)"), and forgets those counts.
  std::vector<std::string> report();
  /// All refusals counted, over the tally's life.
  uint64_t total() const { return total_; }
  /// Kind -> count over the tally's life.
  const std::map<std::string, uint64_t>& byKind() const { return counts_; }

 private:
  struct Since {
    uint64_t count = 0;
    std::string last;
  };
  std::map<std::string, uint64_t> counts_;
  std::map<std::string, Since> since_;
  uint64_t total_ = 0;
};

/// `text` safe to show and store: control characters (terminal escapes
/// among them) as \xNN, backslash as \\, at most `max` bytes (then "...").
std::string escapeText(const std::string& text, size_t max = 2000);

}  // namespace sp::net
