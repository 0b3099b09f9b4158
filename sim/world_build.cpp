// Building the ODE world from the model: bodies with their mass properties,
// geoms, joints, the terrain, the contact table; and tearing it down.

#include "sim/world_impl.h"

#include <algorithm>
#include <tuple>

namespace sp {
using namespace world_detail;
namespace {

// The broad phase. For the few geoms of a robot on its terrain (31 for
// WorkPartner on flat ground) ODE's simple space, which tests every pair's
// boxes, makes a rehearsal ~11 % faster than the hash space, whose every
// collide call allocates its cells; at 131 geoms it is still 6 % faster, at
// 231 46 % slower (docs/performance-log.md "The broad phase"). Results are the
// same in either: World::collide sorts the contacts by our own geom
// indices, whatever order a space gives the pairs.
constexpr size_t kSimpleSpaceGeoms = 128;

dSpaceID collisionSpaceFor(const WorldModel& world) {
  size_t geoms = 1;  // the terrain
  for (const ObjectSpec& o : world.objects) geoms += o.geoms.size();
  for (const RobotInstance& r : world.robots)
    for (const LinkSpec& link : r.model.links) geoms += link.geoms.size();
  return geoms <= kSimpleSpaceGeoms ? dSimpleSpaceCreate(nullptr) : dHashSpaceCreate(nullptr);
}

/// Mass properties of `geoms` (in their owner's frame) with `total` mass
/// spread by volume, or with each geom's own mass when every geom has one
/// (a link holdRigid() merged). A geom-less link gets a 5 cm sphere's inertia.
dMass massOf(const std::vector<GeomSpec>& geoms, double total) {
  dMass sum;
  dMassSetZero(&sum);
  double volume = 0;
  for (const GeomSpec& g : geoms) volume += geomVolume(g);
  const bool ownMasses =
      !geoms.empty() && std::all_of(geoms.begin(), geoms.end(), [](const GeomSpec& g) { return g.mass >= 0; });
  if (!ownMasses && (geoms.empty() || volume <= 0)) {
    dMassSetSphereTotal(&sum, total, 0.05);
    return sum;
  }
  for (const GeomSpec& g : geoms) {
    const double m = ownMasses ? g.mass : total * geomVolume(g) / volume;
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

}  // namespace

MassProperties massProperties(const LinkSpec& link) {
  dMass mass = massOf(link.geoms, link.mass);
  const Vec3& shift = link.centreOfMassShift;
  dMassTranslate(&mass, shift.x, shift.y, shift.z);
  MassProperties out;
  out.mass = mass.mass;
  out.centre = {mass.c[0], mass.c[1], mass.c[2]};
  dMassTranslate(&mass, -out.centre.x, -out.centre.y, -out.centre.z);  // about the centre
  // dMass::I is a row-major 3x4 matrix.
  out.ixx = mass.I[0];
  out.iyy = mass.I[5];
  out.izz = mass.I[10];
  out.ixy = mass.I[1];
  out.ixz = mass.I[2];
  out.iyz = mass.I[6];
  return out;
}

namespace {

dSurfaceParameters toSurface(const ContactSpec& c, double step) {
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
  if (c.stiffness > 0) {
    s.mode |= dContactSoftERP | dContactSoftCFM;
    std::tie(s.soft_erp, s.soft_cfm) = springDamper(c.stiffness, c.damping, step);
  }
  if (c.rollingResistance > 0) {
    // Without dContactAxisDep ODE applies rho about all three axes, the
    // spinning one too, and ignores rho2 and rhoN. With it, mu2 is used for
    // the second friction direction: the same mu keeps friction isotropic.
    s.mode |= dContactRolling | dContactAxisDep;
    s.mu2 = c.mu;
    s.rho = c.rollingResistance;
    s.rho2 = c.rollingResistance;
    s.rhoN = 0;  // rolling resistance resists rolling, not spinning in place
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

dReal World::Impl::heightAt(void* data, int x, int z) {
  const HeightGrid& g = *static_cast<const Impl*>(data)->grid;
  // ODE's heightfield is y-up with z rows; rotated +90 deg about x its z
  // axis points to world -y, so ODE row z is our row rows-1-z.
  return g.at(x, g.rows - 1 - z);
}

std::unique_ptr<World> World::create(const WorldModel& model, const SimParams& params, Diagnostics& diag,
                                     WorldOptions options) {
  ensureOdeThread();
  std::unique_ptr<World> w(new World(model, params, options));
  // A model the loader passed can still be one ODE refuses (a mass a fit
  // or a perturbation made not positive definite): an error, not abort().
  try {
    if (!w->build(diag)) return nullptr;
  } catch (const OdeFailure& failure) {
    w->impl_->broken = true;
    diag.error(model.robots.empty() ? std::string_view{} : std::string_view(model.robots[0].model.file), 0,
               std::string("ODE refused the model: ") + failure.what());
    return nullptr;
  }
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
  // After an engine failure the exception left ODE's job list mid-step, and
  // freeing it asserts (abort: exit 134 where the failure was reported as
  // exit 3). It is left allocated: a few hundred bytes per failed world.
  if (!m.broken) dThreadingFreeImplementation(m.threading);
}

const char* World::broadPhase() const {
  return dSpaceGetClass(impl_->space) == dSimpleSpaceClass ? "simple" : "hash";
}

bool World::build(Diagnostics& diag) {
  Impl& m = *impl_;
  m.world = dWorldCreate();
  // Each world its own threading implementation: worlds sharing ODE's global
  // one abort when stepped in parallel (shared/STACK.md).
  m.threading = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(m.world, dThreadingImplementationGetFunctions(m.threading),
                                       m.threading);
  m.space = collisionSpaceFor(model_);
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
  m.resistances.resize(static_cast<size_t>(n * n));
  for (int a = -1; a < m.materialCount; ++a)
    for (int b = -1; b < m.materialCount; ++b) {
      const std::string& na = a < 0 ? std::string() : model_.materials[a];
      const std::string& nb = b < 0 ? std::string() : model_.materials[b];
      const ContactSpec& c = model_.contactFor(na, nb);
      m.surfaces[static_cast<size_t>((a + 1) * n + (b + 1))] = toSurface(c, params_.step);
      m.resistances[static_cast<size_t>((a + 1) * n + (b + 1))] = {c.motionResistance, c.motionResistanceSliding};
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
    m.setTerrainBounds(g.minHeight(), g.maxHeight());
    m.terrainGeom = dCreateHeightfield(m.space, m.heightData, 1);
    // ODE's heightfield is y-up: turn it +90 deg about x so heights point up z.
    const Quat q = t.pose.q * quatFromAxisAngle({1, 0, 0}, kPi / 2);
    dQuaternion oq;
    toOde(q, oq);
    dGeomSetQuaternion(m.terrainGeom, oq);
    dGeomSetPosition(m.terrainGeom, t.pose.p.x, t.pose.p.y, t.pose.p.z);
    m.terrainPose = t.pose;
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
    std::vector<bool> wheelLink(robot.links.size(), false);
    if (robot.drive)
      for (int j : robot.drive->wheels)
        if (j >= 0) wheelLink[static_cast<size_t>(robot.joints[j].child)] = true;
    const std::string prefix = model_.robots.size() > 1 ? "robot '" + inst.name + "' " : "";
    for (size_t li = 0; li < robot.links.size(); ++li) {
      const LinkSpec& link = robot.links[li];
      dMass mass = massOf(link.geoms, link.mass);
      const Vec3& shift = link.centreOfMassShift;
      if (shift.x != 0 || shift.y != 0 || shift.z != 0) dMassTranslate(&mass, shift.x, shift.y, shift.z);
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
        if (g.type == GeomType::Cylinder || g.type == GeomType::Sphere) info.rollRadius = g.radius;
        if (g.type == GeomType::Cylinder && wheelLink[li]) {
          info.tyre = true;
          if (robot.drive->tyreStiffness > 0)
            std::tie(info.tyreErp, info.tyreCfm) =
                springDamper(robot.drive->tyreStiffness, robot.drive->tyreDamping, params_.step);
        }
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
    rt.control.resistance.assign(robot.links.size(), 0.0);
    rt.control.resistanceShare.assign(robot.links.size(), 1.0);
    rt.control.resistanceHold.assign(robot.links.size(), 0.0);
    rt.jointAbove.assign(robot.links.size(), -1);
    for (size_t ji = 0; ji < robot.joints.size(); ++ji)
      rt.jointAbove[static_cast<size_t>(robot.joints[ji].child)] = static_cast<int>(ji);
    rt.rollRadius.assign(robot.links.size(), 0.0);
    for (size_t li = 0; li < robot.links.size(); ++li)
      for (const GeomSpec& g : robot.links[li].geoms)
        if (g.type == GeomType::Cylinder || g.type == GeomType::Sphere)
          rt.rollRadius[li] = std::max(rt.rollRadius[li], g.radius);
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

}  // namespace sp
