// The World's step loop and what it needs of ODE per thread, the command
// queue, and the read-out of state between steps. The stages a step runs are
// in world_*.cpp (see sim/world_impl.h).
#include "sim/world.h"
#include "sim/terrain_brush.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <mutex>

#include "sim/command_check.h"
#include "sim/text.h"
#include "sim/world_impl.h"

// ODE's quick stepper reorders constraints with dRandInt(), which draws from
// one process-wide seed: results would depend on what else ran before, and
// two worlds stepping in parallel would race on it. ODE calls dRand through
// its PLT, so this definition takes its place: each thread has its own state,
// and World::step() loads the world's state into it before stepping and
// saves it after. odeRandomIsPerThread() checks that the override is live.
namespace {
thread_local unsigned long tOdeRandState = 0;
}
extern "C" unsigned long dRand() {
  tOdeRandState = (1664525UL * tOdeRandState + 1013904223UL) & 0xffffffffUL;
  return tOdeRandState;
}

namespace sp {
namespace {

std::once_flag gOdeInit;
std::mutex gStepFallbackMutex;  // only used when the dRand override is not live

// ODE reports solver trouble (an LCP failure, say) through its message
// handler; World::step() points this at its own list while it steps.
thread_local std::vector<std::string>* tOdeMessages = nullptr;

void captureOdeMessage(int errnum, const char* msg, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof text, msg, ap);
  if (tOdeMessages) tOdeMessages->push_back("ODE message " + std::to_string(errnum) + ": " + text);
}

// ODE's internal errors (a quaternion that cannot be normalised after a
// blow-up, say) call abort() once their handler returns. Throwing from the
// handler instead unwinds out of the step (ODE is C++ built with unwind
// tables); World::step() catches it, reports the failure and freezes the
// world, which cannot be trusted again: build a new one and restore into it.
[[noreturn]] void throwOdeFailure(int errnum, const char* msg, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof text, msg, ap);
  throw world_detail::OdeFailure("ODE internal error " + std::to_string(errnum) + ": " + text);
}

}  // namespace

namespace world_detail {
void ensureOdeThread() {
  std::call_once(gOdeInit, [] {
    dInitODE2(0);
    dSetMessageHandler(&captureOdeMessage);
    dSetErrorHandler(&throwOdeFailure);
    dSetDebugHandler(&throwOdeFailure);
  });
  thread_local bool allocated = false;
  if (!allocated) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    allocated = true;
  }
}
}  // namespace world_detail

using namespace world_detail;

World::World(const WorldModel& model, const SimParams& params, WorldOptions options)
    : model_(model), params_(params), options_(options), impl_(std::make_unique<Impl>()) {}

std::string World::submit(const Command& command, int robot) {
  // A terrain edit is the world's, with or without robots.
  if (const auto* patch = std::get_if<TerrainPatchCmd>(&command)) {
    if (std::string why = checkTerrainPatch(*patch); !why.empty()) return why;
    impl_->queue.emplace_back(-1, command);
    return {};
  }
  if (robot < 0 || robot >= robotCount()) return "no robot " + std::to_string(robot);
  CommandCheck check = checkCommand(command, robotModel(robot));
  if (!check.ok()) return std::move(check.message);
  impl_->queue.emplace_back(robot, command);
  return {};
}

bool World::step() {
  Impl& m = *impl_;
  if (!health_.healthy()) return false;
  ensureOdeThread();
  odeMessages_.clear();
  sampledLastStep_.clear();
  tOdeMessages = &odeMessages_;
  for (const auto& [robot, command] : m.queue) applyCommand(command, robot);
  m.queue.clear();
  if (options_.controllers) runActuators();
  applyMotionResistance();
  collide();
  {
    std::unique_lock<std::mutex> fallback;
    if (!m.perThreadRandom) fallback = std::unique_lock<std::mutex>(gStepFallbackMutex);
    tOdeRandState = m.randState;
    try {
      if (params_.solver == Solver::Quick) dWorldQuickStep(m.world, params_.step);
      else dWorldStep(m.world, params_.step);
    } catch (const world_detail::OdeFailure& failure) {
      m.broken = true;
      health_ = {HealthReport::Kind::EngineFailure, failure.what(), steps_ + 1, time() + params_.step, 0, 0};
    }
    m.randState = tOdeRandState;
  }
  ++steps_;
  if (!m.broken) checkHealth();
  if (health_.healthy()) canonicalizeQuaternions();
  // Contact feedback is valid until the contact joints go.
  if (health_.healthy()) updateMotionResistance();
  if ((options_.sensors || options_.wheelForces) && health_.healthy()) {
    accumulateWheelForces();
    sampleSensors();
  }
  dJointGroupEmpty(m.contacts);
  tOdeMessages = nullptr;
  return true;
}

