#include "net/robot_client.h"

#include <asio.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "net/auth.h"
#include "net/frame.h"
#include "net/thread_priority.h"

namespace sp::net {

const char* toString(ConnectionState state) {
  switch (state) {
    case ConnectionState::Stopped: return "stopped";
    case ConnectionState::Connecting: return "connecting";
    case ConnectionState::Authenticating: return "authenticating";
    case ConnectionState::Ready: return "ready";
    case ConnectionState::Waiting: return "waiting";
    case ConnectionState::Refused: return "refused";
  }
  return "?";
}

double delaySpread(const std::vector<std::pair<double, double>>& frames) {
  if (frames.size() < 3) return 0;
  // Centred sums: the wall clock's seconds since boot would cost digits.
  double mt = 0, mo = 0;
  for (const auto& [arrival, robot] : frames) {
    mt += arrival;
    mo += arrival - robot;
  }
  const double n = static_cast<double>(frames.size());
  mt /= n;
  mo /= n;
  double stt = 0, sto = 0;
  for (const auto& [arrival, robot] : frames) {
    stt += (arrival - mt) * (arrival - mt);
    sto += (arrival - mt) * (arrival - robot - mo);
  }
  const double slope = stt > 0 ? sto / stt : 0;
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& [arrival, robot] : frames) {
    const double r = arrival - robot - mo - slope * (arrival - mt);
    lo = std::min(lo, r);
    hi = std::max(hi, r);
  }
  return hi - lo;
}

std::string linkAdvice(double deadman, double keepalive, double stretch) {
  // Two seconds of frames underrate the worst a session meets (a link that
  // keeps order also hides its shortest delays): half as much again.
  const double needed = keepalive + 1.5 * stretch;
  if (!(deadman > 0) || needed < deadman) return {};
  const double suggest = std::ceil(1.5 * needed / 0.05) * 0.05;
  char text[400];
  std::snprintf(text, sizeof text,
                "this link's delay varies by %.0f ms: keep-alives every %.0f ms may arrive %.0f ms apart or more, and "
                "the robot's deadman (%.0f ms) would fire now and then. Set link.deadman=%.2f on the robot "
                "(docs/protocol.md, settings per link)",
                stretch * 1000, keepalive * 1000, needed * 1000, deadman * 1000, suggest);
  return text;
}

namespace {

using Clock = std::chrono::steady_clock;
/// HEARTBEATs with a seq at or above this are the robot's (docs/protocol.md).
constexpr uint64_t kRobotHeartbeatBase = uint64_t{1} << 62;
/// Longest wait for queued frames to be written when stopping.
constexpr double kFlushOnStop = 0.1;

Clock::duration toDuration(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

/// At most `rate` a second, `burst` at once: what a robot may send beyond
/// that is shed (a flood must not reach the window or the log).
struct TokenBucket {
  double rate = 1, burst = 1, tokens = 1, at = 0;
  void reset(double r, double b, double t) {
    rate = r;
    burst = tokens = b;
    at = t;
  }
  bool take(double t) {
    tokens = std::min(burst, tokens + (t - at) * rate);
    at = t;
    if (tokens < 1) return false;
    tokens -= 1;
    return true;
  }
};

}  // namespace

// Everything below `// Worker thread only` is touched by the io_context's
// thread alone; the public methods reach it by posting handlers. Handlers of
// socket operations carry the generation of the connection they belong to
// and do nothing once it has changed (the connection was closed).
class RobotClient::Impl {
 public:
  Impl(RobotClientConfig config, RobotClientCallbacks callbacks)
      : config_(std::move(config)), cb_(std::move(callbacks)), emulator_(config_.emulation) {}

  // --- Any thread -----------------------------------------------------------

  void start() {
    std::lock_guard lock(lifeMutex_);
    if (started_) return;
    if (thread_.joinable()) thread_.join();  // a stop requested from a callback
    started_ = true;
    io_.restart();
    asio::post(io_, [this] { begin(); });
    thread_ = std::thread([this] {
      workerId_ = std::this_thread::get_id();
      raiseLinkThreadPriority();
      io_.run();
    });
  }

  void stop() {
    if (std::this_thread::get_id() == workerId_.load()) {
      // From a callback: the thread cannot join itself.
      if (started_.exchange(false)) asio::post(io_, [this] { shutdown(); });
      return;
    }
    std::lock_guard lock(lifeMutex_);
    if (started_.exchange(false)) asio::post(io_, [this] { shutdown(); });
    // run() returns once shutdown() has closed the socket and cancelled
    // the timers: nothing is left to wait for.
    if (thread_.joinable()) thread_.join();
  }

  template <typename F>
  void post(F&& f) {
    asio::post(io_, std::forward<F>(f));
  }

