#pragma once
// Leg gaits of a wheel-legged robot with an articulated <drive> (WorkPartner):
// controllers that turn a gait mode into hip targets and wheel modes each
// step. Timing and amplitudes come from the parameters file (gait.* keys);
// ODE-free, so they can be tested alone.
//
// Leg order everywhere: front-left, front-right, rear-left, rear-right.
// Hip angles are about the stance pose; a positive hip angle swings the leg
// backwards (the wheel moves to -x relative to the hip).

#include <array>
#include <cstdint>
#include <optional>

#include "sim/command.h"
#include "sim/params.h"

namespace sp {

struct RobotModel;

/// The hip, knee and wheel joints of each leg, found from the <drive>
/// wheels: wheel joint -> its parent link's joint (knee) -> its parent's (hip).
struct LegJoints {
  int hip = -1, knee = -1, wheel = -1;
};
/// nullopt if the robot has no <drive> or a wheel does not hang off a
/// hinge-hinge leg.
std::optional<std::array<LegJoints, 4>> findLegs(const RobotModel& robot);

/// Where a gait is in its cycle. Plain value (part of snapshots).
struct GaitState {
  Gait gait = Gait::Off;
  int phase = 0;            ///< index into the gait's phase list
  int64_t phaseStart = 0;   ///< step at which the phase began
  friend bool operator==(const GaitState&, const GaitState&) = default;
};

/// What one leg should do this step.
struct LegCommand {
  double hip = 0;  ///< hip target [rad] about the stance pose
  enum class Wheel { Brake, Free, Drive } wheel = Wheel::Brake;
  double wheelSpeed = 0;  ///< [rad/s] when Drive
};

/// Advances the gait to `step` and returns the legs' commands. `legLength`
/// is hip-to-wheel-centre [m], `wheelRadius` [m], `dt` the step [s].
std::array<LegCommand, 4> gaitStep(const SimParams& params, GaitState& state, int64_t step, double dt,
                                   double legLength, double wheelRadius);

}  // namespace sp
