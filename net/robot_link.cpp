#include "net/robot_link.h"

#include <algorithm>

#include "net/auth.h"

namespace sp::net {

RobotLink::RobotLink(RobotLinkConfig config, const RobotModel* robot,
                     std::function<CommandCheck(const Command&)> check)
    : config_(std::move(config)), robot_(robot), check_(std::move(check)) {}

void RobotLink::connected(ClientId client, double) {
  Client c;
  c.nonce = randomHex(16);
  send(client, ChallengeMsg{c.nonce});
  clients_[client] = std::move(c);
}

namespace {

// Hex digits compare in either case (a client that prints its HMAC in
// upper case is not refused as a wrong proof).
std::string lowerHex(std::string hex) {
  for (char& ch : hex)
    if (ch >= 'A' && ch <= 'F') ch = static_cast<char>(ch - 'A' + 'a');
  return hex;
}

}  // namespace

std::string RobotLink::authenticationProblem(const Client& c, const HelloMsg& hello) const {
  if (config_.token.empty()) return "the robot has no token";
  if (!hello.token.empty()) {
    if (!config_.clearTokenAllowed) return "a token in clear is accepted on loopback only: send 'proof'";
    return equalConstantTime(lowerHex(hello.token), lowerHex(config_.token)) ? "" : "wrong token";
  }
  return equalConstantTime(lowerHex(hello.proof), helloProof(config_.token, c.nonce, hello.name, hello.role))
             ? ""
             : "wrong proof";
}

void RobotLink::disconnected(ClientId client, double now) {
  const std::string name = who(client);
  clients_.erase(client);
  if (holder_ == client) {
    // The lease goes with the connection; the deadman keeps counting from
    // the holder's last packet and stops the robot (tick()).
    holder_ = 0;
    holderLost_ = true;
    if (awaitingHolder_) {
      // Lost before its first keep-alive: the deadman counts from now.
      awaitingHolder_ = false;
      deadmanArmed_ = true;
      lastFromHolder_ = now;
    }
    notice("link", "lease lost with the connection of " + name);
    broadcastLease();
  }
}

void RobotLink::stalled(ClientId client, const std::string& why, double now) {
  const std::string name = who(client);
  if (holder_ == client)
    stopEverything(EventKind::Failsafe, "the controller " + name + " stopped reading (" + why + "): it loses control", now);
  else
    notice("link", name + " closed: " + why);
}

void RobotLink::robotFault(const std::string& reason, double now) {
  if (!failsafe_) stopEverything(EventKind::Failsafe, reason, now);
}

void RobotLink::shutdown(const std::string& reason, double now) {
  stopEverything(EventKind::Estop, reason + ": every motor stopped", now);
  std::vector<ClientId> everyone;
  for (const auto& [id, c] : clients_) everyone.push_back(id);
  for (ClientId id : everyone) close(id, reason);
}

void RobotLink::notice(std::string kind, std::string text) { notices_.push_back({std::move(kind), std::move(text)}); }

std::string RobotLink::who(ClientId client) const {
  auto it = clients_.find(client);
  const std::string id = "client " + std::to_string(client);
  return it == clients_.end() || !it->second.authenticated ? id : "'" + it->second.name + "' (" + id + ")";
}

void RobotLink::send(ClientId client, Message message) { outgoing_.push_back({client, std::move(message)}); }

void RobotLink::broadcast(const Message& message) {
  for (const auto& [id, c] : clients_)
    if (c.authenticated) send(id, message);
}

void RobotLink::broadcastLease() {
  const std::string holderName = holder_ && clients_.count(holder_) ? clients_[holder_].name : std::string();
  for (const auto& [id, c] : clients_)
    if (c.authenticated) send(id, LeaseStateMsg{holderName, id == holder_});
}

void RobotLink::closeUnauthenticated(ClientId client, const std::string& reason) {
  const auto it = clients_.find(client);
  if (it == clients_.end() || it->second.authenticated) return;
  close(client, reason);
}

void RobotLink::close(ClientId client, const std::string& reason) {
  send(client, ErrorMsg{reason});
  closing_.push_back(client);
}

void RobotLink::refuse(ClientId client, uint64_t seq, ReplyStatus status, std::string reason) {
  ++refused_;
  notice("link", who(client) + ": command " + std::to_string(seq) + " refused (" + toString(status) + "): " + reason);
  send(client, ReplyMsg{seq, status, std::move(reason)});
}

void RobotLink::stopRobot(const std::string& why) {
  commands_.emplace_back(std::in_place_type<StopCmd>);
  aborts_.push_back(why);
}

void RobotLink::refuseSequence(ClientId client, const std::string& hash, const std::string& reason) {
  notice("link", who(client) + ": sequence " + hash.substr(0, 16) + " refused: " + reason);
  SequenceStateMsg m{hash, SequenceStateKind::Refused, 0, 0, 0, reason};
  if (m.hash.empty()) m.hash = "-";
  send(client, m);
}

void RobotLink::sequenceState(const SequenceStateMsg& state) {
  std::string text = "sequence " + state.hash + " " + toString(state.state);
  if (state.state == SequenceStateKind::Running)
    text += ": " + std::to_string(state.index) + " of " + std::to_string(state.count) + " commands applied";
  if (!state.reason.empty()) text += ": " + state.reason;
  notice("sequence", text);
  broadcast(state);
}

void RobotLink::stopEverything(EventKind why, const std::string& text, double now) {
  stopRobot(text);
  if (why == EventKind::Failsafe) {
    failsafe_ = true;
    lastFailsafe_ = now;
  } else {
    estop_ = true;
  }
  notice(toString(why), text);
  broadcast(EventMsg{why, text});
}

void RobotLink::malformed(ClientId client, const std::string& error, double) {
  close(client, "malformed frame: " + error);
}

void RobotLink::refused(ClientId client, const std::string& error, double) {
  auto it = clients_.find(client);
  if (it == clients_.end()) return;
  if (!it->second.authenticated) {
    notice("link", who(client) + " closed before HELLO: refused: " + error);
    return close(client, "refused: " + error);
  }
  send(client, ErrorMsg{"refused: " + error});
}

void RobotLink::received(ClientId client, const Message& message, double now) {
  auto it = clients_.find(client);
  if (it == clients_.end()) return;
  Client& c = it->second;

  if (const auto* hello = std::get_if<HelloMsg>(&message)) {
    if (c.authenticated) return send(client, ErrorMsg{"already authenticated"});
    // The client learns only that it failed; the log says why.
    if (const std::string problem = authenticationProblem(c, *hello); !problem.empty()) {
      notice("link", who(client) + " refused: authentication failed: " + problem);
      return close(client, problem.starts_with("a token in clear") ? "authentication failed: " + problem
                                                                    : "authentication failed");
    }
    c.authenticated = true;
    c.name = hello->name;
    c.role = hello->role;
    notice("link", who(client) + " authenticated as " + toString(c.role));
    send(client, WelcomeMsg{config_.robotName, ++session_, config_.telemetryRate, config_.deadman,
                                config_.worldHash, config_.robotHash, config_.capabilities});
    if (robot_) send(client, limitsOf(*robot_));
    const std::string holderName = holder_ ? clients_[holder_].name : std::string();
    send(client, LeaseStateMsg{holderName, false});
    if (failsafe_) send(client, EventMsg{EventKind::Failsafe, "failsafe latched: re-arm to move"});
    if (estop_) send(client, EventMsg{EventKind::Estop, "e-stop latched: re-arm to move"});
    return;
  }
  // Nothing but HELLO before authentication: no telemetry, no control.
  if (!c.authenticated) {
    notice("link", who(client) + " closed: a message before HELLO");
    return close(client, "HELLO first");
  }

  std::visit(
      [&](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, LeaseAcquireMsg>) {
          if (c.role != Role::Control) {
            notice("link", who(client) + ": lease refused: a monitor cannot take the control lease");
            return send(client, ErrorMsg{"a monitor cannot take the control lease"});
          }
          if (holder_ && holder_ != client) {
            notice("link", who(client) + ": lease refused: " + who(holder_) + " holds it");
            return send(client, LeaseStateMsg{clients_[holder_].name, false});
          }
          // A new holder must not inherit a lost operator's motion: if the
          // deadman is still counting for a dropped holder, fire it now.
          if (holderLost_ && deadmanArmed_ && !failsafe_)
            stopEverything(EventKind::Failsafe, "the previous controlling client's connection was lost", now);
          holderLost_ = false;
          if (holder_ != client) {
            notice("link", "lease taken by " + who(client));
            // The holder hears of the grant a one-way trip from now and its
            // keep-alives take another: the deadman waits for the first.
            holder_ = client;
            deadmanArmed_ = false;
            awaitingHolder_ = true;
            grantedAt_ = now;
          } else {
            heardFromHolder(now);
          }
          broadcastLease();
        } else if constexpr (std::is_same_v<T, LeaseKeepaliveMsg>) {
          if (client == holder_) {
            heardFromHolder(now);
          } else {
            send(client, ErrorMsg{"LEASE_KEEPALIVE without the lease"});
          }
        } else if constexpr (std::is_same_v<T, LeaseReleaseMsg>) {
          if (client == holder_) {
            // A deliberate release stops the robot too, without latching:
            // nobody is in control any more.
            holder_ = 0;
            deadmanArmed_ = false;
            awaitingHolder_ = false;
            stopRobot("the lease was released");
            notice("link", "lease released by " + who(client) + " (the robot stops)");
            broadcastLease();
          }
        } else if constexpr (std::is_same_v<T, CommandMsg>) {
          if (client != holder_) {
            const std::string who = holder_ ? "'" + clients_[holder_].name + "' holds the lease" : "nobody holds the lease";
            return refuse(client, m.seq, ReplyStatus::NotOwner, who);
          }
          if (c.anySeq && m.seq <= c.lastSeq)
            return refuse(client, m.seq, ReplyStatus::Duplicate,
                          m.seq == c.lastSeq ? "sequence number already used"
                                             : "out of order: last sequence number was " + std::to_string(c.lastSeq));
          c.anySeq = true;
          c.lastSeq = m.seq;
          heardFromHolder(now);
          // Expiry against the link's own delay: the clocks are not shared,
          // so (arrival - sent) is the one-way delay plus an unknown offset;
          // its smallest value so far stands for the link's usual delay, and
          // a command later than that by more than its expiry is stale.
          if (m.sentMs > 0) {
            const double offset = now * 1000 - static_cast<double>(m.sentMs);
            if (!c.anyOffset || offset < c.minOffsetMs) c.minOffsetMs = offset;
            c.anyOffset = true;
            const double late = offset - c.minOffsetMs;
            if (late > static_cast<double>(m.expiresMs))
              return refuse(client, m.seq, ReplyStatus::Expired,
                            "arrived " + std::to_string(static_cast<int64_t>(late)) +
                                " ms later than the link's usual delay, expiry " + std::to_string(m.expiresMs) + " ms");
          }
          if (failsafe_ || estop_)
            return refuse(client, m.seq, ReplyStatus::Failed,
                          std::string(estop_ ? "e-stop" : "failsafe") + " latched: re-arm first");
          std::string error;
          const std::optional<Command> command = parseCommandMsg(m, robot_, error);
          if (!command) return refuse(client, m.seq, ReplyStatus::Invalid, error);
          if (CommandCheck verdict = check_ ? check_(*command) : CommandCheck{}; !verdict.ok()) {
            // Limits are refused, never clipped.
            const bool limit = verdict.kind == CommandCheck::Kind::OutOfLimits;
            return refuse(client, m.seq, limit ? ReplyStatus::OutOfLimits : ReplyStatus::Invalid, verdict.message);
          }
          commands_.push_back(*command);
          ++accepted_;
          send(client, ReplyMsg{m.seq, ReplyStatus::Ok, ""});
        } else if constexpr (std::is_same_v<T, SequenceMsg>) {
          if (client != holder_)
            return refuseSequence(client, m.hash, holder_ ? "'" + clients_[holder_].name + "' holds the lease"
                                                         : "nobody holds the lease");
          heardFromHolder(now);
          if (failsafe_ || estop_)
            return refuseSequence(client, m.hash, std::string(estop_ ? "e-stop" : "failsafe") + " latched: re-arm first");
          std::string error;
          std::optional<std::vector<TimedCommand>> commands = parseSequenceMsg(m, robot_, error);
          if (!commands) return refuseSequence(client, m.hash, error);
          for (size_t i = 0; i < commands->size(); ++i)
            if (CommandCheck verdict = check_ ? check_((*commands)[i].command) : CommandCheck{}; !verdict.ok())
              return refuseSequence(client, m.hash, "command " + std::to_string(i + 1) + ": " + verdict.message);
          notice("link", who(client) + " sent sequence " + m.hash + " (" + std::to_string(commands->size()) +
                             " commands)");
          sequences_.push_back({client, m, std::move(*commands)});
        } else if constexpr (std::is_same_v<T, AbortMsg>) {
          if (c.role != Role::Control) {
            notice("link", who(client) + ": abort refused: a monitor does not control the robot");
            return send(client, ErrorMsg{"a monitor cannot abort"});
          }
          const std::string why = "ABORT from '" + c.name + "'" + (m.reason.empty() ? "" : ": " + m.reason);
          notice("link", why + " (sequence " + m.hash + "; the robot stops)");
          stopRobot(why);
        } else if constexpr (std::is_same_v<T, HeartbeatMsg>) {
          // An echo of one of ours measures the round trip; the client's
          // own heartbeats are echoed back for it to do the same.
          if (m.seq >= (uint64_t{1} << 62)) c.rttMs = (now - m.time) * 1000;
          else send(client, m);
        } else if constexpr (std::is_same_v<T, EstopMsg>) {
          stopEverything(EventKind::Estop, "e-stop from '" + c.name + "'" + (m.reason.empty() ? "" : ": " + m.reason),
                         now);
        } else if constexpr (std::is_same_v<T, RearmMsg>) {
          if (c.role != Role::Control || (holder_ && holder_ != client)) {
            notice("link", who(client) + ": re-arm refused: only the lease holder re-arms");
            return send(client, ErrorMsg{"only the lease holder re-arms"});
          }
          if (!failsafe_ && !estop_) return;
          failsafe_ = estop_ = false;
          lastFromHolder_ = now;
          deadmanArmed_ = holder_ != 0;
          notice(toString(EventKind::Rearmed), "re-armed by " + who(client));
          broadcast(EventMsg{EventKind::Rearmed, "re-armed by '" + c.name + "'"});
        } else if constexpr (std::is_same_v<T, ErrorMsg>) {
          // A client's own ERROR: noted, never answered (no ping-pong).
          notice("link", who(client) + " reported an error: " + m.reason);
        } else {
          send(client, ErrorMsg{std::string(toString(typeOf(message))) + " is not sent to the robot"});
        }
      },
      message);
}

