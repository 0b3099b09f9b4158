#pragma once
// The ghost's estimate of the robot's clock (app/ghost/ghost.h, "Time"):
//   robot_now(w) = w + offset,  offset = max over the last 2 s of
//   (T - arrival wall time)
// (the least-delayed frame bounds it best, as NTP's filters do), and the
// time the ghost shows, ghost(w) = w + offset + round trip: the robot's now
// plus the uplink's one-way delay, when a command sent now arrives.
//
// Thread: a plain value; its owner guards it (the Ghost's mutex).

#include <deque>
#include <utility>

namespace sp {

class GhostClock {
 public:
  static constexpr double kOffsetWindow = 2;  ///< [s] of arrivals the offset is the max over

  /// A frame of robot time `robotTime` [s] arrived at wall time `wall` [s]
  /// over a link of round trip `roundTrip` [s] (not finite or <= 0: none
  /// known). Returns true when the robot's clock went back (a reset): the
  /// estimate starts over from this frame.
  bool frame(double robotTime, double wall, double roundTrip);
  /// Robot time the ghost shows at wall time `wall`: ghost(wall), or the
  /// newest frame's time before a frame came.
  double ghostTime(double wall) const { return haveClock_ ? wall + offset_ + roundTrip_ : newest_; }
  /// The newest frame's robot time.
  double newest() const { return newest_; }
  double offset() const { return offset_; }
  double roundTrip() const { return roundTrip_; }
  /// [s] the standard deviation of (robot time - arrival) over the offset
  /// window: the downlink's jitter, which a command's arrival shares
  /// (ghost_region.h); 0 before two frames.
  double spread() const;

 private:
  std::deque<std::pair<double, double>> offsets_;  // (arrival, T - arrival), last kOffsetWindow
  double offset_ = 0, roundTrip_ = 0, newest_ = 0;
  bool haveClock_ = false;
};

}  // namespace sp