  uint64_t sendCommand(CommandMsg message) {
    // The seq is taken and the handler posted under one lock, so that
    // handlers run in seq order whichever threads call.
    std::lock_guard lock(postMutex_);
    message.seq = nextSeq_++;
    if (message.expiresMs == 0) message.expiresMs = config_.commandExpiryMs;
    const uint64_t seq = message.seq;
    asio::post(io_, [this, m = std::move(message)] { doCommand(m); });
    return seq;
  }

  RobotClientStats stats() const {
    std::lock_guard lock(statsMutex_);
    return stats_;
  }

  std::optional<LimitsMsg> limits() const {
    std::lock_guard lock(statsMutex_);
    return limits_;
  }

  const RobotClientConfig config_;
  const RobotClientCallbacks cb_;

  // --- Worker thread only ---------------------------------------------------

  void doAcquire() {
    if (ready_) {
      send(LeaseAcquireMsg{});
    } else {
      acquireOnWelcome_ = true;
    }
  }

  void doRelease() {
    acquireOnWelcome_ = false;
    if (!ready_) return;
    send(LeaseReleaseMsg{});
    // No more keep-alives; the robot's LEASE_STATE confirms.
    setLeaseHeld(false);
  }

  void doEstop(const std::string& reason) {
    if (ready_) {
      send(EstopMsg{reason});
      return;
    }
    estopOnWelcome_ = reason;
    notice("client: ESTOP not sent yet: not connected; it goes out when the robot welcomes the next connection");
  }

  void doSend(const Message& message, const char* what) {
    if (ready_) send(message);
    else notice(std::string("client: ") + what + " not sent: not connected");
  }

  void doRearm() {
    if (ready_) send(RearmMsg{});
    else notice("client: REARM not sent: not connected");
  }

  void doDrop() {
    if (running_ && isConnectionUp()) dropped("connection dropped by the client", false);
  }

  void doSetEmulation(const LinkEmulatorConfig& emulation) {
    emulator_.setConfig(emulation);
  }

 private:
  // --- Worker thread only ---------------------------------------------------

  double now() const { return std::chrono::duration<double>(Clock::now() - epoch_).count(); }

  template <typename F>
  void updateStats(F&& f) {
    std::lock_guard lock(statsMutex_);
    f(stats_);
  }

  bool isConnectionUp() const {
    return state_ == ConnectionState::Connecting || state_ == ConnectionState::Authenticating ||
           state_ == ConnectionState::Ready;
  }

  void setState(ConnectionState state, const std::string& detail) {
    state_ = state;
    updateStats([&](RobotClientStats& s) {
      s.state = state;
      s.connected = state == ConnectionState::Ready;
      if (state == ConnectionState::Waiting || state == ConnectionState::Refused) s.lastError = detail;
    });
    if (cb_.connection) cb_.connection(state, detail);
  }

  void notice(const std::string& text) {
    updateStats([&](RobotClientStats& s) { s.lastError = text; });
    if (cb_.error) cb_.error(ErrorMsg{text});
  }

  // A message not passed on: said at once when the first of its kind on
  // this connection, else counted for the next summary (housekeeping).
  void refuse(const Refusal& r) {
    updateStats([](RobotClientStats& s) { ++s.refused; });
    if (tally_.add(r)) notice("client: refused " + r.kind + ": " + r.detail + " (more like it are counted, not shown)");
  }
  // Something odd said once per kind, the message used all the same.
  void remark(const Refusal& r) {
    if (tally_.add(r)) notice("client: " + r.kind + ": " + r.detail);
  }
  void refuseBeforeWelcome(MessageType type) {
    refuse(Refusal{"before WELCOME", std::string(toString(type)) + " from a robot that has not welcomed this connection"});
  }
  // Shed for its rate: counted, said once per kind.
  void shed(const std::string& kind, const std::string& detail) {
    updateStats([](RobotClientStats& s) { ++s.shed; });
    remark(Refusal{kind, detail});
  }

  void setLeaseHeld(bool held) {
    leaseHeld_ = held;
    updateStats([&](RobotClientStats& s) { s.leaseHeld = held; });
  }

  void localReply(uint64_t seq, ReplyStatus status, std::string reason) {
    if (cb_.reply) cb_.reply(ReplyMsg{seq, status, std::move(reason)});
  }

  // Started by start(): the timers run until shutdown() and keep run() busy.
  void begin() {
    running_ = true;
    backoff_ = config_.reconnectMin;
    const double t = now();
    nextKeepalive_ = t + config_.keepaliveInterval;
    nextHeartbeat_ = t + config_.heartbeatInterval;
    keepaliveLoop();
    heartbeatLoop();
    connect();
  }

