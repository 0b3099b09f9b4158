#pragma once
// Typed messages of the robot link and their payload encoding
// (docs/protocol.md is the reference; keep the two in step).
//
// A payload is UTF-8 text, one `key=value` per line, lines ended by '\n'.
// Keys match [a-z_]+; a value is everything after the first '=' up to the
// end of its line. Numbers are written in their shortest round-trip form
// (std::to_chars): unsigned integers in decimal, floating-point values as
// `0.5`, `1e-07`, `inf`, `-inf` or `nan`; a list is its items separated by
// spaces; a flag is 0 or 1. Receivers ignore empty lines and keys they do not
// know (so that later versions may add keys), and reject a message that
// lacks a required key, repeats a key, or holds a value that does not parse
// or breaks a rule below; the error names the message type and the key.
//
// Units are SI with angles in radians, except where a key says otherwise
// (`*_ms` keys are milliseconds; the command text uses the sequence-file
// syntax, angles in degrees, see docs/formats.md).
//
// Plain values and free functions: usable from any thread.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "net/frame.h"
#include "sim/command.h"
#include "sim/math.h"

namespace sp {
struct RobotModel;
}

namespace sp::net {

/// The message type byte of a frame. C = sent by clients, R = by the robot.
enum class MessageType : uint8_t {
  Hello = 1,           ///< C: first message: name, token, role
  Welcome = 2,         ///< R: answer to a good HELLO
  LeaseAcquire = 3,    ///< C: asks for the control lease
  LeaseKeepalive = 4,  ///< C: keeps the lease (and the deadman) alive
  LeaseRelease = 5,    ///< C: gives the lease up
  LeaseState = 6,      ///< R: who holds the lease
  Command = 7,         ///< C: one twin command with sequence number and expiry
  Reply = 8,           ///< R: exactly one per COMMAND
  Telemetry = 9,       ///< R: state at the telemetry rate
  Laser = 10,          ///< R: a laser scan at the scanner's rate
  Heartbeat = 11,      ///< C and R
  Estop = 12,          ///< C: emergency stop, from any authenticated client
  Rearm = 13,          ///< C: clears a latched failsafe or e-stop
  Event = 14,          ///< R: failsafe, divergence, e-stop, re-armed, link
  Error = 15,          ///< C and R: a message was refused
  Challenge = 16,      ///< R: first message on a connection: the nonce HELLO's proof covers
  Limits = 17,         ///< R: after WELCOME: the robot's joint and drive limits
  Sequence = 18,       ///< C: a rehearsed command sequence for the robot to run on board
  SequenceState = 19,  ///< R: a sequence accepted, refused, running (progress), done or aborted
  Abort = 20,          ///< C: stop the running sequence; the robot stops
};
inline constexpr uint8_t kFirstMessageType = 1;
inline constexpr uint8_t kLastMessageType = 20;

/// "HELLO", "LEASE_ACQUIRE", ... as in docs/protocol.md.
const char* toString(MessageType type);
/// The name of a type byte, or "unknown" for a byte that is no MessageType.
const char* messageTypeName(uint8_t type);

/// HELLO role: a controlling client may take the lease; a monitor only reads.
enum class Role { Control, Monitor };
/// REPLY status.
enum class ReplyStatus { Ok, Invalid, OutOfLimits, NotOwner, Busy, Failed, Expired, Duplicate };
/// EVENT kind.
enum class EventKind { Failsafe, Divergence, Estop, Rearmed, Link };
/// SEQUENCE_STATE state.
enum class SequenceStateKind { Accepted, Refused, Running, Done, Aborted };
const char* toString(Role role);                  ///< "control", "monitor"
const char* toString(SequenceStateKind state);    ///< "accepted", "refused", ...
const char* toString(ReplyStatus status);         ///< "ok", "out_of_limits", ...
const char* toString(EventKind kind);             ///< "failsafe", ...

/// HELLO: keys `name`, `role`, and `proof` or (loopback only) `token`.
struct HelloMsg {
  std::string name;   ///< the client's name, not empty; shown to other clients
  /// The shared secret in clear (optional key `token`, >= 32 hex digits):
  /// accepted only by a robot listening on loopback.
  std::string token;
  Role role = Role::Monitor;
  /// HMAC-SHA256 over the robot's CHALLENGE nonce, the name and the role,
  /// keyed by the token (optional key `proof`, 64 hex digits; net/auth.h).
  std::string proof;
  friend bool operator==(const HelloMsg&, const HelloMsg&) = default;
};
/// WELCOME: keys `robot`, `session`, `telemetry_rate`.
struct WelcomeMsg {
  std::string robot;           ///< the robot's name
  uint64_t session = 0;        ///< this connection's session id
  double telemetryRate = 50;   ///< [Hz], finite and > 0
  double deadman = 0;          ///< [s] the robot's deadman (optional key `deadman`; 0 = not announced)
  /// FNV-1a 64 of the world and robot files the robot runs, 16 hex digits
  /// each (optional keys `world_hash`, `robot_hash`; "" = not
  /// announced): a console checks its own twin's files against them.
  std::string worldHash, robotHash;
  /// What the robot takes beyond robot commands (optional key
  /// `capabilities`: words of a-z and _, space-separated; "" = none).
  /// `terrain_edit`: a simulator that takes `terrain` commands.
  std::string capabilities;
  friend bool operator==(const WelcomeMsg&, const WelcomeMsg&) = default;
};
/// LEASE_ACQUIRE: no keys.
struct LeaseAcquireMsg {
  friend bool operator==(const LeaseAcquireMsg&, const LeaseAcquireMsg&) = default;
};
/// LEASE_KEEPALIVE: no keys.
struct LeaseKeepaliveMsg {
  friend bool operator==(const LeaseKeepaliveMsg&, const LeaseKeepaliveMsg&) = default;
};
/// LEASE_RELEASE: no keys.
struct LeaseReleaseMsg {
  friend bool operator==(const LeaseReleaseMsg&, const LeaseReleaseMsg&) = default;
};
/// LEASE_STATE: keys `holder`, `yours`.
struct LeaseStateMsg {
  std::string holder;  ///< name of the client holding the lease; empty if none
  bool yours = false;  ///< whether the receiving connection holds it
  friend bool operator==(const LeaseStateMsg&, const LeaseStateMsg&) = default;
};
/// COMMAND: keys `seq`, `expires_ms`, `command`.
struct CommandMsg {
  uint64_t seq = 0;        ///< increasing per connection
  uint64_t expiresMs = 0;  ///< [ms] > 0: not to be executed later than this after sending
  std::string command;     ///< sequence-file syntax without time, e.g. `drive 0.5 10`
  /// [ms] the sender's monotonic clock when sent (optional key `sent_ms`;
  /// 0 = not given: then the robot cannot judge expiry and does not).
  uint64_t sentMs = 0;
  friend bool operator==(const CommandMsg&, const CommandMsg&) = default;
};
/// REPLY: keys `seq`, `status`, `reason` (optional, default empty).
struct ReplyMsg {
  uint64_t seq = 0;  ///< the COMMAND's seq
  ReplyStatus status = ReplyStatus::Ok;
  std::string reason;  ///< why, when status is not ok
  friend bool operator==(const ReplyMsg&, const ReplyMsg&) = default;
};
/// A named pose in the world: a dynamic object of TELEMETRY's `objects`.
struct ObjectPose {
  std::string name;  ///< the object's name in the world file: not empty, without spaces
  Pose pose;         ///< [m], unit quaternion
  friend bool operator==(const ObjectPose&, const ObjectPose&) = default;
};
/// TELEMETRY: keys `seq`, `time`, `pose`, `joint_names`, `joint_positions`,
/// `joint_velocities`, `wheel_normal`, `wheel_tangential`, `roll`, `pitch`,
/// `rtt_ms`, `lost`, `failsafe`, `estop`, `health` (optional, default empty),
/// `objects` (optional, default none).
/// The joint names come in every frame, so that any frame can be read alone.
struct TelemetryMsg {
  uint64_t seq = 0;    ///< increasing per connection; gaps are lost frames
  double time = 0;     ///< [s] robot (twin) time of the state
  Pose pose;           ///< main body in the world: [m], unit quaternion (`x y z qw qx qy qz`)
  /// The main body's twist (optional key `base_velocity`: `vx vy vz wx wy wz`,
  /// world frame, of its frame's origin [m/s] and [rad/s]); empty when not
  /// reported. With the joints' rates it lets a client rebuild the whole
  /// state (the predictive ghost).
  std::vector<double> baseVelocity;
  std::vector<std::string> jointNames;   ///< non-empty, without spaces
  std::vector<double> jointPositions;    ///< [rad or m], one per name
  std::vector<double> jointVelocities;   ///< [rad/s or m/s], one per name
  std::array<double, 4> wheelNormal{};      ///< [N], FL FR RL RR
  std::array<double, 4> wheelTangential{};  ///< [N], FL FR RL RR
  double roll = 0, pitch = 0;  ///< [rad], body inclination
  double rttMs = 0;            ///< [ms] round trip to this client, as the robot measures it
  uint64_t lost = 0;           ///< telemetry frames the robot dropped for this client
  /// [ms] the lease holder's frames only (optional key `heard_ms`): since the
  /// robot last received its keep-alive or command, the gap the deadman
  /// judges; 0 = absent (not the holder, or before its first after the grant).
  double heardMs = 0;
  bool failsafe = false;       ///< the deadman failsafe is latched
  bool estop = false;          ///< an e-stop is latched
  std::string health;          ///< empty when healthy, else why the twin stopped
  /// The world's dynamic objects the robot knows of, each as `name x y z qw
  /// qx qy qz` (groups of 8 list items); empty when there are none.
  std::vector<ObjectPose> objects;
  friend bool operator==(const TelemetryMsg&, const TelemetryMsg&) = default;
};
/// LASER: keys `seq`, `time`, `angle_min`, `angle_step`, `ranges`.
struct LaserMsg {
  uint64_t seq = 0;
  double time = 0;          ///< [s] robot time of the scan
  double angleMin = 0;      ///< [rad] first beam, about the sensor's z; finite
  double angleStep = 0;     ///< [rad] between beams; finite
  std::vector<double> ranges;  ///< [m]; inf = no return, nan = invalid
  friend bool operator==(const LaserMsg&, const LaserMsg&) = default;
};
/// HEARTBEAT: keys `seq`, `time`.
struct HeartbeatMsg {
  uint64_t seq = 0;  ///< the sender's heartbeat count
  double time = 0;   ///< [s] the sender's monotonic clock when sent
  friend bool operator==(const HeartbeatMsg&, const HeartbeatMsg&) = default;
};
/// ESTOP: key `reason` (optional).
struct EstopMsg {
  std::string reason;
  friend bool operator==(const EstopMsg&, const EstopMsg&) = default;
};
/// REARM: no keys.
struct RearmMsg {
  friend bool operator==(const RearmMsg&, const RearmMsg&) = default;
};
/// EVENT: keys `kind`, `text` (optional).
struct EventMsg {
  EventKind kind = EventKind::Link;
  std::string text;
  friend bool operator==(const EventMsg&, const EventMsg&) = default;
};
/// ERROR: key `reason`.
struct ErrorMsg {
  std::string reason;
  friend bool operator==(const ErrorMsg&, const ErrorMsg&) = default;
};

/// CHALLENGE: key `nonce`.
struct ChallengeMsg {
  std::string nonce;  ///< fresh random hex digits (at least 32) for this connection's HELLO proof
  friend bool operator==(const ChallengeMsg&, const ChallengeMsg&) = default;
};
/// LIMITS: keys `joints`, `lower`, `upper`, `max_velocity`, `max_torque`
/// (one number per joint), and for a robot with a drive `drive_speed`,
/// `wheel_speed`, `articulation` (optional). What the robot refuses as
/// `out_of_limits`, so that a client can refuse it before sending.
struct LimitsMsg {
  std::vector<std::string> joints;  ///< the actuated joints (names without spaces)
  /// [rad or m] per joint; -inf and inf for a joint without limits.
  std::vector<double> lower, upper;
  std::vector<double> maxVelocity;  ///< [rad/s or m/s] per joint
  std::vector<double> maxTorque;    ///< [N m or N] per joint
  double driveSpeed = 0;            ///< [m/s] top speed of drive/turn (0: no drive)
  double wheelSpeed = 0;            ///< [rad/s] the slowest wheel motor's top speed (0: no drive)
  std::string articulation;         ///< the steering hinge's joint name ("" = no drive)
  friend bool operator==(const LimitsMsg&, const LimitsMsg&) = default;
};

/// SEQUENCE: keys `hash`, `commands`, `start`, `start_position`, `start_heading`.
/// A sequence that passed its rehearsal, sent whole. The robot checks the
/// hash against the commands, every command against its limits, and its own
/// state against the rehearsal's start; then runs the commands against its
/// own clock (t = 0 at its next step) and reports SEQUENCE_STATE.
struct SequenceMsg {
  std::string hash;      ///< FNV-1a 64 of the canonical text (commands joined by line feeds, each line ended by one), 16 hex digits
  /// The canonical lines `TIME COMMAND` (sequence-file syntax, times from
  /// the start [s]), joined by `;` (a command never holds one).
  std::string commands;
  Pose start;                ///< the base pose the rehearsal started from
  double startPosition = 0;  ///< [m] how far the robot's base may be from `start`, > 0
  double startHeading = 0;   ///< [rad] how far its heading may be, > 0
  friend bool operator==(const SequenceMsg&, const SequenceMsg&) = default;
};
/// SEQUENCE_STATE: keys `hash`, `state`, `index` (optional), `count`
/// (optional), `start_time` (optional), `reason` (optional).
struct SequenceStateMsg {
  std::string hash;  ///< the SEQUENCE's (as received, when it is refused for a bad one)
  SequenceStateKind state = SequenceStateKind::Accepted;
  uint64_t index = 0;     ///< commands applied so far
  uint64_t count = 0;     ///< commands in the sequence
  double startTime = 0;   ///< [s] robot time of the sequence's t = 0 (running, done, aborted)
  std::string reason;     ///< refused, aborted: why
  friend bool operator==(const SequenceStateMsg&, const SequenceStateMsg&) = default;
};
/// ABORT: keys `hash`, `reason` (optional). From any controlling client.
struct AbortMsg {
  std::string hash;  ///< the sequence to abort
  std::string reason;
  friend bool operator==(const AbortMsg&, const AbortMsg&) = default;
};

/// Any message. The alternatives are in type-code order: index() + 1 is the
/// MessageType.
using Message = std::variant<HelloMsg, WelcomeMsg, LeaseAcquireMsg, LeaseKeepaliveMsg, LeaseReleaseMsg,
                             LeaseStateMsg, CommandMsg, ReplyMsg, TelemetryMsg, LaserMsg, HeartbeatMsg,
                             EstopMsg, RearmMsg, EventMsg, ErrorMsg, ChallengeMsg, LimitsMsg, SequenceMsg,
                             SequenceStateMsg, AbortMsg>;

MessageType typeOf(const Message& message);

/// The payload text of `message`. On error (a text value with a line feed
/// or invalid UTF-8, a joint or object name that is empty or has a space, a value
/// that breaks a rule above) returns nullopt and sets `error`, e.g.
/// `HELLO: key 'name': must not be empty`.
std::optional<std::string> encodePayload(const Message& message, std::string& error);

/// The whole frame of `message`, ready to send; nullopt and `error` as for
/// encodePayload, or when the payload exceeds kMaxPayloadSize (a laser scan
/// of more than some 3400 full-precision ranges); never cut.
std::optional<std::string> encodeMessage(const Message& message, std::string& error);

/// One TELEMETRY state for many clients: the payload is encoded once and
/// only the per-connection keys (`seq`, `rtt_ms`, `lost`) are written per
/// client; frame() is byte for byte what encodeMessage() makes of the same
/// message. The robot's fan-out, where encoding per client cost 500 idle
/// monitors the controller's round trip (bench/bench_link).
class TelemetryFanOut {
 public:
  /// `common`'s seq, rttMs, lost and heardMs are ignored.
  explicit TelemetryFanOut(const TelemetryMsg& common);
  /// The frame for one client; nullopt and `error` as encodeMessage().
  /// `heardMs` > 0 adds `heard_ms` (the lease holder's frames).
  std::optional<std::string> frame(uint64_t seq, double rttMs, uint64_t lost, std::string& error,
                                   double heardMs = 0) const;

