// Tests of sp::sphereContacts (sim/height_grid_sphere.h): a sphere (a tyre)
// against a HeightGrid's triangles, checked against geometry and against
// ODE's own sphere-vs-heightfield where that one is right.

#include <QTest>
#include <cmath>
#include <random>

#include "sim/height_grid.h"
#include "sim/height_grid_sphere.h"
#include "tests/sim/ode_heightfield.h"

using namespace sp;

namespace {

HeightGrid grid(int columns, int rows, double width, double depth) {
  HeightGrid g;
  g.columns = columns;
  g.rows = rows;
  g.width = width;
  g.depth = depth;
  g.heights.assign(static_cast<size_t>(columns) * static_cast<size_t>(rows), 0.0);
  return g;
}

// 0.5 m cells, a ridge 3 cm high along x at y = 0 (rows 0 and 2 at 0, row 1
// at 3 cm): two planes meeting at a convex crease, symmetric in y.
HeightGrid ridge() {
  HeightGrid g = grid(3, 3, 1, 1);
  for (int i = 0; i < 3; ++i) g.at(i, 1) = 0.03;
  return g;
}

std::vector<SurfaceContact> contacts(const HeightGrid& g, Vec3 centre, double radius) {
  std::vector<SurfaceContact> out(64);
  out.resize(static_cast<size_t>(sphereContacts(g, centre, radius, out.data(), 64)));
  return out;
}

double deepest(const std::vector<SurfaceContact>& c) {
  double d = 0;
  for (const SurfaceContact& k : c) d = std::max(d, k.depth);
  return d;
}

}  // namespace

