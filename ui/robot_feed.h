#pragma once
// Feeds: where the console's views get what they draw. A feed emits robot
// frames, laser scans, events and its own state; the 3D view, the plots and
// the event list connect to a FeedSwitch, not to the link. LiveLinkFeed is
// the robot link (through the console session, which maps joints, measures
// the real-time factor and logs); ReplayFeed is a session log at the replay
// cursor; GhostFeed is the predictive ghost. The switch passes on what its
// current feed emits, so the views draw a replay exactly as the live robot,
// and nothing the live link sends reaches them while a replay is shown.
//
// Thread: GUI thread only (construction, methods, every signal).

#include <QList>
#include <QObject>
#include <QString>

#include <cstdint>
#include <optional>
#include <vector>

#include "app/ghost/prediction_record.h"
#include "app/state/robot_frame.h"
#include "net/message.h"

namespace sp {

class ConsoleSession;
class Ghost;
class ReplayPanel;
class RobotConnection;
struct HeightGrid;
struct WorldModel;

/// A source of robot frames for the views.
class RobotFeed : public QObject {
  Q_OBJECT

 public:
  using QObject::QObject;
  /// What the operator calls this source ("live link", "replay", "ghost").
  virtual QString sourceName() const = 0;
  /// What exactly is shown, for the banner ("demo.splog"); sourceName() by default.
  virtual QString label() const { return sourceName(); }
  /// The session log the feed plays back ("" for a live or predicted feed).
  virtual QString logPath() const { return {}; }
  /// The world this feed's frames move in (drawn when the feed is shown),
  /// or null before it has one.
  virtual const WorldModel* shownWorld() const = 0;

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
  /// The feed's world changed (a new world opened, a log opened).
  void worldChanged(const sp::WorldModel& world);
  /// The ground changed under the feed's frames (a log's terrain edits at
  /// the cursor): the whole grid.
  void terrain(const sp::HeightGrid& grid);
};

/// The robot link as a feed. Telemetry and scans reach the console
/// session's tap on the link's worker (`session` must outlive the feed),
/// which turns them into frames in the model's joint order, logs them when
/// the robot is remote and anchors the ghost: the feed only passes the
/// frames on to be drawn.
class LiveLinkFeed : public RobotFeed {
  Q_OBJECT

 public:
  LiveLinkFeed(RobotConnection* connection, ConsoleSession* session, QObject* parent = nullptr);
  QString sourceName() const override { return tr("live link"); }
  const WorldModel* shownWorld() const override;
  /// The session's world changed: shown anew by whoever shows this feed.
  void announceWorld();

  /// The ghost's error for the frame last emitted (nullopt: it had shown
  /// nothing for that frame's time).
  const std::optional<GhostError>& lastPrediction() const { return lastPrediction_; }
  /// The latest telemetry as it arrived, if any.
  const std::optional<net::TelemetryMsg>& lastTelemetry() const { return lastTelemetry_; }
  int64_t telemetryCount() const { return telemetryCount_; }
  int64_t laserCount() const { return laserCount_; }
  /// Forgets the last telemetry (a new world is drawn).
  void clear() {
    lastTelemetry_.reset();
    lastPrediction_.reset();
  }

 private:
  /// An event for the list, logged (when the robot is remote) as `logKind`.
  void linkEvent(const QString& kind, const QString& text, const char* logKind = nullptr);

  ConsoleSession* session_;
  std::optional<net::TelemetryMsg> lastTelemetry_;
  std::optional<GhostError> lastPrediction_;
  int64_t telemetryCount_ = 0, laserCount_ = 0;
};

/// The predictive ghost (app/ghost/ghost.h) as a feed: poll() emits its
/// newest predicted frame and trail when they changed (the ghost runs on
/// threads of its own; the 3D view polls it once per drawn frame).
class GhostFeed : public RobotFeed {
  Q_OBJECT

 public:
  /// `session` must outlive the feed; its ghost may come and go.
  explicit GhostFeed(ConsoleSession* session, QObject* parent = nullptr);
  QString sourceName() const override { return tr("ghost"); }
  const WorldModel* shownWorld() const override;
  /// Emits `frame` (and `trail`) when the ghost predicted anew since the last poll.
  void poll();
  /// Forget what was polled (a new world, or the ghost shown again).
  void reset();

 signals:
  /// The ghost's predicted path (ground points) changed.
  void trail(const std::vector<sp::Vec3>& points);
  /// ... and its band: the outer region's radius at each point [m].
  void trailBand(const std::vector<double>& radii);
  /// The ghost's inner and outer regions about its base [m] (with each frame).
  void region(double inner, double outer);

 private:
  ConsoleSession* session_;
  int64_t version_ = -1;     // of the view last emitted
  double trailTime_ = -1;    // of the trail last emitted
};

/// Which feed the views show: the live link unless another feed (a replay)
/// is shown. The views connect to the switch once; it passes on what the
/// current feed emits and announces each switch.
class FeedSwitch : public QObject {
  Q_OBJECT

 public:
  /// `live` must outlive the switch.
  explicit FeedSwitch(RobotFeed* live, QObject* parent = nullptr);
  RobotFeed* live() const { return live_; }
  RobotFeed* current() const { return current_; }
  bool showingLive() const { return current_ == live_; }
  /// Shows `feed` (null = the live link) from now on.
  void show(RobotFeed* feed);

 signals:
  /// The current feed changed to `feed`: views redraw its world.
  void switched(sp::RobotFeed* feed);
  void frame(const sp::RobotFrame& frame);
  void laser(const sp::LaserFrame& scan);
  void terrain(const sp::HeightGrid& grid);
  void worldChanged(const sp::WorldModel& world);

 private:
  RobotFeed* live_;
  RobotFeed* current_;
  QList<QMetaObject::Connection> links_;
};

}  // namespace sp