Pose World::linkPose(int robot, int link) const {
  const Impl::Robot& rt = impl_->robots[robot];
  return bodyPose(rt.bodies[link]) * Pose{-rt.comOffset[link], {}};
}

Vec3 World::linkLinearVelocity(int robot, int link) const {
  const Impl::Robot& rt = impl_->robots[robot];
  const Pose origin = linkPose(robot, link);
  dVector3 v;
  dBodyGetPointVel(rt.bodies[link], origin.p.x, origin.p.y, origin.p.z, v);
  return {v[0], v[1], v[2]};
}

Vec3 World::linkAngularVelocity(int robot, int link) const {
  const dReal* w = dBodyGetAngularVel(impl_->robots[robot].bodies[link]);
  return {w[0], w[1], w[2]};
}

Vec3 World::robotCentreOfMass(int robot) const {
  const RobotModel& model = robotModel(robot);
  Vec3 sum;
  double mass = 0;
  for (size_t l = 0; l < model.links.size(); ++l) {
    const dReal* p = dBodyGetPosition(impl_->robots[robot].bodies[l]);
    sum = sum + model.links[l].mass * Vec3{p[0], p[1], p[2]};
    mass += model.links[l].mass;
  }
  return (1.0 / mass) * sum;
}

double World::jointPosition(int robot, int joint) const {
  dJointID j = impl_->robots[robot].joints[joint];
  switch (robotModel(robot).joints[joint].type) {
    case JointType::Hinge: return dJointGetHingeAngle(j);
    case JointType::Slider: return dJointGetSliderPosition(j);
    case JointType::Universal: return dJointGetUniversalAngle1(j);
    case JointType::Ball:
    case JointType::Fixed: return 0;
  }
  return 0;
}

double World::jointRate(int robot, int joint) const {
  dJointID j = impl_->robots[robot].joints[joint];
  switch (robotModel(robot).joints[joint].type) {
    case JointType::Hinge: return dJointGetHingeAngleRate(j);
    case JointType::Slider: return dJointGetSliderPositionRate(j);
    case JointType::Universal: return dJointGetUniversalAngle1Rate(j);
    case JointType::Ball:
    case JointType::Fixed: return 0;
  }
  return 0;
}

const ActuatorState& World::actuatorState(int robot, int actuator) const {
  return impl_->robots[robot].control.actuators[actuator];
}

Pose World::objectPose(int object) const {
  dBodyID b = impl_->objectBodies[object];
  if (!b) return impl_->staticObjectPoses[object];
  return bodyPose(b) * Pose{-impl_->objectComOffset[object], {}};
}

std::string World::scaleFriction(double factor) {
  if (!std::isfinite(factor) || factor <= 0) return "friction factor " + shortestText(factor) + ": must be > 0";
  for (dSurfaceParameters& s : impl_->surfaces) {
    s.mu *= factor;
    s.mu2 *= factor;
  }
  model_.defaultContact.mu *= factor;
  for (ContactSpec& c : model_.contacts) c.mu *= factor;
  return {};
}

const HeightGrid* World::terrainGrid() const {
  return impl_->heightData ? impl_->grid.get() : nullptr;
}

double World::terrainHeight(double x, double y) const {
  const Impl& m = *impl_;
  if (!m.heightData) return m.planeHeight;
  const Pose& p = model_.terrain.pose;
  const Vec3 local = rotate(conjugate(p.q), Vec3{x, y, 0} - Vec3{p.p.x, p.p.y, 0});
  return m.grid->heightAt(local.x, local.y) + p.p.z;
}

std::string World::checkTerrainPatch(const TerrainPatchCmd& c) const {
  const Impl& m = *impl_;
  return patchFits(m.heightData ? &*m.grid : nullptr, c);
}

