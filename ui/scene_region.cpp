// The 3D view's picture of how sure the ghost is (ui/scene_view_impl.h):
// two translucent discs on the ground about the ghost's base (the inner and
// outer regions), the ghost's faint spread (two fainter ghosts as far ahead
// and behind as the outer region reaches), a band along its trail that widens with the horizon, and
// red marks where the robot departed from its twin; and the rehearsed
// path's band, where the robustness runs went.
#include "ui/scene_view_impl.h"

namespace sp {

namespace {

constexpr int kSegments = 48;
constexpr float kLift = 0.03f;  // [m] above the ground, under the trail's line
// [m] an outer region narrower than this puts the spread inside the ghost: not drawn.
constexpr double kSpreadMin = 0.05;

osg::ref_ptr<osg::Geometry> filled(GLenum mode, osg::Vec4 colour) {
  osg::ref_ptr<osg::Geometry> g = newGeometry();
  g->setVertexArray(new osg::Vec3Array);
  auto* c = new osg::Vec4Array;
  c->push_back(colour);
  g->setColorArray(c, osg::Array::BIND_OVERALL);
  g->addPrimitiveSet(new osg::DrawArrays(mode, 0, 0));
  g->setDataVariance(osg::Object::DYNAMIC);
  return g;
}

void setCount(osg::Geometry* g) {
  auto* v = static_cast<osg::Vec3Array*>(g->getVertexArray());
  v->dirty();
  static_cast<osg::DrawArrays*>(g->getPrimitiveSet(0))->setCount(static_cast<GLsizei>(v->size()));
  g->dirtyBound();
}

// A band along `p` on the ground: each point moved sideways by its radius, both ways.
void fillBand(osg::Geometry* g, const TerrainSpec& terrain, const std::vector<Vec3>& p, const std::vector<double>& radius) {
  auto* v = static_cast<osg::Vec3Array*>(g->getVertexArray());
  v->clear();
  if (radius.size() == p.size() && p.size() > 1)
    for (size_t k = 0; k < p.size(); ++k) {
      const Vec3 a = p[k > 0 ? k - 1 : k], b = p[k + 1 < p.size() ? k + 1 : k];
      const double dx = b.x - a.x, dy = b.y - a.y, d = std::hypot(dx, dy);
      const double nx = d > 1e-9 ? -dy / d : 0, ny = d > 1e-9 ? dx / d : 0;
      for (double side : {1.0, -1.0}) {
        const double x = p[k].x + side * nx * radius[k], y = p[k].y + side * ny * radius[k];
        v->push_back({f(x), f(y), f(groundHeight(terrain, x, y)) + kLift});
      }
    }
  setCount(g);
}

}  // namespace

void SceneView::Impl::buildRegion() {
  Region& r = region;
  r.node = new osg::Geode;
  // The ghost's blue, the outer region fainter than the inner; the band as faint as the outer.
  r.outer = filled(GL_TRIANGLE_FAN, {0.05f, 0.45f, 1.00f, 0.14f});
  r.inner = filled(GL_TRIANGLE_FAN, {0.05f, 0.45f, 1.00f, 0.30f});
  r.bandStrip = filled(GL_TRIANGLE_STRIP, {0.05f, 0.45f, 1.00f, 0.14f});
  for (osg::Geometry* g : {r.bandStrip.get(), r.outer.get(), r.inner.get()}) r.node->addDrawable(g);
  osg::StateSet* s = r.node->getOrCreateStateSet();
  s->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  s->setMode(GL_BLEND, osg::StateAttribute::ON);
  s->setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA), osg::StateAttribute::ON);
  // Tested against the ground, never hiding what is drawn after it.
  s->setAttributeAndModes(new osg::Depth(osg::Depth::LESS, 0.0, 1.0, false), osg::StateAttribute::ON);
  s->setAttributeAndModes(new osg::CullFace(osg::CullFace::BACK), osg::StateAttribute::OFF);
  s->setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
  r.node->setNodeMask(0);
  root->addChild(r.node);
  // The spread: the ghost's link transforms under an offset each, in the
  // ghost's blue at a third of its strength, writing no depth (two faint
  // copies never hide each other or what stands behind).
  for (osg::ref_ptr<osg::MatrixTransform>& spread : r.spread) {
    spread = new osg::MatrixTransform;
    spread->addChild(ghost.body);
    auto* tint = new osg::Material;
    tint->setColorMode(osg::Material::OFF);
    const osg::Vec4 faint{kGhostTint[0], kGhostTint[1], kGhostTint[2], kGhostTint[3] / 3};
    tint->setDiffuse(osg::Material::FRONT_AND_BACK, faint);
    tint->setAmbient(osg::Material::FRONT_AND_BACK, {faint.r() / 2, faint.g() / 2, faint.b() / 2, faint.a()});
    tint->setSpecular(osg::Material::FRONT_AND_BACK, {0, 0, 0, faint.a()});
    osg::StateSet* st = spread->getOrCreateStateSet();
    st->setAttributeAndModes(tint, osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
    st->setMode(GL_BLEND, osg::StateAttribute::ON);
    st->setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA), osg::StateAttribute::ON);
    st->setAttributeAndModes(new osg::Depth(osg::Depth::LESS, 0.0, 1.0, false), osg::StateAttribute::ON);
    st->setAttributeAndModes(new osg::CullFace(osg::CullFace::BACK), osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
    st->setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
    spread->setNodeMask(0);
    root->addChild(spread);
  }
  // The rehearsed path's band: the rehearsal's amber, as faint, the same state.
  r.rehearsalNode = new osg::Geode;
  r.rehearsalStrip = filled(GL_TRIANGLE_STRIP, {1.00f, 0.60f, 0.10f, 0.18f});
  r.rehearsalNode->addDrawable(r.rehearsalStrip);
  r.rehearsalNode->setStateSet(s);
  r.rehearsalNode->setNodeMask(0);
  root->addChild(r.rehearsalNode);
  // Departures: a red ring and a post at each, unlit, over everything near.
  r.marksNode = new osg::Geode;
  r.marks = filled(GL_LINES, {0.85f, 0.10f, 0.10f, 1.0f});
  r.marksNode->addDrawable(r.marks);
  osg::StateSet* m = r.marksNode->getOrCreateStateSet();
  m->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  m->setAttributeAndModes(new osg::LineWidth(3.0f));
  r.marksNode->setNodeMask(0);
  root->addChild(r.marksNode);
}

