#include "ui/scene_view.h"

#include "sim/terrain_brush.h"

#include <QElapsedTimer>
#include <QSurfaceFormat>
#include <QLabel>
#include <QMouseEvent>
#include <QOpenGLContext>
#include <QOpenGLFunctions>
#include <QTimer>
#include <QWheelEvent>

#include <osg/BlendColor>
#include <osg/BlendFunc>
#include <osg/CullFace>
#include <osg/Fog>
#include <osg/Depth>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Light>
#include <osg/LightModel>
#include <osg/LightSource>
#include <osg/LineWidth>
#include <osg/Material>
#include <osgUtil/RenderBin>
#include <osg/MatrixTransform>
#include <osg/Point>
#include <osg/PolygonOffset>
#include <osg/ShapeDrawable>
#include <osgViewer/GraphicsWindow>
#include <osgViewer/Viewer>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "sim/kinematics.h"

namespace sp {
namespace {

// Sky blue; the fog fades distant ground into it so the horizon has no edge.
const osg::Vec4 kSkyColor(0.66f, 0.78f, 0.90f, 1.0f);
const osg::Vec4 kEarthColor(0.60f, 0.56f, 0.48f, 1.0f);
const osg::Vec4 kGridColor(0.45f, 0.42f, 0.36f, 1.0f);
const osg::Vec4 kGridMajorColor(0.33f, 0.31f, 0.27f, 1.0f);  // every 5 m
const osg::Vec4 kBeamHitColor(1.0f, 0.15f, 0.10f, 0.35f);
const osg::Vec4 kBeamMissColor(1.0f, 1.0f, 1.0f, 0.18f);
const osg::Vec4 kHitPointColor(1.0f, 0.10f, 0.05f, 1.0f);

constexpr double kFovY = 40.0;            // [deg]
constexpr double kPlaneHalfSize = 200.0;  // [m]; fogged out long before its edge
constexpr double kMinDisplayCell = 0.1;   // [m] finest heightfield cell drawn
constexpr double kPlaneCell = 10.0;       // [m]; coarse: software GL pays per vertex
constexpr int kGridHalfSize = 50;         // [m] of 1 m grid around the origin
constexpr double kGridLift = 0.005;       // [m] lines above the ground, with polygon offset
constexpr double kDefaultAzimuth = degToRad(-150);  // behind the robot, to its right
// The render bin of the translucent robots: after the opaque scene (0) and
// OSG's depth-sorted transparent bin (10), sorted nearest first.
constexpr int kPhantomBin = 20;
constexpr const char* kFrontToBackBin = "SimPartnerFrontToBack";

/// Registers kFrontToBackBin with OSG (once per process).
void registerFrontToBackBin() {
  static const bool registered = [] {
    osgUtil::RenderBin::addRenderBinPrototype(kFrontToBackBin,
                                              new osgUtil::RenderBin(osgUtil::RenderBin::SORT_FRONT_TO_BACK));
    return true;
  }();
  (void)registered;
}
constexpr double kDefaultElevation = degToRad(19);
constexpr double kDefaultDistance = 7.0;  // [m]
constexpr double kMinElevation = degToRad(1), kMaxElevation = degToRad(89);
constexpr double kMinDistance = 0.5, kMaxDistance = 300.0;
constexpr double kOrbitRadPerPixel = 0.006;

float f(double v) { return static_cast<float>(v); }
osg::Vec3 toOsg(Vec3 v) { return {f(v.x), f(v.y), f(v.z)}; }
osg::Vec3d toOsgD(Vec3 v) { return {v.x, v.y, v.z}; }
osg::Quat toOsg(const Quat& q) { return {q.x, q.y, q.z, q.w}; }  // osg order: x, y, z, w
osg::Vec4 toOsg(const Color& c) { return {f(c.r), f(c.g), f(c.b), f(c.a)}; }
// OSG multiplies row vectors: rotate first, then translate.
osg::Matrixd toMatrix(const Pose& p) {
  return osg::Matrixd::rotate(toOsg(p.q)) * osg::Matrixd::translate(toOsgD(p.p));
}

// Buffers rather than display lists: the laser's arrays change every scan.
osg::ref_ptr<osg::Geometry> newGeometry() {
  osg::ref_ptr<osg::Geometry> g = new osg::Geometry;
  g->setUseDisplayList(false);
  g->setUseVertexBufferObjects(true);
  return g;
}

void makeTransparent(osg::StateSet* s) {
  // Colour blends; the framebuffer's alpha stays 1, or Qt would compose the
  // widget's image as translucent over whatever lies behind it.
  s->setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE));
  s->setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
}

/// One geom of a link or object, in its owner's frame.
osg::ref_ptr<osg::Drawable> geomDrawable(const GeomSpec& g) {
  const osg::Vec3 c = toOsg(g.pose.p);
  const osg::Quat q = toOsg(g.pose.q);
  auto rotated = [&q](auto* s) {
    s->setRotation(q);
    return s;
  };
  osg::ref_ptr<osg::Shape> shape;
  switch (g.type) {
    case GeomType::Box:
      shape = rotated(new osg::Box(c, f(g.size.x), f(g.size.y), f(g.size.z)));
      break;
    case GeomType::Cylinder:
      shape = rotated(new osg::Cylinder(c, f(g.radius), f(g.length)));
      break;
    case GeomType::Sphere:
      shape = new osg::Sphere(c, f(g.radius));
      break;
    case GeomType::Capsule:  // osg::Capsule's height is the straight part, as in ODE
      shape = rotated(new osg::Capsule(c, f(g.radius), f(g.length)));
      break;
  }
  osg::ref_ptr<osg::ShapeDrawable> d = new osg::ShapeDrawable(shape.get());
  d->setColor(toOsg(g.color));
  if (g.color.a < 1.0) makeTransparent(d->getOrCreateStateSet());
  return d;
}

osg::ref_ptr<osg::Geode> geomsNode(const std::vector<GeomSpec>& geoms) {
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  for (const GeomSpec& g : geoms) geode->addDrawable(geomDrawable(g));
  return geode;
}

/// Ground height at world (x, y): the plane's height, or the heightfield's
/// (its edge value outside it, as HeightGrid::heightAt does).
double groundHeight(const TerrainSpec& t, double x, double y) {
  if (t.kind == TerrainSpec::Kind::Plane || t.grid.columns < 2 || t.grid.rows < 2) return t.pose.p.z;
  const Vec3 local = transformPoint(inverse(t.pose), {x, y, 0});
  return t.grid.heightAt(local.x, local.y) + t.pose.p.z;
}

