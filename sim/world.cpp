#include "sim/world.h"

#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <deque>
#include <mutex>

#include "sim/command_check.h"
#include "sim/height_grid_ray.h"
#include "sim/random.h"

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
struct OdeFailure {
  std::string message;
};

[[noreturn]] void throwOdeFailure(int errnum, const char* msg, va_list ap) {
  char text[512];
  std::vsnprintf(text, sizeof text, msg, ap);
  throw OdeFailure{"ODE internal error " + std::to_string(errnum) + ": " + text};
}

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

void toOde(const Quat& q, dQuaternion out) {
  out[0] = q.w;
  out[1] = q.x;
  out[2] = q.y;
  out[3] = q.z;
}

Pose bodyPose(dBodyID b) {
  const dReal* p = dBodyGetPosition(b);
  const dReal* q = dBodyGetQuaternion(b);
  return {{p[0], p[1], p[2]}, {q[0], q[1], q[2], q[3]}};
}

double geomVolume(const GeomSpec& g) {
  const double r = g.radius;
  switch (g.type) {
    case GeomType::Box: return g.size.x * g.size.y * g.size.z;
    case GeomType::Cylinder: return kPi * r * r * g.length;
    case GeomType::Capsule: return kPi * r * r * g.length + 4.0 / 3.0 * kPi * r * r * r;
    case GeomType::Sphere: return 4.0 / 3.0 * kPi * r * r * r;
  }
  return 0;
}

/// Mass properties of `geoms` (in their owner's frame) with `total` mass
/// spread by volume. A geom-less link gets a 5 cm sphere's inertia.
dMass massOf(const std::vector<GeomSpec>& geoms, double total) {
  dMass sum;
  dMassSetZero(&sum);
  double volume = 0;
  for (const GeomSpec& g : geoms) volume += geomVolume(g);
  if (geoms.empty() || volume <= 0) {
    dMassSetSphereTotal(&sum, total, 0.05);
    return sum;
  }
  for (const GeomSpec& g : geoms) {
    const double m = total * geomVolume(g) / volume;
    dMass part;
    switch (g.type) {
      case GeomType::Box: dMassSetBoxTotal(&part, m, g.size.x, g.size.y, g.size.z); break;
      case GeomType::Cylinder: dMassSetCylinderTotal(&part, m, 3, g.radius, g.length); break;
      case GeomType::Capsule: dMassSetCapsuleTotal(&part, m, 3, g.radius, g.length); break;
      case GeomType::Sphere: dMassSetSphereTotal(&part, m, g.radius); break;
    }
    dQuaternion q;
    toOde(g.pose.q, q);
    dMatrix3 R;
    dQtoR(q, R);
    dMassRotate(&part, R);
    dMassTranslate(&part, g.pose.p.x, g.pose.p.y, g.pose.p.z);
    dMassAdd(&sum, &part);
  }
  return sum;
}

/// What a geom belongs to; the index gives contacts a canonical order.
struct GeomInfo {
  int index = 0;
  int material = -1;  // index into WorldModel::materials, -1 = default
  int robot = -1;
  int link = -1;
  int object = -1;
  int wheelSensor = -1;  // a wheel_force sensor on this geom's link
};

void hashBytes(uint64_t& h, const void* data, size_t size) {
  // FNV-1a, 64 bit: simple, and stable across builds and machines.
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ULL;
  }
}
template <typename T>
void hashValue(uint64_t& h, const T& value) {
  hashBytes(h, &value, sizeof value);
}

bool finite(const dReal* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

}  // namespace

struct World::Impl {
  struct Robot {
    std::vector<dBodyID> bodies;     // per link
    std::vector<Vec3> comOffset;     // per link: centre of mass in the link frame
    std::vector<dJointID> joints;    // per joint
    RobotControlState control;
    std::vector<SensorState> sensors;
    std::vector<int64_t> sensorPeriod;          // steps between samples
    std::vector<dJointFeedback> jointFeedback;  // per joint (joint_force sensors read it)
    std::optional<std::array<LegJoints, 4>> legs;  // for gaits
    double legLength = 0;  // hip to wheel centre [m], for gaits
  };
  // A contact joint whose force a wheel_force sensor sums.
  struct WheelContact {
    int robot, sensor;
    size_t feedback;  // index into contactFeedback
    bool wheelInF1;   // the wheel's force is the feedback's f1 (else f2)
    Vec3 normal;      // from the ground into the wheel
  };

  dWorldID world = nullptr;
  dSpaceID space = nullptr;
  dJointGroupID contacts = nullptr;
  dThreadingImplementationID threading = nullptr;
  unsigned long randState = 0;
  bool perThreadRandom = true;

  std::deque<GeomInfo> geomInfos;  // stable addresses for dGeomSetData
  std::vector<Robot> robots;
  std::vector<dBodyID> allBodies;     // robots' links in order, then dynamic objects
  std::vector<std::string> bodyNames;  // for health reports
  std::vector<BodyState> previous;     // body states one step ago (accelerations)
  std::vector<std::array<double, 4>> preimage;  // per body, see canonicalizeQuaternions()
  std::vector<dBodyID> objectBodies;  // nullptr for static objects
  std::vector<std::vector<dGeomID>> objectGeoms;
  std::vector<Pose> staticObjectPoses;
  std::vector<Vec3> objectComOffset;  // dynamic objects: centre of mass in the object frame

  dGeomID terrainGeom = nullptr;
  dHeightfieldDataID heightData = nullptr;
  // Live heights, read by the ODE callback. Shared with snapshots and
  // copied on the first edit after one (copy on write).
  std::shared_ptr<HeightGrid> grid;
  double planeHeight = 0;
  dGeomID ray = nullptr;  // for castRay(); in no space
  struct RayTarget {
    dGeomID geom;
    std::array<double, 6> box;  // ODE's AABB: min x, max x, min y, ...
  };
  std::vector<RayTarget> rayTargets;  // geoms the current scan may hit
  Random random;
  bool broken = false;  // ODE failed inside a step; the world is frozen for good
  int64_t penetrationCheckFrom = 0;  // step; later after a terrain edit

  std::vector<dSurfaceParameters> surfaces;  // (materials+1)^2 table
  int materialCount = 0;

  struct Candidate {
    int lo, hi, order;
    dGeomID g1, g2;
    dContactGeom geom;
  };
  std::vector<Candidate> candidates;
  std::vector<dContactGeom> scratch;
  std::vector<dJointFeedback> contactFeedback;
  std::vector<WheelContact> wheelContacts;
  // Deepest contact of the last collision, for the health check.
  double deepest = 0;
  const Candidate* deepestContact = nullptr;

  std::vector<std::pair<int, Command>> queue;

  const dSurfaceParameters& surface(int a, int b) const {
    return surfaces[static_cast<size_t>((a + 1) * (materialCount + 1) + (b + 1))];
  }

  GeomInfo& newInfo(int material, int robot, int link, int object = -1) {
    GeomInfo& info = geomInfos.emplace_back();
    info.index = static_cast<int>(geomInfos.size()) - 1;
    info.material = material;
    info.robot = robot;
    info.link = link;
    info.object = object;
    return info;
  }

