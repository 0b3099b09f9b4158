#include "sim/world.h"

#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <mutex>

#include "sim/command_file.h"

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

void ensureOdeThread() {
  std::call_once(gOdeInit, [] { dInitODE2(0); });
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
};

}  // namespace

struct World::Impl {
  struct Robot {
    std::vector<dBodyID> bodies;     // per link
    std::vector<Vec3> comOffset;     // per link: centre of mass in the link frame
    std::vector<dJointID> joints;    // per joint
    std::vector<ActuatorState> actuators;
    bool driveActive = false;
    double driveSpeed = 0;
    double driveArticulation = 0;
  };

  dWorldID world = nullptr;
  dSpaceID space = nullptr;
  dJointGroupID contacts = nullptr;
  dThreadingImplementationID threading = nullptr;
  unsigned long randState = 0;
  bool perThreadRandom = true;

  std::deque<GeomInfo> geomInfos;  // stable addresses for dGeomSetData
  std::vector<Robot> robots;
  std::vector<dBodyID> objectBodies;  // nullptr for static objects
  std::vector<std::vector<dGeomID>> objectGeoms;
  std::vector<Pose> staticObjectPoses;

  dGeomID terrainGeom = nullptr;
  dHeightfieldDataID heightData = nullptr;
  HeightGrid grid;  // live heights, read by the ODE callback
  double planeHeight = 0;

  std::vector<dSurfaceParameters> surfaces;  // (materials+1)^2 table
  int materialCount = 0;

  struct Candidate {
    int lo, hi, order;
    dGeomID g1, g2;
    dContactGeom geom;
  };
  std::vector<Candidate> candidates;
  std::vector<dContactGeom> scratch;

  std::vector<std::pair<int, Command>> queue;

  const dSurfaceParameters& surface(int a, int b) const {
    return surfaces[static_cast<size_t>((a + 1) * (materialCount + 1) + (b + 1))];
  }

  GeomInfo& newInfo(int material, int robot, int link) {
    GeomInfo& info = geomInfos.emplace_back();
    info.index = static_cast<int>(geomInfos.size()) - 1;
    info.material = material;
    info.robot = robot;
    info.link = link;
    return info;
  }