/// Earth at the bottom, grass in the middle, dry light grass on top.
osg::Vec4 heightColor(double t) {
  const osg::Vec4 low(0.45f, 0.38f, 0.28f, 1.0f), mid(0.50f, 0.55f, 0.33f, 1.0f),
      high(0.74f, 0.72f, 0.56f, 1.0f);
  t = std::clamp(t, 0.0, 1.0);
  return t < 0.5 ? low + (mid - low) * f(2 * t) : mid + (high - mid) * f(2 * t - 1);
}

/// Two triangles per cell of a row-major grid of `columns` x `rows`
/// vertices, split along the diagonal (i, j)-(i+1, j+1) as ODE's
/// heightfield is, counter-clockwise seen from above.
osg::ref_ptr<osg::DrawElementsUInt> gridTriangles(int columns, int rows) {
  osg::ref_ptr<osg::DrawElementsUInt> tris = new osg::DrawElementsUInt(GL_TRIANGLES);
  tris->reserve(static_cast<size_t>(columns - 1) * static_cast<size_t>(rows - 1) * 6);
  auto index = [columns](int i, int j) { return static_cast<unsigned>(j * columns + i); };
  for (int j = 0; j + 1 < rows; ++j)
    for (int i = 0; i + 1 < columns; ++i)
      for (unsigned k : {index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j), index(i + 1, j + 1),
                         index(i, j + 1)})
        tris->push_back(k);
  return tris;
}

/// The plane as a grid of cells rather than one quad: fixed-function fog is
/// computed per vertex, and a quad whose corners lie far away (or behind the
/// camera) would be fogged all over.
osg::ref_ptr<osg::Node> planeNode(double z) {
  const int n = static_cast<int>(2 * kPlaneHalfSize / kPlaneCell);  // cells per side
  osg::ref_ptr<osg::Geometry> g = newGeometry();
  auto* v = new osg::Vec3Array;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      v->push_back({f(-kPlaneHalfSize + i * kPlaneCell), f(-kPlaneHalfSize + j * kPlaneCell), f(z)});
  g->setVertexArray(v);
  auto* normal = new osg::Vec3Array;
  normal->push_back({0, 0, 1});
  g->setNormalArray(normal, osg::Array::BIND_OVERALL);
  auto* c = new osg::Vec4Array;
  c->push_back(kEarthColor);
  g->setColorArray(c, osg::Array::BIND_OVERALL);
  g->addPrimitiveSet(gridTriangles(n + 1, n + 1));
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  geode->addDrawable(g);
  return geode;
}

/// The heightfield's mesh as drawn: which grid samples its vertices are
/// (every stride-th, the last row and column always), in tiles of at most
/// kTile x kTile cells, each its own geometry, so that an edit re-uploads
/// only the tiles it touches (a vertex buffer is sent whole when dirtied).
/// Tiles share their edge vertices.
struct TerrainMesh {
  static constexpr size_t kTile = 64;  // cells per tile side
  struct Tile {
    osg::ref_ptr<osg::Geometry> geometry;
    size_t a0, b0, columns;  // first mesh column and row, vertices per row
    bool dirty = false;
  };
  std::vector<int> columns, rows;  // grid sample of each mesh column and row
  size_t tilesX = 0, tilesY = 0;
  std::vector<Tile> tiles;         // row by row
  double low = 0, span = 1;        // the colour ramp, fixed when built

  /// Sets mesh vertex (a, b) from the grid, in each tile holding it:
  /// height, normal (central differences on the full grid, one-sided at
  /// the edges), colour.
  void update(const HeightGrid& grid, size_t a, size_t b) {
    const int i = columns[a], j = rows[b];
    const double sx = grid.spacingX(), sy = grid.spacingY(), h = grid.at(i, j);
    const osg::Vec3 vertex(f(-grid.width / 2 + i * sx), f(-grid.depth / 2 + j * sy), f(h));
    const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, grid.columns - 1);
    const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, grid.rows - 1);
    const double dx = (grid.at(i1, j) - grid.at(i0, j)) / ((i1 - i0) * sx);
    const double dy = (grid.at(i, j1) - grid.at(i, j0)) / ((j1 - j0) * sy);
    osg::Vec3 normal(f(-dx), f(-dy), 1.0f);
    normal.normalize();
    const osg::Vec4 colour = heightColor((h - low) / span);
    // The tile a / kTile, and the one before when (a, b) is on its edge.
    for (size_t ty = b / kTile - (b % kTile == 0 && b > 0 ? 1 : 0); ty <= std::min(b / kTile, tilesY - 1); ++ty)
      for (size_t tx = a / kTile - (a % kTile == 0 && a > 0 ? 1 : 0); tx <= std::min(a / kTile, tilesX - 1); ++tx) {
        Tile& t = tiles[ty * tilesX + tx];
        const size_t k = (b - t.b0) * t.columns + (a - t.a0);
        static_cast<osg::Vec3Array&>(*t.geometry->getVertexArray())[k] = vertex;
        static_cast<osg::Vec3Array&>(*t.geometry->getNormalArray())[k] = normal;
        static_cast<osg::Vec4Array&>(*t.geometry->getColorArray())[k] = colour;
        t.dirty = true;
      }
  }
  /// Sends the changed tiles' arrays to the GPU at the next frame.
  void flush() {
    for (Tile& t : tiles) {
      if (!t.dirty) continue;
      for (osg::Array* array : {t.geometry->getVertexArray(), t.geometry->getNormalArray(), t.geometry->getColorArray()})
        array->dirty();
      t.geometry->dirtyBound();
      t.dirty = false;
    }
  }
  /// The drawn height of mesh vertex (a, b).
  float height(size_t a, size_t b) const {
    const Tile& t = tiles[std::min(b / kTile, tilesY - 1) * tilesX + std::min(a / kTile, tilesX - 1)];
    return static_cast<const osg::Vec3Array&>(*t.geometry->getVertexArray())[(b - t.b0) * t.columns + (a - t.a0)].z();
  }
};