  static dReal heightAt(void* data, int x, int z) {
    const HeightGrid& g = *static_cast<const Impl*>(data)->grid;
    // ODE's heightfield is y-up with z rows; rotated +90 deg about x its z
    // axis points to world -y, so ODE row z is our row rows-1-z.
    return g.at(x, g.rows - 1 - z);
  }

  static void nearCallback(void* data, dGeomID g1, dGeomID g2) {
    static_cast<Impl*>(data)->near(g1, g2);
  }

  void near(dGeomID g1, dGeomID g2) {
    dBodyID b1 = dGeomGetBody(g1), b2 = dGeomGetBody(g2);
    if (b1 == b2) return;  // same body, or two static geoms
    if (b1 && b2 && dAreConnectedExcluding(b1, b2, dJointTypeContact)) return;
    auto* i1 = static_cast<GeomInfo*>(dGeomGetData(g1));
    auto* i2 = static_cast<GeomInfo*>(dGeomGetData(g2));
    if (i1->index > i2->index) {
      std::swap(g1, g2);
      std::swap(i1, i2);
    }
    const int n = dCollide(g1, g2, static_cast<int>(scratch.size()), scratch.data(), sizeof(dContactGeom));
    for (int k = 0; k < n; ++k) candidates.push_back({i1->index, i2->index, k, g1, g2, scratch[k]});
  }
};

namespace {

dSurfaceParameters toSurface(const ContactSpec& c) {
  dSurfaceParameters s{};
  s.mode = dContactApprox1;
  s.mu = c.mu;
  if (c.bounce > 0) {
    s.mode |= dContactBounce;
    s.bounce = c.bounce;
    s.bounce_vel = c.bounceVelocity;
  }
  if (c.softErp >= 0) {
    s.mode |= dContactSoftERP;
    s.soft_erp = c.softErp;
  }
  if (c.softCfm >= 0) {
    s.mode |= dContactSoftCFM;
    s.soft_cfm = c.softCfm;
  }
  if (c.rollingResistance > 0) {
    s.mode |= dContactRolling;
    s.rho = c.rollingResistance;
    s.rho2 = c.rollingResistance;
    s.rhoN = 0;
  }
  return s;
}

int materialIndex(const WorldModel& model, const std::string& name) {
  for (size_t i = 0; i < model.materials.size(); ++i)
    if (model.materials[i] == name) return static_cast<int>(i);
  return -1;
}

dGeomID createGeom(dSpaceID space, const GeomSpec& g) {
  switch (g.type) {
    case GeomType::Box: return dCreateBox(space, g.size.x, g.size.y, g.size.z);
    case GeomType::Cylinder: return dCreateCylinder(space, g.radius, g.length);
    case GeomType::Capsule: return dCreateCapsule(space, g.radius, g.length);
    case GeomType::Sphere: return dCreateSphere(space, g.radius);
  }
  return nullptr;
}

void setGeomOffset(dGeomID geom, const Pose& offset) {
  dGeomSetOffsetPosition(geom, offset.p.x, offset.p.y, offset.p.z);
  dQuaternion q;
  toOde(offset.q, q);
  dGeomSetOffsetQuaternion(geom, q);
}

void setBodyPose(dBodyID body, const Pose& pose) {
  dBodySetPosition(body, pose.p.x, pose.p.y, pose.p.z);
  dQuaternion q;
  toOde(pose.q, q);
  dBodySetQuaternion(body, q);
}

BodyState readBody(dBodyID b) {
  BodyState s;
  std::memcpy(s.position.data(), dBodyGetPosition(b), sizeof s.position);
  std::memcpy(s.quaternion.data(), dBodyGetQuaternion(b), sizeof s.quaternion);
  std::memcpy(s.linearVelocity.data(), dBodyGetLinearVel(b), sizeof s.linearVelocity);
  std::memcpy(s.angularVelocity.data(), dBodyGetAngularVel(b), sizeof s.angularVelocity);
  return s;
}

}  // namespace

std::array<double, 4> articulatedWheelSpeeds(const DriveGeometry& g, double speed, double wheelRadius) {
  const double gamma = g.articulation;
  if (std::abs(gamma) < 1e-6) {
    const double w = speed / wheelRadius;
    return {w, w, w, w};
  }
  // Instantaneous centre O of the two axle lines (workpartner-facts.md §3):
  // signed radii, positive when O lies to the left (gamma > 0).
  const double s = std::sin(gamma), c = std::cos(gamma);
  const double lf = g.frontLength, lr = g.rearLength;
  const double rRear = (lf + lr * c) / s;
  const double rFront = (lr + lf * c) / s;
  const double rHinge = std::copysign(std::sqrt(lr * lr + rRear * rRear), s);
  const double yawRate = speed / rHinge;
  return {yawRate * (rFront - g.frontTrack / 2) / wheelRadius,
          yawRate * (rFront + g.frontTrack / 2) / wheelRadius,
          yawRate * (rRear - g.rearTrack / 2) / wheelRadius,
          yawRate * (rRear + g.rearTrack / 2) / wheelRadius};
}

double articulationForTurn(const DriveGeometry& g, double speed, double yawRate, double maxAngle) {
  if (yawRate == 0 || speed == 0) return 0;
  // The hinge radius R_H = |speed / yawRate| grows monotonically smaller as
  // gamma grows on (0, pi): bisect for it.
  const double wanted = std::abs(speed / yawRate);
  auto radius = [&](double gamma) {
    const double rRear = (g.frontLength + g.rearLength * std::cos(gamma)) / std::sin(gamma);
    return std::hypot(g.rearLength, rRear);
  };
  double lo = 1e-6, hi = std::min(maxAngle, kPi - 1e-3);
  if (radius(hi) > wanted) return std::copysign(hi, yawRate * speed);  // tighter than the hinge allows
  for (int i = 0; i < 60; ++i) {
    const double mid = (lo + hi) / 2;
    (radius(mid) > wanted ? lo : hi) = mid;
  }
  return std::copysign((lo + hi) / 2, yawRate * speed);
}

World::World(const WorldModel& model, const SimParams& params, WorldOptions options)
    : model_(model), params_(params), options_(options), impl_(std::make_unique<Impl>()) {}

std::unique_ptr<World> World::create(const WorldModel& model, const SimParams& params, Diagnostics& diag,
                                     WorldOptions options) {
  ensureOdeThread();
  std::unique_ptr<World> w(new World(model, params, options));
  if (!w->build(diag)) return nullptr;
  return w;
}

World::~World() {
  Impl& m = *impl_;
  if (!m.world) return;
  ensureOdeThread();
  dJointGroupDestroy(m.contacts);
  dSpaceDestroy(m.space);  // destroys the geoms too (cleanup mode on)
  dGeomDestroy(m.ray);
  if (m.heightData) dGeomHeightfieldDataDestroy(m.heightData);
  dWorldSetStepThreadingImplementation(m.world, nullptr, nullptr);
  dWorldDestroy(m.world);
  dThreadingFreeImplementation(m.threading);
}

