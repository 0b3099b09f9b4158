#pragma once
// What the console knows of the robot link and shows around the 3D view,
// computed from what arrives (connection changes, the lease, telemetry
// frames, the robot's events) and what the operator opens (a replay): the
// latches, whether the data is stale, the terrain's edge, the banner's
// lines, the health text, which controls may act and why not. Plain values,
// no Qt: the window only draws what this says, and tests drive it without
// a window.
//
//   sp::ConsoleState state;
//   state.connection(net::ConnectionState::Ready, "");
//   state.lease(true);
//   state.frame(frame, wallSeconds, edge);   // every telemetry frame
//   state.tick(wallSeconds);                 // at the panel timer: staleness
//   if (!state.controlsRefusal().empty()) disable controls, say why;
//
// Live frames update the state even while a replay is shown: the replay
// changes what is shown and what the controls may do, never what is known
// of the live robot.
//
// Thread: its owner's only (the console's GUI thread).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "app/state/robot_frame.h"
#include "net/robot_client.h"

namespace sp {

/// How the health field looks.
enum class HealthLevel { Neutral, Good, Warning, Alarm };

/// The status bar's health field: what is shown, and how loudly.
struct HealthStatus {
  std::string text;     ///< "healthy", "no data", "diverged", ...
  HealthLevel level = HealthLevel::Neutral;
  std::string detail;   ///< the tooltip: the twin's own words, "" if none
};

/// What a frame changed, for the caller to act on (each bit is rare).
struct FrameChanges {
  bool latchedNow = false;   ///< an e-stop or failsafe latched: the controls go back to the robot's state
  bool latches = false;      ///< failsafe, e-stop or health changed
  bool banner = false;       ///< the banner's lines changed
  bool staleEnded = false;   ///< data flows again after being stale
};

class ConsoleState {
 public:
  struct Config {
    double staleAfter = 0.5;   ///< [s] without telemetry the data is stale (console.stale_after)
    double edgeWarning = 1.5;  ///< [m] within this of a heightfield's edge the banner warns
  };
  ConsoleState() = default;
  explicit ConsoleState(Config config) : config_(config) {}
  void setConfig(Config config) { config_ = config; }
  const Config& config() const { return config_; }

  // --- What arrives -------------------------------------------------------
  /// The link's state changed. Returns true when the lease was held and is
  /// lost with it (the controls go back to the robot's state).
  bool connection(net::ConnectionState state, std::string detail);
  /// The robot's LEASE_STATE: whether this console holds the lease. Returns
  /// true when it was held and is not any more.
  bool lease(bool yours);
  /// The robot said why it stopped (EVENT failsafe): the banner repeats it.
  void failsafeReason(std::string text);
  /// The robot runs other files than the console's ("" = the same).
  void filesMismatch(std::string text);
  /// The robot departs from its twin (app/ghost/ghost_region.h): the
  /// banner says so in `text` until it clears ("").
  void departure(std::string text);
  const std::string& departureText() const { return departure_; }
  /// The drawn terrain: a heightfield of `width` × `depth` [m], or a plane.
  void terrain(bool heightfield, double width, double depth);
  /// A live telemetry frame arrived at wall time `wall` [s]; `edge` is how
  /// far its base is inside the heightfield's edge [m] (nullopt on a plane).
  FrameChanges frame(const RobotFrame& frame, double wall, std::optional<double> edge);
  /// At wall time `wall` [s]: true when staleness began or ended.
  bool tick(double wall);
  /// The stand-in's twin runs at `factor` times real time, asked to run at
  /// `target` (0: not measured yet), at wall time `wall` [s]: below 0.8 ×
  /// the target for 3 s the banner says the twin cannot keep real time
  /// (the robot and its deadman run slow), until it is back above 0.9 ×.
  void realTime(double factor, double target, double wall);
  bool slowTwin() const { return slowTwin_; }
  /// A new session or world: no frame yet, no edge, nothing latched from
  /// the old robot's frames.
  void clearFrames();
  /// A replay (named `label`) is shown instead of the live robot, or ("") not.
  void replay(std::string label);
  /// This console sent an e-stop (a re-arm) at wall time `wall` [s] that
  /// lands on the robot in about `landsIn` [s] (half the round trip; < 0:
  /// not known yet): until a frame shows the latch on (off), or the link
  /// drops, the banner says it is in flight, counting down at tick(), then
  /// that it should have landed and the robot's report is awaited; the
  /// controls wait for it.
  void estopSent(double landsIn, double wall);
  void rearmSent(double landsIn, double wall);
  /// What the operator is told of an e-stop pressed now: "E-STOP sent"
  /// when connected, else that it is not sent and when it will be
  /// (`queued`: the client sends it once the robot welcomes it again).
  std::string estopPressedText(bool queued) const;
  bool estopInFlight() const { return estopInFlight_; }
  bool rearmInFlight() const { return rearmInFlight_; }

