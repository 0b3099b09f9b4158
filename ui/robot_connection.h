#pragma once
// The console's end of the robot link, for Qt: a RobotClient whose callbacks
// (on the client's worker thread) are re-posted to the GUI thread and
// emitted as signals there, so widgets are only ever touched by the GUI
// thread (STYLE.md habit 6). Telemetry is handed on where it arrives, on
// the worker: to the sequence guard, then to the tap (the session's log,
// ghost and calibration: app/console/telemetry_tap.h); the window is sent
// the frame to draw.
//
// Thread: GUI thread only (construction, every method, every signal).

#include <QObject>
#include <QString>

#include <atomic>
#include <memory>

#include "app/console/telemetry_tap.h"
#include "app/rehearse/sequence_guard.h"
#include "net/robot_client.h"

namespace sp {

class RobotConnection : public QObject {
  Q_OBJECT

 public:
  explicit RobotConnection(QObject* parent = nullptr);
  /// Stops the client: no signal is emitted afterwards.
  ~RobotConnection() override;

  /// Where telemetry goes on the worker, before the window sees it (null:
  /// nowhere; the `telemetry` signal's frame then has no joints). Set it
  /// before open().
  void setTap(std::shared_ptr<TelemetryTap> tap) { tap_ = std::move(tap); }
  /// (Re)connects with `config`; drops a previous connection first.
  void open(const net::RobotClientConfig& config);
  /// Releases the lease if held, then closes the connection.
  void close();
  bool isOpen() const { return client_ != nullptr; }
  /// The configuration of the current or last connection.
  const net::RobotClientConfig& config() const { return config_; }

  void acquireLease();
  void releaseLease();
  /// The COMMAND's sequence number (the `reply` signal carries it), or 0
  /// when not open (then `reply` is emitted with status Failed at once).
  uint64_t send(const Command& command, const RobotModel* robot);
  void estop(const QString& reason);
  /// The guard of relayed sequences: fed on the client's worker thread,
  /// which sends ABORT itself when it trips (then guardTripped follows).
  const std::shared_ptr<SequenceGuard>& guard() const { return guard_; }
  /// SEQUENCE (the answer comes as sequenceState) and ABORT.
  void sendSequence(const net::SequenceMsg& message);
  void abortSequence(const QString& hash, const QString& reason);
  void rearm();
  /// Drops the connection as a lost link would (the client reconnects).
  void dropConnection();
  net::RobotClientStats stats() const;
  /// Telemetry frames not handed to the window because it had
  /// kTelemetryQueued waiting (the newest goes once it takes them).
  uint64_t telemetryShed() const { return telemetryShed_.load(); }

 signals:
  /// A telemetry frame, and what the tap made of it (the frame to draw,
  /// the ghost's error for it).
  void telemetry(const sp::net::TelemetryMsg& message, const sp::TelemetryTap::Tapped& tapped);
  void laser(const sp::net::LaserMsg& message);
  void reply(const sp::net::ReplyMsg& message);
  void event(const sp::net::EventMsg& message);
  void lease(const sp::net::LeaseStateMsg& message);
  void sequenceState(const sp::net::SequenceStateMsg& message);
  /// The guard tripped and ABORT went out (from the worker thread, already).
  void guardTripped(const QString& hash, const sp::GuardDeparture& departure);
  void connectionChanged(sp::net::ConnectionState state, const QString& detail);
  void linkError(const QString& reason);
  /// An ESTOP (a REARM) went out to the robot (not when not connected).
  void estopSent();
  void rearmSent();

 private:
  /// The guard tripped (on the worker thread): ABORT now, the window told after.
  void guardAbort(const GuardDeparture& departure);
  /// Runs `emitIt` on the GUI thread, unless this object is gone by then.
  template <typename F>
  void post(F&& emitIt);

  net::RobotClientConfig config_;
  std::unique_ptr<net::RobotClient> client_;
  std::atomic<uint64_t> generation_{0};  // of the client; post() reads it on the worker
  static constexpr int kTelemetryQueued = 50;  // a second at 50 Hz
  std::atomic<int> telemetryQueued_{0};   // telemetry posted to the window, not yet emitted
  std::atomic<uint64_t> telemetryShed_{0};  // ... not posted: the window was behind
  std::shared_ptr<SequenceGuard> guard_ = std::make_shared<SequenceGuard>();
  std::shared_ptr<TelemetryTap> tap_;  // read by the worker: set before open()
};

}  // namespace sp
