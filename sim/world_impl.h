#pragma once
// Private to the World's implementation files (world*.cpp): the ODE handles
// and the mutable state behind World, shared by its pipeline stages, one
// file per stage as MuJoCo's engine is laid out:
//   world.cpp          the step loop, command queue, ODE's per-thread set-up, read-out
//   world_build.cpp    building the ODE world from the model
//   world_drive.cpp    commands, articulated-steering drive, gaits, actuators
//   world_contacts.cpp collision and contact joints in a canonical order
//   world_health.cpp   divergence checks and their reports
//   world_sensors.cpp  sensor sampling
//   world_ray_cast.cpp rays and laser fans
//   world_snapshot.cpp snapshots, restore, state hash
// Nothing outside sim/world*.cpp includes this header.

#include <ode/ode.h>

#include <array>
#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/random.h"
#include "sim/world.h"

namespace sp {
namespace world_detail {

/// What ODE's error and debug handlers throw in place of abort() (world.cpp).
struct OdeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Initialises ODE once per process and its per-thread data once per
/// thread; every World entry point that touches ODE calls it (world.cpp).
void ensureOdeThread();

inline void toOde(const Quat& q, dQuaternion out) {
  out[0] = q.w;
  out[1] = q.x;
  out[2] = q.y;
  out[3] = q.z;
}

inline Pose bodyPose(dBodyID b) {
  const dReal* p = dBodyGetPosition(b);
  const dReal* q = dBodyGetQuaternion(b);
  return {{p[0], p[1], p[2]}, {q[0], q[1], q[2], q[3]}};
}

/// What a geom belongs to; the index gives contacts a canonical order.
struct GeomInfo {
  int index = 0;
  int material = -1;  // index into WorldModel::materials, -1 = default
  int robot = -1;
  int link = -1;
  int object = -1;
  int wheelSensor = -1;  // a wheel_force sensor on this geom's link
  double rollRadius = 0;  // a robot's cylinder or sphere: the radius it rolls on (motion resistance)
  bool tyre = false;      // a cylinder on a drive wheel: one contact per surface it touches
  double tyreErp = -1, tyreCfm = -1;  // its drive's tyre compliance for this step (-1: rigid)
};

/// ODE's soft ERP and CFM that make a spring k and damper c for a step h
/// (ODE's manual, "Soft constraint and constraint force mixing").
inline std::pair<double, double> springDamper(double k, double c, double h) {
  return {h * k / (h * k + c), 1 / (h * k + c)};
}

inline bool finite(const dReal* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

inline BodyState readBody(dBodyID b) {
  BodyState s;
  std::memcpy(s.position.data(), dBodyGetPosition(b), sizeof s.position);
  std::memcpy(s.quaternion.data(), dBodyGetQuaternion(b), sizeof s.quaternion);
  std::memcpy(s.linearVelocity.data(), dBodyGetLinearVel(b), sizeof s.linearVelocity);
  std::memcpy(s.angularVelocity.data(), dBodyGetAngularVel(b), sizeof s.angularVelocity);
  return s;
}

}  // namespace world_detail

// The ODE side of a World. Stages reach it as `*impl_`.
struct World::Impl {
  using GeomInfo = world_detail::GeomInfo;

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
    std::vector<int> jointAbove;     // per link: the joint whose child it is, -1 for the base
    std::vector<double> rollRadius;  // per link: its largest cylinder or sphere radius (0: none)
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
  double gridMin = 0, gridMax = 0;  // the grid's lowest and highest height (ODE's bounds)
  void setTerrainBounds(double lo, double hi) {
    gridMin = lo;
    gridMax = hi;
    dGeomHeightfieldDataSetBounds(heightData, lo, hi);
  }
  Pose terrainPose;  // the heightfield's (world frame), for collidePair()
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
  struct Resistance {
    double c = 0;         // motion resistance coefficient
    bool sliding = true;  // a sliding wheel meets it too
  };
  std::vector<Resistance> resistances;  // the same table: each pair's motion resistance
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
  // A contact of a robot's wheel with a surface that has motion resistance.
  struct ResistingContact {
    int robot, link;
    size_t feedback;  // index into contactFeedback
    bool wheelInF1;
    Vec3 normal;      // from the ground into the wheel
    double c;         // the surface's motion resistance coefficient
    bool sliding;     // a sliding wheel meets it too
    double radius;    // the wheel's rolling radius
  };
  std::vector<ResistingContact> resisting;
  // Deepest contact of the last collision, for the health check.
  double deepest = 0;
  const Candidate* deepestContact = nullptr;

  std::vector<std::pair<int, Command>> queue;

  const dSurfaceParameters& surface(int a, int b) const {
    return surfaces[static_cast<size_t>((a + 1) * (materialCount + 1) + (b + 1))];
  }
  const Resistance& resistance(int a, int b) const {
    return resistances[static_cast<size_t>((a + 1) * (materialCount + 1) + (b + 1))];
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

  // ODE's heightfield callback: the height of sample (x, z) in ODE's frame
  // (world_build.cpp).
  static dReal heightAt(void* data, int x, int z);
  // ODE's broad-phase callback and the narrow phase of one pair; they
  // gather contact candidates (world_contacts.cpp).
  static void nearCallback(void* data, dGeomID g1, dGeomID g2);
  /// dCollide, except that a tyre meets a heightfield as a sphere of its
  /// radius (world_contacts.cpp says why); the contacts name g1 and g2.
  int collidePair(dGeomID g1, dGeomID g2, dContactGeom* out, int max);
  /// How deep each geom of `bodies` reaches into the terrain (0: not
  /// touching), in the bodies' geom order (world.cpp).
  std::vector<double> terrainDepths(const std::vector<dBodyID>& bodies);
  void near(dGeomID g1, dGeomID g2);
};

}  // namespace sp
