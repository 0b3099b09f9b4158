#pragma once
// The fields of the twin's state structs, listed once (MuJoCo's mjxmacro):
// the session log's snapshot codec (app/log/snapshot_codec.cpp) encodes and
// decodes them, and World::stateHash() hashes them, by visiting these lists,
// so a field added to a struct and listed here reaches all three, and one
// that is not listed fails to compile (the size checks below).
//
// A visitor is called as `v(field, kHashed)` or `v(field, kUnhashed)` for
// each field in order (a compile-time tag): kUnhashed marks what the state
// hash leaves out (it fingerprints the
// dynamics, not the sensors' last readings). Fields that are vectors of
// listed structs are visited element by element by the visitor itself
// (visitState() on each). The motion resistance pair goes through
// `v.resistance(forces, shares)`: it is hashed only where a surface has it,
// so that runs without it keep the hashes they always had.
//
// Thread: any (pure functions of their arguments).

#include <type_traits>

#include "sim/world.h"

namespace sp {

// A field added to one of these structs must be listed below too: these
// sizes (x86-64, GCC) change with it, and the build stops here.
static_assert(sizeof(BodyState) == 13 * 8, "list the new BodyState field in visitState() below");
static_assert(sizeof(ActuatorState) == 5 * 8, "list the new ActuatorState field in visitState() below");
static_assert(sizeof(RobotControlState) == 160 && sizeof(GaitState) == 16,
              "list the new RobotControlState field in visitState() below");
static_assert(sizeof(SensorState) == 8 + 3 * 24 + 8 + sizeof(SensorSample),
              "list the new SensorState field in visitState() below");

/// Tags of a field: in the state hash or not.
inline constexpr std::true_type kHashed{};
inline constexpr std::false_type kUnhashed{};

template <class T>
concept StateOf = std::is_same_v<std::remove_const_t<T>, BodyState> ||
                  std::is_same_v<std::remove_const_t<T>, ActuatorState> ||
                  std::is_same_v<std::remove_const_t<T>, RobotControlState> ||
                  std::is_same_v<std::remove_const_t<T>, SensorState>;

/// One rigid body as ODE holds it.
template <class B, class V>
  requires std::is_same_v<std::remove_const_t<B>, BodyState>
void visitState(B& b, V&& v) {
  v(b.position, kHashed);
  v(b.quaternion, kHashed);
  v(b.linearVelocity, kHashed);
  v(b.angularVelocity, kHashed);
}

/// One actuator's set-points and controller memory.
template <class A, class V>
  requires std::is_same_v<std::remove_const_t<A>, ActuatorState>
void visitState(A& a, V&& v) {
  v(a.mode, kHashed);
  v(a.velocity, kHashed);
  v(a.target, kHashed);
  v(a.torque, kHashed);
  v(a.integral, kHashed);
}

/// One robot's controllers: actuators, drive, gait, motion resistance.
template <class R, class V>
  requires std::is_same_v<std::remove_const_t<R>, RobotControlState>
void visitState(R& rc, V&& v) {
  v(rc.actuators, kHashed);
  v(rc.driveActive, kHashed);
  v(rc.driveSpeed, kHashed);
  v(rc.driveArticulation, kHashed);
  v(rc.driveByYawRate, kHashed);
  v(rc.driveYawRate, kHashed);
  v(rc.gaitActive, kHashed);
  v(rc.gait, kHashed);
  v.resistance(rc.resistance, rc.resistanceShare, rc.resistanceHold);
}

/// One sensor's sampling state and its latest reading.
template <class S, class V>
  requires std::is_same_v<std::remove_const_t<S>, SensorState>
void visitState(S& s, V&& v) {
  v(s.nextStep, kHashed);
  v(s.lastVelocity, kUnhashed);
  v(s.forceSum, kHashed);
  v(s.normalSum, kUnhashed);
  v(s.contactSum, kUnhashed);
  v(s.stepsSummed, kHashed);
  v(s.latest, kUnhashed);
}

}  // namespace sp
