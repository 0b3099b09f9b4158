#pragma once
// The console's client of the robot link (docs/protocol.md): one TCP
// connection to the robot or to `simpartner-robot`, kept up by reconnecting,
// with the protocol's housekeeping done for the caller: HELLO after every
// connect, keep-alives while holding the lease, heartbeats both ways, and
// link statistics (round-trip time, telemetry rate, lost telemetry frames).
//
// Threads. The client owns a worker thread running its own asio::io_context
// (start() creates it, stop() joins it). Every public method may be called
// from any thread: it posts its work into the io_context and returns at once
// (stats() copies under a mutex). All callbacks run on the worker thread,
// one at a time, in the order the messages arrived: they must return quickly
// and must not touch widgets. A Qt console re-posts what it needs to the GUI
// thread, e.g.
//
//   callbacks.telemetry = [console](const sp::net::TelemetryMsg& t) {
//     QMetaObject::invokeMethod(console, [console, t] { console->showTelemetry(t); },
//                               Qt::QueuedConnection);
//   };
//
// Asio does not appear in this header (the state lives behind a pointer), so
// the console's Qt code includes it without Asio's headers.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "net/link_check.h"
#include "net/link_emulator.h"
#include "net/message.h"
#include "sim/command.h"

namespace sp::net {

/// Where the client connects and how it behaves. Defaults give a console
/// client of a robot on this machine at the protocol's default port.
struct RobotClientConfig {
  std::string host = "127.0.0.1";  ///< name or address of the robot
  uint16_t port = 47800;           ///< the robot's `port.robot`
  std::string name = "console";    ///< HELLO `name`: shown to other clients as the lease holder
  /// The robot's shared secret, >= 32 hex digits: keys HELLO's `proof` over
  /// the robot's CHALLENGE; never sent.
  std::string token;
  Role role = Role::Control;       ///< HELLO `role`: Monitor never asks for the lease