class TestHeightGridSphere : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() { sp::test::initOde(); }
  void cleanupTestCase() { dCloseODE(); }

  // On a face, 1 mm in: one contact, straight up, at the sphere's lowest
  // point, as ODE gives it.
  void faceAsOde() {
    const HeightGrid g = grid(3, 3, 1, 1);
    const Vec3 centre{-1.0 / 6, -1.0 / 3, 0.199};  // inside triangle (0,0)-(1,0)-(1,1)
    const std::vector<SurfaceContact> c = contacts(g, centre, 0.2);
    QCOMPARE(c.size(), size_t{1});
    QVERIFY(std::abs(c[0].depth - 0.001) < 1e-12);
    QVERIFY(norm(c[0].normal - Vec3{0, 0, 1}) < 1e-12);
    QVERIFY(norm(c[0].position - Vec3{centre.x, centre.y, -0.001}) < 1e-12);
    test::OdeHeightfield ode(g);
    const std::vector<dContactGeom> o = ode.sphere(centre, 0.2);
    QCOMPARE(o.size(), size_t{1});
    QVERIFY(std::abs(o[0].depth - c[0].depth) < 1e-12);
    QVERIFY(norm(Vec3{o[0].pos[0], o[0].pos[1], o[0].pos[2]} - c[0].position) < 1e-12);
    QVERIFY(norm(Vec3{o[0].normal[0], o[0].normal[1], o[0].normal[2]} - c[0].normal) < 1e-12);
  }

  // Over the ridge, 1 cm in: held by the ridge, straight up. ODE finds
  // nothing there (each plane's contact point lies in the other plane's
  // triangles), the fault this collider mends: the control shows the case
  // is the one it misses.
  void ridgeHolds() {
    const HeightGrid g = ridge();
    const Vec3 centre{0.1, 0, 0.03 + 0.2 - 0.01};
    const std::vector<SurfaceContact> c = contacts(g, centre, 0.2);
    QVERIFY(!c.empty());
    QVERIFY2(std::abs(deepest(c) - 0.01) < 1e-12, qPrintable(QString::number(deepest(c), 'g', 17)));
    for (const SurfaceContact& k : c) QVERIFY(k.normal.z > 0.998);
    test::OdeHeightfield ode(g);
    QCOMPARE(ode.sphere(centre, 0.2).size(), size_t{0});  // control: ODE's path sinks here
    // Deeper still (10 cm), as a sinking wheel would be: still held, as deep.
    const std::vector<SurfaceContact> deep = contacts(g, {0.1, 0, 0.03 + 0.1}, 0.2);
    QVERIFY(std::abs(deepest(deep) - 0.1) < 1e-12);
    QCOMPARE(ode.sphere({0.1, 0, 0.03 + 0.1}, 0.2).size(), size_t{0});
  }

  // A centre below the surface is pushed out along the face's normal, by
  // its depth plus the radius; off the grid there is no ground.
  void centreBelowAndOffTheGrid() {
    const HeightGrid g = grid(3, 3, 1, 1);
    const std::vector<SurfaceContact> c = contacts(g, {-1.0 / 6, -1.0 / 3, -0.05}, 0.2);
    QVERIFY(!c.empty());
    QVERIFY(std::abs(deepest(c) - 0.25) < 1e-12);
    for (const SurfaceContact& k : c) QVERIFY(norm(k.normal - Vec3{0, 0, 1}) < 1e-12);
    QCOMPARE(contacts(g, {0.8, 0, 0.1}, 0.2).size(), size_t{0});
    QCOMPARE(contacts(g, {0.1, 0, 0.25}, 0.2).size(), size_t{0});  // above, not touching
  }

  // On a rough grid, wherever ODE reports a contact whose foot (the point
  // of its plane nearest the centre) lies on the surface, one of ours has its
  // depth and normal: the faces are ODE's. (ODE keeps a plane's contact when
  // the sphere's lowest point is over the triangle; near an edge the foot
  // may lie over the next triangle, and the plane's depth overstates the
  // surface's: ours is the surface's nearest point.) And every sphere over
  // the surface within its radius touches.
  void roughGridAgreesWithOdeOnFaces() {
    HeightGrid g = grid(21, 21, 10, 10);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> h(-0.05, 0.05), x(-4.5, 4.5), in(0.001, 0.03);
    for (double& v : g.heights) v = h(rng);
    test::OdeHeightfield ode(g);
    int odeContacts = 0, onFaces = 0, oursDeeper = 0;
    for (int n = 0; n < 300; ++n) {
      const double px = x(rng), py = x(rng);
      const Vec3 centre{px, py, g.heightAt(px, py) + 0.2 - in(rng)};
      const std::vector<SurfaceContact> ours = contacts(g, centre, 0.2);
      QVERIFY(!ours.empty());  // the centre stands over the surface, less than r above it
      const std::vector<dContactGeom> o = ode.sphere(centre, 0.2);
      double odeDeepest = 0;
      for (const dContactGeom& k : o) {
        ++odeContacts;
        odeDeepest = std::max(odeDeepest, static_cast<double>(k.depth));
        const Vec3 normal{k.normal[0], k.normal[1], k.normal[2]};
        const Vec3 foot = centre - (0.2 - k.depth) * normal;
        if (std::abs(g.heightAt(foot.x, foot.y) - foot.z) > 1e-9) continue;
        ++onFaces;
        bool matched = false;
        for (const SurfaceContact& m : ours)
          matched = matched || (std::abs(m.depth - k.depth) < 1e-9 && norm(m.normal - normal) < 1e-9);
        QVERIFY2(matched, qPrintable(QString("sphere %1: ODE depth %2 unmatched").arg(n).arg(k.depth)));
      }
      if (deepest(ours) > odeDeepest + 1e-6) ++oursDeeper;
    }
    qInfo("300 spheres: %d ODE contacts, %d with their foot on the surface, each matched; %d spheres reached "
          "deeper than ODE's deepest (a ridge or a vertex)",
          odeContacts, onFaces, oursDeeper);
    QVERIFY(onFaces > 200);
  }
};

QTEST_GUILESS_MAIN(TestHeightGridSphere)
#include "tst_height_grid_sphere.moc"
