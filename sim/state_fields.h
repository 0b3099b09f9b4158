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
// (visitState() on each). A Snapshot's own fields are listed too; what is
// not a plain value goes through the visitor's own method: the robots'
// controllers with their sensors `v.robots(controls, sensors)` (the hash
// takes them robot by robot, the codec all controls first), the terrain
// `v.terrain(grid)` (hashed only where edited). The motion resistance pair goes through
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
static_assert(sizeof(Snapshot) == 3 * 8 + 3 * 24 + 8 + 32 + 16 + 24, "list the new Snapshot field in visitState() below");

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

/// A whole snapshot: its own fields in order, the structs above through them.
template <class T, class V>
  requires std::is_same_v<std::remove_const_t<T>, Snapshot>
void visitState(T& s, V&& v) {
  v(s.modelKey, kUnhashed);  // the layout it fits: checked by restore(), not state
  v(s.step, kHashed);
  v(s.stepSize, kUnhashed);  // the world's, not the state's (a snapshot restores into another step)
  v(s.bodies, kHashed);
  v.robots(s.robots, s.sensors);
  v(s.odeRandom, kHashed);
  v(s.random, kHashed);
  v.terrain(s.terrain);
  v(s.pending, kUnhashed);  // the commands queued: they act at the next step, whose state is hashed
}

}  // namespace sp