  static dReal heightAt(void* data, int x, int z) {
    const HeightGrid& g = *static_cast<const HeightGrid*>(data);
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

World::World(const WorldModel& model, const SimParams& params)
    : model_(model), params_(params), impl_(std::make_unique<Impl>()) {}

std::unique_ptr<World> World::create(const WorldModel& model, const SimParams& params, Diagnostics& diag) {
  ensureOdeThread();
  std::unique_ptr<World> w(new World(model, params));
  if (!w->build(diag)) return nullptr;
  return w;
}

World::~World() {
  Impl& m = *impl_;
  if (!m.world) return;
  ensureOdeThread();
  dJointGroupDestroy(m.contacts);
  dSpaceDestroy(m.space);  // destroys the geoms too (cleanup mode on)
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
    m.grid = t.grid;
    if (m.grid.columns < 2 || m.grid.rows < 2) {
      diag.error(model_.file, t.line, "terrain: heightfield has no data");
      return false;
    }
    m.heightData = dGeomHeightfieldDataCreate();
    dGeomHeightfieldDataBuildCallback(m.heightData, &m.grid, &Impl::heightAt, m.grid.width, m.grid.depth,
                                      m.grid.columns, m.grid.rows, 1.0, 0.0, 1.0, 0);
    dGeomHeightfieldDataSetBounds(m.heightData, m.grid.minHeight(), m.grid.maxHeight());
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
  for (const ObjectSpec& o : model_.objects) {
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
      dGeomSetData(geom, &m.newInfo(materialIndex(model_, g.material), -1, -1));
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
  }

  // Robots.
  for (size_t r = 0; r < model_.robots.size(); ++r) {
    const RobotInstance& inst = model_.robots[r];
    const RobotModel& robot = inst.model;
    Impl::Robot& rt = m.robots.emplace_back();
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
        dGeomSetData(geom, &m.newInfo(materialIndex(model_, g.material), static_cast<int>(r),
                                      static_cast<int>(li)));
        dGeomSetBody(geom, body);
        setGeomOffset(geom, Pose{-com, {}} * g.pose);
      }
      rt.bodies.push_back(body);
      rt.comOffset.push_back(com);
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
    for (const ActuatorSpec& a : robot.actuators) rt.actuators.push_back(initialActuatorState(a));
  }
  return true;
}

std::string World::submit(const Command& command, int robot) {
  if (robot < 0 || robot >= robotCount()) return "no robot " + std::to_string(robot);
  std::string error = checkCommand(command, robotModel(robot));
  if (!error.empty()) return error;
  impl_->queue.emplace_back(robot, command);
  return {};
}

void World::applyCommand(const Command& command, int robot) {
  Impl::Robot& rt = impl_->robots[robot];
  const RobotModel& model = robotModel(robot);
  auto actuatorOf = [&](const std::string& joint) { return model.findActuator(joint); };
  auto cancelDriveIfDriveJoint = [&](int actuator) {
    if (!model.drive) return;
    const int joint = model.actuators[actuator].joint;
    const DriveSpec& d = *model.drive;
    if (joint == d.articulation || std::find(d.wheels.begin(), d.wheels.end(), joint) != d.wheels.end())
      rt.driveActive = false;
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
          setMode(rt.actuators[a], JointMode::Velocity);
          rt.actuators[a].velocity = c.velocity;
        } else if constexpr (std::is_same_v<T, JointTargetCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.actuators[a], JointMode::Position);
          rt.actuators[a].target = c.position;
        } else if constexpr (std::is_same_v<T, JointTorqueCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.actuators[a], JointMode::Torque);
          rt.actuators[a].torque = c.torque;
        } else if constexpr (std::is_same_v<T, JointModeCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.actuators[a], c.mode);
        } else if constexpr (std::is_same_v<T, WheelsCmd>) {
          rt.driveActive = false;
          for (int w = 0; w < 4; ++w) {
            const int a = actuatorOf(model.joints[model.drive->wheels[w]].name);
            setMode(rt.actuators[a], JointMode::Velocity);
            rt.actuators[a].velocity = c.omega[w];
          }
        } else if constexpr (std::is_same_v<T, DriveCmd>) {
          rt.driveActive = true;
          rt.driveSpeed = c.speed;
          rt.driveArticulation = c.articulation;
        } else if constexpr (std::is_same_v<T, StopCmd>) {
          // Wheels and speed-driven joints brake; joints with a position
          // controller hold where they are now; free joints stay free.
          rt.driveActive = false;
          for (size_t a = 0; a < model.actuators.size(); ++a) {
            ActuatorState& s = rt.actuators[a];
            const ActuatorSpec& spec = model.actuators[a];
            if (s.mode == JointMode::Free) continue;
            bool isWheel = false;
            if (model.drive)
              for (int w : model.drive->wheels) isWheel = isWheel || w == spec.joint;
            if (spec.hasPid && spec.kp > 0 && !isWheel) {
              setMode(s, JointMode::Position);
              s.target = jointPosition(robot, spec.joint);
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
    if (rt.driveActive && model.drive) {
      const DriveSpec& d = *model.drive;
      const std::array<double, 4> w =
          articulatedWheelSpeeds(*driveGeometry(static_cast<int>(r)), rt.driveSpeed, d.wheelRadius);
      for (int i = 0; i < 4; ++i) {
        ActuatorState& s = rt.actuators[model.findActuator(model.joints[d.wheels[i]].name)];
        s.mode = JointMode::Velocity;
        s.velocity = w[i];
      }
      ActuatorState& art = rt.actuators[model.findActuator(model.joints[d.articulation].name)];
      if (art.mode != JointMode::Position) art.integral = 0;
      art.mode = JointMode::Position;
      art.target = rt.driveArticulation;
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
          updateActuator(spec, rt.actuators[a], jointPosition(static_cast<int>(r), spec.joint), rate, dt);
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
  for (const Impl::Candidate& c : m.candidates) {
    const auto* i1 = static_cast<const GeomInfo*>(dGeomGetData(c.g1));
    const auto* i2 = static_cast<const GeomInfo*>(dGeomGetData(c.g2));
    dContact contact{};
    contact.surface = m.surface(i1->material, i2->material);
    contact.geom = c.geom;
    dJointID j = dJointCreateContact(m.world, m.contacts, &contact);
    dJointAttach(j, dGeomGetBody(c.g1), dGeomGetBody(c.g2));
  }
  lastContactCount_ = static_cast<int>(m.candidates.size());
}

void World::step() {
  Impl& m = *impl_;
  ensureOdeThread();
  for (const auto& [robot, command] : m.queue) applyCommand(command, robot);
  m.queue.clear();
  runActuators();
  collide();
  std::unique_lock<std::mutex> fallback;
  if (!m.perThreadRandom) fallback = std::unique_lock<std::mutex>(gStepFallbackMutex);
  tOdeRandState = m.randState;
  if (params_.solver == Solver::Quick) dWorldQuickStep(m.world, params_.step);
  else dWorldStep(m.world, params_.step);
  m.randState = tOdeRandState;
  dJointGroupEmpty(m.contacts);
  ++steps_;
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
  return impl_->robots[robot].actuators[actuator];
}

Pose World::objectPose(int object) const {
  dBodyID b = impl_->objectBodies[object];
  if (!b) return impl_->staticObjectPoses[object];
  const ObjectSpec& o = model_.objects[object];
  const dMass mass = massOf(o.geoms, o.mass);
  return bodyPose(b) * Pose{Vec3{-mass.c[0], -mass.c[1], -mass.c[2]}, {}};
}

const HeightGrid* World::terrainGrid() const {
  return impl_->heightData ? &impl_->grid : nullptr;
}

double World::terrainHeight(double x, double y) const {
  const Impl& m = *impl_;
  if (!m.heightData) return m.planeHeight;
  const Pose& p = model_.terrain.pose;
  const Vec3 local = rotate(conjugate(p.q), Vec3{x, y, 0} - Vec3{p.p.x, p.p.y, 0});
  return m.grid.heightAt(local.x, local.y) + p.p.z;
}

bool World::setTerrainHeights(const std::vector<double>& heights) {
  Impl& m = *impl_;
  if (!m.heightData || heights.size() != m.grid.heights.size()) return false;
  m.grid.heights = heights;
  dGeomHeightfieldDataSetBounds(m.heightData, m.grid.minHeight(), m.grid.maxHeight());
  // The bounds feed the geom's AABB, which ODE recomputes only for a moved
  // geom: setting the same position marks it dirty.
  const dReal* pos = dGeomGetPosition(m.terrainGeom);
  dGeomSetPosition(m.terrainGeom, pos[0], pos[1], pos[2]);
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
