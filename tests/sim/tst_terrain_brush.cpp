// Terrain brushes and terrain files (issue 16): each brush against its
// formula on a known grid; a box resting on raised ground rises with it;
// grids saved as .asc, .pgm and .csv load back as they were, and a world
// file saved with its terrain loads.

#include <QTest>

#include <cmath>
#include <filesystem>
#include <tuple>

#include "sim/model_loader.h"
#include "sim/terrain_brush.h"
#include "sim/terrain_file.h"
#include "tests/sim/world_fixture.h"

using namespace sp;
using sp::test::stepFor;
using sp::test::WorldFixture;

namespace {

// 21 x 21 samples over 2 m x 2 m (0.1 m apart), h = 0.01 i + 0.02 j + a
// bump, so that every sample differs from its neighbours' mean.
HeightGrid knownGrid() {
  HeightGrid g{21, 21, 2.0, 2.0, {}};
  g.heights.resize(21 * 21);
  for (int j = 0; j < 21; ++j)
    for (int i = 0; i < 21; ++i) g.at(i, j) = 0.01 * i + 0.02 * j + 0.05 * std::sin(i * 0.7) * std::cos(j * 0.4);
  return g;
}

// The formula, written out again: w(d) = (1 - (d/r)^2)^2 inside r.
double weight(double d, double r) { return d < r ? std::pow(1 - (d / r) * (d / r), 2) : 0.0; }

double mean3x3(const HeightGrid& g, int i, int j) {
  double sum = 0;
  int n = 0;
  for (int b = std::max(0, j - 1); b <= std::min(g.rows - 1, j + 1); ++b)
    for (int a = std::max(0, i - 1); a <= std::min(g.columns - 1, i + 1); ++a, ++n) sum += g.at(a, b);
  return sum / n;
}

}  // namespace

class TestTerrainBrush : public QObject {
  Q_OBJECT

 private slots:
  void brushesFollowTheirFormulas_data() {
    QTest::addColumn<int>("kind");
    QTest::newRow("raise") << static_cast<int>(BrushKind::Raise);
    QTest::newRow("lower") << static_cast<int>(BrushKind::Lower);
    QTest::newRow("smooth") << static_cast<int>(BrushKind::Smooth);
    QTest::newRow("flatten") << static_cast<int>(BrushKind::Flatten);
  }
  // Criterion: every sample within the radius of the dab's centre is in the
  // patch with the formula's height (1e-12 m), every other sample of the
  // patch keeps its height, and no sample within the radius is left out.
  void brushesFollowTheirFormulas() {
    QFETCH(int, kind);
    const HeightGrid g = knownGrid();
    const Brush brush{static_cast<BrushKind>(kind), 0.45, kind >= 2 ? 0.7 : 0.03, 0.12, 1};
    const Vec2 centre{0.03, -0.02};  // between samples
    const std::optional<TerrainPatchCmd> patch = brushDab(g, centre, brush);
    QVERIFY(patch);
    int inside = 0;
    for (int j = 0; j < g.rows; ++j)
      for (int i = 0; i < g.columns; ++i) {
        const double x = -1.0 + 0.1 * i, y = -1.0 + 0.1 * j;
        const double w = weight(std::hypot(x - centre.x, y - centre.y), brush.radius);
        const bool inPatch = i >= patch->column && i < patch->column + patch->columns && j >= patch->row &&
                             j < patch->row + patch->rows;
        if (w > 0) QVERIFY(inPatch);
        if (!inPatch) continue;
        const double h = g.at(i, j);
        double expected = h;
        switch (static_cast<BrushKind>(kind)) {
          case BrushKind::Raise: expected = h + 0.03 * w; break;
          case BrushKind::Lower: expected = h - 0.03 * w; break;
          case BrushKind::Smooth: expected = h + 0.7 * w * (mean3x3(g, i, j) - h); break;
          case BrushKind::Flatten: expected = h + 0.7 * w * (0.12 - h); break;
          default: break;
        }
        const double got = patch->heights[static_cast<size_t>((j - patch->row) * patch->columns + (i - patch->column))];
        QVERIFY2(std::abs(got - expected) < 1e-12, qPrintable(QStringLiteral("sample %1,%2: %3 vs %4").arg(i).arg(j).arg(got).arg(expected)));
        if (w > 0 && kind != static_cast<int>(BrushKind::Smooth)) QVERIFY(got != h);  // it did something
        inside += w > 0;
      }
    QVERIFY(inside >= 50);  // pi 0.45^2 / 0.01 = 64 samples
  }

