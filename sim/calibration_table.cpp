// The twins' calibration.* parameters (sim/calibration_table.h).
#include "sim/calibration_table.h"

namespace sp {

namespace {

using P = CalParam;
using S = SimParams;

constexpr std::array<CalParamInfo, kCalParams> kTable{{
    // Probes of half a scale: a smaller one drowns in the contacts' noise.
    {P::WheelRadius, &S::calWheelRadius, "calibration.wheel_radius", "wheel radius", "radius",
     "twins: factor on the tyres' effective radius, both axles", "", 1, 0.8, 1.2, 0.03, 0.015, 0},
    {P::WheelRadiusSplit, &S::calWheelRadiusSplit, "calibration.wheel_radius_split", "radius front - rear", "radius F−R",
     "twins: front minus rear tyre radius, relative", "", 0, -0.1, 0.1, 0.03, 0.015, 0},
    {P::WheelRadiusSide, &S::calWheelRadiusSide, "calibration.wheel_radius_side", "radius left - right", "radius L−R",
     "twins: left minus right tyre radius, relative", "", 0, -0.1, 0.1, 0.03, 0.015, 0},
    {P::WheelRadiusDiag, &S::calWheelRadiusDiag, "calibration.wheel_radius_diag", "radius FL+RR - FR+RL", "radius diagonal",
     "twins: front-left and rear-right minus front-right and rear-left tyre radius, relative", "", 0, -0.1, 0.1, 0.03,
     0.015, 0},
    {P::Friction, &S::calFriction, "calibration.friction", "tyre friction", "friction",
     "twins: factor on every contact's friction", "", 1, 0.3, 3, 0.3, 0.15, 0},
    {P::MotorGain, &S::calMotorGain, "calibration.motor_gain", "wheel motor gain", "motor gain",
     "twins: the wheel motors reach this times the commanded speed", "", 1, 0.5, 1.5, 0.2, 0.1, 0},
    {P::Delay, &S::calDelay, "calibration.delay", "command delay", "delay",
     "twins: a command acts this long after it arrives [s]", "s", 0, 0, 0.5, 0.06, 0.03, 0},
    {P::Mass, &S::calMass, "calibration.mass", "total mass", "mass", "twins: factor on every link's mass", "", 1, 0.5, 2,
     0.15, 0, 0},
    // Each link's centre may be 2 cm off on each axis (sim/perturbation.h);
    // the robot's, their mass-weighted mean, rather less.
    {P::ComX, &S::calComX, "calibration.com_x", "centre of mass forward", "CoM forward",
     "twins: [m] the centre of mass moved forward (every link's centre)", "m", 0, -0.1, 0.1, 0.02, 0, kComBias},
    {P::ComY, &S::calComY, "calibration.com_y", "centre of mass left", "CoM left",
     "twins: [m] the centre of mass moved left (every link's centre)", "m", 0, -0.1, 0.1, 0.02, 0, kComBias},
    // A motor's limit shows only where the wheel asks more of it than it
    // has: the forces the twin's wheels put on the ground against the
    // robot's (app/calibration/calibration_torque.cpp). Probes go down: above
    // what the wheel asks, a limit changes nothing.
    {P::TorqueFL, &S::calTorqueFL, "calibration.torque_fl", "front-left motor torque", "torque FL",
     "twins: factor on the front-left wheel motor's torque limit", "", 1, 0.1, 2, 0.2, 0.15, 0},
    {P::TorqueFR, &S::calTorqueFR, "calibration.torque_fr", "front-right motor torque", "torque FR",
     "twins: factor on the front-right wheel motor's torque limit", "", 1, 0.1, 2, 0.2, 0.15, 0},
    {P::TorqueRL, &S::calTorqueRL, "calibration.torque_rl", "rear-left motor torque", "torque RL",
     "twins: factor on the rear-left wheel motor's torque limit", "", 1, 0.1, 2, 0.2, 0.15, 0},
    {P::TorqueRR, &S::calTorqueRR, "calibration.torque_rr", "rear-right motor torque", "torque RR",
     "twins: factor on the rear-right wheel motor's torque limit", "", 1, 0.1, 2, 0.2, 0.15, 0},
}};

constexpr bool inOrder() {
  for (int i = 0; i < kCalParams; ++i)
    if (static_cast<int>(kTable[static_cast<size_t>(i)].id) != i) return false;
  return true;
}
static_assert(inOrder(), "calParams() lists the parameters in CalParam order");

}  // namespace

const std::array<CalParamInfo, kCalParams>& calParams() { return kTable; }

}  // namespace sp
