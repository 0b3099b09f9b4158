#pragma once
// The 3D view's insides (ui/scene_view.h), shared by its files: the scene
// graph's builders and colours, and SceneView::Impl, the state the setters
// store and sync() brings the graph up to before each frame.
//   scene_view.cpp          the view, the robot, laser, camera, GL, mouse
//   scene_phantoms.cpp      the translucent robots: ghost and rehearsal
//   scene_terrain_edit.cpp  terrain editing: the brush ring, picks, patches
// Internal to ui/.

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
namespace scene {

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
inline void registerFrontToBackBin() {
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

inline float f(double v) { return static_cast<float>(v); }
inline osg::Vec3 toOsg(Vec3 v) { return {f(v.x), f(v.y), f(v.z)}; }
inline osg::Vec3d toOsgD(Vec3 v) { return {v.x, v.y, v.z}; }
inline osg::Quat toOsg(const Quat& q) { return {q.x, q.y, q.z, q.w}; }  // osg order: x, y, z, w
inline osg::Vec4 toOsg(const Color& c) { return {f(c.r), f(c.g), f(c.b), f(c.a)}; }
// OSG multiplies row vectors: rotate first, then translate.
inline osg::Matrixd toMatrix(const Pose& p) {
  return osg::Matrixd::rotate(toOsg(p.q)) * osg::Matrixd::translate(toOsgD(p.p));
}

// Buffers rather than display lists: the laser's arrays change every scan.
inline osg::ref_ptr<osg::Geometry> newGeometry() {
  osg::ref_ptr<osg::Geometry> g = new osg::Geometry;
  g->setUseDisplayList(false);
  g->setUseVertexBufferObjects(true);
  return g;
}

inline void makeTransparent(osg::StateSet* s) {
  // Colour blends; the framebuffer's alpha stays 1, or Qt would compose the
  // widget's image as translucent over whatever lies behind it.
  s->setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE));
  s->setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
}

/// One geom of a link or object, in its owner's frame.
inline osg::ref_ptr<osg::Drawable> geomDrawable(const GeomSpec& g) {
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

inline osg::ref_ptr<osg::Geode> geomsNode(const std::vector<GeomSpec>& geoms) {
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  for (const GeomSpec& g : geoms) geode->addDrawable(geomDrawable(g));
  return geode;
}

/// The circle of `radius` about (x, y) draped on the ground, `lift` above
/// it: `segments` + 1 points, the last the first again (the brush's ring,
/// the ghost's regions, the departures' marks).
inline std::vector<osg::Vec3> drapedCircle(const TerrainSpec& t, double x, double y, double radius, int segments,
                                           float lift) {
  std::vector<osg::Vec3> out;
  out.reserve(static_cast<size_t>(segments) + 1);
  for (int k = 0; k <= segments; ++k) {
    const double a = 2 * kPi * (k % segments) / segments;
    const double px = x + radius * std::cos(a), py = y + radius * std::sin(a);
    out.push_back({f(px), f(py), f(groundHeight(t, px, py)) + lift});
  }
  return out;
}

/// Earth at the bottom, grass in the middle, dry light grass on top.
inline osg::Vec4 heightColor(double t) {
  const osg::Vec4 low(0.45f, 0.38f, 0.28f, 1.0f), mid(0.50f, 0.55f, 0.33f, 1.0f),
      high(0.74f, 0.72f, 0.56f, 1.0f);
  t = std::clamp(t, 0.0, 1.0);
  return t < 0.5 ? low + (mid - low) * f(2 * t) : mid + (high - mid) * f(2 * t - 1);
}

/// Two triangles per cell of a row-major grid of `columns` x `rows`
/// vertices, split along the diagonal (i, j)-(i+1, j+1) as ODE's
/// heightfield is, counter-clockwise seen from above.
inline osg::ref_ptr<osg::DrawElementsUInt> gridTriangles(int columns, int rows) {
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
inline osg::ref_ptr<osg::Node> planeNode(double z) {
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
inline osg::ref_ptr<osg::Node> heightfieldNode(const TerrainSpec& t, TerrainMesh& mesh) {
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
inline osg::ref_ptr<osg::Node> gridNode(const TerrainSpec& t) {
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
inline osg::ref_ptr<osg::Node> axesNode(double groundZ) {
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

}  // namespace scene

using namespace scene;

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
  // How sure the ghost is (scene_region.cpp): its discs about its base and
  // the trail's band, translucent on the ground, shown with the ghost; the
  // departures' marks, shown always.
  struct Region {
    osg::ref_ptr<osg::Geode> node, marksNode;
    osg::ref_ptr<osg::Geometry> inner, outer, bandStrip, marks;
    double innerRadius = 0, outerRadius = 0;
    std::vector<double> band;  // per ghost.pathPoints
    // The ghost's faint spread: the ghost's body again, fainter, as far
    // ahead and behind along its heading as the outer region reaches.
    std::array<osg::ref_ptr<osg::MatrixTransform>, 2> spread;
    double spreadDrawn = 0;  // [m] their offset as drawn; 0 hidden
    osg::ref_ptr<osg::Geode> rehearsalNode;  // the rehearsed path's band, shown with that path
    osg::ref_ptr<osg::Geometry> rehearsalStrip;
    std::vector<double> rehearsalBand;  // per rehearsal.pathPoints
    bool rehearsalDirty = false;
    std::vector<Vec3> places;  // departures
    bool lastOn = false;
    bool dirty = false, marksDirty = false;
    Vec3 drawnAt;  // the ghost's base the discs were drawn about
  } region;
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
  void buildRegion();
  void syncRegion();
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

}  // namespace sp