  // Noise: within +-strength w of the height, the same for the same seed
  // and another for another; both signs; a dab off the grid is nothing.
  void noiseIsBoundedAndSeeded() {
    const HeightGrid g = knownGrid();
    const Brush brush{BrushKind::Noise, 0.6, 0.02, 0, 7};
    const auto a = brushDab(g, {0, 0}, brush), b = brushDab(g, {0, 0}, brush);
    Brush other = brush;
    other.seed = 8;
    const auto c = brushDab(g, {0, 0}, other);
    QVERIFY(a && b && c);
    QCOMPARE(a->heights, b->heights);
    QVERIFY(a->heights != c->heights);
    int up = 0, down = 0;
    for (int r = 0; r < a->rows; ++r)
      for (int k = 0; k < a->columns; ++k) {
        const int i = a->column + k, j = a->row + r;
        const double w = weight(std::hypot(-1.0 + 0.1 * i, -1.0 + 0.1 * j), 0.6);
        const double d = a->heights[static_cast<size_t>(r * a->columns + k)] - g.at(i, j);
        QVERIFY(std::abs(d) <= 0.02 * w + 1e-15);
        up += d > 0;
        down += d < 0;
      }
    QVERIFY(up > 20 && down > 20);
    QVERIFY(!brushDab(g, {5, 5}, brush));              // off the grid
    QVERIFY(!brushDab(g, {0, 0}, Brush{BrushKind::Raise, 0, 0.1, 0, 1}));  // no radius
  }

  // A box resting on a heightfield rises with ground raised under it.
  // Criterion (stated before the run): raised 0.1 m by a 2 m brush, the box
  // settles within 5 mm of 0.1 m higher (the samples under it rise 0.098
  // to 0.1 m: the falloff at 0.2 m of 2 m is 0.98); a box 3 m away, outside the brush, moves less
  // than 1 mm (the control).
  void boxRisesWithRaisedGround() {
    WorldFixture f;
    QString rows;
    for (int r = 0; r < 41; ++r) rows += QString("0") + QString(",0").repeated(40) + "\n";
    f.write("flat.csv", rows.toStdString());
    auto world = f.build(R"(<world name="w">
      <terrain type="heightfield" file="flat.csv" width="8" depth="8"/>
      <object name="box" static="false" mass="5" xyz="0 0 0.1"><geom type="box" size="0.2 0.2 0.2"/></object>
      <object name="far" static="false" mass="5" xyz="3 0 0.1"><geom type="box" size="0.2 0.2 0.2"/></object>
    </world>)");
    QVERIFY(world);
    stepFor(*world, 1.0);
    const double z0 = world->objectPose(0).p.z, far0 = world->objectPose(1).p.z;
    const auto patch = brushDab(*world->terrainGrid(), {0, 0}, Brush{BrushKind::Raise, 2.0, 0.1, 0, 1});
    QVERIFY(patch);
    QCOMPARE(patchFits(world->terrainGrid(), *patch), std::string());
    world->submit(*patch);
    stepFor(*world, 2.0);
    const double rise = world->objectPose(0).p.z - z0, farRise = world->objectPose(1).p.z - far0;
    qInfo("raised 0.1 m: the box rose %.4f m, the box outside the brush %.5f m", rise, farRise);
    QVERIFY(std::abs(rise - 0.1) < 0.005);
    QVERIFY(std::abs(farRise) < 0.001);
    QVERIFY(std::abs(world->terrainHeight(0, 0) - 0.1) < 1e-12);
  }