  void keepaliveLoop() {
    keepaliveTimer_.expires_at(epoch_ + toDuration(nextKeepalive_));
    keepaliveTimer_.async_wait([this](const asio::error_code& ec) {
      if (ec || !running_) return;
      // How late this thread woke: a loaded machine delays what it reads
      // as much as what it sends, and that is not the link's jitter.
      ownLate_ = std::max(ownLate_, now() - nextKeepalive_);
      if (ready_ && leaseHeld_) send(LeaseKeepaliveMsg{});
      // Fixed deadlines, no drift; after a stall, resync instead of a burst.
      nextKeepalive_ = std::max(nextKeepalive_ + keepaliveInterval_, now());
      keepaliveLoop();
    });
  }

  void heartbeatLoop() {
    heartbeatTimer_.expires_at(epoch_ + toDuration(nextHeartbeat_));
    heartbeatTimer_.async_wait([this](const asio::error_code& ec) {
      if (ec || !running_) return;
      if (ready_) sendHeartbeat();
      housekeeping();
      nextHeartbeat_ = std::max(nextHeartbeat_ + config_.heartbeatInterval, now());
      heartbeatLoop();
    });
  }

  void sendHeartbeat() { send(HeartbeatMsg{++heartbeatSeq_, now()}); }

  // Every heartbeat period: telemetry rate, overdue replies, a silent link.
  void housekeeping() {
    const double t = now();
    if (ready_ && t - rateWindowStart_ >= 1.0) {
      const double rate = static_cast<double>(rateWindowCount_) / (t - rateWindowStart_);
      updateStats([&](RobotClientStats& s) { s.telemetryRateHz = rate; });
      rateWindowStart_ = t;
      rateWindowCount_ = 0;
    }
    for (auto it = pending_.begin(); it != pending_.end();) {
      if (t > it->second.deadline) {
        const uint64_t seq = it->first;
        const auto waitedMs = static_cast<long long>((t - it->second.sent) * 1000);
        it = pending_.erase(it);
        localReply(seq, ReplyStatus::Failed, "client: no reply within " + std::to_string(waitedMs) + " ms");
      } else {
        ++it;
      }
    }
    if (t - lastReport_ >= kRefusalReport) {
      lastReport_ = t;
      for (const std::string& line : tally_.report()) notice("client: refused or shed since the last summary: " + line);
    }
    if (state_ == ConnectionState::Authenticating && t - connectedAt_ > config_.helloTimeout)
      return dropped("no WELCOME within " + std::to_string(static_cast<int>(config_.helloTimeout * 1000)) +
                         " ms of connecting (link.hello_timeout): the handshake is given up",
                     false);
    if ((state_ == ConnectionState::Authenticating || state_ == ConnectionState::Ready) &&
        t - lastReceived_ > config_.silenceTimeout)
      dropped("nothing from the robot for " + std::to_string(static_cast<int>(config_.silenceTimeout * 1000)) + " ms",
              false);
  }

  void connect() {
    const uint64_t gen = ++generation_;
    setState(ConnectionState::Connecting, config_.host + ":" + std::to_string(config_.port));
    resolver_.async_resolve(
        config_.host, std::to_string(config_.port),
        [this, gen](const asio::error_code& ec, const asio::ip::tcp::resolver::results_type& results) {
          if (gen != generation_ || !running_) return;
          if (ec) return dropped("cannot resolve '" + config_.host + "': " + ec.message(), false);
          asio::async_connect(socket_, results,
                              [this, gen](const asio::error_code& error, const asio::ip::tcp::endpoint&) {
                                if (gen != generation_ || !running_) return;
                                if (error)
                                  return dropped("cannot connect to " + config_.host + ":" +
                                                     std::to_string(config_.port) + ": " + error.message(),
                                                 false);
                                connected();
                              });
        });
  }

  void connected() {
    asio::error_code ec;
    socket_.set_option(asio::ip::tcp::no_delay(true), ec);  // small frames, latency matters
    decoder_ = FrameDecoder{};
    errorBeforeWelcome_.clear();
    haveTelemetrySeq_ = false;
    challenged_ = false;
    check_ = TelemetryCheck(config_.bounds);
    lastReceived_ = connectedAt_ = now();
    queuedBytes_ = 0;
    tally_ = RefusalTally{};  // each connection says its problems anew
    lastReport_ = connectedAt_;
    if (everConnected_) updateStats([](RobotClientStats& s) { ++s.reconnects; });
    everConnected_ = true;
    setState(ConnectionState::Authenticating, config_.host + ":" + std::to_string(config_.port));
    // HELLO answers the robot's CHALLENGE (handle(ChallengeMsg)).
    read();
  }

