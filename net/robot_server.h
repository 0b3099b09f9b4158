#pragma once
// The robot's TCP endpoint: accepts clients on loopback (or another address
// with a token), decodes frames, lets RobotLink decide, and sends replies,
// telemetry, laser scans and heartbeats. The same server fronts the twin
// (simpartner-robot) and would front a real robot's adapter: the robot is
// reached only through RobotPort.
//
// Thread: everything runs on the io_context's thread; RobotPort methods are
// called from it.

#include <asio.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "net/frame.h"
#include "net/link_emulator.h"
#include "net/message.h"
#include "net/robot_link.h"

namespace sp::net {

/// A sequence the link accepted (SEQUENCE), for the robot to run on board.
struct SequenceRun {
  std::string hash;
  std::vector<TimedCommand> commands;  ///< times from the sequence's start [s]
  Pose start;                          ///< the rehearsal's start pose
  double startPosition = 0;            ///< [m] tolerance of the base's position
  double startHeading = 0;             ///< [rad] tolerance of its heading
};

/// Where the robot's latest sequence stands; the server sends
/// SEQUENCE_STATE to every client when it changes.
struct SequenceStatus {
  std::string hash;  ///< "" = no sequence yet
  SequenceStateKind state = SequenceStateKind::Accepted;
  uint64_t index = 0, count = 0;  ///< commands applied, in the sequence
  double startTime = 0;           ///< [s] robot time of its t = 0
  std::string reason;             ///< aborted: why
  friend bool operator==(const SequenceStatus&, const SequenceStatus&) = default;
};

/// The robot's state for one TELEMETRY frame (the server adds the per-client
/// sequence number, round trip, losses and latches).
struct RobotState {
  double time = 0;
  Pose pose;
  Vec3 baseLinearVelocity, baseAngularVelocity;  ///< world frame, of the base frame's origin
  std::vector<std::string> jointNames;
  std::vector<double> jointPositions, jointVelocities;
  std::array<double, 4> wheelNormal{}, wheelTangential{};
  double roll = 0, pitch = 0;
  std::string health;  ///< empty when healthy
  /// Poses of the world's dynamic objects the robot knows of (names without
  /// spaces); empty when there are none.
  std::vector<ObjectPose> objects;
  SequenceStatus sequence;
};

struct LaserScanState {
  uint64_t count = 0;  ///< scans taken so far; a new scan has a higher count
  double time = 0, angleMin = 0, angleStep = 0;
  std::vector<double> ranges;
};

/// What the server needs of the robot. Called on the server's thread; an
/// implementation hands work to its own threads (the twin's physics thread).
class RobotPort {
 public:
  virtual ~RobotPort() = default;
  virtual const RobotModel* model() const = 0;
  /// Whether the robot would take the command, and if not, why.
  virtual CommandCheck check(const Command& command) const = 0;
  /// Carries out checked commands, in order, at the next step boundary.
  virtual void apply(const std::vector<Command>& commands) = 0;
  virtual RobotState state() const = 0;
  /// The latest laser scan, if one newer than `afterCount` exists.
  virtual std::optional<LaserScanState> laserAfter(uint64_t afterCount) const = 0;
  /// Starts a checked sequence at the next step boundary: "" when it
  /// starts, else why the robot refuses (its state departed from the
  /// rehearsal's start, another sequence runs). A robot that cannot run
  /// sequences refuses them all.
  virtual std::string startSequence(const SequenceRun&) { return "this robot does not run sequences"; }
  /// Stops the running sequence (its remaining commands are dropped; the
  /// link queues the stop itself). Nothing when none runs.
  virtual void abortSequence(const std::string& /*reason*/) {}
  /// Why the robot must stop now, "" when nothing is wrong: polled every
  /// tick; while it is not "", the failsafe fires with it (again after a
  /// re-arm). A bridge's stale sensor input, say; the twin has none.
  virtual std::string fault() const { return {}; }
};

struct RobotServerConfig {
  std::string address = "127.0.0.1";
  uint16_t port = 47800;             ///< 0 = any free port
  RobotLinkConfig link;
  size_t maxQueuedFrames = 64;       ///< per client; telemetry beyond it is dropped and counted
  size_t maxQueuedControl = 1024;    ///< replies and events beyond it close a client that does not read
  /// [s] a controller (the lease holder) that takes no byte of a frame for
  /// this long does not read (the kernel's buffers are full both ways): it
  /// is blind, and loses control with a failsafe and its connection.
  double stallTimeout = 1.0;
  /// Connections open at once; one more is accepted and closed at once
  /// (logged), so the backlog never fills with clients nobody serves.
  size_t maxConnections = 64;
  /// Of those, connections that have not authenticated yet. When they are
  /// this many, a new connection closes the oldest of them: a flood of
  /// connections that dribble their HELLO can never lock the operator out
  /// (a connection on loopback or a LAN says HELLO within milliseconds).
  /// More than maxConnections: no such pool (a test's control).
  size_t maxUnauthenticated = 32;
  /// [s] a connection without a good HELLO by then, counted from its
  /// opening, is closed (told why); see SimParams::linkHelloTimeout.
  double helloTimeout = 5.0;
  /// Where the server reports connections, refusals and bad frames (one
  /// line each, no newline); may be empty.
  std::function<void(const std::string&)> log;
  /// Where the server reports what the link decided (RobotLink::Notice:
  /// kind "estop", "failsafe", "rearmed" or "link" for lease changes and
  /// refusals, and one line of text), for a session log; may be empty.
  std::function<void(const std::string& kind, const std::string& text)> events;
  /// Emulated link (delay, jitter, loss), applied to frames in both
  /// directions of every connection; inactive by default.
  LinkEmulatorConfig emulation;
};

struct RobotServerStats {
  uint64_t clientsAccepted = 0;
  uint64_t framesIn = 0;
  uint64_t badFrames = 0;       ///< connections closed for a malformed frame
  uint64_t telemetryDropped = 0;
  uint64_t emulatedLost = 0;    ///< frames the emulated link dropped (both directions)
  uint64_t refusedConnections = 0;  ///< closed at once: maxConnections were open
  uint64_t helloTimeouts = 0;       ///< closed for no HELLO within helloTimeout
  uint64_t acceptErrors = 0;        ///< accept() failures (out of descriptors, say); accepting goes on
  uint64_t stalledClients = 0;      ///< closed at once: their replies filled maxQueuedControl (they do not read)
  double lastStallAt = 0;           ///< [s, steady clock] when the last of them was found
  uint64_t evictedUnauthenticated = 0;  ///< connections without HELLO closed to admit a newer one
};

class RobotServer {
 public:
  RobotServer(asio::io_context& io, RobotServerConfig config, RobotPort& robot);
  ~RobotServer();
  /// Binds and starts accepting; "" on success, else why not (address in use,
  /// a non-loopback address without a token, a token under 128 bits).
  std::string start();
  void stop();
  /// The robot is going away (SIGTERM): no new connections; the robot is
  /// stopped as by an e-stop (latched), every client gets EVENT estop and
  /// then ERROR with `reason`, and is closed once it has them (or after a
  /// second). The server runs on until stop().
  void shutdown(const std::string& reason);
  /// The emulated link fades for `seconds` from now, both ways, for every
  /// connection (LinkEmulator::fade): what a radio outage does to the
  /// deadman, on purpose (tests). On the server's thread.
  void fade(double seconds);
  uint16_t port() const { return port_; }
  const RobotServerStats& stats() const { return stats_; }
  const RobotLink& link() const { return link_; }

