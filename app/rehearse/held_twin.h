#pragma once
// The rehearsal's twin: the robot with the joints nothing is moving welded
// rigid (sim/rigid.h: fewer bodies and constraint rows, the same mass and
// centre of mass). A joint a command moves is freed, with every ancestor
// whose subtree holds it, at the step boundary where that command is due,
// and welded again once it and all freed with it have been still (within
// kBand over kStill) and touched nothing, their servos holding a position.
// So a sequence that moves the arms for 3 s of 60 runs welded for the other
// 57 (issue 32; the ghost does the same from telemetry: app/ghost/hold_policy.h).
// The fast profile welds the legs' hips and knees too (`alsoHeld`), the
// wheels below them turning; a command to one or a gait frees them.
//
// A switch builds the other form of the twin and carries the run across at
// the step boundary: the links from the base's motion and the joints', the
// dynamic objects' bodies as they are, the controllers (a welded joint's
// servo state is kept for when it is freed again), the sensors' state, the
// step count and the random states. Welding drops the freed joints' rates
// (under kBand / kStill by then); nothing else is lost.
//
//   HeldTwin twin(model, params, acting, true);
//   if (std::string why = twin.start(state); !why.empty()) ...
//   twin.setMonitor(...);  twin.setSwitchHook([&](const World& w) { rules.rebind(w.robotModel(0)); });
//   twin.advanceTo(total);
//
// Thread: the caller's; not shared.

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/state/rehearsal_start.h"
#include "sim/math.h"
#include "sim/rigid.h"
#include "sim/runner.h"
#include "sim/world.h"

namespace sp {

class HeldTwin {
 public:
  static constexpr double kCheck = 0.1;   ///< [s] how often freed joints are looked at
  static constexpr double kStill = 1.0;   ///< [s] still (and untouched) this long before welded again
  static constexpr double kBand = 0.002;  ///< [rad] or [m]: what still means

  /// `model`'s robots[0] is the full robot; `acting`: the commands at the
  /// times the twin acts on them (non-decreasing). `hold` false: the full
  /// robot throughout. `alsoHeld`: joints welded too while nothing moves
  /// them though the drive's joints below them turn (the fast profile's
  /// legs, rehearsal.fast_hold; a gait frees them).
  HeldTwin(WorldModel model, SimParams params, std::vector<TimedCommand> acting, bool hold,
           std::vector<int> alsoHeld = {});

  /// Builds the twin at `start` (the full robot's joints), its controllers
  /// holding that pose (placeRobot). "" or why not (a sentence).
  std::string start(const RehearsalStart& start);

  void setMonitor(Runner::Monitor monitor) { monitor_ = std::move(monitor); }
  void setSubmitHook(Runner::SubmitHook hook) { submitHook_ = std::move(hook); }
  /// Called after each switch with the twin's new form.
  void setSwitchHook(std::function<void(const World&)> hook) { switchHook_ = std::move(hook); }

  /// Steps to World::stepCount() == `step` as Runner::advanceTo does,
  /// switching forms on the way.
  RunOutcome advanceTo(int64_t step);

  const World& world() const { return *world_; }
  /// The welded form the world runs, or null for the full robot.
  const RigidRobot* rigid() const { return rigid_ ? &*rigid_ : nullptr; }
  /// The full robot's joints welded now (sorted).
  const std::vector<int>& held() const { return held_; }
  /// Switches made so far.
  int switches() const { return switches_; }
  /// How many of the full robot's joints were welded all along.
  int heldThroughout() const { return static_cast<int>(std::count(always_.begin(), always_.end(), true)); }

 private:
  std::vector<int> heldFor(const std::vector<bool>& freed) const;
  void markFreed(size_t command, std::vector<bool>& freed) const;
  bool movesWelded(size_t command) const;
  // Builds the form that welds `held` and carries the run into it; false
  // (and the run stays in its form) if it cannot.
  bool switchTo(const std::vector<int>& held);
  std::string carryInto(World& to, const RigidRobot* toRigid);
  // The monitor run after each step; `anyFreed`: some joints are freed in
  // this stretch (freed_ changes only between stretches), so contacts count.
  Runner::Monitor watch(bool anyFreed);
  void lookForRest();
  std::vector<double> fullPositions() const;

  WorldModel model_;
  SimParams params_;
  std::vector<TimedCommand> acting_;
  std::vector<int64_t> dueAt_;   // per acting command: its step boundary
  std::vector<int> moves_;       // per acting command: the full robot's joint it moves, kNone, or kLegs (a gait)
  static constexpr int kNone = -1, kLegs = -2;
  bool hold_;
  std::vector<bool> drive_;      // per full joint: the drive's (never welded)
  std::vector<int> alsoHeld_;    // sorted
  std::vector<int> legs_;        // alsoHeld_ joints above a drive joint: what a gait moves
  std::vector<bool> freed_;      // per full joint: a command freed it and it has not come to rest
  std::vector<bool> always_;     // per full joint: welded in every form so far
  std::vector<int> held_;
  std::optional<RigidRobot> rigid_;
  std::unique_ptr<World> world_;
  std::unique_ptr<Runner> runner_;
  std::map<std::string, ActuatorState> welded_;  // servo states of welded actuators, by name
  std::vector<std::pair<int64_t, std::vector<double>>> recent_;  // (step, full joints) at the checks
  std::vector<int64_t> touched_;  // per full link: the last step it touched anything
  Runner::Monitor monitor_;
  Runner::SubmitHook submitHook_;
  std::function<void(const World&)> switchHook_;
  int switches_ = 0;
};

}  // namespace sp
