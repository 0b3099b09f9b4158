// Tests of sp::intersectRay: ray casting against a HeightGrid's triangulated
// surface, checked against analytic planes and against ODE's own heightfield.

#include <ode/ode.h>

#include <QTest>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>

#include "sim/height_grid.h"
#include "sim/height_grid_ray.h"
#include "sim/math.h"
#include "tests/sim/ode_heightfield.h"

using sp::HeightGrid;
using sp::intersectRay;
using sp::Vec3;
using sp::test::OdeHeightfield;

Q_DECLARE_METATYPE(sp::Vec3)

namespace {

// Sample (i, j)'s position, as HeightGrid documents it.
double sampleX(const HeightGrid& g, int i) { return -g.width / 2 + i * g.spacingX(); }
double sampleY(const HeightGrid& g, int j) { return -g.depth / 2 + j * g.spacingY(); }

// A grid whose heights are a + b*x + c*y at the samples: a plane, which the
// two triangles of every cell reproduce exactly.
HeightGrid planeGrid(int columns, int rows, double width, double depth, double a, double b, double c) {
  HeightGrid g;
  g.columns = columns;
  g.rows = rows;
  g.width = width;
  g.depth = depth;
  g.heights.resize(static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows));
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) g.at(i, j) = a + b * sampleX(g, i) + c * sampleY(g, j);
  return g;
}

// Rolling bumps plus per-sample noise in [-noise, noise] from a fixed seed,
// so that no two neighbouring triangles are coplanar.
HeightGrid bumpyGrid(int columns, int rows, double width, double depth, double noise, std::uint64_t seed) {
  HeightGrid g = planeGrid(columns, rows, width, depth, 0, 0, 0);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-noise, noise);
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      const double x = sampleX(g, i), y = sampleY(g, j);
      g.at(i, j) = 0.3 * std::sin(0.9 * x) * std::cos(0.7 * y) + 0.1 * std::sin(2.3 * x + 1.1 * y) + jitter(rng);
    }
  return g;
}

// Unit direction from an azimuth (from +x towards +y) and an elevation
// (positive up), in degrees. Multiples of 45 deg of azimuth are built from
// exactly equal or zero components, so such rays run exactly along grid
// lines or (on square cells) exactly along cell diagonals.
Vec3 direction(double azimuthDeg, double elevationDeg) {
  const double el = sp::degToRad(elevationDeg);
  const double horizontal = std::cos(el);
  double cx = std::cos(sp::degToRad(azimuthDeg));
  double cy = std::sin(sp::degToRad(azimuthDeg));
  const double octant = azimuthDeg / 45.0;
  if (octant == std::round(octant)) {
    static constexpr std::array<std::array<double, 2>, 8> kUnit = {{{1, 0}, {1, 1}, {0, 1}, {-1, 1},  //
                                                                   {-1, 0}, {-1, -1}, {0, -1}, {1, -1}}};
    const auto& e = kUnit[static_cast<std::size_t>((static_cast<long>(octant) % 8 + 8) % 8)];
    const double s = e[0] != 0 && e[1] != 0 ? std::sqrt(0.5) : 1.0;
    cx = e[0] * s;
    cy = e[1] * s;
  }
  return {horizontal * cx, horizontal * cy, std::sin(el)};
}

// The 3x3 grid of tst_height_grid: no cell is planar.
//   j = 2:  6  7  9
//   j = 1:  2  4  5
//   j = 0:  0  1  3
HeightGrid nonPlanarGrid() {
  HeightGrid g = planeGrid(3, 3, 2, 4, 0, 0, 0);
  g.heights = {0, 1, 3, 2, 4, 5, 6, 7, 9};
  return g;
}

QString describe(Vec3 o, Vec3 d, double range) {
  return QString("origin (%1, %2, %3) direction (%4, %5, %6) range %7")
      .arg(o.x, 0, 'g', 17)
      .arg(o.y, 0, 'g', 17)
      .arg(o.z, 0, 'g', 17)
      .arg(d.x, 0, 'g', 17)
      .arg(d.y, 0, 'g', 17)
      .arg(d.z, 0, 'g', 17)
      .arg(range, 0, 'g', 17);
}