/// The heightfield as a smooth-shaded mesh in the terrain frame, split along
/// the same cell diagonals as ODE's, placed by the terrain pose (grid centre).
osg::ref_ptr<osg::Node> heightfieldNode(const TerrainSpec& t, TerrainMesh& mesh) {
  const HeightGrid& grid = t.grid;
  osg::ref_ptr<osg::MatrixTransform> xf = new osg::MatrixTransform(toMatrix(t.pose));
  const int nx = grid.columns, ny = grid.rows;
  if (nx < 2 || ny < 2 || grid.heights.size() != static_cast<size_t>(nx) * static_cast<size_t>(ny)) return xf;
  // Drawn at no finer than kMinDisplayCell: software GL pays for every
  // vertex every frame, and a finer mesh than that shows nothing more of
  // the ground an operator drives on. The last row and column are always
  // drawn, so the mesh covers the whole grid.
  auto samples = [](int n, double spacing) {
    const int stride = std::max(1, static_cast<int>(std::ceil(kMinDisplayCell / spacing - 1e-9)));
    std::vector<int> at;
    for (int i = 0; i < n - 1; i += stride) at.push_back(i);
    at.push_back(n - 1);
    return at;
  };
  mesh.columns = samples(nx, grid.spacingX());
  mesh.rows = samples(ny, grid.spacingY());
  // The colour ramp spans at least 0.5 m, so gentle bumps stay gentle.
  mesh.low = grid.minHeight();
  mesh.span = std::max(grid.maxHeight() - mesh.low, 0.5);
  const size_t cellsX = mesh.columns.size() - 1, cellsY = mesh.rows.size() - 1;
  mesh.tilesX = (cellsX + TerrainMesh::kTile - 1) / TerrainMesh::kTile;
  mesh.tilesY = (cellsY + TerrainMesh::kTile - 1) / TerrainMesh::kTile;
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  for (size_t ty = 0; ty < mesh.tilesY; ++ty)
    for (size_t tx = 0; tx < mesh.tilesX; ++tx) {
      TerrainMesh::Tile tile;
      tile.a0 = tx * TerrainMesh::kTile;
      tile.b0 = ty * TerrainMesh::kTile;
      tile.columns = std::min(cellsX, tile.a0 + TerrainMesh::kTile) - tile.a0 + 1;
      const size_t tileRows = std::min(cellsY, tile.b0 + TerrainMesh::kTile) - tile.b0 + 1;
      const auto count = static_cast<unsigned>(tile.columns * tileRows);
      tile.geometry = newGeometry();
      // Edited in place (applyTerrainPatch).
      tile.geometry->setDataVariance(osg::Object::DYNAMIC);
      tile.geometry->setVertexArray(new osg::Vec3Array(count));
      tile.geometry->setNormalArray(new osg::Vec3Array(count), osg::Array::BIND_PER_VERTEX);
      tile.geometry->setColorArray(new osg::Vec4Array(count), osg::Array::BIND_PER_VERTEX);
      tile.geometry->addPrimitiveSet(gridTriangles(static_cast<int>(tile.columns), static_cast<int>(tileRows)));
      geode->addDrawable(tile.geometry);
      mesh.tiles.push_back(std::move(tile));
    }
  for (size_t b = 0; b < mesh.rows.size(); ++b)
    for (size_t a = 0; a < mesh.columns.size(); ++a) mesh.update(grid, a, b);
  mesh.flush();
  xf->addChild(geode);
  return xf;
}

/// 1 m grid lines in world x and y, darker every 5 m: flat over the plane
/// around the origin, or draped over the heightfield's extent.
osg::ref_ptr<osg::Node> gridNode(const TerrainSpec& t) {
  auto* v = new osg::Vec3Array;
  auto* c = new osg::Vec4Array;
  auto addSegment = [&](osg::Vec3 a, osg::Vec3 b, int line) {
    const osg::Vec4& color = line % 5 == 0 ? kGridMajorColor : kGridColor;
    v->push_back(a);
    v->push_back(b);
    c->push_back(color);
    c->push_back(color);
  };
  const HeightGrid& grid = t.grid;
  if (t.kind == TerrainSpec::Kind::Plane || grid.columns < 2 || grid.rows < 2) {
    // In 5 m pieces, for per-vertex fog as on the plane (no finer: software
    // GL pays for every vertex, every frame).
    const float z = f(t.pose.p.z + kGridLift);
    for (int k = -kGridHalfSize; k <= kGridHalfSize; ++k) {
      const float p = static_cast<float>(k);
      for (int s = -kGridHalfSize; s < kGridHalfSize; s += 5) {
        const float a = static_cast<float>(s), b = static_cast<float>(s + 5);
        addSegment({p, a, z}, {p, b, z}, k);
        addSegment({a, p, z}, {b, p, z}, k);
      }
    }
  } else {
    // World-axis lines over the (possibly yawed) grid's bounding box, cut
    // where they leave the grid, sampled finely enough to follow its cells.
    const Pose toGrid = inverse(t.pose);
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (double sxn : {-0.5, 0.5}) {
      for (double syn : {-0.5, 0.5}) {
        const Vec3 w = transformPoint(t.pose, {sxn * grid.width, syn * grid.depth, 0});
        xmin = std::min(xmin, w.x), xmax = std::max(xmax, w.x);
        ymin = std::min(ymin, w.y), ymax = std::max(ymax, w.y);
      }
    }
    const double step = std::max(std::min(grid.spacingX(), grid.spacingY()), kMinDisplayCell) / 2;
    const double lift = std::max(0.01, 0.01 * (grid.maxHeight() - grid.minHeight()));
    auto point = [&](double x, double y, osg::Vec3& out) {
      const Vec3 local = transformPoint(toGrid, {x, y, 0});
      const double eps = 1e-9;
      if (std::abs(local.x) > grid.width / 2 + eps || std::abs(local.y) > grid.depth / 2 + eps) return false;
      out = {f(x), f(y), f(grid.heightAt(local.x, local.y) + t.pose.p.z + lift)};
      return true;
    };
    auto drape = [&](double x0, double y0, double x1, double y1, int line) {
      const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(x1 - x0, y1 - y0) / step)));
      osg::Vec3 a, b;
      bool aIn = point(x0, y0, a);
      for (int s = 1; s <= n; ++s) {
        const double u = static_cast<double>(s) / n;
        const bool bIn = point(x0 + u * (x1 - x0), y0 + u * (y1 - y0), b);
        if (aIn && bIn) addSegment(a, b, line);
        a = b;
        aIn = bIn;
      }
    };
    for (int k = static_cast<int>(std::ceil(xmin)); k <= static_cast<int>(std::floor(xmax)); ++k)
      drape(k, ymin, k, ymax, k);
    for (int k = static_cast<int>(std::ceil(ymin)); k <= static_cast<int>(std::floor(ymax)); ++k)
      drape(xmin, k, xmax, k, k);
  }
  osg::ref_ptr<osg::Geometry> g = newGeometry();
  g->setVertexArray(v);
  g->setColorArray(c, osg::Array::BIND_PER_VERTEX);
  g->addPrimitiveSet(new osg::DrawArrays(GL_LINES, 0, static_cast<int>(v->size())));
  osg::StateSet* s = g->getOrCreateStateSet();
  s->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  geode->addDrawable(g);
  return geode;
}