bool World::build(Diagnostics& diag) {
  Impl& m = *impl_;
  m.world = dWorldCreate();
  // Each world its own threading implementation: worlds sharing ODE's global
  // one abort when stepped in parallel (shared/STACK.md).
  m.threading = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(m.world, dThreadingImplementationGetFunctions(m.threading),
                                       m.threading);
  m.space = dHashSpaceCreate(nullptr);
  dSpaceSetCleanup(m.space, 1);
  m.contacts = dJointGroupCreate(0);
  m.randState = static_cast<unsigned long>(params_.seed & 0xffffffffu);
  m.random.reseed(params_.seed);
  m.ray = dCreateRay(nullptr, 1.0);
  dGeomRaySetClosestHit(m.ray, 1);
  m.perThreadRandom = odeRandomIsPerThread();
  m.scratch.resize(static_cast<size_t>(std::max(1, params_.maxContacts)));

  dWorldSetGravity(m.world, model_.gravity.x, model_.gravity.y, model_.gravity.z);
  dWorldSetERP(m.world, params_.erp);
  dWorldSetCFM(m.world, params_.cfm);
  dWorldSetContactSurfaceLayer(m.world, params_.surfaceLayer);
  dWorldSetContactMaxCorrectingVel(m.world, params_.maxCorrectingVel);
  dWorldSetQuickStepNumIterations(m.world, params_.iterations);
  dWorldSetAutoDisableFlag(m.world, 0);  // a sleeping body would not feel terrain edits

  // Contact parameters for every pair of materials, looked up per contact.
  m.materialCount = static_cast<int>(model_.materials.size());
  const int n = m.materialCount + 1;
  m.surfaces.resize(static_cast<size_t>(n * n));
  for (int a = -1; a < m.materialCount; ++a)
    for (int b = -1; b < m.materialCount; ++b) {
      const std::string& na = a < 0 ? std::string() : model_.materials[a];
      const std::string& nb = b < 0 ? std::string() : model_.materials[b];
      m.surfaces[static_cast<size_t>((a + 1) * n + (b + 1))] = toSurface(model_.contactFor(na, nb));
    }

  // Terrain.
  const TerrainSpec& t = model_.terrain;
  const int terrainMaterial = materialIndex(model_, t.material);
  if (t.kind == TerrainSpec::Kind::Plane) {
    m.planeHeight = t.pose.p.z;
    m.terrainGeom = dCreatePlane(m.space, 0, 0, 1, t.pose.p.z);
  } else {
    m.grid = std::make_shared<HeightGrid>(t.grid);
    const HeightGrid& g = *m.grid;
    if (g.columns < 2 || g.rows < 2) {
      diag.error(model_.file, t.line, "terrain: heightfield has no data");
      return false;
    }
    m.heightData = dGeomHeightfieldDataCreate();
    dGeomHeightfieldDataBuildCallback(m.heightData, &m, &Impl::heightAt, g.width, g.depth, g.columns, g.rows,
                                      1.0, 0.0, 1.0, 0);
    dGeomHeightfieldDataSetBounds(m.heightData, g.minHeight(), g.maxHeight());
    m.terrainGeom = dCreateHeightfield(m.space, m.heightData, 1);
    // ODE's heightfield is y-up: turn it +90 deg about x so heights point up z.
    const Quat q = t.pose.q * quatFromAxisAngle({1, 0, 0}, kPi / 2);
    dQuaternion oq;
    toOde(q, oq);
    dGeomSetQuaternion(m.terrainGeom, oq);
    dGeomSetPosition(m.terrainGeom, t.pose.p.x, t.pose.p.y, t.pose.p.z);
  }
  dGeomSetData(m.terrainGeom, &m.newInfo(terrainMaterial, -1, -1));

  // Objects.
  for (size_t oi = 0; oi < model_.objects.size(); ++oi) {
    const ObjectSpec& o = model_.objects[oi];
    dBodyID body = nullptr;
    Vec3 com;
    if (!o.isStatic) {
      dMass mass = massOf(o.geoms, o.mass);
      com = {mass.c[0], mass.c[1], mass.c[2]};
      dMassTranslate(&mass, -com.x, -com.y, -com.z);
      body = dBodyCreate(m.world);
      dBodySetMass(body, &mass);
      setBodyPose(body, o.pose * Pose{com, {}});
    }
    std::vector<dGeomID> geoms;
    for (const GeomSpec& g : o.geoms) {
      dGeomID geom = createGeom(m.space, g);
      dGeomSetData(geom, &m.newInfo(materialIndex(model_, g.material), -1, -1, static_cast<int>(oi)));
      if (body) {
        dGeomSetBody(geom, body);
        setGeomOffset(geom, Pose{-com, {}} * g.pose);
      } else {
        const Pose p = o.pose * g.pose;
        dGeomSetPosition(geom, p.p.x, p.p.y, p.p.z);
        dQuaternion q;
        toOde(p.q, q);
        dGeomSetQuaternion(geom, q);
      }
      geoms.push_back(geom);
    }
    m.objectBodies.push_back(body);
    m.objectGeoms.push_back(std::move(geoms));
    m.staticObjectPoses.push_back(o.pose);
    m.objectComOffset.push_back(com);
  }

  // Robots.
  for (size_t r = 0; r < model_.robots.size(); ++r) {
    const RobotInstance& inst = model_.robots[r];
    const RobotModel& robot = inst.model;
    Impl::Robot& rt = m.robots.emplace_back();
    std::vector<int> wheelSensorOfLink(robot.links.size(), -1);
    for (size_t si = 0; si < robot.sensors.size(); ++si)
      if (robot.sensors[si].type == SensorType::WheelForce) wheelSensorOfLink[robot.sensors[si].link] = static_cast<int>(si);
    const std::string prefix = model_.robots.size() > 1 ? "robot '" + inst.name + "' " : "";
    for (size_t li = 0; li < robot.links.size(); ++li) {
      const LinkSpec& link = robot.links[li];
      dMass mass = massOf(link.geoms, link.mass);
      const Vec3 com{mass.c[0], mass.c[1], mass.c[2]};
      // ODE wants the centre of mass at the body origin.
      dMassTranslate(&mass, -com.x, -com.y, -com.z);
      dBodyID body = dBodyCreate(m.world);
      dBodySetMass(body, &mass);
      setBodyPose(body, inst.pose * link.pose * Pose{com, {}});
      for (const GeomSpec& g : link.geoms) {
        dGeomID geom = createGeom(m.space, g);
        GeomInfo& info =
            m.newInfo(materialIndex(model_, g.material), static_cast<int>(r), static_cast<int>(li));
        info.wheelSensor = wheelSensorOfLink[li];
        dGeomSetData(geom, &info);
        dGeomSetBody(geom, body);
        setGeomOffset(geom, Pose{-com, {}} * g.pose);
      }
      rt.bodies.push_back(body);
      rt.comOffset.push_back(com);
      m.allBodies.push_back(body);
      m.bodyNames.push_back(prefix + "link '" + link.name + "'");
    }
    for (const JointSpec& j : robot.joints) {
      dJointID joint = nullptr;
      const Vec3 a = transformPoint(inst.pose, j.anchor);
      const Vec3 ax = rotate(inst.pose.q, j.axis);
      const Vec3 ax2 = rotate(inst.pose.q, j.axis2);
      // ODE measures a joint as body 1 relative to body 2, so the child goes
      // first: angles, rates and motors then read child relative to parent.
      dBodyID parent = j.parent >= 0 ? rt.bodies[j.parent] : nullptr;
      dBodyID child = rt.bodies[j.child];
      switch (j.type) {
        case JointType::Hinge:
          joint = dJointCreateHinge(m.world, nullptr);
          dJointAttach(joint, child, parent);
          dJointSetHingeAnchor(joint, a.x, a.y, a.z);
          dJointSetHingeAxis(joint, ax.x, ax.y, ax.z);
          if (j.limited) {
            dJointSetHingeParam(joint, dParamHiStop, j.upper);
            dJointSetHingeParam(joint, dParamLoStop, j.lower);
          }
          break;
        case JointType::Slider:
          joint = dJointCreateSlider(m.world, nullptr);
          dJointAttach(joint, child, parent);
          dJointSetSliderAxis(joint, ax.x, ax.y, ax.z);
          if (j.limited) {
            dJointSetSliderParam(joint, dParamHiStop, j.upper);
            dJointSetSliderParam(joint, dParamLoStop, j.lower);
          }
          break;
        case JointType::Universal:
          joint = dJointCreateUniversal(m.world, nullptr);
          dJointAttach(joint, child, parent);
          dJointSetUniversalAnchor(joint, a.x, a.y, a.z);
          dJointSetUniversalAxis1(joint, ax.x, ax.y, ax.z);
          dJointSetUniversalAxis2(joint, ax2.x, ax2.y, ax2.z);
          if (j.limited) {
            for (int p : {dParamHiStop, dParamHiStop2}) dJointSetUniversalParam(joint, p, j.upper);
            for (int p : {dParamLoStop, dParamLoStop2}) dJointSetUniversalParam(joint, p, j.lower);
          }
          break;
        case JointType::Ball:
          joint = dJointCreateBall(m.world, nullptr);
          dJointAttach(joint, child, parent);
          dJointSetBallAnchor(joint, a.x, a.y, a.z);
          break;
        case JointType::Fixed:
          joint = dJointCreateFixed(m.world, nullptr);
          dJointAttach(joint, child, parent);
          dJointSetFixed(joint);
          break;
      }
      rt.joints.push_back(joint);
    }
    for (const ActuatorSpec& a : robot.actuators) rt.control.actuators.push_back(initialActuatorState(a));
    rt.legs = findLegs(robot);
    if (rt.legs) {
      const LegJoints& leg = (*rt.legs)[0];
      rt.legLength = norm(robot.joints[leg.wheel].anchor - robot.joints[leg.hip].anchor);
    }
    // Joint feedback for every joint: cheap, and joint_force sensors and
    // health reports read it.
    rt.jointFeedback.resize(robot.joints.size());
    for (size_t ji = 0; ji < robot.joints.size(); ++ji) dJointSetFeedback(rt.joints[ji], &rt.jointFeedback[ji]);
    for (const SensorSpec& spec : robot.sensors) {
      const int64_t period =
          spec.rate > 0 ? std::max<int64_t>(1, std::llround(1.0 / (spec.rate * params_.step))) : 1;
      rt.sensorPeriod.push_back(period);
      SensorState st;
      st.nextStep = period;
      st.latest.robot = static_cast<int>(r);
      st.latest.sensor = static_cast<int>(rt.sensors.size());
      rt.sensors.push_back(st);
    }
  }
  for (size_t oi = 0; oi < m.objectBodies.size(); ++oi) {
    if (!m.objectBodies[oi]) continue;
    m.allBodies.push_back(m.objectBodies[oi]);
    m.bodyNames.push_back("object '" + model_.objects[oi].name + "'");
  }
  m.previous.resize(m.allBodies.size());
  m.preimage.resize(m.allBodies.size());
  for (size_t b = 0; b < m.allBodies.size(); ++b) {
    m.previous[b] = readBody(m.allBodies[b]);
    m.preimage[b] = m.previous[b].quaternion;
    dBodySetQuaternion(m.allBodies[b], m.preimage[b].data());
  }
  return true;
}