  // Issue 31: a stroke under the robot lifts its wheels, it does not bury
  // them. Criterion (stated before the run): WorkPartner standing on a flat
  // heightfield gets 0.12 m raised by a 0.5 m brush right under its front
  // left wheel (steeper than a wheel climbs: buried, the wheel was driven
  // out of the ground or the twin diverged); one step later no contact is
  // deeper than 1 cm, the robot stands 2 s healthy and the wheel's centre
  // ends within 2 cm of 0.32 m (0.2 + the 0.12 raised). The control: the
  // same stroke 4 m away lifts nothing (base within 1 mm).
  void strokeUnderTheRobotLiftsIt() {
    const auto standing = [](Vec2 where) {
      WorldFixture f;
      QString rows;
      for (int r = 0; r < 81; ++r) rows += QString("0") + QString(",0").repeated(80) + "\n";
      f.write("flat.csv", rows.toStdString());
      auto world = f.build("<world name=\"w\">\n"
                           "  <material name=\"rubber\"/>\n"
                           "  <terrain type=\"heightfield\" file=\"flat.csv\" width=\"10\" depth=\"10\"/>\n"
                           "  <robot name=\"workpartner\" file=\"" SP_SOURCE_DIR "/robots/workpartner.xml\"/>\n"
                           "</world>");
      if (!world) return std::make_tuple(false, 0.0, 0.0, 0.0);
      stepFor(*world, 1.0);
      const double base0 = world->linkPose(0, 0).p.z;
      const auto patch = brushDab(*world->terrainGrid(), where, Brush{BrushKind::Raise, 0.5, 0.12, 0, 1});
      if (!patch || !world->submit(*patch).empty()) return std::make_tuple(false, 0.0, 0.0, 0.0);
      world->step();
      double deepest = 0;
      for (const LinkContact& c : world->linkContacts()) deepest = std::max(deepest, c.depth);
      stepFor(*world, 2.0);
      const int wheel = world->robotModel(0).findLink("wheel_fl");
      return std::make_tuple(world->health().healthy(), deepest, world->linkPose(0, wheel).p.z,
                             world->linkPose(0, 0).p.z - base0);
    };
    const auto [healthy, deepest, wheelZ, rise] = standing({0.55, 0.42});
    qInfo("raised 0.12 m under wheel_fl: deepest contact %.4f m a step later, wheel centre at %.3f m, healthy %d",
          deepest, wheelZ, healthy);
    QVERIFY(healthy);
    QVERIFY2(deepest < 0.01, qPrintable(QString::number(deepest)));
    QVERIFY2(std::abs(wheelZ - 0.32) < 0.02, qPrintable(QString::number(wheelZ)));
    const auto [farHealthy, farDeepest, farWheel, farRise] = standing({4.0, 0.0});
    qInfo("the same 4 m away: base moved %.5f m", farRise);
    QVERIFY(farHealthy);
    QVERIFY(std::abs(farRise) < 0.001);
  }

  // Saved and loaded again: .asc and .csv hold every height exactly; .pgm
  // within half a 16-bit step of the height range. A world saved with the
  // terrain loads, its grid the saved one.
  void savedTerrainsLoadBack() {
    const HeightGrid g = knownGrid();
    QTemporaryDir dir;
    for (const char* name : {"t.asc", "t.csv", "t.pgm"}) {
      const std::string path = dir.filePath(name).toStdString();
      std::string error;
      QVERIFY2(saveHeightGrid(path, g, error), error.c_str());
      TerrainSource source{path, TerrainFormat::Auto, 2.0, 2.0, g.minHeight(), g.maxHeight(), 0.05};
      Diagnostics diag;
      const std::optional<HeightGrid> back = loadHeightGrid(source, diag);
      QVERIFY2(back, diag.format().c_str());
      QCOMPARE(back->columns, 21);
      QCOMPARE(back->rows, 21);
      const bool exact = formatOf(path) != TerrainFormat::Pgm;
      const double step = (g.maxHeight() - g.minHeight()) / 65535;
      for (size_t k = 0; k < g.heights.size(); ++k)
        QVERIFY2(exact ? back->heights[k] == g.heights[k] : std::abs(back->heights[k] - g.heights[k]) <= step / 2 + 1e-12, name);
    }
    // The world file that uses it: the robot's path rewritten for the new folder.
    std::string error;
    const std::string world = std::string(SP_SOURCE_DIR) + "/terrains/test_track.world.xml";
    const std::string terrain = dir.filePath("track.csv").toStdString(), out = dir.filePath("track.world.xml").toStdString();
    QVERIFY2(saveHeightGrid(terrain, g, error), error.c_str());
    QVERIFY2(saveWorldWithTerrain(world, out, terrain, g, error), error.c_str());
    Diagnostics diag;
    const std::optional<WorldModel> loaded = loadWorld(out, diag);
    QVERIFY2(loaded, diag.format().c_str());
    QCOMPARE(loaded->terrain.grid.heights, g.heights);
    QVERIFY(!loaded->robots.empty());
    // Bad input: a folder that does not exist names the file, leaves nothing.
    const std::string nowhere = dir.filePath("no/such/t.csv").toStdString();
    QVERIFY(!saveHeightGrid(nowhere, g, error));
    QVERIFY2(error.find(nowhere) != std::string::npos, error.c_str());
    QVERIFY(!saveHeightGrid(dir.filePath("t.png").toStdString(), g, error));
    QVERIFY2(error.find(".asc, .pgm or .csv") != std::string::npos, error.c_str());
  }
};

QTEST_APPLESS_MAIN(TestTerrainBrush)
#include "tst_terrain_brush.moc"