/// Red x, green y, blue z arrows of 1 m at the origin, resting on the ground.
osg::ref_ptr<osg::Node> axesNode(double groundZ) {
  constexpr float kRadius = 0.02f, kLength = 1.0f, kTipRadius = 0.05f, kTipLength = 0.15f;
  osg::ref_ptr<osg::MatrixTransform> xf =
      new osg::MatrixTransform(osg::Matrixd::translate(0, 0, groundZ + kRadius));
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  const struct {
    osg::Vec3 axis;
    osg::Vec4 color;
  } axes[] = {{{1, 0, 0}, {0.85f, 0.10f, 0.10f, 1}},
              {{0, 1, 0}, {0.10f, 0.70f, 0.15f, 1}},
              {{0, 0, 1}, {0.15f, 0.25f, 0.90f, 1}}};
  for (const auto& a : axes) {
    osg::Quat q;
    q.makeRotate(osg::Vec3(0, 0, 1), a.axis);  // shapes lie along z
    const float shaft = kLength - kTipLength;
    auto* cyl = new osg::Cylinder(a.axis * (shaft / 2), kRadius, shaft);
    cyl->setRotation(q);
    // A cone's centre sits a quarter of its height above its base.
    auto* cone = new osg::Cone(a.axis * (shaft + kTipLength / 4), kTipRadius, kTipLength);
    cone->setRotation(q);
    for (osg::Shape* shape : {static_cast<osg::Shape*>(cyl), static_cast<osg::Shape*>(cone)}) {
      auto* d = new osg::ShapeDrawable(shape);
      d->setColor(a.color);
      geode->addDrawable(d);
    }
  }
  xf->addChild(geode);
  return xf;
}

}  // namespace

struct SceneView::Impl {
  osg::ref_ptr<osgViewer::Viewer> viewer;
  osg::ref_ptr<osgViewer::GraphicsWindowEmbedded> window;
  osg::ref_ptr<osg::Group> root;
  osg::ref_ptr<osg::Group> worldNode;  // terrain, grid, axes, objects
  osg::ref_ptr<osg::Group> robotNode;
  std::vector<osg::ref_ptr<osg::MatrixTransform>> links;
  // Translucent robots (the predictive ghost, the rehearsal): the same link
  // geometry, shared, under transforms of their own, each with its path.
  struct Phantom {
    osg::ref_ptr<osg::Group> node;  // the two passes, each over `body`
    osg::ref_ptr<osg::Group> body;  // the link transforms
    std::vector<osg::ref_ptr<osg::MatrixTransform>> links;
    osg::ref_ptr<osg::Geode> pathNode;
    osg::ref_ptr<osg::Geometry> path;
    std::vector<Vec3> pathPoints;
    osg::ref_ptr<osg::Geometry> envelope;  // a closed line (the robustness runs' end positions)
    std::vector<Vec3> envelopePoints;
    bool pathDirty = false;
    Pose base;
    std::vector<double> joints;
    bool dirty = false;
    bool visible = false;
    bool bodyShown = true;  // false: only its path (the rehearsal's robot after the run)
  };
  Phantom ghost, rehearsal;
  osg::ref_ptr<osg::Geode> laserNode;
  osg::ref_ptr<osg::Geometry> beams, hits;
  // The terrain as drawn (its heights kept up to date by edits), its mesh,
  // and the draped grid lines (rebuilt when a stroke ends).
  TerrainSpec terrain;
  TerrainMesh mesh;
  osg::ref_ptr<osg::Node> gridLines;
  osg::ref_ptr<osg::MatrixTransform> planeFollow;  // a plane's ground and grid, following the robot (null on a heightfield)
  // Terrain editing: the mode, a stroke under way, a pick asked for, the
  // brush's footprint (a ring draped on the ground under the cursor).
  bool editing = false, painting = false, picking = false;
  double brushRadius = 1.0;
  bool brushWarning = false;  // the ring amber: the next dab asks too much of the robot
  std::optional<Vec3> hover;
  bool footprintDirty = false;
  osg::ref_ptr<osg::Geode> footprintNode;
  osg::ref_ptr<osg::Geometry> footprint;
  void updateFootprint();
  osg::ref_ptr<osg::Fog> fog;

  // The robot as last set, and whether the graph still shows an older state.
  bool hasRobot = false;
  RobotModel robot;
  Pose base;
  std::vector<double> joints;
  std::vector<Pose> linkWorld;
  bool robotDirty = false;

  // Dynamic objects by name: their transforms and poses as last set.
  struct DynamicObject {
    osg::ref_ptr<osg::MatrixTransform> transform;
    Pose pose;
  };
  std::map<std::string, DynamicObject> objects;
  bool objectsDirty = false;

  // Laser: robot.sensors index, or -1 without one.
  int laser = -1;
  double laserAngleMin = 0, laserAngleStep = 0;
  std::vector<double> laserRanges;
  bool laserDirty = false;
  bool laserVisible = true;
  // Stale data: the robot drawn grey (an override material on its group).
  bool stale = false, staleShown = false;
  osg::ref_ptr<osg::Material> staleTint;

  // Orbit camera around `centre`, z up.
  osg::Vec3d centre;
  double azimuth = kDefaultAzimuth, elevation = kDefaultElevation, distance = kDefaultDistance;
  bool follow = true;
  SceneView::Camera preset = SceneView::Camera::Follow;
  osg::Vec3d eye;  // of the last frame
  Qt::MouseButton dragButton = Qt::NoButton;
  QPointF lastMouse;  // device pixels
  double dpr = 1.0;
  int pixelWidth = 1, pixelHeight = 1;

  QTimer timer;
  QLabel* hud = nullptr;  // child of the view
  QElapsedTimer clock;
  int64_t frames = 0;
  int64_t windowFrames = 0;  // frames since windowStart
  qint64 windowStart = 0;    // [ms] of clock
  double fps = 0;

