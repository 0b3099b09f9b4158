#pragma once
// The robot's side of the link, without sockets: sessions and token
// authentication, the control lease, command checks (sequence, expiry,
// limits), the safety chain (deadman failsafe, e-stop, re-arm, both latched)
// and heartbeats. The stand-in robot and any real robot adapter feed it
// decoded messages and the time, and carry out what it returns; tests drive
// it with a fake clock. docs/protocol.md describes the behaviour.
//
// Thread: one thread at a time (the link's); no method is thread-safe.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "net/message.h"
#include "sim/command.h"
#include "sim/command_check.h"

namespace sp {
struct RobotModel;
}

namespace sp::net {

using ClientId = uint64_t;

struct RobotLinkConfig {
  std::string robotName = "workpartner";
  std::string token;            ///< shared secret, >= 32 hex digits; checked in constant time
  /// [s] longest gap between arrivals of the holder's commands or
  /// keep-alives => failsafe. Judged on arrival, so a constant delay never
  /// trips it; it must exceed the keep-alive period plus twice the link's
  /// jitter (docs/protocol.md has settings per link). Announced in WELCOME.
  double deadman = 0.2;
  /// [s] after granting the lease, how long the robot waits for the new
  /// holder's first keep-alive or command (it learns of the grant a round
  /// trip later) before it takes the lease back. The deadman counts from
  /// that first arrival; the robot stands still meanwhile.
  double leaseConfirm = 10;
  double telemetryRate = 50;    ///< [Hz], announced in WELCOME
  /// FNV-1a 64 of the world and robot files (16 hex digits; "" = not
  /// announced), in WELCOME: a console checks its twin's files against them.
  std::string worldHash = {}, robotHash = {};
  /// WELCOME `capabilities` (net/message.h WelcomeMsg), e.g. "terrain_edit".
  std::string capabilities = {};
  /// Whether a HELLO may carry the token in clear (`token`) instead of a
  /// proof over this connection's CHALLENGE: only for a robot listening on
  /// loopback, where nobody without the machine can read the link
  /// (RobotServer sets it from the address it binds).
  bool clearTokenAllowed = false;
};

class RobotLink {
 public:
  /// `robot` (may be null) parses command text; `check` validates a parsed
  /// command against the robot's limits, e.g. sp::checkCommand; its kind
  /// picks the reply (out_of_limits or invalid).
  RobotLink(RobotLinkConfig config, const RobotModel* robot, std::function<CommandCheck(const Command&)> check);

  /// A new connection: sends it a CHALLENGE with a fresh nonce.
  void connected(ClientId client, double now);
  /// See RobotLinkConfig::clearTokenAllowed.
  void setClearTokenAllowed(bool allowed) { config_.clearTokenAllowed = allowed; }
  /// Drops the client; a lease holder's lease is released (the deadman
  /// then fires, and the failsafe latches, as for any lost holder).
  void disconnected(ClientId client, double now);
  /// The server found `client` not reading (`why`) and is closing it: the
  /// lease holder's robot is stopped with a failsafe saying so, at once
  /// (its keep-alives alone must not keep a blind controller in control).
  void stalled(ClientId client, const std::string& why, double now);
  /// The robot itself must stop (`reason`: its inputs went stale, say): a
  /// failsafe as the deadman's, latched until the lease holder re-arms.
  /// Nothing while the failsafe is latched already.
  void robotFault(const std::string& reason, double now);
  /// `client`, not authenticated, took too long to say HELLO: it gets
  /// ERROR `reason` and is closed (takeClosing).
  void closeUnauthenticated(ClientId client, const std::string& reason);
  /// The robot is going away (`reason`): it is stopped as by an e-stop
  /// (latched), every client is told (EVENT estop) and closed with `reason`.
  void shutdown(const std::string& reason, double now);
  /// One decoded message from a client at time `now` [s, monotonic].
  void received(ClientId client, const Message& message, double now);
  /// A frame from the client could not be decoded: answers ERROR and asks
  /// for the connection to close.
  void malformed(ClientId client, const std::string& error, double now);
  /// A well-framed message whose content was refused (unknown type, a
  /// missing or bad key): answers ERROR `refused: <why>`, naming the message
  /// and the key. Before authentication it also closes the connection (only
  /// a good HELLO opens one).
  void refused(ClientId client, const std::string& error, double now);
  /// Checks the deadman; call often (every few ms).
  void tick(double now);