  void read() {
    socket_.async_read_some(asio::buffer(readBuffer_), [this, gen = generation_](const asio::error_code& ec, size_t n) {
      if (gen != generation_ || !running_) return;
      if (ec)
        return dropped(ec == asio::error::eof ? "the robot closed the connection" : "read failed: " + ec.message(),
                       !errorBeforeWelcome_.empty());
      lastReceived_ = now();
      decoder_.feed(readBuffer_.data(), n);
      while (std::optional<Frame> frame = decoder_.next()) {
        handleFrame(*frame);
        if (gen != generation_ || !running_) return;
      }
      if (decoder_.failed()) return dropped("bad frame from the robot: " + decoder_.errorMessage(), false);
      read();
    });
  }

  // Closes the socket and forgets the connection's state; answers the
  // commands still waiting for a reply.
  void closeConnection() {
    ++generation_;
    asio::error_code ec;
    socket_.close(ec);
    resolver_.cancel();
    emulatorTimer_.cancel();
    writeQueue_.clear();
    queuedBytes_ = 0;
    delayed_.clear();
    writing_ = false;
    ready_ = false;
    const bool hadLease = leaseHeld_;
    if (hadLease && config_.reacquireLease) acquireOnWelcome_ = true;
    setLeaseHeld(false);
    updateStats([](RobotClientStats& s) { s.telemetryRateHz = 0; });
    for (const auto& [seq, p] : std::exchange(pending_, {}))
      localReply(seq, ReplyStatus::Failed, "client: connection lost before the reply (the robot may have applied it)");
    if (hadLease && cb_.lease) cb_.lease(LeaseStateMsg{"", false});
  }

  // The connection is gone or could not be made: close it and reconnect
  // after the backoff, unless the robot refused our HELLO.
  void dropped(const std::string& reason, bool refused) {
    closeConnection();
    if (refused) {
      setState(ConnectionState::Refused, errorBeforeWelcome_.empty() ? reason : errorBeforeWelcome_);
      return;
    }
    setState(ConnectionState::Waiting, reason);
    reconnectTimer_.expires_after(toDuration(backoff_));
    backoff_ = std::min(backoff_ * 2, config_.reconnectMax);
    reconnectTimer_.async_wait([this](const asio::error_code& ec) {
      if (ec || !running_) return;
      connect();
    });
  }

  // --- Sending ---

  bool send(const Message& message, std::string* errorOut = nullptr) {
    std::string error;
    std::optional<std::string> frame = encodeMessage(message, error);
    if (!frame) {
      if (errorOut) *errorOut = error;
      else notice("client: cannot encode " + std::string(toString(typeOf(message))) + ": " + error);
      return false;
    }
    sendFrame(std::move(*frame));
    return true;
  }

  void sendFrame(std::string frame) {
    if (!emulator_.config().active() && delayed_.empty()) return enqueue(std::move(frame));
    const double t = now();
    std::optional<double> due = emulator_.config().active() ? emulator_.schedule(frame.size(), t) : t;
    if (!due) {
      updateStats([](RobotClientStats& s) { ++s.emulatorDropped; });
      return;
    }
    // Switching the emulation off never lets a frame overtake delayed ones.
    if (!emulator_.config().active() && !delayed_.empty()) due = std::max(*due, delayed_.rbegin()->first);
    if (*due <= t && delayed_.empty()) return enqueue(std::move(frame));
    // A multimap keeps frames of equal due times in the order sent.
    delayed_.emplace(*due, std::move(frame));
    armEmulatorTimer();
  }

  void armEmulatorTimer() {
    if (delayed_.empty()) return;
    emulatorTimer_.expires_at(epoch_ + toDuration(delayed_.begin()->first));
    emulatorTimer_.async_wait([this, gen = generation_](const asio::error_code& ec) {
      if (ec || gen != generation_) return;
      const double t = now();
      while (!delayed_.empty() && delayed_.begin()->first <= t) {
        enqueue(std::move(delayed_.begin()->second));
        delayed_.erase(delayed_.begin());
      }
      armEmulatorTimer();
    });
  }

  void enqueue(std::string frame) {
    if (!socket_.is_open()) return;
    // A robot that stops reading must not take the console's memory: it is
    // dropped, as the robot drops a client that does not read.
    if (queuedBytes_ + frame.size() > config_.maxQueuedBytes && !flushing_)
      return dropped("the robot does not read what the console sends: " + std::to_string(queuedBytes_ / 1024) +
                         " KiB unsent (at most " + std::to_string(config_.maxQueuedBytes / 1024) + ")",
                     false);
    queuedBytes_ += frame.size();
    writeQueue_.push_back(std::move(frame));
    if (!writing_) writeNext();
  }

  void writeNext() {
    if (writeQueue_.empty() || !socket_.is_open()) {
      writing_ = false;
      if (flushing_) finishShutdown();
      return;
    }
    writing_ = true;
    // The frame lives with the operation, whatever happens to the queue.
    auto frame = std::make_shared<std::string>(std::move(writeQueue_.front()));
    writeQueue_.pop_front();
    queuedBytes_ -= std::min(queuedBytes_, frame->size());
    asio::async_write(socket_, asio::buffer(*frame),
                      [this, gen = generation_, frame](const asio::error_code& ec, size_t) {
                        if (gen != generation_) return;
                        if (ec) {
                          if (flushing_) return finishShutdown();
                          return dropped("write failed: " + ec.message(), false);
                        }
                        updateStats([](RobotClientStats& s) { ++s.framesSent; });
                        writeNext();
                      });
  }

