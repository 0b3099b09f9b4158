#pragma once
// Feeds: where the console's views get what they draw. A feed emits robot
// frames, laser scans, events and its own state; the 3D view, the plots and
// the event list connect to a feed, not to the link. LiveLinkFeed is the
// robot link (through the console session, which maps joints, measures the
// real-time factor and logs); a log player and the predictive ghost are
// feeds too, so the same views show a replay or a prediction.
//
// Thread: GUI thread only (construction, methods, every signal).

#include <QObject>
#include <QString>

#include <cstdint>
#include <optional>

#include "app/robot_frame.h"
#include "net/message.h"

namespace sp {

class ConsoleSession;
class RobotConnection;

/// A source of robot frames for the views.
class RobotFeed : public QObject {
  Q_OBJECT

 public:
  using QObject::QObject;
  /// What the operator calls this source ("live link", "replay", "ghost").
  virtual QString sourceName() const = 0;

 signals:
  /// A new state of the robot (joints in the drawn robot's model order).
  void frame(const sp::RobotFrame& frame);
  /// A new laser scan.
  void laser(const sp::LaserFrame& scan);
  /// Something the operator should see in the event list: `kind` is
  /// "link", "estop", "failsafe", "rearmed", "refused", "error" or "robot".
  void event(const QString& kind, const QString& text);
  /// The source's own state changed ("connected", "lost", "paused", ...).
  void stateChanged(const QString& state, const QString& detail);
};

/// The robot link as a feed. Telemetry and scans pass through the console
/// session (`session` must outlive the feed), which turns them into frames
/// in the model's joint order and logs them when the robot is remote.
class LiveLinkFeed : public RobotFeed {
  Q_OBJECT

 public:
  LiveLinkFeed(RobotConnection* connection, ConsoleSession* session, QObject* parent = nullptr);
  QString sourceName() const override { return tr("live link"); }

  /// The latest telemetry as it arrived, if any.
  const std::optional<net::TelemetryMsg>& lastTelemetry() const { return lastTelemetry_; }
  int64_t telemetryCount() const { return telemetryCount_; }
  int64_t laserCount() const { return laserCount_; }
  /// Forgets the last telemetry (a new world is drawn).
  void clear() { lastTelemetry_.reset(); }

 private:
  /// An event for the list, logged (when the robot is remote) as `logKind`.
  void linkEvent(const QString& kind, const QString& text, const char* logKind = nullptr);

  ConsoleSession* session_;
  std::optional<net::TelemetryMsg> lastTelemetry_;
  int64_t telemetryCount_ = 0, laserCount_ = 0;
};

}  // namespace sp