 private:
  class Session;
  void accept();
  void startRead(ClientId id);
  void enqueue(Session& session, const Message& message);
  void enqueueFrame(Session& session, std::string frame, bool telemetry);
  /// Starts writing the session's next due frame unless a write is under
  /// way; false when the session is done (closing with nothing queued).
  bool writeNext(ClientId id, Session& session);
  /// Whether telemetry may be queued for `session`; if not, counts it lost.
  bool telemetryRoom(Session& session);
  void schedule();
  void onTimer();
  void flush();
  void received(ClientId id, const std::string& bytes);
  void deliverDue();
  void closeSession(ClientId id);
  /// Writes what is queued, then closes; nothing more is read.
  void markClosing(Session& session);
  /// Makes room for a new connection among those without HELLO (see
  /// maxUnauthenticated): closes the oldest of them when needed.
  void evictForNewcomer();
  double now() const;
  static constexpr double kClosingGrace = 1.0;  // [s] a closing client gets to take its last frames

  asio::io_context& io_;
  RobotServerConfig config_;
  RobotPort& robot_;
  RobotLink link_;
  asio::ip::tcp::acceptor acceptor_;
  asio::steady_timer timer_;
  asio::steady_timer acceptRetry_;  // after an accept error (out of descriptors): try again soon
  double lastAcceptErrorLog_ = -1e9;
  bool emulating_;  // frames pass the emulators: an active emulation, or a fade()
  // Sessions are owned here; asynchronous handlers hold only their id and
  // look the session up, so a closed session is never touched.
  std::map<ClientId, std::unique_ptr<Session>> sessions_;
  ClientId nextId_ = 1;
  uint16_t port_ = 0;
  double nextTelemetry_ = 0, nextHeartbeat_ = 0;
  uint64_t lastLaser_ = 0;
  std::string lastHealth_;  // announced divergence, so it is announced once
  SequenceStatus lastSequence_;  // announced sequence state
  RobotServerStats stats_;
  bool stopped_ = false, shuttingDown_ = false;
};

}  // namespace sp::net
