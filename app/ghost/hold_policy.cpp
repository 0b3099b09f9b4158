#include "app/ghost/hold_policy.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <variant>

#include "sim/params.h"

namespace sp {

bool HoldPolicy::movesHeld(const Command& command) const {
  const auto held = [&](const std::string& joint) {
    return std::binary_search(held_.begin(), held_.end(), robot_.findJoint(joint));
  };
  return std::visit(
      [&](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, JointVelocityCmd> || std::is_same_v<T, JointTargetCmd> ||
                      std::is_same_v<T, JointTorqueCmd> || std::is_same_v<T, JointModeCmd>)
          return held(c.joint);
        else if constexpr (std::is_same_v<T, GaitCmd>)
          return c.gait != Gait::Off;  // a gait walks the legs
        else
          return false;
      },
      command);
}

HoldDecision HoldPolicy::decide(const RobotFrame& frame, const std::vector<SentCommand>& effective,
                                const std::vector<SentCommand>& pending, const RigidRobot* weld, bool built) {
  const bool latched = frame.estop || frame.failsafe;
  for (const SentCommand& c : effective)
    if (std::holds_alternative<GaitCmd>(c.command)) gaitOn_ = std::get<GaitCmd>(c.command).gait != Gait::Off;
    else if (std::holds_alternative<DriveCmd>(c.command) || std::holds_alternative<TurnCmd>(c.command) ||
             std::holds_alternative<WheelsCmd>(c.command) || std::holds_alternative<StopCmd>(c.command))
      gaitOn_ = false;
  if (latched) gaitOn_ = false;  // the robot stops whatever it was doing
  while (!recent_.empty() && recent_.front().first < frame.time - kStillWindow) recent_.pop_front();
  recent_.emplace_back(frame.time, frame.jointPositions);
  // Holding starts after a still window (or on the first frame); it goes on while they stay still.
  bool still = !built || weld || frame.time - recent_.front().first >= kStillWindow - 0.05;
  for (const auto& [time, q] : recent_)
    for (int j : held_)
      still = still && std::abs(q[static_cast<size_t>(j)] - frame.jointPositions[static_cast<size_t>(j)]) <= kStillBand;
  HoldDecision d;
  d.hold = !held_.empty() && still && !gaitOn_;
  // A latched robot refuses what it is sent: nothing in flight moves it.
  for (const SentCommand& c : pending) d.hold = d.hold && (latched || !movesHeld(c.command));
  for (const SentCommand& c : effective) d.hold = d.hold && (latched || !movesHeld(c.command));
  d.rebuild = !built || d.hold != (weld != nullptr);
  if (!d.rebuild && weld)
    for (int j : held_)
      d.rebuild = d.rebuild || std::abs(weld->heldPositions[static_cast<size_t>(j)] -
                                        frame.jointPositions[static_cast<size_t>(j)]) > kReweld;
  return d;
}

void HoldPolicy::reset() {
  recent_.clear();
  gaitOn_ = false;
}

}  // namespace sp
