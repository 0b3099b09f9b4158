#include "net/robot_server.h"

#include <chrono>

namespace sp::net {

/// One client connection: its socket, decoder and bounded write queue.
class RobotServer::Session {
 public:
  Session(asio::ip::tcp::socket connected, ClientId clientId, const LinkEmulatorConfig& emulation)
      : socket(std::move(connected)), id(clientId), toClient(emulation), fromClient(emulation) {
    // Each direction its own engine, so the two do not mirror each other.
    LinkEmulatorConfig back = emulation;
    back.seed = emulation.seed * 2 + 1;
    fromClient.setConfig(back);
  }

  asio::ip::tcp::socket socket;
  ClientId id;
  FrameDecoder decoder;
  std::array<char, 4096> readBuffer{};
  struct Queued {
    std::string bytes;
    bool telemetry;  // telemetry and laser frames may be dropped
    double due;      // when the emulated link lets it go
  };
  std::deque<Queued> queue;  // frames to write, front first

  /// Telemetry frames the client could have read by `now`: due ones still
  /// queued. Frames the emulated link still holds are in flight, not
  /// waiting for a slow reader, so a long delay drops nothing.
  size_t telemetryWaiting(double now, bool inOrder) const {
    size_t n = 0;
    for (const Queued& q : queue) {
      if (q.due > now) {
        if (inOrder) break;  // due times never decrease
        continue;
      }
      n += q.telemetry;
    }
    return n;
  }
  bool writing = false, reading = false;
  double writeStartedAt = 0;  // [s] of the write under way
  bool closing = false;  // write what is queued, then close (nothing more is read)
  double closingSince = 0;  // [s] a closing client that does not take its last frames is closed
  bool stalled = false;  // its control queue overflowed: it does not read, closed at once
  bool closed = false;
  uint64_t telemetrySeq = 0, laserSeq = 0, lost = 0;
  LinkEmulator toClient, fromClient;
  // Received, held back by the emulated link: a message, or why its
  // content was refused.
  struct Inbound {
    double due;
    std::optional<Message> message;
    std::string refusal;
  };
  std::deque<Inbound> inbox;
  double connectedAt = 0;  // [s] for the HELLO timeout
};

RobotServer::RobotServer(asio::io_context& io, RobotServerConfig config, RobotPort& robot)
    : io_(io),
      config_(std::move(config)),
      robot_(robot),
      link_(config_.link, robot.model(), [&robot](const Command& c) { return robot.check(c); }),
      acceptor_(io),
      timer_(io),
      acceptRetry_(io),
      emulating_(config_.emulation.active()) {}

void RobotServer::fade(double seconds) {
  // From now on frames go through the emulators (a perfect link's are due
  // at once); a session opened during the fade is not faded (it is a new
  // connection over the link that came back).
  emulating_ = true;
  const double until = now() + std::max(0.0, seconds);
  for (auto& [id, s] : sessions_) {
    s->toClient.fade(until);
    s->fromClient.fade(until);
  }
}

RobotServer::~RobotServer() { stop(); }

double RobotServer::now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string RobotServer::start() {
  if (config_.link.token.size() < 32) return "the token must have at least 32 hex digits (128 bits)";
  asio::error_code ec;
  const asio::ip::address address = asio::ip::make_address(config_.address, ec);
  if (ec) return "bad address '" + config_.address + "': " + ec.message();
  link_.setClearTokenAllowed(address.is_loopback());
  const asio::ip::tcp::endpoint endpoint(address, config_.port);
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(asio::ip::tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) return "cannot listen on " + config_.address + ":" + std::to_string(config_.port) + ": " + ec.message();
  port_ = acceptor_.local_endpoint().port();
  accept();
  const double t = now();
  nextTelemetry_ = t;
  nextHeartbeat_ = t;
  schedule();
  return {};
}

void RobotServer::stop() {
  if (stopped_) return;
  stopped_ = true;
  asio::error_code ec;
  acceptor_.close(ec);
  timer_.cancel();
  acceptRetry_.cancel();
  for (auto& [id, s] : sessions_) s->socket.close(ec);
}

void RobotServer::accept() {
  acceptor_.async_accept([this](asio::error_code ec, asio::ip::tcp::socket socket) {
    if (stopped_ || ec == asio::error::operation_aborted) return;
    if (ec) {
      // Out of descriptors, say: keep accepting once some are free again
      // (said at most once a second), never stop for good.
      ++stats_.acceptErrors;
      if (config_.log && now() - lastAcceptErrorLog_ >= 1.0) {
        lastAcceptErrorLog_ = now();
        config_.log("cannot accept a connection: " + ec.message() + "; trying again");
      }
      acceptRetry_.expires_after(std::chrono::milliseconds(100));
      acceptRetry_.async_wait([this](asio::error_code e) {
        if (!e && !stopped_) accept();
      });
      return;
    }
    if (shuttingDown_) {
      asio::error_code ignored;
      socket.close(ignored);
      return;  // and accept no more
    }
    evictForNewcomer();
    size_t open = 0;
    for (const auto& [id, s] : sessions_) open += !s->closed;
    if (open >= config_.maxConnections) {
      ++stats_.refusedConnections;
      if (config_.log)
        config_.log("connection refused: " + std::to_string(open) + " connections open already (the limit)");
      asio::error_code ignored;
      socket.close(ignored);
      accept();
      return;
    }
    asio::error_code ignored;
    socket.set_option(asio::ip::tcp::no_delay(true), ignored);
    // A small kernel send buffer keeps a slow client's backlog in our
    // bounded queue, where old telemetry is dropped, instead of megabytes of
    // stale frames in the kernel.
    socket.set_option(asio::socket_base::send_buffer_size(64 * 1024), ignored);
    const ClientId id = nextId_++;
    auto session = std::make_unique<Session>(std::move(socket), id, config_.emulation);
    Session& s = *session;
    sessions_[id] = std::move(session);
    ++stats_.clientsAccepted;
    if (config_.log) {
      asio::error_code peerError;
      const auto peer = s.socket.remote_endpoint(peerError);
      config_.log("client " + std::to_string(id) + " connected from " +
                  (peerError ? std::string("?") : peer.address().to_string() + ":" + std::to_string(peer.port())));
    }
    s.connectedAt = now();
    link_.connected(id, now());
    startRead(id);
    accept();
  });
}

void RobotServer::startRead(ClientId id) {
  auto it = sessions_.find(id);
  // Nothing more is read from a closing client: its keep-alives must not
  // feed the deadman while it is being let go.
  if (it == sessions_.end() || it->second->closed || it->second->closing) return;
  Session& s = *it->second;
  s.reading = true;
  // Completions look the session up by id: a session closed meanwhile is
  // only erased once no operation refers to its buffers.
  s.socket.async_read_some(asio::buffer(s.readBuffer), [this, id](asio::error_code ec, size_t n) {
    auto found = sessions_.find(id);
    if (found == sessions_.end()) return;
    Session& ses = *found->second;
    ses.reading = false;
    if (ec || ses.closed) return closeSession(id);
    received(id, std::string(ses.readBuffer.data(), n));
    startRead(id);
  });
}

bool RobotServer::telemetryRoom(Session& s) {
  if (s.telemetryWaiting(now(), !emulating_ || config_.emulation.keepOrder) < config_.maxQueuedFrames)
    return true;
  // A slow reader loses telemetry; the control loop never waits for it.
  ++s.lost;
  ++stats_.telemetryDropped;
  return false;
}

void RobotServer::enqueue(Session& s, const Message& message) {
  std::string error;
  if (std::optional<std::string> frame = encodeMessage(message, error)) enqueueFrame(s, std::move(*frame), false);
}

void RobotServer::enqueueFrame(Session& s, std::string frame, bool telemetry) {
  if (!telemetry && s.queue.size() >= config_.maxQueuedControl) {
    // A client that does not read its replies is dropped at once (flush()):
    // were it the controller, it would go on driving blind.
    s.stalled = true;
    return;
  }
  double due = 0;
  if (emulating_) {
    const std::optional<double> at = s.toClient.schedule(frame.size(), now());
    if (!at) {
      ++stats_.emulatedLost;
      return;
    }
    due = *at;
  }
  s.queue.push_back({std::move(frame), telemetry, due});
}

void RobotServer::received(ClientId id, const std::string& bytes) {
  Session& s = *sessions_.at(id);
  s.decoder.feed(bytes);
  while (std::optional<Frame> frame = s.decoder.next()) {
    ++stats_.framesIn;
    std::string error;
    std::optional<Message> message = decodeMessage(*frame, error);
    // A well-framed message with bad content: refused, with the reason.
    if (emulating_) {
      const std::optional<double> at =
          s.fromClient.schedule(frame->payload.size() + kFrameHeaderSize + kFrameCrcSize, now());
      if (!at) ++stats_.emulatedLost;
      else s.inbox.push_back({*at, std::move(message), error});
      continue;
    }
    if (message) link_.received(id, *message, now());
    else link_.refused(id, error, now());
  }
  if (s.decoder.failed()) {
    // A broken frame: the stream cannot be resynchronised; close it.
    ++stats_.badFrames;
    if (config_.log) config_.log("client " + std::to_string(id) + " closed: " + s.decoder.errorMessage());
    link_.malformed(id, s.decoder.errorMessage(), now());
  }
  flush();
}

void RobotServer::deliverDue() {
  const double t = now();
  for (auto& [id, ptr] : sessions_) {
    Session& s = *ptr;
    while (!s.closed && !s.inbox.empty() && s.inbox.front().due <= t) {
      Session::Inbound in = std::move(s.inbox.front());
      s.inbox.pop_front();
      if (in.message) link_.received(id, *in.message, t);
      else link_.refused(id, in.refusal, t);
    }
  }
}

void RobotServer::flush() {
  // Notices before commands: an e-stop's notice reaches the robot's log no
  // later than the stop it caused.
  for (RobotLink::Notice& n : link_.takeNotices())
    if (config_.events) config_.events(n.kind, n.text);
  // A new sequence, then what stops sequences, then commands (a stop among
  // them): the robot sees them in the order that keeps it safe.
  for (RobotLink::SequenceRequest& r : link_.takeSequences()) {
    const SequenceMsg& m = r.message;
    const std::string why = robot_.startSequence(
        {m.hash, std::move(r.commands), m.start, m.startPosition, m.startHeading});
    if (!why.empty()) {
      link_.refuseSequence(r.client, m.hash, why);
      continue;
    }
    link_.sequenceState({m.hash, SequenceStateKind::Accepted, 0, 0, 0, ""});
    // The robot reports the accepted sequence until its twin takes it up:
    // that report is this one, not news (else a late twin sends it twice).
    lastSequence_ = robot_.state().sequence;
  }
  for (const std::string& why : link_.takeAborts()) robot_.abortSequence(why);
  for (RobotLink::Notice& n : link_.takeNotices())
    if (config_.events) config_.events(n.kind, n.text);
  const std::vector<Command> commands = link_.takeCommands();
  if (!commands.empty()) robot_.apply(commands);
  for (const RobotLink::Outgoing& o : link_.takeOutgoing()) {
    auto it = sessions_.find(o.client);
    if (it != sessions_.end() && !it->second->closed) enqueue(*it->second, o.message);
  }
  for (ClientId id : link_.takeClosing()) {
    auto it = sessions_.find(id);
    if (it != sessions_.end()) markClosing(*it->second);
  }
  std::vector<ClientId> finished;  // closed after the loop: closing erases sessions
  for (auto& [id, ptr] : sessions_) {
    if (ptr->stalled && !ptr->closed) {
      // Told to the link first: a controller that cannot receive loses the
      // lease with a failsafe and its reason, not after a deadman's wait.
      ++stats_.stalledClients;
      stats_.lastStallAt = now();
      const std::string why = ptr->writing && now() - ptr->writeStartedAt > config_.stallTimeout
                                  ? "nothing taken for " + std::to_string(static_cast<int>((now() - ptr->writeStartedAt) * 1000)) +
                                        " ms, " + std::to_string(ptr->queue.size()) + " frames unsent"
                                  : std::to_string(ptr->queue.size()) + " frames unsent: it does not read";
      if (config_.log) config_.log("client " + std::to_string(id) + " closed: " + why);
      link_.stalled(id, why, now());
      finished.push_back(id);
    } else if (!writeNext(id, *ptr)) {
      finished.push_back(id);
    }
  }
  for (ClientId id : finished) closeSession(id);
}

bool RobotServer::writeNext(ClientId id, Session& s) {
  if (s.writing || s.closed) return true;
  if (s.queue.empty()) return !s.closing;
  if (s.queue.front().due > now()) return true;  // the emulated link holds it; the timer comes back
  s.writing = true;
  s.writeStartedAt = now();
  // One frame per write; the completion continues with this session's next
  // (only: a scan of every session per completion made 500 clients cost
  // the controller its round trip).
  asio::async_write(s.socket, asio::buffer(s.queue.front().bytes), [this, id](asio::error_code ec, size_t) {
    auto it = sessions_.find(id);
    if (it == sessions_.end()) return;
    Session& ses = *it->second;
    ses.writing = false;
    if (ec) return closeSession(id);
    ses.queue.pop_front();
    if (!writeNext(id, ses)) closeSession(id);
  });
  return true;
}

void RobotServer::evictForNewcomer() {
  size_t open = 0, unauthenticated = 0;
  ClientId oldest = 0;
  double oldestAt = 0;
  for (const auto& [id, s] : sessions_) {
    if (s->closed) continue;
    ++open;
    if (link_.authenticated(id)) continue;
    ++unauthenticated;
    if (!oldest || s->connectedAt < oldestAt) oldest = id, oldestAt = s->connectedAt;
  }
  if (!oldest || unauthenticated < config_.maxUnauthenticated) return;
  ++stats_.evictedUnauthenticated;
  if (config_.log)
    config_.log("client " + std::to_string(oldest) + " closed: no HELLO yet and " + std::to_string(unauthenticated) +
                " such connections open; a newer one takes its place");
  closeSession(oldest);
}

void RobotServer::shutdown(const std::string& reason) {
  if (stopped_ || shuttingDown_) return;
  shuttingDown_ = true;
  asio::error_code ec;
  acceptor_.close(ec);
  link_.shutdown(reason, now());
  flush();
}

void RobotServer::markClosing(Session& s) {
  if (s.closing) return;
  s.closing = true;
  s.closingSince = now();
}

void RobotServer::closeSession(ClientId id) {
  auto it = sessions_.find(id);
  if (it == sessions_.end()) return;
  Session& s = *it->second;
  if (!s.closed) {
    s.closed = true;
    if (config_.log) config_.log("client " + std::to_string(id) + " disconnected");
    asio::error_code ec;
    s.socket.shutdown(asio::ip::tcp::socket::shutdown_both, ec);
    s.socket.close(ec);
    link_.disconnected(id, now());
  }
  // Erase only when no operation still refers to the session's buffers.
  if (!s.reading && !s.writing) sessions_.erase(it);
  flush();
}

void RobotServer::schedule() {
  if (stopped_) return;
  // 2 ms: the deadman's resolution (it must stop within 300 ms, fires at 200).
  timer_.expires_after(std::chrono::milliseconds(2));
  timer_.async_wait([this](asio::error_code ec) {
    if (ec || stopped_) return;
    onTimer();
    schedule();
  });
}

void RobotServer::onTimer() {
  const double t = now();
  if (emulating_) deliverDue();
  if (const std::string fault = robot_.fault(); !fault.empty()) link_.robotFault(fault, t);
  link_.tick(t);
  // Connections that never said HELLO are closed: they would hold a slot
  // (and a descriptor) for nothing.
  // Counted from the connection, as on a real link: an emulated link gets
  // no allowance of its own (the timeout is sized for the slowest link).
  std::vector<ClientId> silent;
  for (const auto& [id, s] : sessions_)
    if (!s->closed && !s->closing && t - s->connectedAt > config_.helloTimeout && !link_.authenticated(id))
      silent.push_back(id);
  // A controller that has taken nothing of a frame for stallTimeout does
  // not read (the kernel's buffers both ways are full): it is blind, and
  // loses control with a failsafe at once, as one whose replies overflow.
  // (A monitor that reads too slowly only loses telemetry.)
  if (auto it = sessions_.find(link_.holder()); it != sessions_.end()) {
    Session& s = *it->second;
    if (!s.closed && !s.stalled && s.writing && t - s.writeStartedAt > config_.stallTimeout) {
      s.stalled = true;
      flush();
    }
  }
  // A closing client that has not taken its last frames within a second
  // does not read: it is closed without them.
  std::vector<ClientId> lingering;
  for (const auto& [id, s] : sessions_)
    if (!s->closed && s->closing && t - s->closingSince > kClosingGrace) lingering.push_back(id);
  for (ClientId id : lingering) closeSession(id);
  for (ClientId id : silent) {
    ++stats_.helloTimeouts;
    const std::string why = "no HELLO within " + std::to_string(std::lround(config_.helloTimeout * 1000)) + " ms";
    if (config_.log) config_.log("client " + std::to_string(id) + " closed: " + why);
    // Told why (ERROR), then closed as a refused HELLO is: its last frame
    // gets kClosingGrace to leave (flush() below).
    link_.closeUnauthenticated(id, why + ": closed");
  }
  if (t >= nextHeartbeat_) {
    nextHeartbeat_ = t + 0.5;
    link_.sendHeartbeats(t);
  }
  // Telemetry and laser are encoded once per state and only the
  // per-client keys per client; a client whose queue is full is skipped
  // before any encoding (500 idle monitors must not slow the controller).
  // A skipped frame still takes its sequence number: the gap tells the
  // client it lost one.
  const auto fanOut = [&](uint64_t Session::*seq, const auto& makeFrame) {
    for (ClientId id : link_.subscribers()) {
      auto it = sessions_.find(id);
      if (it == sessions_.end() || it->second->closed || it->second->closing) continue;  // it has its last frames
      Session& s = *it->second;
      ++(s.*seq);
      if (!telemetryRoom(s)) continue;
      std::string error;
      if (std::optional<std::string> frame = makeFrame(s, id, error)) enqueueFrame(s, std::move(*frame), true);
    }
  };
  if (t >= nextTelemetry_) {
    nextTelemetry_ += 1.0 / config_.link.telemetryRate;
    if (nextTelemetry_ < t) nextTelemetry_ = t;  // no burst after a stall
    RobotState st = robot_.state();
    if (st.health != lastHealth_) {
      lastHealth_ = st.health;
      if (!st.health.empty()) link_.announce(EventKind::Divergence, st.health);
    }
    if (st.sequence != lastSequence_ && !st.sequence.hash.empty()) {
      const SequenceStatus& q = st.sequence;
      // A sequence shorter than a telemetry period ends between two looks:
      // clients are still told it ran (done and aborted both mean it did).
      const bool ended = q.state == SequenceStateKind::Done || q.state == SequenceStateKind::Aborted;
      if (ended && lastSequence_.hash == q.hash && lastSequence_.state == SequenceStateKind::Accepted)
        link_.sequenceState({q.hash, SequenceStateKind::Running, 0, q.count, q.startTime, ""});
      lastSequence_ = st.sequence;
      link_.sequenceState({q.hash, q.state, q.index, q.count, q.startTime, q.reason});
    }
    TelemetryMsg m;
    m.time = st.time;
    m.pose = st.pose;
    m.baseVelocity = {st.baseLinearVelocity.x,  st.baseLinearVelocity.y,  st.baseLinearVelocity.z,
                      st.baseAngularVelocity.x, st.baseAngularVelocity.y, st.baseAngularVelocity.z};
    m.jointNames = std::move(st.jointNames);
    m.jointPositions = std::move(st.jointPositions);
    m.jointVelocities = std::move(st.jointVelocities);
    m.wheelNormal = st.wheelNormal;
    m.wheelTangential = st.wheelTangential;
    m.roll = st.roll;
    m.pitch = st.pitch;
    m.failsafe = link_.failsafeLatched();
    m.estop = link_.estopLatched();
    m.health = std::move(st.health);
    m.objects = std::move(st.objects);
    const TelemetryFanOut telemetry(m);
    fanOut(&Session::telemetrySeq, [&](Session& s, ClientId id, std::string& error) {
      // At least a microsecond: 0 would read as absent.
      const std::optional<double> heard = link_.heardMs(id, t);
      return telemetry.frame(s.telemetrySeq, link_.rttMs(id), s.lost, error, heard ? std::max(*heard, 1e-3) : 0);
    });
  }
  if (std::optional<LaserScanState> scan = robot_.laserAfter(lastLaser_)) {
    lastLaser_ = scan->count;
    const LaserFanOut laser(LaserMsg{0, scan->time, scan->angleMin, scan->angleStep, std::move(scan->ranges)});
    fanOut(&Session::laserSeq, [&](Session& s, ClientId, std::string& error) { return laser.frame(s.laserSeq, error); });
  }
  flush();
}

}  // namespace sp::net