  // --- Receiving ---

  void handleFrame(const Frame& frame) {
    updateStats([](RobotClientStats& s) { ++s.framesReceived; });
    std::string error;
    std::optional<Message> message = decodeMessage(frame, error);
    if (!message) {
      // A sound frame with a bad payload: answered, the connection stays.
      refuse(Refusal{"bad message", error});
      // Answered, at most errorReplies_'s rate: a flood of bad frames must
      // not make the console flood back.
      if (ready_ && errorReplies_.take(now())) send(ErrorMsg{error});
      return;
    }
    std::visit(
        [this, type = typeOf(*message)](const auto& m) {
          if constexpr (requires { handle(m); }) {
            handle(m);
          } else {
            // HELLO, COMMAND, ...: only clients send these.
            refuse(Refusal{"not sent to clients", std::string(toString(type))});
            if (ready_ && errorReplies_.take(now())) send(ErrorMsg{std::string(toString(type)) + " is not sent to clients"});
          }
        },
        *message);
  }

  void handle(const ChallengeMsg& m) {
    // One CHALLENGE per connection: a robot that repeats it (each answered
    // with a HELLO) would keep the handshake going and the queue growing.
    if (challenged_ || ready_)
      return dropped("the robot sent CHALLENGE again: the handshake is given up", false);
    challenged_ = true;
    // The token never leaves: the proof covers this connection's nonce only.
    send(HelloMsg{config_.name, {}, config_.role, helloProof(config_.token, m.nonce, config_.name, config_.role)});
  }

  void handle(const SequenceStateMsg& m) {
    if (!ready_) return refuseBeforeWelcome(MessageType::SequenceState);
    if (cb_.sequence) cb_.sequence(m);
  }

  void handle(const LimitsMsg& m) {
    if (!ready_) return refuseBeforeWelcome(MessageType::Limits);
    if (std::string problem = limitsProblem(m); !problem.empty())
      return refuse(Refusal{"LIMITS", problem + "; the robot file's limits stay in use"});
    {
      std::lock_guard lock(statsMutex_);
      limits_ = m;
    }
    if (cb_.limits) cb_.limits(m);
  }

  void handle(const WelcomeMsg& m) {
    if (ready_) return refuse(Refusal{"WELCOME again", "a second WELCOME on this connection is ignored"});
    if (!challenged_) return dropped("WELCOME before any CHALLENGE: the robot is not following the protocol", false);
    if (std::string problem = welcomeProblem(m); !problem.empty())
      return dropped("refused the robot's WELCOME: " + problem, false);
    ready_ = true;
    backoff_ = config_.reconnectMin;
    rateWindowStart_ = now();
    rateWindowCount_ = 0;
    readyAt_ = now();
    linkFrames_.clear();
    ownLate_ = 0;
    linkChecked_ = false;
    updateStats([&](RobotClientStats& s) {
      s.robot = m.robot;
      s.telemetryRateAnnounced = m.telemetryRate;
      s.robotDeadman = m.deadman;
      s.robotWorldHash = m.worldHash;
      s.robotRobotHash = m.robotHash;
      s.robotCapabilities = m.capabilities;
    });
    // Keep-alives at least four per deadman period, so one late or lost
    // keep-alive never trips it.
    keepaliveInterval_ = std::max(
        kMinKeepalive, m.deadman > 0 ? std::min(config_.keepaliveInterval, m.deadman / 4) : config_.keepaliveInterval);
    const double t = now();
    telemetryBucket_.reset(1.5 * m.telemetryRate + 1, std::max(10.0, m.telemetryRate), t);
    // Per connection, not per frame: a flood sheds thousands a second.
    announcedRate_ = m.telemetryRate;
    telemetryShedDetail_ = "frames beyond " + std::to_string(static_cast<int>(telemetryBucket_.rate)) +
                           " a second (WELCOME said " + std::to_string(static_cast<int>(m.telemetryRate)) +
                           " Hz) are shed, the newest kept";
    // Laser scans come at most as fast as telemetry on any robot we know.
    laserBucket_.reset(1.5 * m.telemetryRate + 1, std::max(10.0, m.telemetryRate), t);
    eventBucket_.reset(config_.eventRate, std::max(1.0, config_.eventRate), t);
    errorReplies_.reset(10, 10, t);
    echoBucket_.reset(50, 50, t);
    setState(ConnectionState::Ready, m.robot);
    // Plausible, but worth the operator's knowing before taking control.
    if (m.deadman == 0)
      notice("client: the robot announces no deadman (WELCOME deadman 0): if this console is lost, nothing says "
             "the robot stops");
    else if (m.deadman > 10)
      notice("client: the robot's deadman is " + std::to_string(static_cast<long long>(m.deadman)) +
             " s: if this console is lost the robot drives on that long before it stops");
    sendHeartbeat();  // a first round trip at once
    if (estopOnWelcome_) {
      send(EstopMsg{*estopOnWelcome_});
      estopOnWelcome_.reset();
    }
    if (acquireOnWelcome_ && config_.role == Role::Control) send(LeaseAcquireMsg{});
    acquireOnWelcome_ = false;
  }

