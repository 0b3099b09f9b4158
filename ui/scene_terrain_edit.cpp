// The 3D view's terrain editing: the brush's ring on the ground, picks,
// the patches drawn as they are applied (ui/scene_view_impl.h).
#include "ui/scene_view_impl.h"

namespace sp {

// The footprint ring at the hovered ground point, draped 3 cm above the
// ground; hidden outside edit mode or off the ground.
void SceneView::Impl::updateFootprint() {
  footprintDirty = false;
  const bool shown = editing && hover.has_value();
  footprintNode->setNodeMask(shown ? ~0u : 0u);
  if (!shown) return;
  auto* v = static_cast<osg::Vec3Array*>(footprint->getVertexArray());
  v->clear();
  constexpr int kSegments = 64;
  const std::vector<osg::Vec3> ring = drapedCircle(terrain, hover->x, hover->y, brushRadius, kSegments, 0.03f);
  v->insert(v->end(), ring.begin(), ring.end() - 1);  // a loop: the last point closes it
  v->dirty();
  auto* colour = static_cast<osg::Vec4Array*>(footprint->getColorArray());
  (*colour)[0] = brushWarning ? osg::Vec4(1.0f, 0.45f, 0.0f, 1.0f) : osg::Vec4(1.0f, 0.85f, 0.1f, 1.0f);
  colour->dirty();
  static_cast<osg::DrawArrays*>(footprint->getPrimitiveSet(0))->setCount(kSegments);
  footprint->dirtyBound();
}

void SceneView::setTerrainEditing(bool on) {
  Impl& m = *m_;
  if (m.painting && !on) {
    m.painting = false;
    emit terrainStrokeEnded();
  }
  m.editing = on;
  setMouseTracking(on);  // the footprint follows the cursor without a button down
  setCursor(on ? Qt::CrossCursor : Qt::ArrowCursor);
  if (!on) m.hover.reset();
  m.footprintDirty = true;
}

bool SceneView::terrainEditing() const { return m_->editing; }

void SceneView::setBrushRadius(double radius) {
  m_->brushRadius = radius;
  m_->footprintDirty = true;
}

void SceneView::setBrushWarning(bool on) {
  if (m_->brushWarning == on) return;
  m_->brushWarning = on;
  m_->footprintDirty = true;
  update();
}

void SceneView::pickGround() {
  m_->picking = true;
  setCursor(Qt::PointingHandCursor);
}

std::optional<Vec3> SceneView::groundAt(QPointF pixel) const {
  const Impl& m = *m_;
  const osg::Camera* camera = m.viewer->getCamera();
  const osg::Matrixd toWindow = camera->getViewMatrix() * camera->getProjectionMatrix() *
                                camera->getViewport()->computeWindowMatrix();
  const osg::Matrixd fromWindow = osg::Matrixd::inverse(toWindow);
  // Window coordinates have y up; Qt's have it down.
  const double x = pixel.x() * m.dpr, y = m.pixelHeight - pixel.y() * m.dpr;
  const osg::Vec3d nearPoint = osg::Vec3d(x, y, 0.0) * fromWindow, farPoint = osg::Vec3d(x, y, 1.0) * fromWindow;
  osg::Vec3d dir = farPoint - nearPoint;
  const double length = std::min(dir.length(), 500.0);
  dir.normalize();
  // March along the ray in 5 cm steps to the first point below the ground,
  // then bisect: the heightfield is a function of (x, y).
  const auto below = [&](double t) {
    const osg::Vec3d p = nearPoint + dir * t;
    return p.z() <= groundHeight(m.terrain, p.x(), p.y());
  };
  if (below(0)) return std::nullopt;
  double lo = 0;
  for (double t = 0.05; t <= length; t += 0.05) {
    if (!below(t)) {
      lo = t;
      continue;
    }
    double hi = t;
    for (int k = 0; k < 30; ++k) (below((lo + hi) / 2) ? hi : lo) = (lo + hi) / 2;
    const osg::Vec3d p = nearPoint + dir * hi;
    return Vec3{p.x(), p.y(), groundHeight(m.terrain, p.x(), p.y())};
  }
  return std::nullopt;
}

void SceneView::applyTerrainPatch(const TerrainPatchCmd& patch) {
  Impl& m = *m_;
  HeightGrid& grid = m.terrain.grid;
  if (m.terrain.kind != TerrainSpec::Kind::Heightfield || !patchFits(&grid, patch).empty()) return;
  applyPatch(grid, patch);
  if (m.mesh.tiles.empty()) return;
  // The drawn samples in the patch and one beyond (their normals change).
  const auto range = [](const std::vector<int>& at, int from, int to) {
    const auto a = std::lower_bound(at.begin(), at.end(), from - 1);
    const auto b = std::upper_bound(at.begin(), at.end(), to + 1);
    return std::pair{static_cast<size_t>(a - at.begin()), static_cast<size_t>(b - at.begin())};
  };
  const auto [a0, a1] = range(m.mesh.columns, patch.column, patch.column + patch.columns - 1);
  const auto [b0, b1] = range(m.mesh.rows, patch.row, patch.row + patch.rows - 1);
  for (size_t b = b0; b < b1; ++b)
    for (size_t a = a0; a < a1; ++a) m.mesh.update(grid, a, b);
  m.mesh.flush();
  m.footprintDirty = true;
}

void SceneView::finishTerrainEdit() {
  Impl& m = *m_;
  if (!m.gridLines) return;
  // The grid lines drape over the ground: laid again over the edited heights.
  osg::ref_ptr<osg::Node> lines = gridNode(m.terrain);
  m.worldNode->replaceChild(m.gridLines, lines);
  m.gridLines = lines;
}

std::optional<double> SceneView::drawnTerrainHeight(int i, int j) const {
  const TerrainMesh& mesh = m_->mesh;
  if (mesh.tiles.empty()) return std::nullopt;
  const auto a = std::find(mesh.columns.begin(), mesh.columns.end(), i);
  const auto b = std::find(mesh.rows.begin(), mesh.rows.end(), j);
  if (a == mesh.columns.end() || b == mesh.rows.end()) return std::nullopt;
  return mesh.height(static_cast<size_t>(a - mesh.columns.begin()), static_cast<size_t>(b - mesh.rows.begin()));
}

}  // namespace sp
