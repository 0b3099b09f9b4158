#pragma once
// How an actuator drives its joint: a word shared by the robot model (the
// initial mode) and the commands (which switch it), so that neither header
// needs the other.

namespace sp {

enum class JointMode {
  Velocity,  ///< ODE motor holds a velocity with the actuator's torque limit
  Position,  ///< PID on the angle gives the motor velocity (see actuator.h)
  Torque,    ///< a commanded torque (force for sliders) is applied directly
  Free,      ///< no drive: the joint turns freely (damping still applies)
};

/// "velocity", "position", "torque" or "free" (the file syntax).
inline const char* toString(JointMode mode) {
  switch (mode) {
    case JointMode::Velocity: return "velocity";
    case JointMode::Position: return "position";
    case JointMode::Torque: return "torque";
    case JointMode::Free: return "free";
  }
  return "?";
}

}  // namespace sp