  void handle(const LeaseStateMsg& m) {
    if (!ready_) return refuseBeforeWelcome(MessageType::LeaseState);
    setLeaseHeld(m.yours);
    if (cb_.lease) cb_.lease(m);
  }

  void handle(const ReplyMsg& m) {
    // A reply to nothing pending was answered locally already (timed out): dropped.
    if (pending_.erase(m.seq) == 0) return;
    updateStats([](RobotClientStats& s) { ++s.repliesReceived; });
    if (cb_.reply) cb_.reply(m);
  }

  void handle(const TelemetryMsg& m) {
    if (!ready_) return refuseBeforeWelcome(MessageType::Telemetry);
    const double t = now();
    if (Refusal r = check_.check(m, t); !r.kind.empty()) {
      if (cb_.refusedTelemetry) cb_.refusedTelemetry(r);
      return refuse(r);
    }
    if (!telemetryBucket_.take(t)) return shed("telemetry beyond the announced rate", telemetryShedDetail_);
    checkLink(m.time);
    uint64_t lost = 0;
    if (haveTelemetrySeq_ && m.seq > lastTelemetrySeq_ + 1) {
      // More missing than the robot could have sent since the last frame
      // (three times its announced rate, and some) is a renumbering, not loss.
      const double possible = 3 * announcedRate_ * (t - lastSeqAt_) + 100;
      const uint64_t gap = m.seq - lastTelemetrySeq_ - 1;
      if (static_cast<double>(gap) <= possible) {
        lost = gap;
      } else {
        updateStats([](RobotClientStats& s) { ++s.renumbered; });
        remark(Refusal{"telemetry seq renumbered", "seq " + std::to_string(lastTelemetrySeq_) + " -> " +
                                                       std::to_string(m.seq) + ": not counted as lost"});
      }
    } else if (haveTelemetrySeq_ && m.seq <= lastTelemetrySeq_) {
      updateStats([](RobotClientStats& s) { ++s.renumbered; });
    }
    lastTelemetrySeq_ = m.seq;
    lastSeqAt_ = t;
    haveTelemetrySeq_ = true;
    ++rateWindowCount_;
    updateStats([&](RobotClientStats& s) {
      ++s.telemetryFrames;
      s.telemetryLost += lost;
      s.robotRttMs = m.rttMs;
      s.robotDropped = m.lost;
    });
    if (cb_.telemetry) cb_.telemetry(m);
  }

  // The first kLinkCheckSeconds of telemetry after WELCOME: arrival minus
  // the frame's robot time is the one-way delay plus a constant (plus a
  // trend when the robot's clock runs slow or fast), so its spread about
  // the trend is what the link's jitter can add to a gap between two frames
  // (gaps between arrivals alone underrate it: the link keeps order). Then,
  // once, whether our keep-alives so stretched fit the robot's deadman.
  void checkLink(double robotTime) {
    if (linkChecked_ || !ready_) return;  // once per connection: nothing more per frame
    const double t = now();
    if (linkFrames_.size() < 100000) linkFrames_.emplace_back(t, robotTime);
    if (t - readyAt_ < kLinkCheckSeconds) return;
    linkChecked_ = true;
    const RobotClientStats s = stats();
    // Our own emulated link's jitter stretches what we send, not what we
    // get; our own thread's lateness (a loaded machine) is not the link's.
    const double stretch = std::max(delaySpread(linkFrames_) - ownLate_, 2 * config_.emulation.jitter);
    linkFrames_ = {};
    const std::string advice = linkAdvice(s.robotDeadman, keepaliveInterval_, std::max(0.0, stretch));
    updateStats([&](RobotClientStats& st) {
      st.delaySpreadMs = std::max(0.0, stretch) * 1000;
      st.linkWarning = advice;
    });
    if (!advice.empty() && cb_.error) cb_.error(ErrorMsg{"client: " + advice});
  }

