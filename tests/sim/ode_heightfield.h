#pragma once
// ODE's own heightfield geom, built from a HeightGrid exactly as
// sim/world_build.cpp builds the terrain: the reference our ray caster and
// sphere collider are compared with (tst_height_grid_ray,
// tst_height_grid_sphere). Needs dInitODE2 in the test.

#include <ode/ode.h>

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "sim/height_grid.h"
#include "sim/math.h"

namespace sp::test {

/// ODE for the calling thread (a test's initTestCase; dCloseODE in cleanupTestCase).
inline void initOde() {
  dInitODE2(0);
  dAllocateODEDataForThread(dAllocateMaskAll);
}

/// ODE's heightfield geom, and an ODE ray and sphere to collide with it.
class OdeHeightfield {
 public:
  explicit OdeHeightfield(const sp::HeightGrid& grid) : grid_(grid) {
    data_ = dGeomHeightfieldDataCreate();
    dGeomHeightfieldDataBuildCallback(data_, &grid_, &OdeHeightfield::heightAt, grid_.width, grid_.depth,
                                      grid_.columns, grid_.rows, 1.0, 0.0, 1.0, 0);
    dGeomHeightfieldDataSetBounds(data_, grid_.minHeight(), grid_.maxHeight());
    geom_ = dCreateHeightfield(nullptr, data_, 1);
    // ODE's heightfield is y-up: turn it +90 deg about x so heights point up z.
    const sp::Quat q = sp::quatFromAxisAngle({1, 0, 0}, sp::kPi / 2);
    const dQuaternion oq = {q.w, q.x, q.y, q.z};
    dGeomSetQuaternion(geom_, oq);
    dGeomSetPosition(geom_, 0, 0, 0);
    ray_ = dCreateRay(nullptr, 1.0);
    sphere_ = dCreateSphere(nullptr, 1.0);
  }
  ~OdeHeightfield() {
    dGeomDestroy(sphere_);
    dGeomDestroy(ray_);
    dGeomDestroy(geom_);
    dGeomHeightfieldDataDestroy(data_);
  }
  OdeHeightfield(const OdeHeightfield&) = delete;
  OdeHeightfield& operator=(const OdeHeightfield&) = delete;

  // The nearest of all contacts (ODE reports one per triangle plane crossed,
  // in no particular order); the contact depth of a ray is its distance.
  std::optional<double> cast(Vec3 origin, Vec3 dir, double range) {
    dGeomRaySetLength(ray_, range);
    dGeomRaySet(ray_, origin.x, origin.y, origin.z, dir.x, dir.y, dir.z);
    const int n = dCollide(geom_, ray_, kMaxContacts, contacts_.data(), sizeof(dContactGeom));
    overflowed_ = overflowed_ || n >= kMaxContacts;
    std::optional<double> best;
    for (int k = 0; k < n; ++k)
      if (!best || contacts_[static_cast<std::size_t>(k)].depth < *best) best = contacts_[static_cast<std::size_t>(k)].depth;
    return best;
  }
  bool overflowed() const { return overflowed_; }

  /// ODE's contacts of a sphere with the heightfield (sphere first: the
  /// normals push it out).
  std::vector<dContactGeom> sphere(Vec3 centre, double radius) {
    dGeomSphereSetRadius(sphere_, radius);
    dGeomSetPosition(sphere_, centre.x, centre.y, centre.z);
    const int n = dCollide(sphere_, geom_, kMaxContacts, contacts_.data(), sizeof(dContactGeom));
    return {contacts_.begin(), contacts_.begin() + n};
  }

 private:
  static constexpr int kMaxContacts = 1024;

  static dReal heightAt(void* data, int x, int z) {
    const sp::HeightGrid& g = *static_cast<const sp::HeightGrid*>(data);
    // ODE row z is our row rows-1-z (its z axis points to our -y).
    return g.at(x, g.rows - 1 - z);
  }

  sp::HeightGrid grid_;
  dHeightfieldDataID data_ = nullptr;
  dGeomID geom_ = nullptr;
  dGeomID ray_ = nullptr;
  dGeomID sphere_ = nullptr;
  std::array<dContactGeom, kMaxContacts> contacts_{};
  bool overflowed_ = false;
};

}  // namespace sp::test