  Impl();
  // Builds a phantom's node (tinted `body`, see-through) and its path (an
  // opaque line in `line`) under root.
  void buildPhantom(Phantom& p, osg::Vec4 body, osg::Vec4 line, bool seeThrough);
  void syncPhantom(Phantom& p);
  /// Whether `p` stands where the robot is drawn (kCoincide): then it is not drawn.
  bool coincides(const Phantom& p) const;
  struct Coincide {
    double position, angle;  // [m]; [rad] of the base and of every joint
  };
  static constexpr Coincide kCoincide{0.03, 0.035};
  void buildLaser();
  void updateLaser();
  void sync();
  void updateHud();
};

SceneView::Impl::Impl() {
  root = new osg::Group;
  worldNode = new osg::Group;
  robotNode = new osg::Group;
  root->addChild(worldNode);
  root->addChild(robotNode);
  // The ghost light blue; the rehearsal amber. The paths in the same hues,
  // saturated and opaque: a thin line in a pale tint vanishes against the
  // sky and light ground.
  buildPhantom(ghost, {kGhostTint[0], kGhostTint[1], kGhostTint[2], kGhostTint[3]}, {0.05f, 0.45f, 1.00f, 1.0f}, true);
  buildPhantom(rehearsal, {1.00f, 0.70f, 0.15f, 0.50f}, {0.95f, 0.45f, 0.00f, 1.0f}, false);
  buildLaser();
  root->addChild(laserNode);
  // The brush footprint: a yellow ring, unlit, drawn over the ground.
  footprintNode = new osg::Geode;
  footprint = newGeometry();
  footprint->setVertexArray(new osg::Vec3Array);
  auto* ringColor = new osg::Vec4Array;
  ringColor->push_back({1.0f, 0.85f, 0.1f, 1.0f});
  footprint->setColorArray(ringColor, osg::Array::BIND_OVERALL);
  footprint->addPrimitiveSet(new osg::DrawArrays(GL_LINE_LOOP, 0, 0));
  footprint->setDataVariance(osg::Object::DYNAMIC);
  footprintNode->addDrawable(footprint);
  footprintNode->getOrCreateStateSet()->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  footprintNode->getOrCreateStateSet()->setAttributeAndModes(new osg::LineWidth(2.0f));
  footprintNode->setNodeMask(0);
  root->addChild(footprintNode);

  osg::StateSet* s = root->getOrCreateStateSet();
  // Geometry colours drive ambient and diffuse; a little gloss on the shapes.
  auto* material = new osg::Material;
  material->setColorMode(osg::Material::AMBIENT_AND_DIFFUSE);
  material->setSpecular(osg::Material::FRONT_AND_BACK, {0.25f, 0.25f, 0.25f, 1.0f});
  material->setShininess(osg::Material::FRONT_AND_BACK, 32.0f);
  s->setAttributeAndModes(material);
  auto* lightModel = new osg::LightModel;
  lightModel->setAmbientIntensity({0.18f, 0.18f, 0.20f, 1.0f});
  s->setAttributeAndModes(lightModel);
  // A dim fill light from the opposite side of the sun, so faces turned away
  // from the sun still show their shape.
  auto* fill = new osg::Light(1);
  fill->setPosition({-0.5f, 0.6f, 0.4f, 0.0f});
  fill->setAmbient({0, 0, 0, 1});
  fill->setDiffuse({0.28f, 0.29f, 0.32f, 1.0f});
  fill->setSpecular({0, 0, 0, 1});
  auto* fillSource = new osg::LightSource;
  fillSource->setLight(fill);
  fillSource->setStateSetModes(*s, osg::StateAttribute::ON);
  root->addChild(fillSource);
  fog = new osg::Fog;
  fog->setMode(osg::Fog::LINEAR);
  fog->setColor(kSkyColor);
  s->setAttributeAndModes(fog);

  window = new osgViewer::GraphicsWindowEmbedded(0, 0, 1, 1);
  viewer = new osgViewer::Viewer;
  viewer->setThreadingModel(osgViewer::Viewer::SingleThreaded);
  viewer->setKeyEventSetsDone(0);  // Esc must not end the viewer
  viewer->setQuitEventSetsDone(false);
  osg::Camera* camera = viewer->getCamera();
  camera->setGraphicsContext(window);
  camera->setViewport(0, 0, 1, 1);
  camera->setClearColor(kSkyColor);
  // The sun: a directional light fixed in the world, high up towards +x, -y.
  viewer->setLightingMode(osg::View::SKY_LIGHT);
  osg::Light* sun = viewer->getLight();
  sun->setPosition({0.45f, -0.35f, 0.82f, 0.0f});
  sun->setAmbient({0.30f, 0.30f, 0.32f, 1.0f});
  sun->setDiffuse({0.80f, 0.78f, 0.72f, 1.0f});
  sun->setSpecular({0.5f, 0.5f, 0.5f, 1.0f});
  viewer->setSceneData(root);
  clock.start();
}

void SceneView::Impl::buildLaser() {
  laserNode = new osg::Geode;
  beams = newGeometry();
  beams->setVertexArray(new osg::Vec3Array);
  beams->setColorArray(new osg::Vec4Array, osg::Array::BIND_PER_VERTEX);
  beams->addPrimitiveSet(new osg::DrawArrays(GL_LINES, 0, 0));
  beams->setDataVariance(osg::Object::DYNAMIC);
  hits = newGeometry();
  hits->setVertexArray(new osg::Vec3Array);
  auto* hitColor = new osg::Vec4Array;
  hitColor->push_back(kHitPointColor);
  hits->setColorArray(hitColor, osg::Array::BIND_OVERALL);
  hits->addPrimitiveSet(new osg::DrawArrays(GL_POINTS, 0, 0));
  hits->setDataVariance(osg::Object::DYNAMIC);
  laserNode->addDrawable(beams);
  laserNode->addDrawable(hits);
  osg::StateSet* s = laserNode->getOrCreateStateSet();
  s->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  s->setAttributeAndModes(new osg::LineWidth(1.0f));
  s->setAttributeAndModes(new osg::Point(5.0f));
  makeTransparent(s);
}