  struct Outgoing {
    ClientId client;
    Message message;
  };
  /// Messages to send since the last call, in order.
  std::vector<Outgoing> takeOutgoing();
  /// Twin commands to apply since the last call, in order (checked).
  std::vector<Command> takeCommands();
  /// A SEQUENCE from the lease holder that parsed, matched its hash and
  /// passed every command's check: for the robot to start (or refuse).
  struct SequenceRequest {
    ClientId client;
    SequenceMsg message;
    std::vector<TimedCommand> commands;
  };
  std::vector<SequenceRequest> takeSequences();
  /// `client`'s sequence `hash` is refused (`reason`; the link's own checks
  /// or the robot's): SEQUENCE_STATE refused to that client alone.
  void refuseSequence(ClientId client, const std::string& hash, const std::string& reason);
  /// Why running sequences must stop, in order: an ABORT, an e-stop, the
  /// failsafe, the lease given up or taken back (each also queued a stop).
  std::vector<std::string> takeAborts();
  /// Tells every client where a sequence stands (SEQUENCE_STATE), and notes it.
  void sequenceState(const SequenceStateMsg& state);
  /// Clients whose connection must be closed (after their last messages).
  std::vector<ClientId> takeClosing();

  /// Something the link decided, for the robot's session log: `kind` is an
  /// EVENT kind (toString(EventKind)): "estop", "failsafe", "rearmed", or
  /// "link" for lease changes and refusals (clients, commands); `text` is
  /// one line for a person.
  struct Notice {
    std::string kind;
    std::string text;
  };
  /// Notices since the last call, in order. The server drains them after
  /// every input; a user that never calls this lets them pile up.
  std::vector<Notice> takeNotices();

  bool failsafeLatched() const { return failsafe_; }
  bool estopLatched() const { return estop_; }
  /// The lease holder, 0 if none.
  ClientId holder() const { return holder_; }
  bool authenticated(ClientId client) const;
  /// Clients that receive telemetry (every authenticated one).
  std::vector<ClientId> subscribers() const;
  /// [ms] since the robot last heard a keep-alive or command from
  /// `client` when it holds the lease and the deadman counts (the gap the
  /// deadman judges); nullopt otherwise.
  std::optional<double> heardMs(ClientId client, double now) const {
    if (client != holder_ || !deadmanArmed_) return std::nullopt;
    return (now - lastFromHolder_) * 1000;
  }
  /// Round-trip time to a client from its heartbeat echoes [ms], 0 unknown.
  double rttMs(ClientId client) const;
  /// Counters for logs and tests.
  uint64_t commandsAccepted() const { return accepted_; }
  uint64_t commandsRefused() const { return refused_; }
  /// When the failsafe last fired [s], for deadman timing; -1 if never.
  double lastFailsafeTime() const { return lastFailsafe_; }

  /// Tells every client of something about the robot (a divergence, say).
  void announce(EventKind kind, const std::string& text);

  /// A heartbeat to send to every client now (the robot's own, which
  /// clients echo so that the robot can measure round trips).
  void sendHeartbeats(double now);

 private:
  struct Client {
    bool authenticated = false;
    std::string name;
    Role role = Role::Monitor;
    std::string nonce;  // this connection's CHALLENGE
    uint64_t lastSeq = 0;
    bool anySeq = false;
    double rttMs = 0;
    // Command expiry: the smallest (arrival - sent) seen [ms]; commands
    // that arrive later than that by more than their expiry are refused.
    bool anyOffset = false;
    double minOffsetMs = 0;
  };
  void send(ClientId client, Message message);
  void broadcast(const Message& message);
  void broadcastLease();
  void refuse(ClientId client, uint64_t seq, ReplyStatus status, std::string reason);
  void stopEverything(EventKind why, const std::string& text, double now);
  /// Queues a stop and aborts any running sequence, for `why`.
  void stopRobot(const std::string& why);
  /// A keep-alive or command from the holder arrived: the deadman counts from now.
  void heardFromHolder(double now);
  void close(ClientId client, const std::string& reason);
  void notice(std::string kind, std::string text);
  /// Why `hello` does not authenticate on connection `c`; "" if it does.
  std::string authenticationProblem(const Client& c, const HelloMsg& hello) const;
  /// "'NAME' (client N)" for notices.
  std::string who(ClientId client) const;

  RobotLinkConfig config_;
  const RobotModel* robot_;
  std::function<CommandCheck(const Command&)> check_;
  std::map<ClientId, Client> clients_;
  ClientId holder_ = 0;
  double lastFromHolder_ = 0;
  bool deadmanArmed_ = false;
  bool awaitingHolder_ = false;  // lease granted, nothing from the new holder yet
  double grantedAt_ = 0;
  bool holderLost_ = false;  // the holder's connection dropped; deadman not fired yet
  bool failsafe_ = false, estop_ = false;
  double lastFailsafe_ = -1;
  uint64_t session_ = 0;
  uint64_t heartbeatSeq_ = 0;
  uint64_t accepted_ = 0, refused_ = 0;
  std::vector<Outgoing> outgoing_;
  std::vector<Command> commands_;
  std::vector<SequenceRequest> sequences_;
  std::vector<std::string> aborts_;
  std::vector<ClientId> closing_;
  std::vector<Notice> notices_;
};

}  // namespace sp::net