std::string World::submit(const Command& command, int robot) {
  if (robot < 0 || robot >= robotCount()) return "no robot " + std::to_string(robot);
  CommandCheck check = checkCommand(command, robotModel(robot));
  if (!check.ok()) return std::move(check.message);
  impl_->queue.emplace_back(robot, command);
  return {};
}

void World::applyCommand(const Command& command, int robot) {
  Impl::Robot& rt = impl_->robots[robot];
  const RobotModel& model = robotModel(robot);
  auto actuatorOf = [&](const std::string& joint) { return model.findActuator(joint); };
  auto cancelDriveIfDriveJoint = [&](int actuator) {
    if (rt.legs)
      for (const LegJoints& leg : *rt.legs)
        if (model.actuators[actuator].joint == leg.hip || model.actuators[actuator].joint == leg.knee ||
            model.actuators[actuator].joint == leg.wheel)
          rt.control.gaitActive = false;
    if (!model.drive) return;
    const int joint = model.actuators[actuator].joint;
    const DriveSpec& d = *model.drive;
    if (joint == d.articulation || std::find(d.wheels.begin(), d.wheels.end(), joint) != d.wheels.end())
      rt.control.driveActive = false;
  };
  auto setMode = [&](ActuatorState& s, JointMode mode) {
    if (s.mode != mode) s.integral = 0;
    s.mode = mode;
  };
  std::visit(
      [&](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, JointVelocityCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], JointMode::Velocity);
          rt.control.actuators[a].velocity = c.velocity;
        } else if constexpr (std::is_same_v<T, JointTargetCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], JointMode::Position);
          rt.control.actuators[a].target = c.position;
        } else if constexpr (std::is_same_v<T, JointTorqueCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], JointMode::Torque);
          rt.control.actuators[a].torque = c.torque;
        } else if constexpr (std::is_same_v<T, JointModeCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], c.mode);
        } else if constexpr (std::is_same_v<T, WheelsCmd>) {
          rt.control.driveActive = false;
          rt.control.gaitActive = false;
          for (int w = 0; w < 4; ++w) {
            const int a = actuatorOf(model.joints[model.drive->wheels[w]].name);
            setMode(rt.control.actuators[a], JointMode::Velocity);
            rt.control.actuators[a].velocity = c.omega[w];
          }
        } else if constexpr (std::is_same_v<T, TurnCmd>) {
          rt.control.gaitActive = false;
          rt.control.driveActive = true;
          rt.control.driveByYawRate = true;
          rt.control.driveSpeed = c.speed;
          rt.control.driveYawRate = c.yawRate;
        } else if constexpr (std::is_same_v<T, DriveCmd>) {
          rt.control.gaitActive = false;
          rt.control.driveByYawRate = false;
          rt.control.driveActive = true;
          rt.control.driveSpeed = c.speed;
          rt.control.driveArticulation = c.articulation;
        } else if constexpr (std::is_same_v<T, GaitCmd>) {
          rt.control.driveActive = false;
          rt.control.gaitActive = true;
          rt.control.gait = GaitState{c.gait, 0, steps_};
        } else if constexpr (std::is_same_v<T, StopCmd>) {
          // Wheels and speed-driven joints brake; joints with a position
          // controller hold where they are now; free joints stay free.
          rt.control.driveActive = false;
          rt.control.gaitActive = false;
          for (size_t a = 0; a < model.actuators.size(); ++a) {
            ActuatorState& s = rt.control.actuators[a];
            const ActuatorSpec& spec = model.actuators[a];
            if (s.mode == JointMode::Free) continue;
            bool isWheel = false;
            if (model.drive)
              for (int w : model.drive->wheels) isWheel = isWheel || w == spec.joint;
            if (spec.hasPid && spec.kp > 0 && !isWheel) {
              // A position-controlled joint that is moving stops where it is;
              // one that is still (a gripper squeezing a pole, a leg carrying
              // load) keeps its target and so its force.
              const bool moving = std::abs(jointRate(robot, spec.joint)) > 1e-3;
              if (s.mode != JointMode::Position || moving) s.target = jointPosition(robot, spec.joint);
              setMode(s, JointMode::Position);
            } else {
              setMode(s, JointMode::Velocity);
              s.velocity = 0;
            }
          }
        }
      },
      command);
}

