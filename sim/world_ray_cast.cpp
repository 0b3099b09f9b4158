// Rays and laser fans: the terrain by our own grid walk (ODE's ray against a
// heightfield is 10 to 5000 times slower), objects and robots through ODE.

#include "sim/world_impl.h"

#include <algorithm>
#include "sim/height_grid_ray.h"

namespace sp {
using namespace world_detail;

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

}  // namespace sp