  // --- What the console shows and allows ----------------------------------
  net::ConnectionState connectionState() const { return connection_; }
  const std::string& connectionDetail() const { return connectionDetail_; }
  bool connected() const { return connection_ == net::ConnectionState::Ready; }
  bool leaseHeld() const { return lease_; }
  bool failsafe() const { return failsafe_; }
  bool estop() const { return estop_; }
  bool latched() const { return failsafe_ || estop_; }
  /// The twin's divergence report, "" while healthy.
  const std::string& healthReport() const { return health_; }
  bool haveFrame() const { return haveFrame_; }
  /// Where the robot is by its newest live frame: base x, y [m] and
  /// heading [rad]; its ground speed [m/s] (the reported twist, else from
  /// the last two frames) and the distance driven on the ground [m] since
  /// this session's first frame (clearFrames() starts it over; a leap of
  /// more than 1 m between two frames, a reset, is not driving).
  struct Odometry {
    double x = 0, y = 0, heading = 0, speed = 0, distance = 0;
  };
  const Odometry& odometry() const { return odometry_; }
  /// "x 1.23 m  y -0.40 m  heading 12.3°" and "0.48 m/s, 12.6 m driven", or "" before a frame.
  std::string poseText() const;
  std::string motionText() const;
  /// No live telemetry for config().staleAfter while connected.
  bool stale() const { return stale_; }
  /// [s] since the last live frame (0 before the first).
  double dataAge(double wall) const { return haveFrame_ ? wall - lastFrameWall_ : 0; }
  /// The line over the 3D view while the data is stale or the link is down
  /// with a robot drawn, "" when not shown (fresh data, nothing drawn yet,
  /// or a replay shown).
  std::string staleText(double wall) const;
  const std::optional<double>& edgeDistance() const { return edge_; }
  bool replaying() const { return !replay_.empty(); }
  const std::string& replayLabel() const { return replay_; }

  /// The banner over the 3D view, a line each; empty when nothing is wrong.
  std::vector<std::string> bannerLines() const;
  /// Whether a line of the banner is an alarm (a latch, an e-stop in
  /// flight, a diverged twin, the robot off the terrain, the link down),
  /// drawn in the latch's red; else its lines are warnings (near an edge,
  /// other files), drawn in amber.
  bool bannerAlarm() const;
  /// "" when the drive controls and keys may command the live robot now,
  /// else why not, for the operator (a replay shown comes first).
  std::string controlsRefusal() const;
  /// The status bar's health field for what is shown.
  HealthStatus health() const;
  // Robot menu items.
  bool canReconnect() const { return connection_ == net::ConnectionState::Stopped; }
  bool canDisconnect() const { return connection_ != net::ConnectionState::Stopped; }
  bool canTakeControl() const { return connected() && !lease_; }
  bool canReleaseControl() const { return connected() && lease_; }
  bool canRearm() const { return connected() && latched(); }

  /// Counts changes of anything bannerLines(), controlsRefusal(), health()
  /// or the menu items depend on: a view redraws when it moves.
  uint64_t revision() const { return revision_; }

 private:
  bool nearEdge() const { return edge_ && *edge_ < config_.edgeWarning; }

  Config config_;
  net::ConnectionState connection_ = net::ConnectionState::Stopped;
  std::string connectionDetail_;
  bool lease_ = false;
  bool failsafe_ = false, estop_ = false;
  bool estopInFlight_ = false, rearmInFlight_ = false;
  double estopLandsIn_ = 0, rearmLandsIn_ = 0;  // [s] as said when sent (< 0: not known)
  double estopSentAt_ = 0, rearmSentAt_ = 0;    // [s] wall time sent
  double now_ = 0;                              // [s] wall time of the last frame or tick
  std::string inFlightText(const char* what, double landsIn, double sentAt) const;
  int64_t shownCountdown_ = -1;  // tenths of a second the banner shows (moves the revision)
  std::string health_;
  std::string failsafeReason_;
  std::string filesMismatch_;
  std::string departure_;
  bool heightfield_ = false;
  double terrainWidth_ = 0, terrainDepth_ = 0;
  std::optional<double> edge_;
  double shownEdge_ = 0;  // the distance the banner shows (moves in 0.1 m steps)
  Odometry odometry_;
  bool slowTwin_ = false;
  double slowSince_ = -1, shownFactor_ = 0, targetFactor_ = 1;
  double odometryTime_ = 0;  // [s] robot time of the frame odometry_ is from
  bool haveFrame_ = false, stale_ = false;
  double lastFrameWall_ = 0;
  std::string replay_;
  uint64_t revision_ = 0;
};

}  // namespace sp