std::optional<DriveGeometry> World::driveGeometry(int robot) const {
  const RobotModel& model = robotModel(robot);
  if (!model.drive) return std::nullopt;
  const Impl::Robot& rt = impl_->robots[robot];
  const DriveSpec& d = *model.drive;
  auto wheelCentre = [&](int w) {
    const dReal* p = dBodyGetPosition(rt.bodies[model.joints[d.wheels[w]].child]);
    return Vec3{p[0], p[1], p[2]};
  };
  auto planar = [](Vec3 a, Vec3 b) { return std::hypot(a.x - b.x, a.y - b.y); };
  dVector3 h;
  dJointGetHingeAnchor(rt.joints[d.articulation], h);
  const Vec3 hinge{h[0], h[1], h[2]};
  const Vec3 fl = wheelCentre(0), fr = wheelCentre(1), rl = wheelCentre(2), rr = wheelCentre(3);
  DriveGeometry g;
  g.frontLength = planar(0.5 * (fl + fr), hinge);
  g.rearLength = planar(0.5 * (rl + rr), hinge);
  g.frontTrack = planar(fl, fr);
  g.rearTrack = planar(rl, rr);
  g.articulation = jointPosition(robot, d.articulation);
  return g;
}

void World::runActuators() {
  Impl& m = *impl_;
  const double dt = params_.step;
  for (size_t r = 0; r < m.robots.size(); ++r) {
    Impl::Robot& rt = m.robots[r];
    const RobotModel& model = robotModel(static_cast<int>(r));
    if (rt.control.driveActive && model.drive) {
      const DriveSpec& d = *model.drive;
      const DriveGeometry geometry = *driveGeometry(static_cast<int>(r));
      if (rt.control.driveByYawRate) {
        const JointSpec& hinge = model.joints[d.articulation];
        const double limit = hinge.limited ? std::min(std::abs(hinge.lower), std::abs(hinge.upper)) : kPi / 2;
        rt.control.driveArticulation =
            articulationForTurn(geometry, rt.control.driveSpeed, rt.control.driveYawRate, limit);
      }
      const std::array<double, 4> w = articulatedWheelSpeeds(geometry, rt.control.driveSpeed, d.wheelRadius);
      for (int i = 0; i < 4; ++i) {
        ActuatorState& s = rt.control.actuators[model.findActuator(model.joints[d.wheels[i]].name)];
        s.mode = JointMode::Velocity;
        s.velocity = w[i];
      }
      ActuatorState& art = rt.control.actuators[model.findActuator(model.joints[d.articulation].name)];
      if (art.mode != JointMode::Position) art.integral = 0;
      art.mode = JointMode::Position;
      art.target = rt.control.driveArticulation;
    }
    if (rt.control.gaitActive && rt.legs) {
      const std::array<LegCommand, 4> legs =
          gaitStep(params_, rt.control.gait, steps_, params_.step, rt.legLength, model.drive->wheelRadius);
      auto actuatorOf = [&](int joint) -> ActuatorState& {
        return rt.control.actuators[model.findActuator(model.joints[joint].name)];
      };
      auto hold = [](ActuatorState& s, double target) {
        if (s.mode != JointMode::Position) s.integral = 0;
        s.mode = JointMode::Position;
        s.target = target;
      };
      for (int i = 0; i < 4; ++i) {
        const LegJoints& leg = (*rt.legs)[i];
        hold(actuatorOf(leg.hip), legs[i].hip);
        hold(actuatorOf(leg.knee), 0);
        ActuatorState& wheel = actuatorOf(leg.wheel);
        switch (legs[i].wheel) {
          case LegCommand::Wheel::Free: wheel.mode = JointMode::Free; break;
          case LegCommand::Wheel::Brake:
            wheel.mode = JointMode::Velocity;
            wheel.velocity = 0;
            break;
          case LegCommand::Wheel::Drive:
            wheel.mode = JointMode::Velocity;
            wheel.velocity = legs[i].wheelSpeed;
            break;
        }
      }
    }
    // Actuated joints: motor set-points and explicit torques.
    std::vector<bool> actuated(model.joints.size(), false);
    for (size_t a = 0; a < model.actuators.size(); ++a) {
      const ActuatorSpec& spec = model.actuators[a];
      const JointSpec& js = model.joints[spec.joint];
      dJointID j = rt.joints[spec.joint];
      actuated[spec.joint] = true;
      const double rate = jointRate(static_cast<int>(r), spec.joint);
      const ActuatorOutput out =
          updateActuator(spec, rt.control.actuators[a], jointPosition(static_cast<int>(r), spec.joint), rate, dt);
      const double torque = out.torque - js.damping * rate;
      if (js.type == JointType::Hinge) {
        dJointSetHingeParam(j, dParamVel, out.motorVelocity);
        dJointSetHingeParam(j, dParamFMax, out.motorMaxForce);
        if (torque != 0) dJointAddHingeTorque(j, torque);
      } else {
        dJointSetSliderParam(j, dParamVel, out.motorVelocity);
        dJointSetSliderParam(j, dParamFMax, out.motorMaxForce);
        if (torque != 0) dJointAddSliderForce(j, torque);
      }
    }
    // Damping of the joints without an actuator.
    for (size_t ji = 0; ji < model.joints.size(); ++ji) {
      const JointSpec& js = model.joints[ji];
      if (actuated[ji] || js.damping <= 0) continue;
      dJointID j = rt.joints[ji];
      switch (js.type) {
        case JointType::Hinge: dJointAddHingeTorque(j, -js.damping * dJointGetHingeAngleRate(j)); break;
        case JointType::Slider: dJointAddSliderForce(j, -js.damping * dJointGetSliderPositionRate(j)); break;
        case JointType::Universal:
          dJointAddUniversalTorques(j, -js.damping * dJointGetUniversalAngle1Rate(j),
                                    -js.damping * dJointGetUniversalAngle2Rate(j));
          break;
        case JointType::Ball:
        case JointType::Fixed: break;
      }
    }
  }
}