void SceneView::Impl::syncRegion() {
  Region& r = region;
  const bool shown = ghost.visible && hasRobot && r.outerRadius > 0;
  r.node->setNodeMask(shown ? ~0u : 0u);
  const Vec3 about = ghost.base.p;
  if (shown && (r.dirty || ghost.pathDirty || norm(about - r.drawnAt) > 1e-3)) {
    // A disc draped on the ground: a fan from the ground under the base.
    const auto disc = [&](osg::Geometry* g, double radius) {
      auto* v = static_cast<osg::Vec3Array*>(g->getVertexArray());
      v->clear();
      v->push_back({f(about.x), f(about.y), f(groundHeight(terrain, about.x, about.y)) + kLift});
      const std::vector<osg::Vec3> rim = drapedCircle(terrain, about.x, about.y, radius, kSegments, kLift);
      v->insert(v->end(), rim.begin(), rim.end());
      setCount(g);
    };
    disc(r.outer.get(), r.outerRadius);
    disc(r.inner.get(), r.innerRadius);
    fillBand(r.bandStrip.get(), terrain, ghost.pathPoints, r.band);
    r.drawnAt = about;
    r.dirty = false;
  }
  // The spread follows the ghost's body (drawn only where the ghost is).
  const bool spread = shown && ghost.node->getNodeMask() != 0 && r.outerRadius >= kSpreadMin;
  const Vec3 heading = rotate(ghost.base.q, Vec3{1, 0, 0});
  const double along = std::hypot(heading.x, heading.y);
  for (size_t k = 0; k < r.spread.size(); ++k) {
    r.spread[k]->setNodeMask(spread && along > 1e-6 ? ~0u : 0u);
    const double d = (k == 0 ? 1 : -1) * r.outerRadius / std::max(along, 1e-6);
    r.spread[k]->setMatrix(osg::Matrix::translate(f(heading.x * d), f(heading.y * d), 0.0f));
  }
  r.spreadDrawn = spread && along > 1e-6 ? r.outerRadius : 0;
  const bool rehearsalBand = rehearsal.visible && hasRobot && r.rehearsalBand.size() == rehearsal.pathPoints.size() &&
                             rehearsal.pathPoints.size() > 1;
  r.rehearsalNode->setNodeMask(rehearsalBand ? ~0u : 0u);
  if (r.rehearsalDirty) {
    fillBand(r.rehearsalStrip.get(), terrain, rehearsal.pathPoints, r.rehearsalBand);
    r.rehearsalDirty = false;
  }
  r.marksNode->setNodeMask(hasRobot && !r.places.empty() ? ~0u : 0u);
  if (r.marksDirty) {
    auto* v = static_cast<osg::Vec3Array*>(r.marks->getVertexArray());
    v->clear();
    for (size_t i = 0; i < r.places.size(); ++i) {
      const Vec3 c = r.places[i];
      const double radius = i + 1 == r.places.size() && r.lastOn ? 0.8 : 0.5;
      const float z = f(groundHeight(terrain, c.x, c.y));
      const std::vector<osg::Vec3> ring = drapedCircle(terrain, c.x, c.y, radius, kSegments, kLift);
      for (size_t k = 0; k + 1 < ring.size(); ++k) {  // as line segments: one geometry for every mark
        v->push_back(ring[k]);
        v->push_back(ring[k + 1]);
      }
      v->push_back({f(c.x), f(c.y), z});
      v->push_back({f(c.x), f(c.y), z + 1.5f});  // a post: seen over the rise that hides the ring
    }
    setCount(r.marks.get());
    r.marksDirty = false;
  }
}

