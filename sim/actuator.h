#pragma once
// Joint actuator logic, free of ODE so it can be tested alone. The world asks
// it each step what to tell the joint's ODE motor.
//
// Position mode is a PID on the joint angle whose output is the velocity
// set-point of ODE's motor, which then holds it with at most maxTorque. The
// motor is solved implicitly by ODE, so stiff gains stay stable at any step
// size; a torque-output PID would need tiny steps for the same stiffness.

#include "sim/command.h"
#include "sim/robot_model.h"

namespace sp {

/// The mutable state of one actuator: its mode, set-points and PID memory.
/// Plain value (part of snapshots).
struct ActuatorState {
  JointMode mode = JointMode::Free;
  double velocity = 0;  ///< Velocity mode set-point [rad/s or m/s]
  double target = 0;    ///< Position mode set-point [rad or m]
  double torque = 0;    ///< Torque mode set-point [N m or N]
  double integral = 0;  ///< PID integral of the error [rad s]
  friend bool operator==(const ActuatorState&, const ActuatorState&) = default;
};

/// What to tell the joint this step.
struct ActuatorOutput {
  double motorVelocity = 0;  ///< ODE motor dParamVel
  double motorMaxForce = 0;  ///< ODE motor dParamFMax (0 = motor off)
  double torque = 0;         ///< explicit torque (force) to add
};

/// The initial state from the spec: its mode and initial target.
ActuatorState initialActuatorState(const ActuatorSpec& spec);

/// Wraps an angle to (-pi, pi].
double wrapAngle(double angle);

/// One control step. `position`/`rate` are the joint's measured angle and
/// angular rate; `dt` the step. Updates the PID integral in `state`.
/// Damping is not included (the world adds it for every joint).
ActuatorOutput updateActuator(const ActuatorSpec& spec, ActuatorState& state, double position,
                              double rate, double dt);

}  // namespace sp
