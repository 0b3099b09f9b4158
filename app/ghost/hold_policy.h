#pragma once
// When the ghost may hold its ghost.hold joints rigid (app/ghost/ghost.h):
// only while the robot keeps them still (within kStillBand of their newest
// position over the last kStillWindow of telemetry: legs flex by up to
// 0.018 rad over the test track's bumps, and their rates spike to 2 rad/s
// there, so rates cannot tell) and nothing sent moves them (a gait, a
// command to a held joint in effect or in flight). A hold whose weld is
// kReweld off the reported positions is welded anew.
//
// Thread: the ghost's anchor thread's own.

#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "app/state/robot_frame.h"
#include "app/ghost/in_flight.h"
#include "sim/rigid.h"
#include "sim/robot_model.h"

namespace sp {

/// What the anchor thread does with the next frame.
struct HoldDecision {
  bool hold = false;     ///< weld the held joints (else the full robot)
  bool rebuild = false;  ///< build the ghost's twin anew (first frame, switch, or a weld gone stale)
};

class HoldPolicy {
 public:
  static constexpr double kStillWindow = 1.0;  ///< [s] of robot time
  static constexpr double kStillBand = 0.03;   ///< [rad] or [m]
  static constexpr double kReweld = 0.05;      ///< [rad] or [m]

  /// `held`: the joints that may be held (sorted); `robot` outlives the policy.
  HoldPolicy(std::vector<int> held, const RobotModel& robot) : held_(std::move(held)), robot_(robot) {}
  const std::vector<int>& held() const { return held_; }
  /// Whether `command` moves a held joint (a gait walks the legs).
  bool movesHeld(const Command& command) const;
  /// The frame `frame` arrived with `effective` (in effect by its time)
  /// and `pending` (still in flight) commands; `weld` is the rigid robot
  /// in use (null: the full robot, or none when `!built`).
  HoldDecision decide(const RobotFrame& frame, const std::vector<SentCommand>& effective,
                      const std::vector<SentCommand>& pending, const RigidRobot* weld, bool built);
  /// Forgets what it saw (the robot was reset).
  void reset();

 private:
  std::vector<int> held_;
  const RobotModel& robot_;
  bool gaitOn_ = false;  // a gait is in effect
  std::deque<std::pair<double, std::vector<double>>> recent_;  // (robot time, joint positions), last kStillWindow
};

}  // namespace sp
