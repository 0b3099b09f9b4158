#pragma once
// Keeps the console's state (app/console/console_state.h) up to date from
// what the link reports: the connection, the lease, the robot's events and
// every live telemetry frame, whatever the views show. The window and the
// jobs read the state; they learn of changes through `changed` and of a
// robot that stopped on its own through `robotStopped`.
//
// Thread: GUI thread only (the link's signals arrive queued).

#include <QElapsedTimer>
#include <QObject>
#include <QString>

#include "app/console/console_state.h"
#include "sim/math.h"

namespace sp {

class ConsoleSession;
class LiveLinkFeed;
class RobotConnection;

class ConsoleMonitor : public QObject {
  Q_OBJECT

 public:
  /// `connection`, `live` and `session` must outlive the monitor.
  ConsoleMonitor(RobotConnection* connection, LiveLinkFeed* live, ConsoleSession* session, QObject* parent = nullptr);
  const ConsoleState& state() const { return state_; }
  /// For what only the window knows: the terrain drawn, a replay shown, a new world.
  ConsoleState& state() { return state_; }
  /// [s] on the monotonic clock the state's times are measured on.
  double wallSeconds() const { return static_cast<double>(clock_.nsecsElapsed()) * 1e-9; }
  /// Checks for stale data now (the window's panel timer calls it).
  void tick();
  /// Emits `changed` if the state changed since the last call.
  void notify();

 signals:
  /// The state changed (its revision moved).
  void changed();
  /// The robot stopped on its own (a latch came on, the lease was lost, a
  /// failsafe, e-stop or re-arm event): controls go back to its state.
  void robotStopped();
  /// The failsafe or e-stop latch changed.
  void latchesChanged(bool failsafe, bool estop);
  /// The robot runs other files than the console's (said once per connection).
  void filesDiffer(const QString& text);
  /// The robot began to depart from its twin at `where` (its base), for
  /// the operator in `text` (the banner says it too, until it clears).
  void departure(const sp::Vec3& where, const QString& text);

 private:
  ConsoleSession* session_;
  RobotConnection* connection_;
  ConsoleState state_;
  QElapsedTimer clock_;
  uint64_t notified_ = ~uint64_t{0};
  size_t departuresSeen_ = 0;  // of the ghost's departures, the ones announced
  /// The ghost's departures into the state (the banner) and `departure`.
  void watchDepartures();
};

}  // namespace sp
