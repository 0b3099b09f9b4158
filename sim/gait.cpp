#include "sim/gait.h"

#include <cmath>

#include "sim/robot_model.h"

namespace sp {
namespace {

constexpr int kFL = 0, kFR = 1, kRL = 2, kRR = 3;

/// Smooth 0 -> 1 over tau in [0, 1] (zero speed at both ends).
double ease(double tau) { return (1 - std::cos(kPi * tau)) / 2; }
double easeRate(double tau) { return kPi / 2 * std::sin(kPi * tau); }

/// A hip moving from `from` to `to` over one phase; with `drive`, the wheel
/// turns to keep pace with the foot's forward motion relative to the hip.
LegCommand swing(double from, double to, double tau, double phaseTime, double legLength, double wheelRadius,
                 LegCommand::Wheel wheel) {
  LegCommand c;
  c.hip = from + (to - from) * ease(tau);
  c.wheel = wheel;
  if (wheel == LegCommand::Wheel::Drive) {
    // Wheel x relative to the hip is -L sin(hip), so it moves at
    // -L cos(hip) d(hip)/dt.
    const double hipRate = (to - from) * easeRate(tau) / phaseTime;
    c.wheelSpeed = -legLength * std::cos(c.hip) * hipRate / wheelRadius;
  }
  return c;
}

}  // namespace

std::optional<std::array<LegJoints, 4>> findLegs(const RobotModel& robot) {
  if (!robot.drive) return std::nullopt;
  auto jointWithChild = [&](int link) {
    for (size_t j = 0; j < robot.joints.size(); ++j)
      if (robot.joints[j].child == link) return static_cast<int>(j);
    return -1;
  };
  std::array<LegJoints, 4> legs;
  for (int i = 0; i < 4; ++i) {
    LegJoints& leg = legs[i];
    leg.wheel = robot.drive->wheels[i];
    if (leg.wheel < 0) return std::nullopt;
    leg.knee = jointWithChild(robot.joints[leg.wheel].parent);
    if (leg.knee < 0) return std::nullopt;
    leg.hip = jointWithChild(robot.joints[leg.knee].parent);
    if (leg.hip < 0) return std::nullopt;
    if (robot.joints[leg.knee].type != JointType::Hinge || robot.joints[leg.hip].type != JointType::Hinge)
      return std::nullopt;
  }
  return legs;
}

std::array<LegCommand, 4> gaitStep(const SimParams& p, GaitState& state, int64_t step, double dt,
                                   double legLength, double wheelRadius) {
  std::array<LegCommand, 4> legs{};
  using Wheel = LegCommand::Wheel;
  const double elapsed = static_cast<double>(step - state.phaseStart) * dt;
  switch (state.gait) {
    case Gait::Off:
      return legs;  // stance, wheels braked
    case Gait::Caterpillar: {
      // Two phases. A: the rear wheels brace (braked) while the rear legs
      // push the body forward and the front legs reach forward on rolling
      // wheels. B: the front wheels brace while the front legs draw the body
      // over them and the rear legs are pulled forward on rolling wheels.
      const double s = degToRad(p.caterpillarHipSwing), T = p.caterpillarPhaseTime;
      if (elapsed >= T) {
        state.phase = (state.phase + 1) % 2;
        state.phaseStart = step;
      }
      const double tau = static_cast<double>(step - state.phaseStart) * dt / T;
      const bool a = state.phase == 0;
      for (int leg : {kFL, kFR})
        legs[leg] = swing(a ? s : -s, a ? -s : s, tau, T, legLength, wheelRadius, a ? Wheel::Free : Wheel::Brake);
      for (int leg : {kRL, kRR})
        legs[leg] = swing(a ? -s : s, a ? s : -s, tau, T, legLength, wheelRadius, a ? Wheel::Brake : Wheel::Free);
      return legs;
    }
    case Gait::Rolking: {
      // Five phases: each leg in turn (rear-left, front-left, rear-right,
      // front-right) reaches forward, driven by its hip and its wheel
      // together, while the other wheels roll freely; then all wheels brake
      // and the hips bring the body forward over the feet.
      static constexpr int kOrder[4] = {kRL, kFL, kRR, kFR};
      const double s = degToRad(p.rolkingHipSwing);
      const double T = state.phase < 4 ? p.rolkingLegTime : p.rolkingBodyTime;
      if (elapsed >= T) {
        state.phase = (state.phase + 1) % 5;
        state.phaseStart = step;
      }
      const double Tn = state.phase < 4 ? p.rolkingLegTime : p.rolkingBodyTime;
      const double tau = static_cast<double>(step - state.phaseStart) * dt / Tn;
      if (state.phase == 4) {
        for (int leg = 0; leg < 4; ++leg) legs[leg] = swing(-s, s, tau, Tn, legLength, wheelRadius, Wheel::Brake);
        return legs;
      }
      for (int k = 0; k < 4; ++k) {
        const int leg = kOrder[k];
        if (k < state.phase) legs[leg] = {-s, Wheel::Free, 0};          // already reached
        else if (k > state.phase) legs[leg] = {s, Wheel::Free, 0};      // still behind
        else legs[leg] = swing(s, -s, tau, Tn, legLength, wheelRadius, Wheel::Drive);
      }
      return legs;
    }
  }
  return legs;
}

}  // namespace sp
