// Tests of sp::HeightGrid: extremes and interpolation on the two triangles of
// each cell, split by the diagonal from (i, j) to (i+1, j+1).

#include <QTest>
#include <cmath>

#include "sim/height_grid.h"

namespace {

// 3 x 3 samples over 2 m x 4 m: spacing 1 m along x, 2 m along y, so sample
// (i, j) sits at x = -1 + i, y = -2 + 2j. No cell is planar.
//   j = 2:  6  7  9
//   j = 1:  2  4  5
//   j = 0:  0  1  3
sp::HeightGrid makeGrid() {
  sp::HeightGrid g;
  g.columns = 3;
  g.rows = 3;
  g.width = 2;
  g.depth = 4;
  g.heights = {0, 1, 3,  //
               2, 4, 5,  //
               6, 7, 9};
  return g;
}

}  // namespace

class TestHeightGrid : public QObject {
  Q_OBJECT

 private slots:
  // Extremes are taken over all samples; an empty grid reports 0.
  void minMaxHeight() {
    sp::HeightGrid g = makeGrid();
    g.at(1, 2) = -3.5;
    QCOMPARE(g.minHeight(), -3.5);
    QCOMPARE(g.maxHeight(), 9.0);
    QCOMPARE(sp::HeightGrid{}.minHeight(), 0.0);
    QCOMPARE(sp::HeightGrid{}.maxHeight(), 0.0);
  }

  // at(i, j) addresses index j*columns + i and the spacing follows the extents.
  void indexingAndSpacing() {
    const sp::HeightGrid g = makeGrid();
    QCOMPARE(g.at(2, 0), 3.0);
    QCOMPARE(g.at(0, 1), 2.0);
    QCOMPARE(g.spacingX(), 1.0);
    QCOMPARE(g.spacingY(), 2.0);
  }

  void heightAt_data() {
    QTest::addColumn<double>("x");
    QTest::addColumn<double>("y");
    QTest::addColumn<double>("expected");
    // Samples are returned exactly.
    QTest::newRow("sample (0,0)") << -1.0 << -2.0 << 0.0;
    QTest::newRow("sample (1,0)") << 0.0 << -2.0 << 1.0;
    QTest::newRow("sample (0,1)") << -1.0 << 0.0 << 2.0;
    QTest::newRow("sample (1,1)") << 0.0 << 0.0 << 4.0;
    QTest::newRow("sample (2,2)") << 1.0 << 2.0 << 9.0;
    // Cell (0,0), u = 0.75, v = 0.25: triangle (0,0) (1,0) (1,1):
    // 0 + 0.75*(1-0) + 0.25*(4-1) = 1.5 (bilinear would give 1.4375).
    QTest::newRow("cell 0,0 lower-right") << -0.25 << -1.5 << 1.5;
    // Cell (0,0), u = 0.25, v = 0.75: triangle (0,0) (0,1) (1,1):
    // 0 + 0.75*(2-0) + 0.25*(4-2) = 2.0 (bilinear would give 1.9375).
    QTest::newRow("cell 0,0 upper-left") << -0.75 << -0.5 << 2.0;
    // Cell centre lies on the diagonal: (0 + 4)/2 = 2; the other diagonal
    // would give (1 + 2)/2 = 1.5 and bilinear 1.75.
    QTest::newRow("cell 0,0 centre") << -0.5 << -1.0 << 2.0;
    // Cell (1,1), u = 0.5, v = 0.1: triangle (1,1) (2,1) (2,2):
    // 4 + 0.5*(5-4) + 0.1*(9-5) = 4.9.
    QTest::newRow("cell 1,1 lower-right") << 0.5 << 0.2 << 4.9;
    // Cell (1,1), u = 0.2, v = 0.6: triangle (1,1) (1,2) (2,2):
    // 4 + 0.6*(7-4) + 0.2*(9-7) = 6.2.
    QTest::newRow("cell 1,1 upper-left") << 0.2 << 1.2 << 6.2;
    // Outside points take the nearest edge value.
    QTest::newRow("outside south-west corner") << -5.0 << -7.0 << 0.0;
    QTest::newRow("outside north-east corner") << 5.0 << 10.0 << 9.0;
    QTest::newRow("outside south edge") << -0.25 << -10.0 << 0.75;
    QTest::newRow("outside east edge") << 10.0 << -1.0 << 4.0;
  }

  // heightAt interpolates on the cell's triangle and clamps outside points;
  // expected values are computed by hand in the table.
  void heightAt() {
    QFETCH(double, x);
    QFETCH(double, y);
    QFETCH(double, expected);
    const double h = makeGrid().heightAt(x, y);
    QVERIFY2(std::abs(h - expected) < 1e-12, qPrintable(QStringLiteral("heightAt(%1, %2) = %3, expected %4")
                                                            .arg(x)
                                                            .arg(y)
                                                            .arg(h, 0, 'g', 17)
                                                            .arg(expected)));
  }

  // A tilted plane is reproduced exactly everywhere, whichever triangle a
  // point falls in, so the two triangles of a cell join without a step.
  void planeIsExact() {
    sp::HeightGrid g;
    g.columns = 5;
    g.rows = 4;
    g.width = 8;
    g.depth = 3;
    const auto plane = [](double x, double y) { return 0.3 * x - 0.7 * y + 1.25; };
    for (int j = 0; j < g.rows; ++j)
      for (int i = 0; i < g.columns; ++i) g.heights.push_back(plane(-4.0 + 2.0 * i, -1.5 + 1.0 * j));
    for (double x = -4.0; x <= 4.0; x += 0.37)
      for (double y = -1.5; y <= 1.5; y += 0.23)
        QVERIFY2(std::abs(g.heightAt(x, y) - plane(x, y)) < 1e-12,
                 qPrintable(QStringLiteral("at (%1, %2)").arg(x).arg(y)));
  }
};

QTEST_GUILESS_MAIN(TestHeightGrid)
#include "tst_height_grid.moc"