void World::collide() {
  Impl& m = *impl_;
  m.candidates.clear();
  dSpaceCollide(m.space, &m, &Impl::nearCallback);
  // ODE's space reorders geoms as they move, so the pairs arrive in an order
  // that depends on history. Sorting by our own geom indices makes the
  // constraint order, and so the solution, a function of the state alone.
  std::sort(m.candidates.begin(), m.candidates.end(), [](const Impl::Candidate& a, const Impl::Candidate& b) {
    if (a.lo != b.lo) return a.lo < b.lo;
    if (a.hi != b.hi) return a.hi < b.hi;
    return a.order < b.order;
  });
  // Feedback buffers must not move once ODE holds their addresses.
  m.contactFeedback.resize(m.candidates.size());
  m.wheelContacts.clear();
  m.deepest = 0;
  m.deepestContact = nullptr;
  for (size_t k = 0; k < m.candidates.size(); ++k) {
    const Impl::Candidate& c = m.candidates[k];
    const auto* i1 = static_cast<const GeomInfo*>(dGeomGetData(c.g1));
    const auto* i2 = static_cast<const GeomInfo*>(dGeomGetData(c.g2));
    dContact contact{};
    contact.surface = m.surface(i1->material, i2->material);
    contact.geom = c.geom;
    dJointID j = dJointCreateContact(m.world, m.contacts, &contact);
    dJointAttach(j, dGeomGetBody(c.g1), dGeomGetBody(c.g2));
    if (c.geom.depth > m.deepest) {
      m.deepest = c.geom.depth;
      m.deepestContact = &c;
    }
    // ODE's contact normal points into the first geom; a wheel sensor wants
    // the force from the ground into the wheel.
    const GeomInfo* wheel = i1->wheelSensor >= 0 ? i1 : (i2->wheelSensor >= 0 ? i2 : nullptr);
    if (wheel && options_.sensors) {
      dJointSetFeedback(j, &m.contactFeedback[k]);
      const bool first = wheel == i1;
      const Vec3 n{c.geom.normal[0], c.geom.normal[1], c.geom.normal[2]};
      // ODE fills f1 for the first non-null body it was attached to.
      const bool inF1 = first || dGeomGetBody(c.g1) == nullptr;
      m.wheelContacts.push_back({wheel->robot, wheel->wheelSensor, k, inF1, first ? n : -n});
    }
  }
  lastContactCount_ = static_cast<int>(m.candidates.size());
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
  collide();
  {
    std::unique_lock<std::mutex> fallback;
    if (!m.perThreadRandom) fallback = std::unique_lock<std::mutex>(gStepFallbackMutex);
    tOdeRandState = m.randState;
    try {
      if (params_.solver == Solver::Quick) dWorldQuickStep(m.world, params_.step);
      else dWorldStep(m.world, params_.step);
    } catch (const OdeFailure& failure) {
      m.broken = true;
      health_ = {HealthReport::Kind::EngineFailure, failure.message, steps_ + 1, time() + params_.step, 0, 0};
    }
    m.randState = tOdeRandState;
  }
  ++steps_;
  if (!m.broken) checkHealth();
  if (health_.healthy()) canonicalizeQuaternions();
  // Contact feedback is valid until the contact joints go.
  if (options_.sensors && health_.healthy()) {
    accumulateWheelForces();
    sampleSensors();
  }
  dJointGroupEmpty(m.contacts);
  tOdeMessages = nullptr;
  return true;
}

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