  double reconnectMin = 0.2;  ///< [s] wait before the first reconnect after a drop or failed connect
  double reconnectMax = 2.0;  ///< [s] the wait doubles up to this after each failure
  /// [s] LEASE_KEEPALIVE period while holding the lease; shortened to a
  /// quarter of the deadman the robot announces in WELCOME when that is less.
  double keepaliveInterval = 0.05;
  double heartbeatInterval = 0.2;   ///< [s] period of the client's own HEARTBEATs (round-trip time)
  uint64_t commandExpiryMs = 500;   ///< [ms] COMMAND `expires_ms` when a send call passes 0
  /// [s] a command without REPLY after its expiry plus max(this, 3 x RTT) is
  /// answered locally (status Failed, see sendCommand()).
  double replyGrace = 2.0;
  /// [s] nothing received from the robot for this long (telemetry flows at
  /// tens of Hz, heartbeats every few hundred ms) => the connection is taken
  /// for dead, closed and made again. Must exceed the round trip of the
  /// slowest emulated link (a WELCOME answers the HELLO one round trip later).
  double silenceTimeout = 5.0;
  /// After a reconnect, ask for the lease again if it was held when the
  /// connection dropped. Off by default: the operator takes control again
  /// deliberately. With it on and a reconnect quicker than the robot's
  /// deadman (reconnectMin below 0.2 s plus a round trip), the new lease can
  /// come before the failsafe fires, and the robot carries on; once fired,
  /// the failsafe stays latched until rearm() whatever this says.
  bool reacquireLease = false;
  /// [s] a connection not welcomed by then (no WELCOME after the CHALLENGE
  /// was answered, or no CHALLENGE at all) is given up and made again
  /// (`link.hello_timeout`).
  double helloTimeout = 5.0;
  /// What TELEMETRY is checked against before any of it is used (net/
  /// link_check.h): a console gives its robot file's joints and limits.
  TelemetryBounds bounds;
  /// [bytes] frames queued for a robot that does not read them at most;
  /// beyond it the connection is dropped, as the robot drops a blind client.
  size_t maxQueuedBytes = size_t{1} << 20;
  /// [1/s] the robot's EVENTs (and ERRORs) passed on at most this fast, a
  /// second's worth at once; the rest are counted and said in a summary.
  double eventRate = 20;
  /// Emulated delay, jitter and loss for the frames this client sends
  /// (inactive by default). Frames still on the emulated link when the
  /// connection drops are lost with it.
  LinkEmulatorConfig emulation;
};

/// The client's connection, as reported to the `connection` callback.
enum class ConnectionState {
  Stopped,         ///< not started, or stop() called
  Connecting,      ///< resolving the host and connecting
  Authenticating,  ///< connected, HELLO sent, waiting for WELCOME
  Ready,           ///< WELCOME received: telemetry flows, the lease may be taken
  Waiting,         ///< the connection dropped or failed; reconnecting after the backoff
  Refused,         ///< the robot refused the HELLO (wrong token): no more attempts until stop() and start()
};
const char* toString(ConnectionState state);  ///< "stopped", "connecting", ...

/// Link statistics, a copy taken by RobotClient::stats(). Counters run over
/// the client's life (across reconnects) unless said otherwise.
struct RobotClientStats {
  ConnectionState state = ConnectionState::Stopped;
  bool connected = false;  ///< Ready: WELCOME received on the current connection
  bool leaseHeld = false;  ///< the last LEASE_STATE on this connection said `yours=1`
  std::string robot;       ///< the robot's name from WELCOME
  double rttMs = 0;        ///< [ms] last round trip of our heartbeats (0 before the first echo)
  double rttMeanMs = 0;    ///< [ms] smoothed round trip (moving average, gain 1/8, as TCP's SRTT)
  double rttMaxMs = 0;     ///< [ms] largest round trip seen
  uint64_t rttSamples = 0;            ///< heartbeat echoes received
  double robotRttMs = 0;              ///< [ms] round trip as the robot measures it (TELEMETRY `rtt_ms`)
  double telemetryRateAnnounced = 0;  ///< [Hz] WELCOME `telemetry_rate`
  double robotDeadman = 0;            ///< [s] WELCOME `deadman`: the robot's deadman (0 = not announced)
  std::string robotWorldHash, robotRobotHash;  ///< WELCOME `world_hash`, `robot_hash` ("" = not announced)
  std::string robotCapabilities;  ///< WELCOME `capabilities` ("" = none)
  double telemetryRateHz = 0;         ///< [Hz] TELEMETRY frames received per second, over the last ~1 s
  uint64_t telemetryFrames = 0;       ///< TELEMETRY frames received
  uint64_t telemetryLost = 0;         ///< frames missing from gaps in TELEMETRY `seq` (within each connection)
  uint64_t robotDropped = 0;          ///< TELEMETRY `lost` of the last frame: the robot's count for this connection
  uint64_t reconnects = 0;            ///< connections established after the first
  uint64_t framesSent = 0;            ///< frames written to the socket
  uint64_t framesReceived = 0;        ///< frames decoded from the socket
  uint64_t emulatorDropped = 0;       ///< outgoing frames the link emulation dropped
  uint64_t commandsSent = 0;          ///< COMMANDs written (or handed to the emulated link)
  uint64_t repliesReceived = 0;       ///< REPLYs from the robot that matched a pending command
  uint64_t refused = 0;   ///< messages refused by the checks (net/link_check.h) or sent before WELCOME
  uint64_t shed = 0;      ///< TELEMETRY, LASER and EVENTs beyond their rates, not passed on
  uint64_t renumbered = 0;  ///< TELEMETRY `seq` jumps too large to be loss (not counted in telemetryLost)
  std::string lastError;              ///< the last connection problem or robot ERROR, for the operator
  /// [ms] the spread of the one-way delay (arrival minus robot time, its
  /// trend removed: delaySpread()) of the telemetry over the first
  /// kLinkCheckSeconds of this connection: as
  /// much as the link's jitter can stretch a gap between two frames sent
  /// at a steady rate (our keep-alives too, the other way); 0 before.
  double delaySpreadMs = 0;
  /// "" or, once per connection after kLinkCheckSeconds, why this link
  /// cannot carry the robot's deadman and the setting that would
  /// (linkAdvice); also sent as a `client: ` notice through `error`.
  std::string linkWarning;
};

/// [s] the keep-alive period never goes below this, whatever the robot's
/// deadman asks (WELCOME `deadman` has a floor too: link_check.h).
constexpr double kMinKeepalive = 0.005;
/// [s] how often the refusals and what was shed are summed up (`error`).
constexpr double kRefusalReport = 5.0;

/// [s] telemetry looked at after WELCOME before the link is judged.
constexpr double kLinkCheckSeconds = 2.0;
/// [s] how much a link's one-way delay varies, from telemetry frames'
/// (arrival wall time, robot time) [s]: the peak-to-peak of arrival minus
/// robot time about its least-squares line. A trend is not the link's
/// jitter: a robot whose clock runs slow (a twin below real time on a
/// loaded machine, issue 59: "delay varies by 336 ms" on loopback) or a
/// delay that builds up slowly stretches no gap between two keep-alives.
/// 0 for fewer than 3 frames.
double delaySpread(const std::vector<std::pair<double, double>>& frames);

/// "" when keep-alives every `keepalive` [s], on a link whose one-way delay
/// was seen to vary by `stretch` [s] (1.5 times that taken as its worst),
/// stay within the robot's `deadman` [s]; else what will happen and the
/// setting to use (`link.deadman` at 1.5 times what the gaps need, rounded
/// up to 50 ms). `deadman` 0 (not announced): "".
std::string linkAdvice(double deadman, double keepalive, double stretch);

/// Callbacks of a RobotClient, each optional (empty = not called). All run
/// on the client's worker thread (see the file comment); a callback must
/// not call stop() and then wait for it (stop() from a callback only
/// requests the stop).
struct RobotClientCallbacks {
  std::function<void(const TelemetryMsg&)> telemetry;
  /// A TELEMETRY refused by the checks (net/link_check.h), with why: a
  /// guard that cannot judge the robot's state stops what it guards.
  std::function<void(const Refusal&)> refusedTelemetry;
  std::function<void(const LaserMsg&)> laser;
  /// Exactly one per sendCommand(): the robot's REPLY, or a local one with
  /// status Failed when the command could not be sent, the connection
  /// dropped before the answer, or no answer came in time (see sendCommand()).
  std::function<void(const ReplyMsg&)> reply;
  std::function<void(const EventMsg&)> event;
  /// Every LEASE_STATE from the robot, and a local {"", false} when the
  /// connection drops while holding the lease.
  std::function<void(const LeaseStateMsg&)> lease;
  /// Each change of state, with a detail for the operator (the robot's name
  /// when Ready, the reason when Waiting or Refused).
  std::function<void(ConnectionState, const std::string& detail)> connection;
  /// ERRORs from the robot (a message of ours it refused), and local notices
  /// prefixed `client: ` (an ESTOP or REARM that could not be sent).
  std::function<void(const ErrorMsg&)> error;
  /// Every SEQUENCE_STATE: a sequence accepted, refused, running (each
  /// command applied), done or aborted.
  std::function<void(const SequenceStateMsg&)> sequence;
  /// The robot's LIMITS (after WELCOME on each connection).
  std::function<void(const LimitsMsg&)> limits;
  /// Each heartbeat round trip [ms], as measured (for plots and benchmarks).
  std::function<void(double rttMs)> rtt;
};

/// An asynchronous, reconnecting client of the robot link. Not copyable.
/// See the file comment for threads; every method below may be called from
/// any thread, including from the callbacks, unless it says otherwise.
class RobotClient {
 public:
  RobotClient(RobotClientConfig config, RobotClientCallbacks callbacks);
  /// Calls stop().
  ~RobotClient();
  RobotClient(const RobotClient&) = delete;
  RobotClient& operator=(const RobotClient&) = delete;