void SceneView::setGhostRegion(double inner, double outer) {
  Impl::Region& r = m_->region;
  if (inner == r.innerRadius && outer == r.outerRadius) return;
  r.innerRadius = inner;
  r.outerRadius = outer;
  r.dirty = true;
}

void SceneView::setGhostTrailBand(const std::vector<double>& radii) {
  m_->region.band = radii;
  m_->region.dirty = true;
}

double SceneView::drawnGhostRegion() const { return m_->region.node->getNodeMask() ? m_->region.outerRadius : 0; }

size_t SceneView::drawnTrailBand() const {
  return m_->region.node->getNodeMask() ? m_->region.bandStrip->getVertexArray()->getNumElements() / 2 : 0;
}

double SceneView::drawnGhostSpread() const { return m_->region.spreadDrawn; }

void SceneView::setRehearsalBand(const std::vector<double>& radii) {
  m_->region.rehearsalBand = radii;
  m_->region.rehearsalDirty = true;
  update();
}

size_t SceneView::drawnRehearsalBand() const {
  return m_->region.rehearsalNode->getNodeMask() ? m_->region.rehearsalStrip->getVertexArray()->getNumElements() / 2 : 0;
}

void SceneView::setDepartureMarks(const std::vector<Vec3>& places, bool lastOn) {
  m_->region.places = places;
  m_->region.lastOn = lastOn;
  m_->region.marksDirty = true;
  update();
}

size_t SceneView::drawnDepartureMarks() const {
  return m_->region.marksNode->getNodeMask() ? m_->region.places.size() : 0;
}

}  // namespace sp