std::string patchFits(const HeightGrid* grid, const TerrainPatchCmd& c) {
  if (c.columns <= 0 || c.rows <= 0 || c.column < 0 || c.row < 0 ||
      c.heights.size() != static_cast<size_t>(c.columns) * static_cast<size_t>(c.rows))
    return "terrain: the patch's position, size and heights disagree";
  for (double h : c.heights)
    if (!std::isfinite(h)) return "terrain: a height is not finite";
  if (!grid) return "terrain: the world's terrain is a plane, not a heightfield";
  const HeightGrid& g = *grid;
  if (c.column + c.columns > g.columns || c.row + c.rows > g.rows)
    return "terrain: the patch (columns " + std::to_string(c.column) + ".." + std::to_string(c.column + c.columns - 1) +
           ", rows " + std::to_string(c.row) + ".." + std::to_string(c.row + c.rows - 1) +
           ") lies outside the " + std::to_string(g.columns) + " x " + std::to_string(g.rows) + " heightfield";
  return {};
}

std::vector<double> World::Impl::terrainDepths(const std::vector<dBodyID>& bodies) {
  std::vector<double> out;
  std::array<dContactGeom, 16> found;
  for (dBodyID b : bodies)
    for (dGeomID g = b ? dBodyGetFirstGeom(b) : nullptr; g; g = dBodyGetNextGeom(g)) {
      const int n = collidePair(g, terrainGeom, found.data(), static_cast<int>(found.size()));
      double depth = 0;
      for (int k = 0; k < n; ++k) depth = std::max(depth, static_cast<double>(found[k].depth));
      out.push_back(depth);
    }
  return out;
}

void World::applyTerrainPatch(const TerrainPatchCmd& c) {
  Impl& m = *impl_;
  // Each robot, and each dynamic object, is lifted by as much as the edit
  // pushed the ground into it: a stroke under a robot lifts its wheels
  // instead of burying them, which ODE would then resolve by driving them
  // out sideways or not at all (issue 31: a wheel 0.16 m in the ground and
  // the twin diverged).
  std::vector<std::vector<dBodyID>> movers;
  for (const Impl::Robot& r : m.robots) movers.push_back(r.bodies);
  for (dBodyID b : m.objectBodies)
    if (b) movers.push_back({b});
  std::vector<std::vector<double>> before;
  for (const auto& bodies : movers) before.push_back(m.terrainDepths(bodies));
  if (m.grid.use_count() > 1) m.grid = std::make_shared<HeightGrid>(*m.grid);  // a snapshot shares it
  // The bounds stay exact without reading the whole grid (0.3 ms for 512 x
  // 512): only when the patch replaces the lowest (highest) sample with
  // something higher (lower) may the extreme now lie elsewhere.
  bool touchedMin = false, touchedMax = false;
  for (int r = 0; r < c.rows; ++r)
    for (int k = 0; k < c.columns; ++k) {
      const double old = m.grid->at(c.column + k, c.row + r);
      touchedMin = touchedMin || old == m.gridMin;
      touchedMax = touchedMax || old == m.gridMax;
    }
  applyPatch(*m.grid, c);
  double patchLo = c.heights.front(), patchHi = c.heights.front();
  for (double h : c.heights) patchLo = std::min(patchLo, h), patchHi = std::max(patchHi, h);
  if ((touchedMin && patchLo > m.gridMin) || (touchedMax && patchHi < m.gridMax))
    m.setTerrainBounds(m.grid->minHeight(), m.grid->maxHeight());
  else
    m.setTerrainBounds(std::min(m.gridMin, patchLo), std::max(m.gridMax, patchHi));
  // The bounds feed the geom's AABB, which ODE recomputes only for a moved
  // geom: setting the same position marks it dirty.
  const dReal* pos = dGeomGetPosition(m.terrainGeom);
  dGeomSetPosition(m.terrainGeom, pos[0], pos[1], pos[2]);
  m.penetrationCheckFrom = steps_ + std::llround(1.0 / params_.step);
  for (size_t k = 0; k < movers.size(); ++k) {
    const std::vector<double> after = m.terrainDepths(movers[k]);
    double lift = 0;
    for (size_t g = 0; g < after.size(); ++g) lift = std::max(lift, after[g] - before[k][g]);
    if (lift <= 1e-4) continue;  // a tenth of a millimetre: the contacts take it
    for (dBodyID b : movers[k]) {
      const dReal* p = dBodyGetPosition(b);
      dBodySetPosition(b, p[0], p[1], p[2] + lift);
    }
  }
}

bool odeRandomIsPerThread() {
  ensureOdeThread();
  // dRandInt is ODE's own; it calls dRand through the PLT. If that reaches
  // our definition, our thread-local state advances.
  const unsigned long before = tOdeRandState = 12345;
  (void)dRandInt(100);
  const bool live = tOdeRandState != before;
  tOdeRandState = 0;
  return live;
}

}  // namespace sp