// Rebuilds the beams from the stored scan and the laser's current pose.
void SceneView::Impl::updateLaser() {
  auto* bv = static_cast<osg::Vec3Array*>(beams->getVertexArray());
  auto* bc = static_cast<osg::Vec4Array*>(beams->getColorArray());
  auto* hv = static_cast<osg::Vec3Array*>(hits->getVertexArray());
  bv->clear();
  bc->clear();
  hv->clear();
  if (laser >= 0 && static_cast<size_t>(robot.sensors[laser].link) < linkWorld.size()) {
    const SensorSpec& sensor = robot.sensors[laser];
    const Pose pose = linkWorld[sensor.link] * sensor.pose;
    const osg::Vec3 origin = toOsg(pose.p);
    for (size_t k = 0; k < laserRanges.size(); ++k) {
      const double r = laserRanges[k];
      if (std::isnan(r) || r < 0) continue;  // invalid reading: nothing to show
      const bool hit = r <= sensor.maxRange;
      const double a = laserAngleMin + static_cast<double>(k) * laserAngleStep;
      const osg::Vec3 end = toOsg(transformPoint(pose, {std::cos(a) * (hit ? r : sensor.maxRange),
                                                        std::sin(a) * (hit ? r : sensor.maxRange), 0}));
      bv->push_back(origin);
      bv->push_back(end);
      bc->push_back(hit ? kBeamHitColor : kBeamMissColor);
      bc->push_back(hit ? kBeamHitColor : kBeamMissColor);
      if (hit) hv->push_back(end);
    }
  }
  static_cast<osg::DrawArrays*>(beams->getPrimitiveSet(0))->setCount(static_cast<int>(bv->size()));
  static_cast<osg::DrawArrays*>(hits->getPrimitiveSet(0))->setCount(static_cast<int>(hv->size()));
  for (osg::Array* array : {static_cast<osg::Array*>(bv), static_cast<osg::Array*>(bc),
                            static_cast<osg::Array*>(hv)})
    array->dirty();
  beams->dirtyBound();
  hits->dirtyBound();
}

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
  for (int k = 0; k < kSegments; ++k) {
    const double a = 2 * kPi * k / kSegments;
    const double x = hover->x + brushRadius * std::cos(a), y = hover->y + brushRadius * std::sin(a);
    v->push_back({f(x), f(y), f(groundHeight(terrain, x, y) + 0.03)});
  }
  v->dirty();
  auto* colour = static_cast<osg::Vec4Array*>(footprint->getColorArray());
  (*colour)[0] = brushWarning ? osg::Vec4(1.0f, 0.45f, 0.0f, 1.0f) : osg::Vec4(1.0f, 0.85f, 0.1f, 1.0f);
  colour->dirty();
  static_cast<osg::DrawArrays*>(footprint->getPrimitiveSet(0))->setCount(kSegments);
  footprint->dirtyBound();
}

// Brings the scene graph and camera up to the stored state; called before
// each frame, so setters never touch the graph.
void SceneView::Impl::sync() {
  if (footprintDirty) updateFootprint();
  if (robotDirty) {
    linkWorld = linkPoses(robot, base, joints);
    for (size_t i = 0; i < links.size() && i < linkWorld.size(); ++i) links[i]->setMatrix(toMatrix(linkWorld[i]));
    robotDirty = false;
    laserDirty = true;  // the laser rides on the robot
  }
  syncPhantom(ghost);
  syncPhantom(rehearsal);
  if (stale != staleShown) {
    osg::StateSet* st = robotNode->getOrCreateStateSet();
    if (stale) {
      if (!staleTint) {
        staleTint = new osg::Material;
        staleTint->setColorMode(osg::Material::OFF);
        staleTint->setDiffuse(osg::Material::FRONT_AND_BACK, {0.55f, 0.55f, 0.55f, 1});
        staleTint->setAmbient(osg::Material::FRONT_AND_BACK, {0.25f, 0.25f, 0.25f, 1});
        staleTint->setSpecular(osg::Material::FRONT_AND_BACK, {0, 0, 0, 1});
      }
      st->setAttributeAndModes(staleTint, osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
    } else {
      st->removeAttribute(staleTint.get());
    }
    staleShown = stale;
  }
  if (objectsDirty) {
    for (auto& [name, o] : objects) o.transform->setMatrix(toMatrix(o.pose));
    objectsDirty = false;
  }
  if (laserDirty) {
    updateLaser();
    laserDirty = false;
  }
  laserNode->setNodeMask(laserVisible ? ~0u : 0u);
  if (follow && hasRobot) centre = toOsgD(base.p);
  if (planeFollow && hasRobot) {
    const double x = 5 * std::round(base.p.x / 5), y = 5 * std::round(base.p.y / 5);
    planeFollow->setMatrix(osg::Matrix::translate(x, y, 0));
  }
  // Chase and top turn with the robot: the eye behind it (azimuth is where
  // the eye is seen from the centre).
  if (hasRobot && (preset == SceneView::Camera::Chase || preset == SceneView::Camera::Top))
    azimuth = heading(base.q) + kPi;
  eye = centre + osg::Vec3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                            std::sin(elevation)) *
                     distance;
  viewer->getCamera()->setViewMatrixAsLookAt(eye, centre, osg::Vec3d(0, 0, 1));
  // Fog starts behind what the camera looks at, whatever the zoom.
  fog->setStart(f(distance + 15));
  fog->setEnd(f(distance * 2 + 80));
}

void SceneView::Impl::updateHud() {
  const char* names[] = {"follow", "chase", "top", "free camera"};
  hud->setText(QStringLiteral("%1 fps · %2").arg(fps, 0, 'f', 0).arg(QLatin1String(names[static_cast<int>(preset)])));
  hud->adjustSize();
}

SceneView::SceneView(QWidget* parent) : QOpenGLWidget(parent), m_(std::make_unique<Impl>()) {
  setMinimumSize(160, 120);
  m_->hud = new QLabel(this);
  m_->hud->setAttribute(Qt::WA_TransparentForMouseEvents);
  m_->hud->setStyleSheet(QStringLiteral(
      "QLabel { color: white; background: rgba(0, 0, 0, 110); padding: 2px 6px; border-radius: 3px; }"));
  m_->hud->move(8, 8);
  m_->updateHud();
  m_->hud->show();  // children made after the parent is shown stay hidden otherwise
  m_->timer.setInterval(16);
  connect(&m_->timer, &QTimer::timeout, this, qOverload<>(&QWidget::update));
  m_->timer.start();
}

SceneView::~SceneView() {
  m_->timer.stop();
  if (!isValid()) {
    // Never shown (a start that failed): no GL object exists, and closing
    // the never-realised window would make OSG probe GL without a context
    // ("OpenGL version test failed"): let the viewer go without it.
    m_->viewer->getCamera()->setGraphicsContext(nullptr);
    m_.reset();
    return;
  }
  // OSG deletes its GL objects as the viewer goes: in our context.
  makeCurrent();
  m_.reset();
  doneCurrent();
}