void RobotLink::heardFromHolder(double now) {
  awaitingHolder_ = false;
  lastFromHolder_ = now;
  deadmanArmed_ = true;
}

void RobotLink::tick(double now) {
  // A new holder that never confirms loses the lease again (the robot
  // stood still meanwhile: nothing latches).
  if (awaitingHolder_ && now - grantedAt_ > config_.leaseConfirm) {
    awaitingHolder_ = false;
    notice("link", "lease taken back from " + who(holder_) + ": no keep-alive within " +
                       std::to_string(static_cast<int>(config_.leaseConfirm * 1000)) + " ms of the grant");
    holder_ = 0;
    stopRobot("the lease was taken back");
    broadcastLease();
  }
  // The deadman watches the holder, and keeps watching after a holder is
  // lost until it fires: losing the operator stops the robot.
  if (deadmanArmed_ && !failsafe_ && now - lastFromHolder_ > config_.deadman) {
    stopEverything(EventKind::Failsafe,
                   "no command or keep-alive from the controlling client for " +
                       std::to_string(static_cast<int>(config_.deadman * 1000)) + " ms",
                   now);
    deadmanArmed_ = false;  // until a holder is heard again
    holderLost_ = false;
  }
}

void RobotLink::announce(EventKind kind, const std::string& text) { broadcast(EventMsg{kind, text}); }

