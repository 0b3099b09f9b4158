// Snapshots: the dynamic state as a plain value, restored bit for bit; the
// state hash that compares runs; the model key a snapshot must fit.

#include "sim/world_impl.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>

#include "sim/hash.h"
#include "sim/state_fields.h"

namespace sp {
using namespace world_detail;

void World::canonicalizeQuaternions() {
  // dBodySetQuaternion normalises what it is given, and normalising a unit
  // quaternion again can change its last bit (and repeating it may cycle),
  // so a quaternion read out of ODE does not restore to itself. Instead,
  // after every step each body's quaternion q is set once more: ODE then
  // holds N(q), and q is remembered as its preimage. Snapshots store the
  // preimage; restoring it gives N(q) again, bit for bit.
  Impl& m = *impl_;
  for (size_t b = 0; b < m.allBodies.size(); ++b) {
    std::memcpy(m.preimage[b].data(), dBodyGetQuaternion(m.allBodies[b]), sizeof(dQuaternion));
    dBodySetQuaternion(m.allBodies[b], m.preimage[b].data());
  }
}

Snapshot World::snapshot() const {
  const Impl& m = *impl_;
  Snapshot s;
  s.modelKey = modelKey();
  s.step = steps_;
  s.stepSize = params_.step;
  s.bodies.reserve(m.allBodies.size());
  for (size_t b = 0; b < m.allBodies.size(); ++b) {
    s.bodies.push_back(readBody(m.allBodies[b]));
    s.bodies.back().quaternion = m.preimage[b];  // restores to the exact orientation
  }
  for (const Impl::Robot& rt : m.robots) {
    s.robots.push_back(rt.control);
    s.sensors.push_back(rt.sensors);
  }
  s.odeRandom = m.randState;
  s.random = m.random.state();
  s.terrain = m.grid;
  s.pending = m.queue;
  return s;
}

std::string World::restore(const Snapshot& s) {
  Impl& m = *impl_;
  if (m.broken)
    return "the physics engine failed in this world (" + health_.where +
           "); build a new world and restore into that";
  if (s.modelKey != modelKey() || s.bodies.size() != m.allBodies.size() || s.robots.size() != m.robots.size() ||
      s.sensors.size() != m.robots.size())
    return "the snapshot is of another model (its bodies, joints or sensors differ)";
  for (size_t i = 0; i < s.bodies.size(); ++i) {
    const BodyState& b = s.bodies[i];
    if (!finite(b.position.data(), 3) || !finite(b.quaternion.data(), 4) || !finite(b.linearVelocity.data(), 3) ||
        !finite(b.angularVelocity.data(), 3))
      return "the snapshot's state of " + m.bodyNames[i] + " is not finite";
  }
  // A coarser or finer step keeps the time; the step count must land on it.
  const double steps = static_cast<double>(s.step) * s.stepSize / params_.step;
  const auto newSteps = std::llround(steps);
  if (std::abs(steps - static_cast<double>(newSteps)) > 1e-6)
    return "the snapshot's time is not a whole number of this world's steps";
  const double scale = s.stepSize / params_.step;
  ensureOdeThread();
  for (size_t i = 0; i < m.allBodies.size(); ++i) {
    const BodyState& b = s.bodies[i];
    dBodySetPosition(m.allBodies[i], b.position[0], b.position[1], b.position[2]);
    dBodySetQuaternion(m.allBodies[i], b.quaternion.data());
    m.preimage[i] = b.quaternion;
    dBodySetLinearVel(m.allBodies[i], b.linearVelocity[0], b.linearVelocity[1], b.linearVelocity[2]);
    dBodySetAngularVel(m.allBodies[i], b.angularVelocity[0], b.angularVelocity[1], b.angularVelocity[2]);
    m.previous[i] = readBody(m.allBodies[i]);
  }
  for (size_t r = 0; r < m.robots.size(); ++r) {
    m.robots[r].control = s.robots[r];
    // Snapshots from before motion resistance (or of a welded twin) carry
    // none: the next step's contacts set it.
    const size_t links = m.robots[r].bodies.size();
    RobotControlState& rc = m.robots[r].control;
    if (rc.resistance.size() != links || rc.resistanceShare.size() != links) {
      rc.resistance.assign(links, 0.0);
      rc.resistanceShare.assign(links, 1.0);
    }
    if (rc.resistanceHold.size() != links) rc.resistanceHold.assign(links, 0.0);
    m.robots[r].sensors = s.sensors[r];
    if (scale != 1.0)
      for (SensorState& st : m.robots[r].sensors)
        st.nextStep = std::llround(static_cast<double>(st.nextStep) * scale);
  }
  m.randState = static_cast<unsigned long>(s.odeRandom);
  m.random.setState(s.random);
  if (m.heightData && s.terrain && s.terrain != m.grid) {
    m.grid = std::const_pointer_cast<HeightGrid>(s.terrain);
    // Shared with the snapshot from now on: the next edit copies it first.
    m.setTerrainBounds(m.grid->minHeight(), m.grid->maxHeight());
    const dReal* pos = dGeomGetPosition(m.terrainGeom);
    dGeomSetPosition(m.terrainGeom, pos[0], pos[1], pos[2]);
  }
  m.queue = s.pending;
  steps_ = newSteps;
  health_ = {};
  return {};
}

std::string World::setRobotMotion(int robot, const std::vector<LinkMotion>& links,
                                  const std::vector<std::pair<std::string, Pose>>& objects) {
  Impl& m = *impl_;
  if (robot < 0 || robot >= robotCount()) return "no robot " + std::to_string(robot);
  Impl::Robot& rt = m.robots[static_cast<size_t>(robot)];
  if (links.size() != rt.bodies.size())
    return "expected " + std::to_string(rt.bodies.size()) + " links, got " + std::to_string(links.size());
  for (const LinkMotion& l : links) {
    const double v[] = {l.pose.p.x, l.pose.p.y, l.pose.p.z, l.pose.q.w, l.pose.q.x, l.pose.q.y, l.pose.q.z,
                        l.linear.x,  l.linear.y,  l.linear.z,  l.angular.x, l.angular.y, l.angular.z};
    if (!finite(v, 13)) return "a link's pose or velocity is not finite";
  }
  ensureOdeThread();
  // ODE holds each body at its centre of mass; a link frame's origin is
  // comOffset behind it.
  const auto set = [&](dBodyID body, const Pose& frame, Vec3 com, Vec3 linear, Vec3 angular) {
    const Vec3 offset = rotate(frame.q, com);
    const Vec3 p = frame.p + offset;
    const double qn = std::sqrt(frame.q.w * frame.q.w + frame.q.x * frame.q.x + frame.q.y * frame.q.y + frame.q.z * frame.q.z);
    const Quat q{frame.q.w / qn, frame.q.x / qn, frame.q.y / qn, frame.q.z / qn};
    const dQuaternion dq = {q.w, q.x, q.y, q.z};
    const Vec3 v = linear + cross(angular, offset);
    dBodySetPosition(body, p.x, p.y, p.z);
    dBodySetQuaternion(body, dq);
    dBodySetLinearVel(body, v.x, v.y, v.z);
    dBodySetAngularVel(body, angular.x, angular.y, angular.z);
    dBodyEnable(body);
    for (size_t i = 0; i < m.allBodies.size(); ++i)
      if (m.allBodies[i] == body) {
        m.preimage[i] = {q.w, q.x, q.y, q.z};
        m.previous[i] = readBody(body);
      }
  };
  for (size_t l = 0; l < links.size(); ++l)
    set(rt.bodies[l], links[l].pose, rt.comOffset[l], links[l].linear, links[l].angular);
  for (const auto& [name, pose] : objects)
    for (size_t o = 0; o < model_.objects.size(); ++o)
      if (model_.objects[o].name == name && m.objectBodies[o]) set(m.objectBodies[o], pose, m.objectComOffset[o], {}, {});
  health_ = {};
  return {};
}

namespace {

// Hashes the fields sim/state_fields.h marks hashed, each as its bytes.
struct StateHasher {
  Fnv1a64& h;
  const std::vector<double>& loadedHeights;  // the terrain as the world file gave it
  template <class T, bool Hashed>
  void operator()(const T& v, std::bool_constant<Hashed>) {
    if constexpr (Hashed) {
      static_assert(std::is_trivially_copyable_v<T>, "a hashed field is hashed as its bytes");
      h.value(v);
    }
  }
  template <StateOf T, bool Hashed>
  void operator()(const std::vector<T>& items, std::bool_constant<Hashed>) {
    if constexpr (Hashed)
      for (const T& item : items) visitState(item, *this);
  }
  // Robot by robot: its controllers, then its sensors.
  void robots(const std::vector<RobotControlState>& controls, const std::vector<std::vector<SensorState>>& sensors) {
    for (size_t r = 0; r < controls.size(); ++r) {
      visitState(controls[r], *this);
      (*this)(sensors[r], kHashed);
    }
  }
  // Edited terrain is state too. Heights as loaded add nothing, so runs
  // without edits keep the hashes they always had.
  void terrain(const std::shared_ptr<const HeightGrid>& grid) {
    if (grid && grid->heights != loadedHeights) h.bytes(grid->heights.data(), grid->heights.size() * sizeof(double));
  }
  // Motion resistance only where a surface has it: other runs keep the
  // hashes they always had.
  void resistance(const std::vector<double>& forces, const std::vector<double>& shares,
                  const std::vector<double>& holds) {
    if (std::none_of(forces.begin(), forces.end(), [](double f) { return f != 0; })) return;
    for (size_t l = 0; l < forces.size(); ++l) {
      h.value(forces[l]);
      h.value(shares[l]);
      h.value(l < holds.size() ? holds[l] : 0.0);
    }
  }
};

}  // namespace

uint64_t World::stateHash() const {
  const Impl& m = *impl_;
  // The snapshot's fields, as sim/state_fields.h lists them; the bodies'
  // orientations as ODE holds them (a snapshot keeps each one's preimage,
  // to restore it exactly).
  Snapshot s = snapshot();
  for (size_t b = 0; b < m.allBodies.size(); ++b) s.bodies[b].quaternion = readBody(m.allBodies[b]).quaternion;
  Fnv1a64 h;
  StateHasher hash{h, model_.terrain.grid.heights};
  visitState(std::as_const(s), hash);
  return h.digest();
}

uint64_t World::modelKey() const {
  // The layout a snapshot must fit: names and kinds of bodies, joints,
  // actuators and sensors (not masses or gains: a snapshot may be restored
  // into a world with other parameters on purpose, e.g. a coarser step).
  Fnv1a64 h;
  for (const std::string& n : impl_->bodyNames) h.bytes(n.data(), n.size());
  for (const RobotInstance& r : model_.robots) {
    for (const JointSpec& j : r.model.joints) {
      h.bytes(j.name.data(), j.name.size());
      h.value(j.type);
    }
    for (const ActuatorSpec& a : r.model.actuators) h.value(a.joint);
    for (const SensorSpec& sp : r.model.sensors) h.value(sp.type);
  }
  return h.digest();
}

}  // namespace sp
