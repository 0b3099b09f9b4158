#include "sim/actuator.h"

#include <algorithm>
#include <cmath>

namespace sp {

ActuatorState initialActuatorState(const ActuatorSpec& spec) {
  ActuatorState s;
  s.mode = spec.mode;
  s.target = spec.initialTarget;
  return s;
}

double wrapAngle(double angle) {
  double a = std::remainder(angle, 2 * kPi);  // in [-pi, pi]
  if (a <= -kPi) a += 2 * kPi;
  return a;
}

ActuatorOutput updateActuator(const ActuatorSpec& spec, ActuatorState& state, double position,
                              double rate, double dt) {
  ActuatorOutput out;
  switch (state.mode) {
    case JointMode::Velocity:
      out.motorVelocity = std::clamp(state.velocity * spec.velocityScale, -spec.maxVelocity, spec.maxVelocity);
      out.motorMaxForce = spec.maxTorque;
      break;
    case JointMode::Position: {
      double error = state.target - position;
      if (spec.continuous) error = wrapAngle(error);
      // Clamp the integral so that the I term alone never exceeds the output
      // limit (or the explicit clamp, if tighter): no wind-up.
      double limit = spec.integralLimit;
      if (spec.ki > 0) {
        const double byOutput = spec.maxVelocity / spec.ki;
        limit = limit > 0 ? std::min(limit, byOutput) : byOutput;
      }
      const double integral = std::clamp(state.integral + error * dt, -limit, limit);
      // Derivative on the measurement, not the error: no kick on a new target.
      const double raw = spec.kp * error + spec.ki * integral - spec.kd * rate;
      const double v = std::clamp(raw, -spec.maxVelocity, spec.maxVelocity);
      // Conditional integration: stop integrating while saturated in the
      // direction the error pushes.
      if (v == raw || (raw > v) != (error > 0)) state.integral = integral;
      out.motorVelocity = v;
      out.motorMaxForce = spec.maxTorque;
      break;
    }
    case JointMode::Torque:
      out.torque = std::clamp(state.torque, -spec.maxTorque, spec.maxTorque);
      break;
    case JointMode::Free:
      break;
  }
  return out;
}

}  // namespace sp