void RobotLink::sendHeartbeats(double now) {
  // Our sequence numbers live above 2^62, apart from the clients' own.
  const uint64_t seq = (uint64_t{1} << 62) + ++heartbeatSeq_;
  for (const auto& [id, c] : clients_)
    if (c.authenticated) send(id, HeartbeatMsg{seq, now});
}

std::vector<RobotLink::Outgoing> RobotLink::takeOutgoing() { return std::exchange(outgoing_, {}); }
std::vector<Command> RobotLink::takeCommands() { return std::exchange(commands_, {}); }
std::vector<RobotLink::SequenceRequest> RobotLink::takeSequences() { return std::exchange(sequences_, {}); }
std::vector<std::string> RobotLink::takeAborts() { return std::exchange(aborts_, {}); }
std::vector<ClientId> RobotLink::takeClosing() { return std::exchange(closing_, {}); }
std::vector<RobotLink::Notice> RobotLink::takeNotices() { return std::exchange(notices_, {}); }

bool RobotLink::authenticated(ClientId client) const {
  auto it = clients_.find(client);
  return it != clients_.end() && it->second.authenticated;
}

std::vector<ClientId> RobotLink::subscribers() const {
  std::vector<ClientId> out;
  for (const auto& [id, c] : clients_)
    if (c.authenticated) out.push_back(id);
  return out;
}

double RobotLink::rttMs(ClientId client) const {
  auto it = clients_.find(client);
  return it == clients_.end() ? 0 : it->second.rttMs;
}

}  // namespace sp::net
