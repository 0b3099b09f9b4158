// The 3D view's translucent robots: the predictive ghost and the rehearsal,
// each with its path (ui/scene_view_impl.h).
#include "ui/scene_view_impl.h"

namespace sp {

void SceneView::Impl::buildPhantom(Phantom& p, osg::Vec4 body, osg::Vec4 line, bool seeThrough) {
  registerFrontToBackBin();
  p.node = new osg::Group;
  p.body = new osg::Group;
  root->addChild(p.node);
  // A clean translucent silhouette in one colour: each pixel blends the
  // phantom's nearest surface once. Its links are drawn after the opaque
  // scene, nearest first, writing depth, with back faces culled, so that a
  // surface behind one already drawn fails the depth test instead of
  // blending again. Drawn without depth (as before), the links' faces
  // blended over each other in whatever order they came, and the phantom
  // showed shards of darker and lighter tints. Lighting still shades the
  // one colour, so the shape reads.
  auto* tint = new osg::Material;
  tint->setColorMode(osg::Material::OFF);
  tint->setDiffuse(osg::Material::FRONT_AND_BACK, body);
  tint->setAmbient(osg::Material::FRONT_AND_BACK, {body.r() / 2, body.g() / 2, body.b() / 2, body.a()});
  tint->setSpecular(osg::Material::FRONT_AND_BACK, {0, 0, 0, body.a()});
  p.node->addChild(p.body);
  osg::StateSet* g = p.node->getOrCreateStateSet();
  g->setAttributeAndModes(tint, osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
  g->setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA), osg::StateAttribute::ON);
  g->setAttributeAndModes(new osg::Depth(osg::Depth::LESS, 0.0, 1.0, true), osg::StateAttribute::ON);
  g->setAttributeAndModes(new osg::CullFace(osg::CullFace::BACK), osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
  g->setRenderBinDetails(kPhantomBin, kFrontToBackBin);
  p.node->setNodeMask(0);
  p.pathNode = new osg::Geode;
  p.path = newGeometry();
  p.path->setVertexArray(new osg::Vec3Array);
  auto* color = new osg::Vec4Array;
  color->push_back(line);
  p.path->setColorArray(color, osg::Array::BIND_OVERALL);
  p.path->addPrimitiveSet(new osg::DrawArrays(GL_LINE_STRIP, 0, 0));
  p.path->setDataVariance(osg::Object::DYNAMIC);
  p.pathNode->addDrawable(p.path);
  p.envelope = newGeometry();
  p.envelope->setVertexArray(new osg::Vec3Array);
  p.envelope->setColorArray(color, osg::Array::BIND_OVERALL);
  p.envelope->addPrimitiveSet(new osg::DrawArrays(GL_LINE_STRIP, 0, 0));
  p.envelope->setDataVariance(osg::Object::DYNAMIC);
  p.pathNode->addDrawable(p.envelope);
  osg::StateSet* s = p.pathNode->getOrCreateStateSet();
  s->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  s->setAttributeAndModes(new osg::LineWidth(4.0f));
  p.pathNode->setNodeMask(0);
  root->addChild(p.pathNode);
  // The ghost's trail is seen through whatever stands on it: at low speed
  // it lies wholly under the robot and the ghost. The same lines again,
  // after everything else, only where something nearer hides them, at half
  // their strength (the node mask above shows and hides both). Not the
  // rehearsed path: drawn through the amber robot it only cluttered it.
  if (!seeThrough) return;
  auto* xray = new osg::Group;
  xray->addChild(p.pathNode);
  osg::StateSet* x = xray->getOrCreateStateSet();
  x->setAttributeAndModes(new osg::Depth(osg::Depth::GREATER, 0.0, 1.0, false),
                          osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
  x->setAttributeAndModes(new osg::BlendFunc(GL_CONSTANT_ALPHA, GL_ONE_MINUS_CONSTANT_ALPHA), osg::StateAttribute::ON);
  x->setAttributeAndModes(new osg::BlendColor({0, 0, 0, 0.5f}), osg::StateAttribute::ON);
  x->setRenderBinDetails(kPhantomBin + 1, "RenderBin");
  root->addChild(xray);
}

bool SceneView::Impl::coincides(const Phantom& p) const {
  // Within a few centimetres and degrees of the robot a phantom only
  // z-fights with it (striped flicker over body and torso): not drawn then.
  // Its trail or path still is.
  if (norm(p.base.p - base.p) > kCoincide.position) return false;
  const Quat& a = p.base.q;
  const Quat& b = base.q;
  const double cosHalf = std::abs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
  if (2 * std::acos(std::min(1.0, cosHalf)) > kCoincide.angle) return false;
  if (p.joints.size() != joints.size()) return false;
  for (size_t j = 0; j < joints.size(); ++j)
    if (std::abs(p.joints[j] - joints[j]) > kCoincide.angle) return false;
  return true;
}

void SceneView::Impl::syncPhantom(Phantom& p) {
  if (p.dirty) {
    const std::vector<Pose> poses = linkPoses(robot, p.base, p.joints);
    for (size_t i = 0; i < p.links.size() && i < poses.size(); ++i) p.links[i]->setMatrix(toMatrix(poses[i]));
    p.dirty = false;
  }
  p.node->setNodeMask(p.visible && p.bodyShown && hasRobot && !coincides(p) ? ~0u : 0u);
  if (p.pathDirty) {
    for (auto [geometry, points] : {std::pair{p.path.get(), &p.pathPoints}, std::pair{p.envelope.get(), &p.envelopePoints}}) {
      auto* v = static_cast<osg::Vec3Array*>(geometry->getVertexArray());
      v->clear();
      // A little above the given points (on the ground), so the ground does
      // not hide the line.
      for (const Vec3& q : *points) v->push_back(toOsg(q) + osg::Vec3(0, 0, 0.05f));
      v->dirty();
      static_cast<osg::DrawArrays*>(geometry->getPrimitiveSet(0))->setCount(static_cast<GLsizei>(v->size()));
      geometry->dirtyBound();
    }
    p.pathDirty = false;
  }
  p.pathNode->setNodeMask(p.visible && hasRobot && p.pathPoints.size() > 1 ? ~0u : 0u);
}

void SceneView::setGhostState(const Pose& base, const std::vector<double>& jointPositions) {
  m_->ghost.base = base;
  m_->ghost.joints = jointPositions;
  m_->ghost.dirty = true;
}

void SceneView::setGhostVisible(bool visible) { m_->ghost.visible = visible; }

void SceneView::setGhostTrail(const std::vector<Vec3>& points) {
  m_->ghost.pathPoints = points;
  m_->ghost.pathDirty = true;
}

size_t SceneView::drawnTrailPoints() const {
  return m_->ghost.pathNode->getNodeMask() ? m_->ghost.pathPoints.size() : 0;
}
bool SceneView::ghostVisible() const { return m_->ghost.visible; }

namespace {
Pose drawnPhantomBase(const std::vector<osg::ref_ptr<osg::MatrixTransform>>& links, bool visible) {
  if (links.empty() || !visible) return {};
  const osg::Matrixd m = links[0]->getMatrix();
  const osg::Vec3d t = m.getTrans();
  const osg::Quat q = m.getRotate();
  return Pose{{t.x(), t.y(), t.z()}, Quat{q.w(), q.x(), q.y(), q.z()}};
}
}  // namespace

Pose SceneView::drawnGhostBasePose() const { return drawnPhantomBase(m_->ghost.links, m_->ghost.visible); }

void SceneView::setRehearsalState(const Pose& base, const std::vector<double>& jointPositions) {
  m_->rehearsal.base = base;
  m_->rehearsal.joints = jointPositions;
  m_->rehearsal.dirty = true;
}
void SceneView::setRehearsalPath(const std::vector<Vec3>& points) {
  m_->rehearsal.pathPoints = points;
  m_->rehearsal.pathDirty = true;
}
void SceneView::setRehearsalEnvelope(const std::vector<Vec3>& points) {
  m_->rehearsal.envelopePoints = points;
  m_->rehearsal.pathDirty = true;
}
void SceneView::setRehearsalVisible(bool visible) { m_->rehearsal.visible = visible; }
bool SceneView::rehearsalVisible() const { return m_->rehearsal.visible; }
void SceneView::setRehearsalRobotShown(bool shown) { m_->rehearsal.bodyShown = shown; }
bool SceneView::rehearsalRobotDrawn() const { return m_->rehearsal.node->getNodeMask() != 0; }
size_t SceneView::drawnRehearsalPathPoints() const {
  return m_->rehearsal.pathNode->getNodeMask() ? m_->rehearsal.pathPoints.size() : 0;
}
Pose SceneView::drawnRehearsalBasePose() const {
  return drawnPhantomBase(m_->rehearsal.links, m_->rehearsal.visible);
}

}  // namespace sp
