// Collision: the candidate contacts of a step, put in a canonical order so
// that the solution depends on the state alone, then made ODE contact joints.

#include "sim/world_impl.h"

#include <algorithm>

namespace sp {
using namespace world_detail;

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
  const int n = dCollide(g1, g2, static_cast<int>(scratch.size()), scratch.data(), sizeof(dContactGeom));
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
    if (wheel && options_.sensors) {
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