  void handle(const LaserMsg& m) {
    if (!ready_) return refuseBeforeWelcome(MessageType::Laser);
    if (!laserBucket_.take(now())) return shed("laser beyond the telemetry rate", "scans beyond it are shed");
    if (m.ranges.size() > 100000 || !std::isfinite(m.time))
      return refuse(Refusal{"laser", std::to_string(m.ranges.size()) + " ranges at time " + std::to_string(m.time)});
    if (cb_.laser) cb_.laser(m);
  }

  void handle(const HeartbeatMsg& m) {
    if (m.seq >= kRobotHeartbeatBase) {
      // The robot's: back unchanged, it measures its round trip; a robot
      // that floods them is answered at most echoBucket_'s rate.
      if (!ready_) return refuseBeforeWelcome(MessageType::Heartbeat);
      if (echoBucket_.take(now())) send(m);
      else shed("robot heartbeats beyond 50 a second", "not echoed");
      return;
    }
    if (m.seq == 0 || m.seq > heartbeatSeq_) return;  // not one of ours
    const double rtt = (now() - m.time) * 1000;
    if (!std::isfinite(rtt) || rtt < 0) return refuse(Refusal{"heartbeat", "an echo that is not ours"});
    updateStats([&](RobotClientStats& s) {
      s.rttMs = rtt;
      s.rttMeanMs = s.rttSamples == 0 ? rtt : s.rttMeanMs + (rtt - s.rttMeanMs) / 8;
      s.rttMaxMs = std::max(s.rttMaxMs, rtt);
      ++s.rttSamples;
    });
    if (cb_.rtt) cb_.rtt(rtt);
  }

  void handle(const EventMsg& m) {
    if (!ready_) return refuseBeforeWelcome(MessageType::Event);
    if (!eventBucket_.take(now()))
      return shed(eventShedKind_, "the robot's EVENTs beyond that are counted, not shown");
    if (cb_.event) cb_.event(m);
  }

  void handle(const ErrorMsg& m) {
    // Before WELCOME an ERROR means the HELLO was refused; the robot closes.
    if (!ready_) errorBeforeWelcome_ = m.reason.empty() ? "refused" : m.reason;
    else if (!eventBucket_.take(now()))
      return shed(errorShedKind_, "counted, not shown");
    updateStats([&](RobotClientStats& s) { s.lastError = m.reason; });
    if (cb_.error) cb_.error(m);
  }

  void doCommand(CommandMsg m) {
    if (!ready_) return localReply(m.seq, ReplyStatus::Failed, "client: not connected, not sent");
    // Stamped as it leaves, for the robot's expiry judgement (any monotonic
    // clock will do: the robot only compares our stamps with each other).
    m.sentMs = static_cast<uint64_t>(
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch()).count());
    std::string error;
    if (!send(m, &error)) return localReply(m.seq, ReplyStatus::Invalid, "client: " + error);
    const double t = now();
    const double rttS = stats().rttMs / 1000;
    pending_[m.seq] = Pending{t, t + static_cast<double>(m.expiresMs) / 1000 + std::max(config_.replyGrace, 3 * rttS)};
    updateStats([](RobotClientStats& s) { ++s.commandsSent; });
  }

  void shutdown() {
    if (!running_) return;
    running_ = false;
    reconnectTimer_.cancel();
    keepaliveTimer_.cancel();
    heartbeatTimer_.cancel();
    resolver_.cancel();
    emulatorTimer_.cancel();
    delayed_.clear();
    // Exactly one reply per command, even now.
    for (const auto& [seq, p] : std::exchange(pending_, {}))
      localReply(seq, ReplyStatus::Failed, "client: stopped before the reply (the robot may have applied it)");
    if (socket_.is_open() && writing_) {
      // Let what is queued go out (a LEASE_RELEASE before stop(), say), briefly.
      flushing_ = true;
      flushTimer_.expires_after(toDuration(kFlushOnStop));
      flushTimer_.async_wait([this](const asio::error_code& ec) {
        if (!ec) finishShutdown();
      });
      return;
    }
    finishShutdown();
  }

  void finishShutdown() {
    flushing_ = false;
    flushTimer_.cancel();
    closeConnection();
    setState(ConnectionState::Stopped, "");
  }

  struct Pending {
    double sent = 0;      ///< [s] when written
    double deadline = 0;  ///< [s] answered locally after this
  };

  std::mutex lifeMutex_;  ///< start()/stop()
  std::atomic<bool> started_{false};
  std::atomic<std::thread::id> workerId_{};
  std::thread thread_;

  std::mutex postMutex_;
  uint64_t nextSeq_ = 1;  ///< under postMutex_

  mutable std::mutex statsMutex_;
  RobotClientStats stats_;  ///< under statsMutex_
  std::optional<LimitsMsg> limits_;  ///< under statsMutex_

 public:
  // Declared before everything that uses it, so destroyed after.
  asio::io_context io_;