  /// Starts the worker thread and connects; after a drop or a failed
  /// connect it reconnects after 0.2 s, doubling to 2 s (the config's
  /// reconnectMin/Max), and sends HELLO again. Does nothing if running.
  /// May be called again after stop(). Not from a callback.
  void start();
  /// Closes the connection, after writing what is already queued (at most
  /// 100 ms; frames held by the link emulation are dropped), and joins the
  /// worker thread; no callback runs after stop() returns. Does NOT release
  /// the lease: to the robot this is a lost operator, its deadman stops the
  /// robot and latches the failsafe. Call releaseLease() first for a clean
  /// exit. Called from a callback, it only requests the stop (the thread is
  /// joined by the next start() or the destructor).
  void stop();

  /// Asks for the control lease (LEASE_ACQUIRE) now, or as soon as the
  /// robot has welcomed the connection. While the robot says the lease is
  /// ours, the client sends LEASE_KEEPALIVE every keepaliveInterval.
  void acquireLease();
  /// Gives the lease up (LEASE_RELEASE; the robot stops, without latching)
  /// and stops asking for it after reconnects.
  void releaseLease();

  /// Sends `command` as a COMMAND expiring `expiresMs` [ms] after sending
  /// (0: the config's commandExpiryMs) and returns its sequence number, which
  /// increases over the client's life. The REPLY comes through the `reply`
  /// callback with this `seq`. If the client is not Ready the command is not
  /// sent and the reply is local: Failed, `client: not connected, not sent`
  /// (Invalid, `client: ` and the encoder's error, for a text that cannot be
  /// sent at all: empty or with a line feed).
  /// If the connection drops before the reply: Failed, `client: connection
  /// lost before the reply (the robot may have applied it)`. If no reply
  /// comes within the expiry plus max(replyGrace, 3 x RTT): Failed, `client:
  /// no reply within N ms`; a REPLY arriving after that is dropped.
  /// `robot` (may be null, must outlive the call) tells slider joints from
  /// hinges, so their values travel in metres rather than degrees.
  uint64_t sendCommand(const Command& command, uint64_t expiresMs = 0, const RobotModel* robot = nullptr);
  /// As sendCommand(), with the command in sequence-file syntax (`drive 0.5
  /// 0`, `stop`); the robot parses it and answers `invalid` if it cannot.
  uint64_t sendCommandText(std::string text, uint64_t expiresMs = 0);