void SceneView::setWorld(const WorldModel& world) {
  Impl& m = *m_;
  m.worldNode->removeChildren(0, m.worldNode->getNumChildren());
  m.robotNode->removeChildren(0, m.robotNode->getNumChildren());
  for (Impl::Phantom* p : {&m.ghost, &m.rehearsal}) {
    p->body->removeChildren(0, p->body->getNumChildren());
    p->links.clear();
  }
  m.links.clear();
  m.objects.clear();
  m.objectsDirty = false;

  m.terrain = world.terrain;
  m.mesh = {};
  const TerrainSpec& t = m.terrain;
  osg::ref_ptr<osg::Node> terrain = t.kind == TerrainSpec::Kind::Plane ? planeNode(t.pose.p.z) : heightfieldNode(t, m.mesh);
  // Matte ground, pushed back in depth so the grid lines on it always win.
  auto* matte = new osg::Material;
  matte->setColorMode(osg::Material::AMBIENT_AND_DIFFUSE);
  matte->setSpecular(osg::Material::FRONT_AND_BACK, {0, 0, 0, 1});
  terrain->getOrCreateStateSet()->setAttributeAndModes(matte);
  terrain->getOrCreateStateSet()->setAttributeAndModes(new osg::PolygonOffset(1.0f, 1.0f));
  m.gridLines = gridNode(t);
  if (t.kind == TerrainSpec::Kind::Plane) {
    // An endless plane is drawn (ground and grid) around the robot, moved
    // with it in whole 5 m steps so the lines stay on the world's metres:
    // 200 m around the origin ended where a long drive went (issue 59).
    m.planeFollow = new osg::MatrixTransform;
    m.planeFollow->setDataVariance(osg::Object::DYNAMIC);
    m.planeFollow->addChild(terrain);
    m.planeFollow->addChild(m.gridLines);
    m.worldNode->addChild(m.planeFollow);
  } else {
    m.planeFollow = nullptr;
    m.worldNode->addChild(terrain);
    m.worldNode->addChild(m.gridLines);
  }
  m.footprintDirty = true;
  m.worldNode->addChild(axesNode(groundHeight(t, 0, 0)));
  // Objects start where the file puts them; dynamic ones move with setObjectPoses.
  for (const ObjectSpec& o : world.objects) {
    osg::ref_ptr<osg::MatrixTransform> xf = new osg::MatrixTransform(toMatrix(o.pose));
    xf->addChild(geomsNode(o.geoms));
    m.worldNode->addChild(xf);
    if (!o.isStatic) {
      xf->setDataVariance(osg::Object::DYNAMIC);
      m.objects[o.name] = {xf, o.pose};
    }
  }

  m.hasRobot = !world.robots.empty() && !world.robots[0].model.links.empty();
  m.robot = m.hasRobot ? world.robots[0].model : RobotModel{};
  m.laser = -1;
  for (size_t i = 0; i < m.robot.sensors.size(); ++i) {
    const SensorSpec& s = m.robot.sensors[i];
    if (s.type == SensorType::Laser && s.link >= 0 && static_cast<size_t>(s.link) < m.robot.links.size()) {
      m.laser = static_cast<int>(i);
      break;
    }
  }
  for (const LinkSpec& link : m.robot.links) {
    osg::ref_ptr<osg::MatrixTransform> xf = new osg::MatrixTransform;
    xf->setDataVariance(osg::Object::DYNAMIC);
    osg::ref_ptr<osg::Geode> shape = geomsNode(link.geoms);
    xf->addChild(shape);
    m.robotNode->addChild(xf);
    m.links.push_back(xf);
    for (Impl::Phantom* p : {&m.ghost, &m.rehearsal}) {
      osg::ref_ptr<osg::MatrixTransform> phantom = new osg::MatrixTransform;
      phantom->setDataVariance(osg::Object::DYNAMIC);
      phantom->addChild(shape);
      p->body->addChild(phantom);
      p->links.push_back(phantom);
    }
  }
  m.base = m.hasRobot ? world.robots[0].pose * m.robot.links[0].pose : Pose{};
  m.joints.assign(m.robot.joints.size(), 0.0);
  m.linkWorld.clear();
  m.robotDirty = true;
  for (Impl::Phantom* p : {&m.ghost, &m.rehearsal}) {
    p->base = m.base;
    p->joints = m.joints;
    p->dirty = true;
    p->pathPoints.clear();
    p->envelopePoints.clear();
    p->pathDirty = true;
  }
  m.laserRanges.clear();
  m.laserDirty = true;
  if (!m.hasRobot) m.centre = {};
}