 private:
  // Worker thread only.
  const Clock::time_point epoch_ = Clock::now();
  asio::ip::tcp::resolver resolver_{io_};
  asio::ip::tcp::socket socket_{io_};
  asio::steady_timer reconnectTimer_{io_}, keepaliveTimer_{io_}, heartbeatTimer_{io_}, emulatorTimer_{io_},
      flushTimer_{io_};
  uint64_t generation_ = 0;
  bool running_ = false, flushing_ = false;
  ConnectionState state_ = ConnectionState::Stopped;
  double backoff_ = 0.2;
  bool everConnected_ = false;
  FrameDecoder decoder_;
  std::array<char, 16384> readBuffer_{};
  std::deque<std::string> writeQueue_;
  bool writing_ = false;
  LinkEmulator emulator_;
  std::multimap<double, std::string> delayed_;  ///< due time [s] -> frame, on the emulated link
  bool ready_ = false, leaseHeld_ = false, acquireOnWelcome_ = false;
  double keepaliveInterval_ = 0.05;  // [s] config's, or a quarter of the robot's deadman if shorter
  std::optional<std::string> estopOnWelcome_;
  std::string errorBeforeWelcome_;
  std::map<uint64_t, Pending> pending_;  ///< commands sent, waiting for their REPLY
  uint64_t heartbeatSeq_ = 0;
  double nextKeepalive_ = 0, nextHeartbeat_ = 0, lastReceived_ = 0;
  bool haveTelemetrySeq_ = false, challenged_ = false;
  uint64_t lastTelemetrySeq_ = 0;
  double lastSeqAt_ = 0, connectedAt_ = 0, lastReport_ = 0;
  size_t queuedBytes_ = 0;  ///< in writeQueue_
  TelemetryCheck check_;
  RefusalTally tally_;
  TokenBucket telemetryBucket_, laserBucket_, eventBucket_, errorReplies_, echoBucket_;
  double announcedRate_ = 50;        // [Hz] this connection's WELCOME telemetry_rate
  std::string telemetryShedDetail_;  // what a shed frame is said to be (made at WELCOME)
  // The kinds the event and ERROR floods are counted under, made once.
  const std::string eventShedKind_ = "events beyond " + std::to_string(static_cast<int>(config_.eventRate)) + " a second";
  const std::string errorShedKind_ = "robot ERRORs beyond " + std::to_string(static_cast<int>(config_.eventRate)) + " a second";
  double rateWindowStart_ = 0;
  uint64_t rateWindowCount_ = 0;
  double readyAt_ = 0;  // [s] the link check (checkLink)
  std::vector<std::pair<double, double>> linkFrames_;  // its frames: (arrival, robot time)
  double ownLate_ = 0;  // [s] the keep-alive timer's worst lateness over the check
  bool linkChecked_ = false;
};

RobotClient::RobotClient(RobotClientConfig config, RobotClientCallbacks callbacks)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(callbacks))) {}

RobotClient::~RobotClient() { stop(); }

void RobotClient::start() { impl_->start(); }
void RobotClient::stop() { impl_->stop(); }

void RobotClient::acquireLease() {
  impl_->post([impl = impl_.get()] { impl->doAcquire(); });
}
void RobotClient::releaseLease() {
  impl_->post([impl = impl_.get()] { impl->doRelease(); });
}

uint64_t RobotClient::sendCommand(const Command& command, uint64_t expiresMs, const RobotModel* robot) {
  return impl_->sendCommand(makeCommandMsg(0, expiresMs, command, robot));
}
uint64_t RobotClient::sendCommandText(std::string text, uint64_t expiresMs) {
  return impl_->sendCommand(CommandMsg{0, expiresMs, std::move(text)});
}

void RobotClient::estop(std::string reason) {
  impl_->post([impl = impl_.get(), r = std::move(reason)] { impl->doEstop(r); });
}
void RobotClient::sendSequence(SequenceMsg sequence) {
  impl_->post([impl = impl_.get(), m = std::move(sequence)] { impl->doSend(m, "SEQUENCE"); });
}
void RobotClient::abortSequence(std::string hash, std::string reason) {
  impl_->post([impl = impl_.get(), m = AbortMsg{std::move(hash), std::move(reason)}] { impl->doSend(m, "ABORT"); });
}
void RobotClient::rearm() {
  impl_->post([impl = impl_.get()] { impl->doRearm(); });
}
void RobotClient::dropConnection() {
  impl_->post([impl = impl_.get()] { impl->doDrop(); });
}
void RobotClient::setEmulation(const LinkEmulatorConfig& emulation) {
  impl_->post([impl = impl_.get(), emulation] { impl->doSetEmulation(emulation); });
}

RobotClientStats RobotClient::stats() const { return impl_->stats(); }
std::optional<LimitsMsg> RobotClient::limits() const { return impl_->limits(); }
const RobotClientConfig& RobotClient::config() const { return impl_->config_; }

}  // namespace sp::net