  /// ESTOP with an optional reason. If not Ready, it is sent as soon as the
  /// next connection is welcomed (and `error` reports the delay).
  void estop(std::string reason = {});
  /// SEQUENCE: a rehearsed sequence to run on board (only the lease holder's
  /// is taken); the answer comes as SEQUENCE_STATE. If not Ready it is not
  /// sent; `error` says so.
  void sendSequence(SequenceMsg sequence);
  /// ABORT of the running sequence `hash`: the robot stops. If not Ready
  /// it is not sent; `error` says so (an e-stop is the way then).
  void abortSequence(std::string hash, std::string reason = {});
  /// REARM: clears a latched failsafe or e-stop (the robot accepts it from
  /// the lease holder, or from a controlling client when nobody holds the
  /// lease). If not Ready it is not sent; `error` says so.
  void rearm();

  /// Closes the current connection abruptly, as a lost link would (nothing
  /// queued is flushed); the client then reconnects after the backoff. For
  /// tests and for a console's "reconnect" button.
  void dropConnection();
  /// Replaces the link emulation of outgoing frames (applies to frames sent
  /// from now on).
  void setEmulation(const LinkEmulatorConfig& emulation);

  /// A copy of the statistics. Thread-safe (a short lock).
  RobotClientStats stats() const;
  /// The robot's last LIMITS; nullopt before the first. Thread-safe.
  std::optional<LimitsMsg> limits() const;
  /// The configuration given to the constructor.
  const RobotClientConfig& config() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sp::net