void World::checkHealth() {
  Impl& m = *impl_;
  const double dt = params_.step;
  auto fail = [&](HealthReport::Kind kind, std::string where, double value, double limit) {
    if (!health_.healthy()) return;  // the first trouble found is the one reported
    health_ = {kind, std::move(where), steps_, time(), value, limit};
  };
  for (size_t b = 0; b < m.allBodies.size(); ++b) {
    const BodyState now = readBody(m.allBodies[b]);
    const BodyState& before = m.previous[b];
    m.previous[b] = now;
    if (!finite(now.position.data(), 3) || !finite(now.quaternion.data(), 4) ||
        !finite(now.linearVelocity.data(), 3) || !finite(now.angularVelocity.data(), 3)) {
      fail(HealthReport::Kind::NotFinite, m.bodyNames[b], 0, 0);
      continue;
    }
    auto length = [](const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
    auto change = [&](const std::array<double, 3>& a, const std::array<double, 3>& c) {
      return std::sqrt((a[0] - c[0]) * (a[0] - c[0]) + (a[1] - c[1]) * (a[1] - c[1]) + (a[2] - c[2]) * (a[2] - c[2])) / dt;
    };
    const double v = length(now.linearVelocity), w = length(now.angularVelocity);
    if (v > params_.maxLinearSpeed) fail(HealthReport::Kind::Speed, m.bodyNames[b], v, params_.maxLinearSpeed);
    if (w > params_.maxAngularSpeed)
      fail(HealthReport::Kind::AngularSpeed, m.bodyNames[b], w, params_.maxAngularSpeed);
    const double a = change(now.linearVelocity, before.linearVelocity);
    if (a > params_.maxLinearAcceleration)
      fail(HealthReport::Kind::Acceleration, m.bodyNames[b], a, params_.maxLinearAcceleration);
    const double alpha = change(now.angularVelocity, before.angularVelocity);
    if (alpha > params_.maxAngularAcceleration)
      fail(HealthReport::Kind::AngularAcceleration, m.bodyNames[b], alpha, params_.maxAngularAcceleration);
  }
  // Joints pulled apart: the anchor as seen from each of the two bodies.
  for (size_t r = 0; r < m.robots.size(); ++r) {
    const RobotModel& robot = robotModel(static_cast<int>(r));
    for (size_t ji = 0; ji < robot.joints.size(); ++ji) {
      dJointID j = m.robots[r].joints[ji];
      dVector3 a1, a2;
      switch (robot.joints[ji].type) {
        case JointType::Hinge: dJointGetHingeAnchor(j, a1); dJointGetHingeAnchor2(j, a2); break;
        case JointType::Universal: dJointGetUniversalAnchor(j, a1); dJointGetUniversalAnchor2(j, a2); break;
        case JointType::Ball: dJointGetBallAnchor(j, a1); dJointGetBallAnchor2(j, a2); break;
        case JointType::Slider:
        case JointType::Fixed: continue;  // no anchor pair to compare
      }
      const double e = std::sqrt((a1[0] - a2[0]) * (a1[0] - a2[0]) + (a1[1] - a2[1]) * (a1[1] - a2[1]) +
                                 (a1[2] - a2[2]) * (a1[2] - a2[2]));
      if (!(e <= params_.maxJointError))
        fail(HealthReport::Kind::JointSeparation, "joint '" + robot.joints[ji].name + "'", e, params_.maxJointError);
    }
  }
  // A terrain edit may leave bodies inside the new ground: that is the
  // operator's doing, and contacts lift them out (at most
  // contact.max_correcting_velocity), so the check waits a second.
  if (m.deepestContact && m.deepest > params_.maxPenetration && steps_ >= m.penetrationCheckFrom) {
    auto name = [&](dGeomID g) -> std::string {
      const auto* info = static_cast<const GeomInfo*>(dGeomGetData(g));
      if (info->robot >= 0) return "link '" + robotModel(info->robot).links[info->link].name + "'";
      if (info->object >= 0) return "object '" + model_.objects[info->object].name + "'";
      return "the ground";
    };
    fail(HealthReport::Kind::Penetration,
         name(m.deepestContact->g2) + " in " + name(m.deepestContact->g1), m.deepest, params_.maxPenetration);
  }
}

std::string HealthReport::message() const {
  if (healthy()) return "healthy";
  char head[96];
  std::snprintf(head, sizeof head, "step %lld (t = %.3f s): ", static_cast<long long>(step), time);
  auto number = [](double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", x);
    return std::string(b);
  };
  std::string what;
  switch (kind) {
    case Kind::Healthy: break;
    case Kind::NotFinite: return std::string(head) + where + " has a non-finite position or velocity (NaN or Inf)";
    case Kind::EngineFailure: return std::string(head) + "the physics engine failed: " + where;
    case Kind::Speed: what = " speed " + number(value) + " m/s exceeds health.max_linear_speed = "; break;
    case Kind::AngularSpeed:
      what = " angular speed " + number(value) + " rad/s exceeds health.max_angular_speed = ";
      break;
    case Kind::Acceleration:
      what = " acceleration " + number(value) + " m/s^2 exceeds health.max_linear_acceleration = ";
      break;
    case Kind::AngularAcceleration:
      what = " angular acceleration " + number(value) + " rad/s^2 exceeds health.max_angular_acceleration = ";
      break;
    case Kind::JointSeparation:
      what = " pulled apart by " + number(value) + " m, more than health.max_joint_error = ";
      break;
    case Kind::Penetration: what = " by " + number(value) + " m, deeper than health.max_penetration = "; break;
  }
  return head + where + what + number(limit);
}

void World::accumulateWheelForces() {
  Impl& m = *impl_;
  for (Impl::Robot& rt : m.robots)
    for (SensorState& st : rt.sensors) ++st.stepsSummed;  // only wheel_force reads it
  for (const Impl::WheelContact& c : m.wheelContacts) {
    SensorState& st = m.robots[c.robot].sensors[c.sensor];
    const dJointFeedback& f = m.contactFeedback[c.feedback];
    const dReal* fv = c.wheelInF1 ? f.f1 : f.f2;
    const Vec3 force{fv[0], fv[1], fv[2]};
    st.forceSum = st.forceSum + force;
    st.normalSum = st.normalSum + dot(force, c.normal) * c.normal;
    ++st.contactSum;
  }
}

void World::sampleSensors() {
  Impl& m = *impl_;
  const double t = time();
  for (size_t r = 0; r < m.robots.size(); ++r) {
    Impl::Robot& rt = m.robots[r];
    const RobotModel& robot = robotModel(static_cast<int>(r));
    for (size_t si = 0; si < robot.sensors.size(); ++si) {
      SensorState& st = rt.sensors[si];
      if (steps_ < st.nextStep) continue;
      const int64_t period = rt.sensorPeriod[si];
      st.nextStep += period;
      const SensorSpec& spec = robot.sensors[si];
      const double sigma = spec.noise;
      auto noise = [&] { return sigma > 0 ? sigma * m.random.normal() : 0.0; };
      SensorSample& out = st.latest;
      out.step = steps_;
      out.time = t;
      switch (spec.type) {
        case SensorType::Pose: {
          PoseReading p{linkPose(static_cast<int>(r), spec.link) * spec.pose};
          if (sigma > 0) p.pose.p = p.pose.p + Vec3{noise(), noise(), noise()};
          out.value = p;
          break;
        }
        case SensorType::Encoder: {
          EncoderReading e{jointPosition(static_cast<int>(r), spec.joint), jointRate(static_cast<int>(r), spec.joint)};
          e.position += noise();
          out.value = e;
          break;
        }
        case SensorType::JointForce: {
          const dJointFeedback& f = rt.jointFeedback[spec.joint];
          // The child is ODE's body 1 (see the joint attach order).
          JointForceReading jf{{f.f1[0], f.f1[1], f.f1[2]}, {f.t1[0], f.t1[1], f.t1[2]}};
          jf.force = jf.force + Vec3{noise(), noise(), noise()};
          out.value = jf;
          break;
        }
        case SensorType::WheelForce: {
          // The mean over the steps since the last sample (accumulateWheelForces).
          WheelForceReading w;
          const double n = std::max(1, st.stepsSummed);
          w.force = (1.0 / n) * st.forceSum;
          const Vec3 normal = (1.0 / n) * st.normalSum;
          w.normal = norm(normal);
          w.tangential = norm(w.force - normal);
          w.contacts = static_cast<int>(std::lround(st.contactSum / n));
          st.forceSum = st.normalSum = Vec3{};
          st.contactSum = st.stepsSummed = 0;
          w.normal += noise();
          w.tangential += noise();
          out.value = w;
          break;
        }
        case SensorType::Imu: {
          const Pose sensor = linkPose(static_cast<int>(r), spec.link) * spec.pose;
          dVector3 v;
          dBodyGetPointVel(rt.bodies[spec.link], sensor.p.x, sensor.p.y, sensor.p.z, v);
          const Vec3 vel{v[0], v[1], v[2]};
          const Vec3 accelWorld = (1.0 / (static_cast<double>(period) * params_.step)) * (vel - st.lastVelocity);
          st.lastVelocity = vel;
          const Quat toSensor = conjugate(sensor.q);
          ImuReading imu;
          imu.acceleration = rotate(toSensor, accelWorld - model_.gravity);
          imu.angularRate = rotate(toSensor, linkAngularVelocity(static_cast<int>(r), spec.link));
          // Roll and pitch from where gravity's "up" lies in the sensor frame.
          const Vec3 up = rotate(toSensor, {0, 0, 1});
          imu.roll = std::atan2(up.y, up.z);
          imu.pitch = std::atan2(-up.x, std::hypot(up.y, up.z));
          imu.roll += noise();
          imu.pitch += noise();
          imu.angularRate = imu.angularRate + Vec3{noise(), noise(), noise()};
          imu.acceleration = imu.acceleration + Vec3{noise(), noise(), noise()};
          out.value = imu;
          break;
        }
        case SensorType::Laser: {
          LaserReading scan;
          scan.sensorPose = linkPose(static_cast<int>(r), spec.link) * spec.pose;
          scan.minRange = spec.minRange;
          scan.maxRange = spec.maxRange;
          scan.angleMin = -spec.fov / 2;
          scan.angleStep = spec.beams > 1 ? spec.fov / (spec.beams - 1) : 0;
          scan.ranges.resize(static_cast<size_t>(spec.beams));
          // The scanner never sees the link it sits in; the rest of its
          // robot only without exclude_self.
          const int excludeLink = spec.excludeSelf ? -1 : spec.link;
          castFan(scan.sensorPose, scan.angleMin, scan.angleStep, spec.maxRange, static_cast<int>(r), excludeLink,
                  scan.ranges);
          for (double& range : scan.ranges) {
            if (std::isfinite(range)) {
              range += noise();
              if (range < spec.minRange) range = std::nan("");
              else if (range > spec.maxRange) range = LaserReading::kNoReturn;
            }
          }
          out.value = std::move(scan);
          break;
        }
      }
      sampledLastStep_.emplace_back(static_cast<int>(r), static_cast<int>(si));
    }
  }
}

const SensorSample& World::sensorSample(int robot, int sensor) const {
  return impl_->robots[robot].sensors[sensor].latest;
}

void World::prepareRayTargets(int excludeRobot, int excludeLink) const {
  Impl& m = *impl_;
  m.rayTargets.clear();
  const int geoms = dSpaceGetNumGeoms(m.space);
  for (int gi = 0; gi < geoms; ++gi) {
    dGeomID g = dSpaceGetGeom(m.space, gi);
    if (g == m.terrainGeom) continue;
    const auto* info = static_cast<const GeomInfo*>(dGeomGetData(g));
    if (excludeRobot >= 0 && info->robot == excludeRobot && (excludeLink < 0 || info->link == excludeLink)) continue;
    Impl::RayTarget& t = m.rayTargets.emplace_back();
    t.geom = g;
    dGeomGetAABB(g, t.box.data());
  }
}

double World::castPrepared(Vec3 origin, Vec3 direction, double maxRange) const {
  Impl& m = *impl_;
  double best = LaserReading::kNoReturn;
  // Terrain: analytically for a plane; by walking the grid for a heightfield
  // (ODE's own ray against a heightfield costs 10 to 5000 times more).
  if (!m.heightData) {
    if (direction.z < 0) {
      const double t = (m.planeHeight - origin.z) / direction.z;
      if (t >= 0 && t <= maxRange) best = t;
      else if (t < 0) best = 0;  // the origin is below the plane
    }
  } else {
    const Pose& tp = model_.terrain.pose;
    const Quat toGrid = conjugate(tp.q);
    const std::optional<double> t =
        intersectRay(*m.grid, rotate(toGrid, origin - tp.p), rotate(toGrid, direction), maxRange);
    if (t) best = *t;
  }
  // Objects and robot bodies through ODE's ray, after a slab test against
  // each geom's bounding box.
  const double reach = std::min(maxRange, best);
  const double o[3] = {origin.x, origin.y, origin.z}, d[3] = {direction.x, direction.y, direction.z};
  bool raySet = false;
  for (const Impl::RayTarget& t : m.rayTargets) {
    double lo = 0, hi = reach;
    for (int a = 0; a < 3 && lo <= hi; ++a) {
      if (d[a] == 0) {
        if (o[a] < t.box[2 * a] || o[a] > t.box[2 * a + 1]) hi = -1;
        continue;
      }
      double t0 = (t.box[2 * a] - o[a]) / d[a], t1 = (t.box[2 * a + 1] - o[a]) / d[a];
      if (t0 > t1) std::swap(t0, t1);
      lo = std::max(lo, t0);
      hi = std::min(hi, t1);
    }
    if (lo > hi || lo > best) continue;
    if (!raySet) {
      dGeomRaySetLength(m.ray, reach);
      dGeomRaySet(m.ray, origin.x, origin.y, origin.z, direction.x, direction.y, direction.z);
      raySet = true;
    }
    dContactGeom hit;
    if (dCollide(m.ray, t.geom, 1, &hit, sizeof hit) > 0 && hit.depth < best) best = hit.depth;
  }
  return best <= maxRange ? best : LaserReading::kNoReturn;
}

void World::castFan(const Pose& pose, double angleMin, double angleStep, double maxRange, int excludeRobot,
                    int excludeLink, std::vector<double>& ranges) const {
  prepareRayTargets(excludeRobot, excludeLink);
  for (size_t b = 0; b < ranges.size(); ++b) {
    const double a = angleMin + static_cast<double>(b) * angleStep;
    ranges[b] = castPrepared(pose.p, rotate(pose.q, {std::cos(a), std::sin(a), 0}), maxRange);
  }
}

double World::castRay(Vec3 origin, Vec3 direction, double maxRange, int excludeRobot, int excludeLink) const {
  prepareRayTargets(excludeRobot, excludeLink);
  return castPrepared(origin, direction, maxRange);
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
    dGeomHeightfieldDataSetBounds(m.heightData, m.grid->minHeight(), m.grid->maxHeight());
    const dReal* pos = dGeomGetPosition(m.terrainGeom);
    dGeomSetPosition(m.terrainGeom, pos[0], pos[1], pos[2]);
  }
  m.queue = s.pending;
  steps_ = newSteps;
  health_ = {};
  return {};
}