QString show(std::optional<double> t) { return t ? QString::number(*t, 'g', 17) : QString("miss"); }

}  // namespace

class TestHeightGridRay : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() { sp::test::initOde(); }

  void cleanupTestCase() { dCloseODE(); }

  void flatGrid_data() {
    QTest::addColumn<Vec3>("origin");
    QTest::addColumn<double>("azimuth");
    QTest::addColumn<double>("tilt");
    // Off the grid lines, and exactly on a grid vertex (so that 45-degree
    // beams run along cell diagonals and others through vertices).
    const std::array<Vec3, 2> origins = {Vec3{0.3, -0.7, 1.6}, Vec3{0.0, 0.0, 1.6}};
    for (const Vec3& o : origins)
      for (double tilt : {5.0, 10.0, 30.0, 45.0, 60.0, 89.5})
        for (double az : {0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0, 17.3, 200.0})
          QTest::addRow("at (%g,%g) tilt %g az %g", o.x, o.y, tilt, az) << o << az << tilt;
  }

  // On a flat grid at height h, a scanner at z0 tilted down by a hits at
  // (z0 - h)/sin(a), for any azimuth: along the axes, along the diagonals, and
  // from a grid vertex.
  void flatGrid() {
    QFETCH(Vec3, origin);
    QFETCH(double, azimuth);
    QFETCH(double, tilt);
    const double h = 0.25;
    const HeightGrid g = planeGrid(81, 81, 40, 40, h, 0, 0);  // 0.5 m cells
    const auto t = intersectRay(g, origin, direction(azimuth, -tilt), 30);
    QVERIFY(t.has_value());
    QVERIFY2(std::abs(*t - (origin.z - h) / std::sin(sp::degToRad(tilt))) < 1e-9, qPrintable(show(t)));
  }

  void slope_data() {
    QTest::addColumn<double>("b");  // dz/dx
    QTest::addColumn<double>("c");  // dz/dy
    QTest::addColumn<double>("azimuth");
    QTest::addColumn<double>("elevation");
    for (double b : {0.2, -0.5, 1.5})
      for (double az : {0.0, 30.0, 90.0, 180.0, 225.0, 300.0})
        for (double el : {-20.0, -60.0, 5.0}) QTest::addRow("s=%g az %g el %g", b, az, el) << b << 0.0 << az << el;
    QTest::newRow("tilted both ways, az 45") << 0.3 << -0.4 << 45.0 << -15.0;
    QTest::newRow("tilted both ways, az 260") << -0.7 << 0.25 << 260.0 << -35.0;
  }

  // On a slope z = 0.1 + b*x + c*y (cells 0.5 m x 0.6 m), the distance is the
  // analytic ray-plane intersection, or a miss where that point lies outside
  // the grid or behind the ray.
  void slope() {
    QFETCH(double, b);
    QFETCH(double, c);
    QFETCH(double, azimuth);
    QFETCH(double, elevation);
    const double a = 0.1;
    const HeightGrid g = planeGrid(41, 31, 20, 18, a, b, c);
    const Vec3 d = direction(azimuth, elevation);
    Vec3 o{1.1, -0.4, 0};
    o.z = a + b * o.x + c * o.y + 2.0;  // 2 m above the slope
    // z(t) = plane(x(t), y(t)):  o.z + t d.z = a + b (o.x + t d.x) + c (o.y + t d.y)
    const double denominator = d.z - b * d.x - c * d.y;
    std::optional<double> expected;
    if (denominator < 0) {
      const double t = (a + b * o.x + c * o.y - o.z) / denominator;
      const double x = o.x + t * d.x, y = o.y + t * d.y;
      if (std::abs(x) <= g.width / 2 && std::abs(y) <= g.depth / 2) expected = t;
    }
    const auto t = intersectRay(g, o, d, 100);
    QCOMPARE(t.has_value(), expected.has_value());
    if (expected) QVERIFY2(std::abs(*t - *expected) < 1e-9, qPrintable(show(t) + " vs " + show(expected)));
  }

  void verticalRay_data() {
    QTest::addColumn<double>("x");
    QTest::addColumn<double>("y");
    QTest::newRow("cell 0,0 lower-right triangle") << -0.25 << -1.5;
    QTest::newRow("cell 0,0 upper-left triangle") << -0.75 << -0.5;
    QTest::newRow("cell 1,1 lower-right triangle") << 0.5 << 0.2;
    QTest::newRow("cell 1,1 upper-left triangle") << 0.2 << 1.2;
    QTest::newRow("on a diagonal") << -0.5 << -1.0;
    QTest::newRow("on a shared edge") << 0.0 << -1.3;
    QTest::newRow("on a shared vertex") << 0.0 << 0.0;
    QTest::newRow("on the outer edge") << 1.0 << 0.5;
    QTest::newRow("on the outer corner") << -1.0 << -2.0;
  }

  // A vertical ray down onto non-planar cells hits at exactly heightAt(x, y),
  // in both triangles and on their boundaries.
  void verticalRay() {
    QFETCH(double, x);
    QFETCH(double, y);
    const HeightGrid g = nonPlanarGrid();
    const Vec3 o{x, y, 20};
    const auto t = intersectRay(g, o, {0, 0, -1}, 50);
    QVERIFY(t.has_value());
    QVERIFY2(std::abs((o.z - *t) - g.heightAt(x, y)) < 1e-12, qPrintable(show(t)));
  }

  void sharedVertexAndDiagonal_data() {
    QTest::addColumn<double>("fi");  // target in sample units: x = -5 + fi
    QTest::addColumn<double>("fj");
    QTest::addColumn<double>("azimuth");
    // Exactly along the main diagonal through cells (k, k) and vertices (k, k).
    QTest::newRow("vertex, along the diagonals") << 3.0 << 3.0 << 45.0;
    QTest::newRow("vertex, along the diagonals backwards") << 3.0 << 3.0 << 225.0;
    // Exactly along a row line, then a column line (shared edges all the way).
    QTest::newRow("vertex, along a row line") << 3.0 << 3.0 << 0.0;
    QTest::newRow("vertex, along a column line") << 3.0 << 3.0 << 90.0;
    QTest::newRow("vertex, along a column line backwards") << 3.0 << 3.0 << 270.0;
    // Through the vertex across the diagonals, and at an odd angle.
    QTest::newRow("vertex, across the diagonals") << 3.0 << 3.0 << 135.0;
    QTest::newRow("vertex, az 31") << 6.0 << 2.0 << 31.0;
    // Onto the middle of shared edges and of a diagonal.
    QTest::newRow("edge midpoint, along x") << 4.0 << 5.5 << 0.0;
    QTest::newRow("edge midpoint, along y") << 4.5 << 5.0 << 90.0;
    QTest::newRow("edge midpoint, az 200") << 7.0 << 2.5 << 200.0;
    QTest::newRow("diagonal midpoint, along it") << 5.5 << 5.5 << 45.0;
    QTest::newRow("diagonal midpoint, across it") << 2.5 << 6.5 << 135.0;
    QTest::newRow("diagonal midpoint, az 290") << 6.5 << 3.5 << 290.0;
  }

  // A steep ray aimed at a shared grid vertex, a shared edge or a cell
  // diagonal of a bumpy grid hits there (3 m from its origin): the surface has
  // no gaps along edges, at vertices or along diagonals.
  void sharedVertexAndDiagonal() {
    QFETCH(double, fi);
    QFETCH(double, fj);
    QFETCH(double, azimuth);
    const HeightGrid g = bumpyGrid(11, 11, 10, 10, 0.05, 7);  // 1 m square cells, slopes < 0.7
    const Vec3 d = direction(azimuth, -70);                    // steeper than any triangle
    const Vec3 target{-5 + fi, -5 + fj, g.heightAt(-5 + fi, -5 + fj)};
    const Vec3 o = target - 3.0 * d;
    const auto t = intersectRay(g, o, d, 10);
    QVERIFY2(t.has_value(), qPrintable(describe(o, d, 10)));
    QVERIFY2(std::abs(*t - 3.0) < 1e-9, qPrintable(show(t)));
  }

  void misses_data() {
    QTest::addColumn<Vec3>("origin");
    QTest::addColumn<Vec3>("dir");
    QTest::addColumn<double>("range");
    // Flat grid at z = 0 over [-10, 10] x [-10, 10].
    QTest::newRow("pointing up") << Vec3{1, 2, 1.6} << direction(30, 10) << 10.0;
    QTest::newRow("vertical up") << Vec3{1, 2, 1.6} << Vec3{0, 0, 1} << 10.0;
    QTest::newRow("level") << Vec3{1, 2, 1.6} << direction(0, 0) << 10.0;
    QTest::newRow("hit 1e-9 beyond the range") << Vec3{1, 2, 1.6} << Vec3{0, 0, -1} << 1.6 - 1e-9;
    QTest::newRow("hit beyond the range, tilted") << Vec3{1, 2, 1.6} << direction(200, -10) << 9.0;
    QTest::newRow("zero range above ground") << Vec3{1, 2, 1.6} << direction(120, -5) << 0.0;
    QTest::newRow("leaves the grid before it would hit") << Vec3{8, 0, 1.6} << direction(0, -5) << 30.0;
    QTest::newRow("leaves through a corner") << Vec3{8, 8, 1.6} << direction(45, -5) << 30.0;
    QTest::newRow("outside, heading away") << Vec3{12, 0, 1.6} << direction(0, -5) << 30.0;
    QTest::newRow("outside, passing beside") << Vec3{-12, 11, 1.6} << direction(0, -3) << 30.0;
    QTest::newRow("outside, vertical beside") << Vec3{-12, 0, 1.6} << Vec3{0, 0, -1} << 30.0;
    QTest::newRow("crosses the grid too high") << Vec3{-12, 0, 1.6} << direction(0, -2) << 60.0;
    QTest::newRow("enters below the surface and stays below") << Vec3{-12, 0, -1} << direction(0, -1) << 60.0;
  }

  // No hit: rays pointing up or level, hits beyond maxRange, rays leaving the
  // grid before they would reach the (extended) surface, rays outside it.
  void misses() {
    QFETCH(Vec3, origin);
    QFETCH(Vec3, dir);
    QFETCH(double, range);
    const HeightGrid g = planeGrid(41, 41, 20, 20, 0, 0, 0);
    const auto t = intersectRay(g, origin, dir, range);
    QVERIFY2(!t, qPrintable(show(t)));
  }

  void originOutside_data() {
    QTest::addColumn<Vec3>("origin");
    QTest::addColumn<double>("azimuth");
    QTest::addColumn<double>("elevation");
    QTest::addColumn<double>("expected");
    // Flat grid at z = 0 over [-10, 10] x [-10, 10]; distance z/sin(tilt).
    QTest::newRow("west, level az") << Vec3{-15, 0.5, 2} << 0.0 << -5.0 << 2 / std::sin(sp::degToRad(5));
    QTest::newRow("south, az 90") << Vec3{0.3, -30, 4} << 90.0 << -10.0 << 4 / std::sin(sp::degToRad(10));
    QTest::newRow("north-east corner, az 225") << Vec3{14, 13, 3} << 225.0 << -8.0 << 3 / std::sin(sp::degToRad(8));
    QTest::newRow("east, az 170") << Vec3{16, 2, 1.5} << 170.0 << -6.0 << 1.5 / std::sin(sp::degToRad(6));
    // Enters below the surface and comes up through it (as ODE reports it).
    QTest::newRow("enters below, comes up") << Vec3{-15, 0, -7} << 0.0 << 30.0 << 7 / std::sin(sp::degToRad(30));
  }

  // A ray from outside the grid's rectangle is clipped to it and hits inside.
  void originOutside() {
    QFETCH(Vec3, origin);
    QFETCH(double, azimuth);
    QFETCH(double, elevation);
    QFETCH(double, expected);
    const HeightGrid g = planeGrid(41, 41, 20, 20, 0, 0, 0);
    const auto t = intersectRay(g, origin, direction(azimuth, elevation), 60);
    QVERIFY(t.has_value());
    QVERIFY2(std::abs(*t - expected) < 1e-9, qPrintable(show(t)));
  }

  void originBelow_data() {
    QTest::addColumn<Vec3>("dir");
    QTest::addColumn<double>("depthBelow");
    QTest::newRow("down") << direction(20, -30) << 0.3;
    QTest::newRow("up") << direction(20, 30) << 0.3;
    QTest::newRow("level") << direction(250, 0) << 0.3;
    QTest::newRow("vertical up") << Vec3{0, 0, 1} << 0.3;
    QTest::newRow("vertical down") << Vec3{0, 0, -1} << 0.3;
    QTest::newRow("just below, up") << direction(100, 60) << 1e-12;
    QTest::newRow("on the surface, up") << direction(100, 60) << 0.0;
    QTest::newRow("on the surface, vertical up") << Vec3{0, 0, 1} << 0.0;
  }

  // A ray starting on or below the surface reports distance 0, whatever its
  // direction.
  void originBelow() {
    QFETCH(Vec3, dir);
    QFETCH(double, depthBelow);
    const HeightGrid g = bumpyGrid(41, 41, 10, 10, 0.05, 3);
    for (const auto& [x, y] : {std::pair{0.33, -1.21}, std::pair{-3.9, 4.07}, std::pair{2.2, 2.1}}) {
      const Vec3 o{x, y, g.heightAt(x, y) - depthBelow};
      const auto t = intersectRay(g, o, dir, 10);
      QVERIFY2(t == 0.0, qPrintable(describe(o, dir, 10) + ": " + show(t)));
    }
  }

  // Every reported hit lies on the surface heightAt describes (2000 random
  // rays on a bumpy grid with 0.25 m x 0.3 m cells).
  void hitsLieOnSurface() {
    const HeightGrid g = bumpyGrid(41, 41, 10, 12, 0.05, 11);
    std::mt19937_64 rng(20240611);
    std::uniform_real_distribution<double> ux(-5, 5), uy(-6, 6), uz(0.01, 2), uaz(0, 360), uel(-80, 10);
    int hits = 0;
    for (int k = 0; k < 2000; ++k) {
      const double x = ux(rng), y = uy(rng);
      const Vec3 o{x, y, g.heightAt(x, y) + uz(rng)};
      const Vec3 d = direction(uaz(rng), uel(rng));
      const auto t = intersectRay(g, o, d, 15);
      if (!t) continue;
      ++hits;
      const Vec3 p = o + *t * d;
      QVERIFY2(std::abs(p.z - g.heightAt(p.x, p.y)) < 1e-9, qPrintable(describe(o, d, 15) + ": " + show(t)));
    }
    QVERIFY(hits > 1000);
  }

  // maxRange may be infinite, for vertical and slanted rays alike.
  void infiniteRange() {
    const double inf = std::numeric_limits<double>::infinity();
    const HeightGrid g = nonPlanarGrid();
    const auto down = intersectRay(g, {0.2, 1.2, 20}, {0, 0, -1}, inf);
    QVERIFY(down.has_value());
    QVERIFY(std::abs((20 - *down) - g.heightAt(0.2, 1.2)) < 1e-12);
    QVERIFY(!intersectRay(g, {0.2, 1.2, 20}, {0, 0, 1}, inf));
    QCOMPARE(intersectRay(g, {0.2, 1.2, -20}, {0, 0, 1}, inf), std::optional<double>(0.0));
    const HeightGrid flat = planeGrid(41, 41, 20, 20, 0, 0, 0);
    const auto slanted = intersectRay(flat, {-15, 0.5, 2}, direction(0, -5), inf);
    QVERIFY(slanted.has_value());
    QVERIFY(std::abs(*slanted - 2 / std::sin(sp::degToRad(5))) < 1e-9);
  }

  // Unusable input gives nullopt instead of reading out of bounds.
  void invalidInput() {
    const HeightGrid g = planeGrid(5, 5, 4, 4, 0, 0, 0);
    const Vec3 o{0, 0, 1}, down{0, 0, -1};
    QVERIFY(intersectRay(g, o, down, 5).has_value());
    QVERIFY(!intersectRay(HeightGrid{}, o, down, 5));
    HeightGrid wrongSize = g;
    wrongSize.heights.pop_back();
    QVERIFY(!intersectRay(wrongSize, o, down, 5));
    QVERIFY(!intersectRay(g, o, {0, 0, 0}, 5));
    QVERIFY(!intersectRay(g, {std::nan(""), 0, 1}, down, 5));
    QVERIFY(!intersectRay(g, o, down, -1));
    QVERIFY(!intersectRay(g, o, down, std::nan("")));
  }

  // Our surface is ODE's: on a bumpy 41x41 grid (non-square 0.25 m x 0.3 m
  // cells, so a swapped axis or flipped row would show), 2000 random rays give
  // the same hit or miss and distances within 1e-6 m as ODE's ray against a
  // heightfield geom built as sim/world.cpp builds it. Only rays whose outcome
  // flips when moved by 1e-9 m (grazing an edge or ending at the surface) may
  // disagree on hit or miss.
  void matchesOde() {
    const HeightGrid g = bumpyGrid(41, 41, 10, 12, 0.05, 5);
    OdeHeightfield ode(g);
    const double top = g.maxHeight();
    std::mt19937_64 rng(0x5eed);
    std::uniform_real_distribution<double> ux(-6, 6), uy(-7.2, 7.2), uz(0.01, 2), uaz(0, 360), uel(-75, 12),
        urange(0.5, 14), u01(0, 1);
    int hits = 0, misses = 0, grazing = 0;
    double maxDiff = 0;
    for (int k = 0; k < 2000; ++k) {
      const double x = ux(rng), y = uy(rng);
      const bool inside = std::abs(x) <= g.width / 2 && std::abs(y) <= g.depth / 2;
      // Origins above the surface (ODE reports rays wholly under it differently).
      const Vec3 o{x, y, (inside ? g.heightAt(x, y) : top) + uz(rng)};
      double az = uaz(rng);
      const double pick = u01(rng);
      if (pick < 0.1) az = 45.0 * std::floor(az / 45.0);  // axis-parallel and diagonal beams
      const Vec3 d = pick > 0.97 ? Vec3{0, 0, -1} : direction(az, uel(rng));
      const double range = urange(rng);

      const auto ours = intersectRay(g, o, d, range);
      const auto theirs = ode.cast(o, d, range);
      if (ours && theirs && std::abs(*ours - *theirs) <= 1e-6) {
        maxDiff = std::max(maxDiff, std::abs(*ours - *theirs));
        ++hits;
        continue;
      }
      if (!ours && !theirs) {
        ++misses;
        continue;
      }
      // Disagreement: allowed only where a 1e-9 m change flips our outcome.
      auto flips = [&](Vec3 oo, double rr) { return intersectRay(g, oo, d, rr).has_value() != ours.has_value(); };
      const bool graze = flips(o + Vec3{0, 0, 1e-9}, range) || flips(o - Vec3{0, 0, 1e-9}, range) ||
                         flips(o, range + 1e-9) || flips(o, range - 1e-9);
      QVERIFY2(graze, qPrintable(describe(o, d, range) + ": ours " + show(ours) + ", ODE " + show(theirs)));
      ++grazing;
    }
    QVERIFY(!ode.overflowed());
    qInfo("%d hits, %d misses, %d grazing; largest distance difference %.3g m", hits, misses, grazing, maxDiff);
    QVERIFY(hits > 600 && misses > 200);
    QVERIFY(grazing <= 2);
  }
};

QTEST_GUILESS_MAIN(TestHeightGridRay)
#include "tst_height_grid_ray.moc"