void SceneView::setRobotState(const Pose& base, const std::vector<double>& jointPositions) {
  m_->base = base;
  m_->joints = jointPositions;
  m_->robotDirty = true;
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

void SceneView::setObjectPoses(const std::vector<NamedPose>& objects) {
  for (const NamedPose& o : objects) {
    const auto it = m_->objects.find(o.name);
    if (it == m_->objects.end()) continue;  // not a dynamic object of this world
    it->second.pose = o.pose;
    m_->objectsDirty = true;
  }
}

void SceneView::setLaser(double angleMin, double angleStep, const std::vector<double>& ranges) {
  m_->laserAngleMin = angleMin;
  m_->laserAngleStep = angleStep;
  m_->laserRanges = ranges;
  m_->laserDirty = true;
}

Pose SceneView::drawnBasePose() const {
  if (m_->links.empty()) return {};
  const osg::Matrixd m = m_->links[0]->getMatrix();
  const osg::Vec3d t = m.getTrans();
  const osg::Quat q = m.getRotate();
  return Pose{{t.x(), t.y(), t.z()}, Quat{q.w(), q.x(), q.y(), q.z()}};
}

void SceneView::setLaserVisible(bool visible) { m_->laserVisible = visible; }
void SceneView::setStale(bool stale) { m_->stale = stale; }
bool SceneView::stale() const { return m_->stale; }
bool SceneView::laserVisible() const { return m_->laserVisible; }

void SceneView::setFollow(bool on) {
  if (on == m_->follow && (on || m_->preset == Camera::Free)) return;
  setCamera(on ? Camera::Follow : Camera::Free);
}

bool SceneView::follow() const { return m_->follow; }

void SceneView::setCamera(Camera camera) {
  Impl& m = *m_;
  const Camera was = m.preset;
  m.preset = camera;
  m.follow = camera != Camera::Free;
  if (camera == Camera::Chase) {
    m.elevation = degToRad(15);
    m.distance = 6;
  } else if (camera == Camera::Top) {
    m.elevation = kMaxElevation;
    m.distance = 18;
  }
  m.updateHud();
  update();
  if (was != camera) emit cameraChanged(camera);
}

SceneView::Camera SceneView::camera() const { return m_->preset; }

Vec3 SceneView::cameraEye() const { return {m_->eye.x(), m_->eye.y(), m_->eye.z()}; }

void SceneView::resetView() {
  m_->azimuth = kDefaultAzimuth;
  m_->elevation = kDefaultElevation;
  m_->distance = kDefaultDistance;
  m_->centre = m_->hasRobot ? toOsgD(m_->base.p) : osg::Vec3d();
}

int64_t SceneView::framesDrawn() const { return m_->frames; }
double SceneView::framesPerSecond() const { return m_->fps; }

void SceneView::initializeGL() {
  if (!isValid()) return;
  // OSG needs the context current while it realizes; Qt has made it so.
  if (!m_->viewer->isRealized()) m_->viewer->realize();
}

void SceneView::resizeGL(int w, int h) {
  // Qt passes logical pixels; OSG draws in device pixels.
  m_->dpr = devicePixelRatioF();
  m_->pixelWidth = std::max(1, static_cast<int>(std::lround(w * m_->dpr)));
  m_->pixelHeight = std::max(1, static_cast<int>(std::lround(h * m_->dpr)));
  m_->window->resized(0, 0, m_->pixelWidth, m_->pixelHeight);
  m_->window->getEventQueue()->windowResize(0, 0, m_->pixelWidth, m_->pixelHeight);
  osg::Camera* camera = m_->viewer->getCamera();
  camera->setViewport(0, 0, m_->pixelWidth, m_->pixelHeight);
  camera->setProjectionMatrixAsPerspective(kFovY, static_cast<double>(m_->pixelWidth) / m_->pixelHeight, 0.1,
                                           1000.0);
}

void SceneView::paintGL() {
  Impl& m = *m_;
  if (!isValid() || !m.viewer->isRealized()) return;
  emit frameStarting();  // sources that change every frame (the ghost) set their state now
  // QOpenGLWidget draws into its own FBO, not 0 (shared/STACK.md).
  m.window->setDefaultFboId(defaultFramebufferObject());
  m.sync();
  m.viewer->frame();
  // OSG leaves byte-aligned unpacking after texture uploads; Qt expects 4.
  QOpenGLFunctions* gl = context()->functions();
  gl->glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl->glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);

  ++m.frames;
  ++m.windowFrames;
  const qint64 now = m.clock.elapsed();
  if (now - m.windowStart >= 1000) {
    m.fps = 1000.0 * static_cast<double>(m.windowFrames) / static_cast<double>(now - m.windowStart);
    m.windowFrames = 0;
    m.windowStart = now;
    m.updateHud();
  }
}

void SceneView::mousePressEvent(QMouseEvent* event) {
  Impl& m = *m_;
  if (event->button() == Qt::LeftButton && (m.editing || m.picking)) {
    if (const std::optional<Vec3> g = groundAt(event->position())) {
      if (m.picking) {
        m.picking = false;
        unsetCursor();
        emit groundPicked(*g);
      } else {
        m.painting = true;
        emit terrainDab(*g);
      }
    }
    event->accept();
    return;
  }
  if (m_->dragButton == Qt::NoButton) {
    m_->dragButton = event->button();
    m_->lastMouse = event->position() * m_->dpr;
  }
  event->accept();
}

void SceneView::mouseMoveEvent(QMouseEvent* event) {
  Impl& m = *m_;
  if (m.editing) {
    m.hover = groundAt(event->position());
    m.footprintDirty = true;
    if (m.hover) emit terrainHover(*m.hover);
    if (m.painting && m.hover) emit terrainDab(*m.hover);
  }
  if (m.dragButton == Qt::NoButton) return;
  const QPointF p = event->position() * m.dpr;
  const QPointF d = p - m.lastMouse;
  m.lastMouse = p;
  if (m.dragButton == Qt::LeftButton) {
    if (m.preset == Camera::Chase || m.preset == Camera::Top) setCamera(Camera::Follow);
    m.azimuth -= d.x() * kOrbitRadPerPixel;
    m.elevation = std::clamp(m.elevation + d.y() * kOrbitRadPerPixel, kMinElevation, kMaxElevation);
  } else if (m.dragButton == Qt::RightButton || m.dragButton == Qt::MiddleButton) {
    // Drag the ground under the cursor: the centre moves against the mouse,
    // in the image plane, by the metres one pixel spans at the centre.
    if (m.follow) setFollow(false);
    const double metresPerPixel = 2 * m.distance * std::tan(degToRad(kFovY) / 2) / m.pixelHeight;
    const osg::Vec3d forward(-std::cos(m.elevation) * std::cos(m.azimuth),
                             -std::cos(m.elevation) * std::sin(m.azimuth), -std::sin(m.elevation));
    const osg::Vec3d right(-std::sin(m.azimuth), std::cos(m.azimuth), 0);
    const osg::Vec3d up = right ^ forward;
    m.centre += (right * -d.x() + up * d.y()) * metresPerPixel;
  }
  event->accept();
}

void SceneView::mouseReleaseEvent(QMouseEvent* event) {
  if (event->button() == Qt::LeftButton && m_->painting) {
    m_->painting = false;
    emit terrainStrokeEnded();
  }
  if (event->button() == m_->dragButton) m_->dragButton = Qt::NoButton;
  event->accept();
}

void SceneView::wheelEvent(QWheelEvent* event) {
  // One notch (120) zooms by 12 %.
  const double notches = event->angleDelta().y() / 120.0;
  m_->distance = std::clamp(m_->distance * std::pow(0.88, notches), kMinDistance, kMaxDistance);
  event->accept();
}

}  // namespace sp

namespace sp {

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

namespace sp {

void setSceneSurfaceFormat() {
  QSurfaceFormat format;
  format.setVersion(2, 1);
  format.setProfile(QSurfaceFormat::CompatibilityProfile);
  format.setDepthBufferSize(24);
  format.setSamples(0);
  format.setSwapInterval(0);  // the view paces itself with a timer
  QSurfaceFormat::setDefaultFormat(format);
}

}  // namespace sp