uint64_t World::stateHash() const {
  const Impl& m = *impl_;
  uint64_t h = 0xcbf29ce484222325ULL;
  hashValue(h, steps_);
  for (dBodyID b : m.allBodies) {
    const BodyState s = readBody(b);
    hashValue(h, s);
  }
  for (const Impl::Robot& rt : m.robots) {
    for (const ActuatorState& a : rt.control.actuators) {
      hashValue(h, a.mode);
      hashValue(h, a.velocity);
      hashValue(h, a.target);
      hashValue(h, a.torque);
      hashValue(h, a.integral);
    }
    hashValue(h, rt.control.driveActive);
    hashValue(h, rt.control.driveSpeed);
    hashValue(h, rt.control.driveArticulation);
    hashValue(h, rt.control.driveByYawRate);
    hashValue(h, rt.control.driveYawRate);
    hashValue(h, rt.control.gaitActive);
    hashValue(h, rt.control.gait);
    for (const SensorState& st : rt.sensors) {
      hashValue(h, st.nextStep);
      hashValue(h, st.forceSum);
      hashValue(h, st.stepsSummed);
    }
  }
  hashValue(h, m.randState);
  hashValue(h, m.random.state());
  return h;
}

uint64_t World::modelKey() const {
  // The layout a snapshot must fit: names and kinds of bodies, joints,
  // actuators and sensors (not masses or gains: a snapshot may be restored
  // into a world with other parameters on purpose, e.g. a coarser step).
  uint64_t h = 0xcbf29ce484222325ULL;
  for (const std::string& n : impl_->bodyNames) hashBytes(h, n.data(), n.size());
  for (const RobotInstance& r : model_.robots) {
    for (const JointSpec& j : r.model.joints) {
      hashBytes(h, j.name.data(), j.name.size());
      hashValue(h, j.type);
    }
    for (const ActuatorSpec& a : r.model.actuators) hashValue(h, a.joint);
    for (const SensorSpec& sp : r.model.sensors) hashValue(h, sp.type);
  }
  return h;
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

bool World::setTerrainHeights(const std::vector<double>& heights) {
  Impl& m = *impl_;
  if (!m.heightData || heights.size() != m.grid->heights.size()) return false;
  if (m.grid.use_count() > 1) m.grid = std::make_shared<HeightGrid>(*m.grid);  // a snapshot shares it
  m.grid->heights = heights;
  dGeomHeightfieldDataSetBounds(m.heightData, m.grid->minHeight(), m.grid->maxHeight());
  // The bounds feed the geom's AABB, which ODE recomputes only for a moved
  // geom: setting the same position marks it dirty.
  const dReal* pos = dGeomGetPosition(m.terrainGeom);
  dGeomSetPosition(m.terrainGeom, pos[0], pos[1], pos[2]);
  m.penetrationCheckFrom = steps_ + std::llround(1.0 / params_.step);
  return true;
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
