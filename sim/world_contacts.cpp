// Collision: the candidate contacts of a step, put in a canonical order so
// that the solution depends on the state alone, then made ODE contact joints.

#include "sim/world_impl.h"

#include <algorithm>
#include <array>

#include "sim/height_grid_sphere.h"

namespace sp {
using namespace world_detail;

namespace {

// A tyre on its side touches a surface along a line, and ODE reports the
// line's two ends (the rims). Kept apart, they let a rigid solver put a
// wheel's load on either rim at will, and on soft tyres they make the wheel
// scrub like a 10 cm wide skid as it yaws through a turn (the articulated
// drive then left its kinematic circle by 3 %). A tyre's patch is one point:
// contacts whose normals agree within 5 degrees become one at their mean
// position, as deep as the deepest; ones on other facets (a step's edge)
// stay apart.
int mergeTyrePatch(dContactGeom* c, int n) {
  int kept = 0;
  std::array<int, 64> count{};  // physics.max_contacts is at most 64
  for (int k = 0; k < n; ++k) {
    int into = -1;
    for (int j = 0; j < kept && into < 0; ++j)
      if (dCalcVectorDot3(c[j].normal, c[k].normal) > 0.996) into = j;
    if (into < 0) {
      count[static_cast<size_t>(kept)] = 1;
      c[kept++] = c[k];
      continue;
    }
    dContactGeom& m = c[into];
    const double w = 1.0 / ++count[static_cast<size_t>(into)];
    for (int a = 0; a < 3; ++a) {
      m.pos[a] += w * (c[k].pos[a] - m.pos[a]);
      m.normal[a] += w * (c[k].normal[a] - m.normal[a]);
    }
    dNormalize3(m.normal);
    m.depth = std::max(m.depth, c[k].depth);
  }
  return kept;
}

}  // namespace

// A tyre meets a heightfield as a sphere of its rolling radius at its
// centre, which touches ground where the tyre does on level ground and
// within the tread's half-width on side slopes up to about 14 degrees
// (asin(0.05 / 0.2)). ODE's cylinder path threw a wheel 9 cm into the ground
// at a crease between two triangles (tst_terrain_edit
// whatPassesTheCheckIsDriven); ODE's sphere path misses ridges
// (sim/height_grid_sphere.h), so the sphere is collided here, with the
// grid ODE reads.
int World::Impl::collidePair(dGeomID g1, dGeomID g2, dContactGeom* out, int max) {
  const auto* i1 = static_cast<const GeomInfo*>(dGeomGetData(g1));
  const auto* i2 = static_cast<const GeomInfo*>(dGeomGetData(g2));
  const bool tyreFirst = i1->tyre && dGeomGetClass(g2) == dHeightfieldClass;
  if (tyreFirst || (i2->tyre && dGeomGetClass(g1) == dHeightfieldClass)) {
    const dReal* p = dGeomGetPosition(tyreFirst ? g1 : g2);
    const Vec3 local = rotate(conjugate(terrainPose.q), Vec3{p[0], p[1], p[2]} - terrainPose.p);
    std::array<SurfaceContact, 64> found;
    const int n = sphereContacts(*grid, local, (tyreFirst ? i1 : i2)->rollRadius, found.data(),
                                 std::min(max, static_cast<int>(found.size())));
    // ODE's convention: the normal pushes the first geom out of the second.
    const double sign = tyreFirst ? 1.0 : -1.0;
    for (int k = 0; k < n; ++k) {
      const Vec3 at = terrainPose.p + rotate(terrainPose.q, found[static_cast<size_t>(k)].position);
      const Vec3 normal = sign * rotate(terrainPose.q, found[static_cast<size_t>(k)].normal);
      out[k] = dContactGeom{};
      out[k].pos[0] = at.x, out[k].pos[1] = at.y, out[k].pos[2] = at.z;
      out[k].normal[0] = normal.x, out[k].normal[1] = normal.y, out[k].normal[2] = normal.z;
      out[k].depth = found[static_cast<size_t>(k)].depth;
      out[k].g1 = g1, out[k].g2 = g2;
      out[k].side1 = out[k].side2 = -1;
    }
    return n;
  }
  return dCollide(g1, g2, max, out, sizeof(dContactGeom));
}

void World::Impl::nearCallback(void* data, dGeomID g1, dGeomID g2) {
  static_cast<Impl*>(data)->near(g1, g2);
}

void World::Impl::near(dGeomID g1, dGeomID g2) {
  dBodyID b1 = dGeomGetBody(g1), b2 = dGeomGetBody(g2);
  if (b1 == b2) return;  // same body, or two static geoms
  if (b1 && b2 && dAreConnectedExcluding(b1, b2, dJointTypeContact)) return;
  auto* i1 = static_cast<GeomInfo*>(dGeomGetData(g1));
  auto* i2 = static_cast<GeomInfo*>(dGeomGetData(g2));
  if (i1->index > i2->index) {
    std::swap(g1, g2);
    std::swap(i1, i2);
  }
  int n = collidePair(g1, g2, scratch.data(), static_cast<int>(scratch.size()));
  if (i1->tyre || i2->tyre) n = mergeTyrePatch(scratch.data(), n);
  for (int k = 0; k < n; ++k) candidates.push_back({i1->index, i2->index, k, g1, g2, scratch[k]});
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
  m.resisting.clear();
  m.deepest = 0;
  m.deepestContact = nullptr;
  for (size_t k = 0; k < m.candidates.size(); ++k) {
    const Impl::Candidate& c = m.candidates[k];
    const auto* i1 = static_cast<const GeomInfo*>(dGeomGetData(c.g1));
    const auto* i2 = static_cast<const GeomInfo*>(dGeomGetData(c.g2));
    dContact contact{};
    contact.surface = m.surface(i1->material, i2->material);
    // A tyre's compliance, unless the world gives the pair its own.
    const GeomInfo* tyre = i1->tyre ? i1 : (i2->tyre ? i2 : nullptr);
    if (tyre && tyre->tyreCfm >= 0 && !(contact.surface.mode & (dContactSoftERP | dContactSoftCFM))) {
      contact.surface.mode |= dContactSoftERP | dContactSoftCFM;
      contact.surface.soft_erp = tyre->tyreErp;
      contact.surface.soft_cfm = tyre->tyreCfm;
    }
    contact.geom = c.geom;
    dJointID j = dJointCreateContact(m.world, m.contacts, &contact);
    dJointAttach(j, dGeomGetBody(c.g1), dGeomGetBody(c.g2));
    if (c.geom.depth > m.deepest) {
      m.deepest = c.geom.depth;
      m.deepestContact = &c;
    }
    // ODE's contact normal points into the first geom; a wheel sensor wants
    // the force from the ground into the wheel.
    const Vec3 n{c.geom.normal[0], c.geom.normal[1], c.geom.normal[2]};
    const GeomInfo* wheel = i1->wheelSensor >= 0 ? i1 : (i2->wheelSensor >= 0 ? i2 : nullptr);
    if (wheel && (options_.sensors || options_.wheelForces)) {
      dJointSetFeedback(j, &m.contactFeedback[k]);
      const bool first = wheel == i1;
      // ODE fills f1 for the first non-null body it was attached to.
      const bool inF1 = first || dGeomGetBody(c.g1) == nullptr;
      m.wheelContacts.push_back({wheel->robot, wheel->wheelSensor, k, inF1, first ? n : -n});
    }
    // A robot's wheel (cylinder or sphere) on a surface with motion
    // resistance: its normal force sets the resistance of the next step.
    const Impl::Resistance& resist = m.resistance(i1->material, i2->material);
    const GeomInfo* roller = i1->robot >= 0 && i1->rollRadius > 0 ? i1 : (i2->robot >= 0 && i2->rollRadius > 0 ? i2 : nullptr);
    if (roller && resist.c > 0) {
      dJointSetFeedback(j, &m.contactFeedback[k]);
      const bool first = roller == i1;
      const bool inF1 = first || dGeomGetBody(c.g1) == nullptr;
      m.resisting.push_back({roller->robot, roller->link, k, inF1, first ? n : -n, resist.c, resist.sliding,
                             roller->rollRadius});
    }
  }
  lastContactCount_ = static_cast<int>(m.candidates.size());
}

std::vector<LinkContact> World::linkContacts() const {
  std::vector<LinkContact> out;
  for (const Impl::Candidate& c : impl_->candidates) {
    const auto* a = static_cast<const GeomInfo*>(dGeomGetData(c.g1));
    const auto* b = static_cast<const GeomInfo*>(dGeomGetData(c.g2));
    if (a->robot < 0) std::swap(a, b);  // the robot link first
    if (a->robot < 0 || a->link < 0) continue;
    LinkContact k;
    k.robot = a->robot;
    k.link = a->link;
    if (b->robot >= 0) {
      k.otherRobot = b->robot;
      k.otherLink = b->link;
    } else if (b->object >= 0) {
      k.object = b->object;
    } else {
      k.terrain = true;
    }
    k.position = {c.geom.pos[0], c.geom.pos[1], c.geom.pos[2]};
    k.depth = c.geom.depth;
    out.push_back(k);
  }
  return out;
}

}  // namespace sp