 private:
  std::string error_;
  std::string middle_;  // the lines between `seq` and `rtt_ms`
  std::string tail_;    // the lines after `lost`
};

/// LASER for many clients, as TelemetryFanOut: only `seq` differs.
class LaserFanOut {
 public:
  explicit LaserFanOut(const LaserMsg& common);
  std::optional<std::string> frame(uint64_t seq, std::string& error) const;

 private:
  std::string error_;
  std::string tail_;  // the lines after `seq`
};

/// The message in `frame`; on error nullopt and `error` names the type and,
/// where there is one, the key or line, e.g. `COMMAND: missing key 'seq'`,
/// `COMMAND: key 'seq': expected an unsigned integer, got '-1'`,
/// `unknown message type 200`. Values are quoted at most 40 bytes long with
/// control characters escaped; a bad token is never echoed.
std::optional<Message> decodeMessage(const Frame& frame, std::string& error);

/// The commands of a SEQUENCE, parsed against `robot` (may be null) and
/// with their times; nullopt and `error` naming the command (`SEQUENCE: key
/// 'commands': command 3: ...`) when one does not parse, the times are
/// unsorted, or the hash does not match the text.
std::optional<std::vector<TimedCommand>> parseSequenceMsg(const SequenceMsg& message, const RobotModel* robot,
                                                          std::string& error);

/// The limits `robot` enforces on commands (sp::checkCommand), for LIMITS.
LimitsMsg limitsOf(const RobotModel& robot);

/// A COMMAND carrying `command` as text (sp::toText: degrees for hinges,
/// metres for the slider joints of `robot`; without a robot every joint is
/// written as a hinge).
CommandMsg makeCommandMsg(uint64_t seq, uint64_t expiresMs, const Command& command,
                          const RobotModel* robot = nullptr);

/// The twin command a COMMAND carries, parsed with sp::parseCommand against
/// `robot` (may be null: every joint taken for a hinge). On error nullopt and
/// `error` is `COMMAND: key 'command': ` plus the parser's message. Syntax
/// only: limits are checked by sp::checkCommand.
std::optional<Command> parseCommandMsg(const CommandMsg& message, const RobotModel* robot, std::string& error);

}  // namespace sp::net
