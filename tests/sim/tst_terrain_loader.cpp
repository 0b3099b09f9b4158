// Tests of sp::loadHeightGrid: every file format, the north-first row flip,
// scaling and extents, and the exact text of each diagnostic, line included.

#include <QTest>
#include <cmath>
#include <optional>

#include "sim/terrain_loader.h"

namespace {

struct Loaded {
  std::optional<sp::HeightGrid> grid;
  QString diagnostics;  // Diagnostics::format(), one line per problem
};

Loaded load(const sp::TerrainSource& source) {
  sp::Diagnostics diag;
  std::optional<sp::HeightGrid> grid = sp::loadHeightGrid(source, diag);
  return {std::move(grid), QString::fromStdString(diag.format())};
}

sp::TerrainSource makeSource(const QString& path, sp::TerrainFormat format = sp::TerrainFormat::Auto,
                             double width = 0, double depth = 0) {
  sp::TerrainSource s;
  s.path = path.toStdString();
  s.format = format;
  s.width = width;
  s.depth = depth;
  return s;
}

// Heights in HeightGrid order (row 0 = min y), compared to 1e-12.
void compareHeights(const sp::HeightGrid& grid, const QList<double>& expected) {
  QCOMPARE(grid.heights.size(), static_cast<size_t>(expected.size()));
  QCOMPARE(grid.heights.size(), static_cast<size_t>(grid.columns) * static_cast<size_t>(grid.rows));
  for (qsizetype k = 0; k < expected.size(); ++k)
    QVERIFY2(std::abs(grid.heights[static_cast<size_t>(k)] - expected[k]) < 1e-12,
             qPrintable(QStringLiteral("height %1 is %2, expected %3")
                            .arg(k)
                            .arg(grid.heights[static_cast<size_t>(k)], 0, 'g', 17)
                            .arg(expected[k])));
}

// A valid 3 x 2 ESRI grid; its first data row is line 7.
const QByteArray kAscHeader =
    "ncols 3\n"
    "nrows 2\n"
    "xllcorner 0\n"
    "yllcorner 0\n"
    "cellsize 0.5\n"
    "NODATA_value -9999\n";

}  // namespace

class TestTerrainLoader : public QObject {
  Q_OBJECT

  QTemporaryDir dir_;

  // Writes content to a file in the temporary directory; returns its path.
  QString write(const QString& name, const QByteArray& content) {
    const QString path = dir_.filePath(name);
    QFile file(path);
    if (!file.open(QIODevice::WriteOnly | QIODevice::Truncate) || file.write(content) != content.size())
      qFatal("cannot write %s", qPrintable(path));
    return path;
  }

  // Loads content that must fail and compares the diagnostics; "{}" in
  // expected stands for the file path.
  void expectErrors(const QString& name, const QByteArray& content, sp::TerrainSource source,
                    QString expected) {
    const QString path = write(name, content);
    source.path = path.toStdString();
    const Loaded r = load(source);
    QCOMPARE(r.diagnostics, expected.replace(QStringLiteral("{}"), path));
    QVERIFY(!r.grid);
  }

 private slots:
  void initTestCase() { QVERIFY(dir_.isValid()); }

  // ------------------------------------------------------------------ asc

  void asc_data() {
    QTest::addColumn<QByteArray>("content");
    QTest::addColumn<double>("width");
    QTest::addColumn<double>("depth");
    QTest::addColumn<double>("expectedWidth");
    QTest::addColumn<double>("expectedDepth");
    // Every row describes the grid  north: 1 2 3 / south: 4 5 6.
    QTest::newRow("one row per line") << kAscHeader + "1 2 3\n4 5 6\n" << 0.0 << 0.0 << 1.0 << 0.5;
    QTest::newRow("rows wrapped over lines") << kAscHeader + "1 2\n3 4 5\n\n6\n" << 0.0 << 0.0 << 1.0 << 0.5;
    QTest::newRow("upper-case keys, centers, no NODATA, CRLF")
        << QByteArray(
               "NCOLS 3\r\nNROWS 2\r\nXLLCENTER 10\r\nYLLCENTER -4\r\nCellSize 0.5\r\n1 2 3\r\n4 5 6\r\n")
        << 0.0 << 0.0 << 1.0 << 0.5;
    QTest::newRow("extents from the world file win") << kAscHeader + "1 2 3\n4 5 6\n"
                                                     << 7.0 << 3.0 << 7.0 << 3.0;
    QTest::newRow("blank lines and tabs") << "\n" + kAscHeader + "\n1\t2 3\n\n 4 5  6 \n\n"
                                          << 0.0 << 0.0 << 1.0 << 0.5;
  }

  // ESRI grids load in any whitespace layout; samples are grid points, so
  // the extent is (n-1)*cellsize; the first (north) row ends up at max y.
  void asc() {
    QFETCH(QByteArray, content);
    QFETCH(double, width);
    QFETCH(double, depth);
    QFETCH(double, expectedWidth);
    QFETCH(double, expectedDepth);
    const Loaded r = load(makeSource(write("grid.asc", content), sp::TerrainFormat::Auto, width, depth));
    QCOMPARE(r.diagnostics, QString());
    QVERIFY(r.grid);
    QCOMPARE(r.grid->columns, 3);
    QCOMPARE(r.grid->rows, 2);
    QCOMPARE(r.grid->width, expectedWidth);
    QCOMPARE(r.grid->depth, expectedDepth);
    compareHeights(*r.grid, {4, 5, 6, 1, 2, 3});
    if (QTest::currentTestFailed()) return;
    // The north-west sample (file row 1, column 1) is at min x, max y.
    QCOMPARE(r.grid->heightAt(-expectedWidth / 2, expectedDepth / 2), 1.0);
  }

  void ascErrors_data() {
    QTest::addColumn<QByteArray>("content");
    QTest::addColumn<QString>("expected");
    QTest::newRow("short row") << kAscHeader + "1 2 3\n4 5\n"
                               << "{}:8: error: expected 3 values in row 2, found 2\n";
    QTest::newRow("long row") << kAscHeader + "1 2 3 4\n4 5 6\n"
                              << "{}:7: error: expected 3 values in row 1, found 4\n";
    QTest::newRow("wrapped, too few") << kAscHeader + "1 2\n3 4\n5\n"
                                      << "{}:9: error: expected 2 rows of 3 values (6 in all), found 5\n";
    QTest::newRow("wrapped, too many") << kAscHeader + "1 2\n3 4\n5 6 7\n8\n"
                                       << "{}:9: error: expected 2 rows of 3 values (6 in all), found 8\n";
    QTest::newRow("NODATA cell") << kAscHeader + "1 2 3\n4 5 -9999\n"
                                 << "{}:8: error: NODATA value -9999 in row 2, column 3\n";
    QTest::newRow("NODATA cell, wrapped") << kAscHeader + "1 2\n-9999 4\n5 6\n"
                                          << "{}:8: error: NODATA value -9999 in row 1, column 3\n";
    QTest::newRow("not a number") << kAscHeader + "1 x 3\n4 5 nan\n"
                                  << "{}:7: error: 'x' is not a finite number (row 1, column 2)\n"
                                     "{}:8: error: 'nan' is not a finite number (row 2, column 3)\n";
    QTest::newRow("all data errors in one pass")
        << kAscHeader + "1 x 3\n-9999 4 5\n"
        << "{}:7: error: 'x' is not a finite number (row 1, column 2)\n"
           "{}:8: error: NODATA value -9999 in row 2, column 1\n";
    QTest::newRow("unknown key") << QByteArray(
                                        "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 0.5\n"
                                        "nodata -1\n1 2 3\n4 5 6\n")
                                 << "{}:6: error: unknown header key 'nodata'\n";
    QTest::newRow("missing cellsize")
        << QByteArray("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2 3\n4 5 6\n")
        << "{}:5: error: missing header key 'cellsize'\n";
    QTest::newRow("missing yll") << QByteArray("ncols 3\nnrows 2\nxllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n")
                                 << "{}:5: error: missing header key 'yllcorner' or 'yllcenter'\n";
    QTest::newRow("corner and center") << QByteArray(
                                              "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\nxllcenter 0\n"
                                              "cellsize 1\n1 2 3\n4 5 6\n")
                                       << "{}:5: error: both 'xllcorner' and 'xllcenter' given\n";
    QTest::newRow("duplicate key") << QByteArray(
                                          "ncols 3\nnrows 2\nNCOLS 3\nxllcorner 0\nyllcorner 0\n"
                                          "cellsize 1\n1 2 3\n4 5 6\n")
                                   << "{}:3: error: duplicate header key 'NCOLS' (first on line 1)\n";
    QTest::newRow("key without value")
        << QByteArray(
               "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize\n"
               "1 2 3\n4 5 6\n")
        << "{}:5: error: header line needs one value after 'cellsize', found 0\n"
           "{}:6: error: missing header key 'cellsize'\n";
    QTest::newRow("ncols not an integer") << QByteArray(
                                                 "ncols 3.5\nnrows 2\nxllcorner 0\nyllcorner 0\n"
                                                 "cellsize 1\n1 2 3\n4 5 6\n")
                                          << "{}:1: error: ncols must be an integer, got '3.5'\n";
    QTest::newRow("too small and too large") << QByteArray(
                                                    "ncols 1\nnrows 5000\nxllcorner 0\nyllcorner 0\n"
                                                    "cellsize 1\n1\n")
                                             << "{}:1: error: ncols must be between 2 and 4096, got 1\n"
                                                "{}:2: error: nrows must be between 2 and 4096, got 5000\n";
    QTest::newRow("cellsize zero") << QByteArray(
                                          "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 0\n"
                                          "1 2 3\n4 5 6\n")
                                   << "{}:5: error: cellsize must be > 0, got '0'\n";
    QTest::newRow("bad numbers in header") << QByteArray(
                                                  "ncols 3\nnrows 2\nxllcorner west\nyllcorner 0\n"
                                                  "cellsize 1\nnodata_value none\n1 2 3\n4 5 6\n")
                                           << "{}:3: error: xllcorner must be a number, got 'west'\n"
                                              "{}:6: error: nodata_value must be a number, got 'none'\n";
    QTest::newRow("empty file") << QByteArray() << "{}: error: terrain file is empty\n";
  }

  // Each ESRI grid problem is reported with its line; all of them at once.
  void ascErrors() {
    QFETCH(QByteArray, content);
    QFETCH(QString, expected);
    expectErrors("bad.asc", content, makeSource({}), expected);
  }

  // ------------------------------------------------------------------ pgm

  void pgm_data() {
    QTest::addColumn<QByteArray>("content");
    QTest::addColumn<double>("minHeight");
    QTest::addColumn<double>("maxHeight");
    QTest::addColumn<int>("columns");
    QTest::addColumn<QList<double>>("heights");
    // Grey 0..10 onto -1..1 m; comments anywhere in the header.
    QTest::newRow("P2 with comments")
        << QByteArray("P2\n# made by hand\n3 2 # width height\n10\n0 5 10\n10 5 0\n") << -1.0 << 1.0 << 3
        << QList<double>{1, 0, -1, -1, 0, 1};
    // Grey 0..255 onto 0..1 m; 51/255 = 0.2 and 102/255 = 0.4.
    QByteArray p5 = "P5\n3 2\n255\n";
    p5.append("\x00\x33\xff\xff\x66\x00", 6);
    QTest::newRow("P5 8-bit") << p5 << 0.0 << 1.0 << 3 << QList<double>{1, 0.4, 0, 0, 0.2, 1};
    // 16-bit samples are big-endian: 0x0102 = 258 (little-endian would be 513).
    QByteArray p5wide = "P5\n2 2\n65535\n";
    p5wide.append("\x00\x00\x01\x02\xff\xff\x80\x00", 8);
    QTest::newRow("P5 16-bit") << p5wide << 0.0 << 65535.0 << 2 << QList<double>{65535, 32768, 0, 258};
  }

  // PGM grey values scale linearly onto min..max height, the first image
  // row (north) ends up at max y, and width/depth come from the source.
  void pgm() {
    QFETCH(QByteArray, content);
    QFETCH(double, minHeight);
    QFETCH(double, maxHeight);
    QFETCH(int, columns);
    QFETCH(QList<double>, heights);
    sp::TerrainSource s = makeSource(write("image.pgm", content), sp::TerrainFormat::Auto, 4, 2);
    s.minHeight = minHeight;
    s.maxHeight = maxHeight;
    const Loaded r = load(s);
    QCOMPARE(r.diagnostics, QString());
    QVERIFY(r.grid);
    QCOMPARE(r.grid->columns, columns);
    QCOMPARE(r.grid->rows, 2);
    QCOMPARE(r.grid->width, 4.0);
    QCOMPARE(r.grid->depth, 2.0);
    compareHeights(*r.grid, heights);
  }

  void pgmErrors_data() {
    QTest::addColumn<QByteArray>("content");
    QTest::addColumn<double>("width");
    QTest::addColumn<QString>("expected");
    QTest::newRow("bad magic") << QByteArray("P6\n2 2\n255\n") << 1.0
                               << "{}:1: error: not a PGM file: expected magic 'P2' or 'P5', found 'P6'\n";
    QTest::newRow("width not an integer") << QByteArray("P2\n# c\nx 2\n10\n") << 1.0
                                          << "{}:3: error: PGM image width must be an integer, got 'x'\n";
    QTest::newRow("width too small") << QByteArray("P2\n1 2\n10\n1 2\n") << 1.0
                                     << "{}:2: error: PGM image width must be between 2 and 4096, got 1\n";
    QTest::newRow("maxval too large") << QByteArray("P2\n2 2\n70000\n1 2 3 4\n") << 1.0
                                      << "{}:3: error: PGM maxval must be between 1 and 65535, got 70000\n";
    QTest::newRow("header truncated")
        << QByteArray("P2\n2 2\n") << 1.0 << "{}:3: error: PGM header ends before the maxval\n";
    QTest::newRow("P2 value above maxval")
        << QByteArray("P2\n2 2\n10\n0 11\n3 4\n") << 1.0
        << "{}:4: error: grey value 11 exceeds maxval 10 (row 1, column 2)\n";
    QTest::newRow("P2 not grey values") << QByteArray("P2\n2 2\n10\n-1 2\n3 x\n") << 1.0
                                        << "{}:4: error: '-1' is not a grey value (row 1, column 1)\n"
                                           "{}:5: error: 'x' is not a grey value (row 2, column 2)\n";
    QTest::newRow("P2 too few") << QByteArray("P2\n2 2\n10\n1 2\n3\n") << 1.0
                                << "{}:5: error: expected 4 grey values (2 rows of 2), found 3\n";
    QTest::newRow("P2 too many") << QByteArray("P2\n2 2\n10\n1 2\n3 4\n5\n") << 1.0
                                 << "{}:6: error: expected 4 grey values (2 rows of 2), found more\n";
    // Binary data errors carry no line: line 0 and the byte offset instead.
    QTest::newRow("P5 8-bit truncated")
        << QByteArray("P5\n2 2\n255\n\x01\x02\x03") << 1.0
        << "{}: error: pixel data ends at byte offset 14 in row 2 of 2: expected "
           "4 bytes (2 rows of 2, 1 byte each), found 3\n";
    QTest::newRow("P5 16-bit truncated")
        << QByteArray("P5\n2 2\n65535\n\x01\x02\x03\x04\x05") << 1.0
        << "{}: error: pixel data ends at byte offset 18 in row 2 of 2: expected "
           "8 bytes (2 rows of 2, 2 bytes each), found 5\n";
    QTest::newRow("P5 value above maxval")
        << QByteArray("P5\n2 2\n100\n\x01\x02\xc8\x04") << 1.0
        << "{}: error: grey value 200 exceeds maxval 100 at byte offset 13 "
           "(row 2, column 1)\n";
    QTest::newRow("no extents") << QByteArray("P2\n2 2\n10\n1 2\n3 4\n") << 0.0
                                << "{}: error: width must be given (> 0) for a pgm terrain\n"
                                   "{}: error: depth must be given (> 0) for a pgm terrain\n";
  }

  // Each PGM problem is reported with its header line, or for binary pixel
  // data with the byte offset and image row.
  void pgmErrors() {
    QFETCH(QByteArray, content);
    QFETCH(double, width);
    QFETCH(QString, expected);
    expectErrors("bad.pgm", content, makeSource({}, sp::TerrainFormat::Auto, width, width), expected);
  }

  // ------------------------------------------------------------------ csv grid

  // A CSV grid skips comments and blank lines, tolerates spaces around
  // values, takes its extents from the source and flips the north row to max y.
  void csvGrid() {
    const QString path = write("grid.csv", "# north row first\n\n1, 2 ,3\r\n  # another comment\n4,5,6\n\n");
    const Loaded r = load(makeSource(path, sp::TerrainFormat::Auto, 2, 1));
    QCOMPARE(r.diagnostics, QString());
    QVERIFY(r.grid);
    QCOMPARE(r.grid->columns, 3);
    QCOMPARE(r.grid->rows, 2);
    QCOMPARE(r.grid->width, 2.0);
    QCOMPARE(r.grid->depth, 1.0);
    compareHeights(*r.grid, {4, 5, 6, 1, 2, 3});
  }

  void csvGridErrors_data() {
    QTest::addColumn<QByteArray>("content");
    QTest::addColumn<double>("width");
    QTest::addColumn<QString>("expected");
    QTest::newRow("ragged rows") << QByteArray("# c\n1,2,3\n4,5\n6,7,8,9\n") << 1.0
                                 << "{}:3: error: expected 3 values as on line 2, found 2\n"
                                    "{}:4: error: expected 3 values as on line 2, found 4\n";
    QTest::newRow("not a number") << QByteArray("1,a,3\n4,5,inf\n") << 1.0
                                  << "{}:1: error: 'a' is not a finite number (column 2)\n"
                                     "{}:2: error: 'inf' is not a finite number (column 3)\n";
    QTest::newRow("empty value") << QByteArray("1,,3\n4,5,\n") << 1.0
                                 << "{}:1: error: empty value (column 2)\n"
                                    "{}:2: error: empty value (column 3)\n";
    QTest::newRow("one row") << QByteArray("1,2,3\n") << 1.0
                             << "{}: error: a csv grid needs at least 2 rows, found 1\n";
    QTest::newRow("one column")
        << QByteArray("\n1\n2\n") << 1.0
        << "{}:2: error: number of values per row must be between 2 and 4096, got 1\n";
    QTest::newRow("no extents") << QByteArray("1,2\n3,4\n") << 0.0
                                << "{}: error: width must be given (> 0) for a csv grid terrain\n"
                                   "{}: error: depth must be given (> 0) for a csv grid terrain\n";
    QTest::newRow("profile read as a grid") << QByteArray("# profile\ndistance_m,height_m\n0,0\n1,1\n") << 1.0
                                            << "{}:2: error: 'distance_m' is not a finite number (column 1)\n"
                                               "{}:2: error: 'height_m' is not a finite number (column 2)\n";
  }

  // Each CSV grid problem is reported with its line.
  void csvGridErrors() {
    QFETCH(QByteArray, content);
    QFETCH(double, width);
    QFETCH(QString, expected);
    expectErrors("bad.csv", content, makeSource({}, sp::TerrainFormat::Auto, width, width), expected);
  }

  // A hopelessly broken file stops after 20 errors with one closing line.
  void errorLimit() {
    QString expected;
    for (int line = 1; line <= 20; ++line)
      expected += QStringLiteral("{}:%1: error: 'x' is not a finite number (column 1)\n").arg(line);
    expected += QStringLiteral("{}:21: error: too many errors; giving up\n");
    expectErrors("broken.csv", QByteArray("x,1\n").repeated(30),
                 makeSource({}, sp::TerrainFormat::Auto, 1, 1), expected);
  }

  // ------------------------------------------------------------------ profile

  void profile_data() {
    QTest::addColumn<QByteArray>("content");
    QTest::addColumn<double>("width");
    QTest::addColumn<double>("depth");
    QTest::addColumn<double>("resolution");
    QTest::addColumn<double>("expectedWidth");
    QTest::addColumn<int>("expectedRows");
    QTest::addColumn<QList<double>>("row");
    const QByteArray tent = "# a tent\ndistance_m,height_m\n0,0\n1,1\n3,0\n";
    // Span 3 m at 0.5 m: 7 columns; depth 1 m at 0.5 m: 3 rows.
    QTest::newRow("resampled at resolution")
        << tent << 0.0 << 1.0 << 0.5 << 3.0 << 3 << QList<double>{0, 0.5, 1, 0.75, 0.5, 0.25, 0};
    // round(1/0.3) + 1 = 4 columns at 1/3 m; depth 0.1 m still gives 2 rows.
    QTest::newRow("spacing adjusted to span, no header")
        << QByteArray("2,0\n3,1\n") << 0.0 << 0.1 << 0.3 << 1.0 << 2 << QList<double>{0, 1.0 / 3, 2.0 / 3, 1};
    // A given width stretches the 3 m span over 6 m: 7 columns at 1 m.
    QTest::newRow("width stretches the span")
        << tent << 6.0 << 1.0 << 1.0 << 6.0 << 2 << QList<double>{0, 0.5, 1, 0.75, 0.5, 0.25, 0};
  }

  // A profile is resampled linearly at the resolution along x and extruded
  // into identical rows along y.
  void profile() {
    QFETCH(QByteArray, content);
    QFETCH(double, width);
    QFETCH(double, depth);
    QFETCH(double, resolution);
    QFETCH(double, expectedWidth);
    QFETCH(int, expectedRows);
    QFETCH(QList<double>, row);
    sp::TerrainSource s = makeSource(write("profile.csv", content), sp::TerrainFormat::Profile, width, depth);
    s.resolution = resolution;
    const Loaded r = load(s);
    QCOMPARE(r.diagnostics, QString());
    QVERIFY(r.grid);
    QCOMPARE(r.grid->columns, static_cast<int>(row.size()));
    QCOMPARE(r.grid->rows, expectedRows);
    QCOMPARE(r.grid->width, expectedWidth);
    QCOMPARE(r.grid->depth, depth);
    QList<double> all;
    for (int j = 0; j < expectedRows; ++j) all += row;
    compareHeights(*r.grid, all);
  }

  void profileErrors_data() {
    QTest::addColumn<QByteArray>("content");
    QTest::addColumn<double>("depth");
    QTest::addColumn<double>("resolution");
    QTest::addColumn<QString>("expected");
    QTest::newRow("header not first") << QByteArray("0,0\ndistance,height\n1,1\n") << 1.0 << 0.5
                                      << "{}:2: error: distance 'distance' is not a finite number\n"
                                         "{}:2: error: height 'height' is not a finite number\n";
    QTest::newRow("bad height") << QByteArray("0,0\n1,abc\n2,0\n") << 1.0 << 0.5
                                << "{}:2: error: height 'abc' is not a finite number\n";
    QTest::newRow("repeated distance")
        << QByteArray("0,0\n1,1\n1,2\n2,0\n") << 1.0 << 0.5
        << "{}:3: error: distance 1 does not increase (previous 1 on line 2)\n";
    QTest::newRow("decreasing distance")
        << QByteArray("d,h\n0,0\n2,1\n# c\n1.5,0\n3,0\n") << 1.0 << 0.5
        << "{}:5: error: distance 1.5 does not increase (previous 2 on line 3)\n";
    QTest::newRow("three values") << QByteArray("0,0,0\n1,1\n2,2\n") << 1.0 << 0.5
                                  << "{}:1: error: expected 2 values (distance,height), found 3\n";
    QTest::newRow("one point") << QByteArray("distance,height\n0,0\n") << 1.0 << 0.5
                               << "{}: error: a profile needs at least 2 points, found 1\n";
    QTest::newRow("no depth")
        << QByteArray("0,0\n1,0\n") << 0.0 << 0.5
        << "{}: error: depth (lateral width) must be given (> 0) for a profile terrain\n";
    QTest::newRow("zero resolution") << QByteArray("0,0\n1,0\n") << 1.0 << 0.0
                                     << "{}: error: resolution must be > 0 for a profile terrain, got 0\n";
    QTest::newRow("too many samples") << QByteArray("0,0\n300,0\n") << 1.0 << 0.05
                                      << "{}: error: profile length of 300 m at resolution 0.05 m needs 6001 "
                                         "samples; the limit is 4096\n";
  }

  // Each profile problem is reported with its line.
  void profileErrors() {
    QFETCH(QByteArray, content);
    QFETCH(double, depth);
    QFETCH(double, resolution);
    QFETCH(QString, expected);
    sp::TerrainSource s = makeSource({}, sp::TerrainFormat::Profile, 0, depth);
    s.resolution = resolution;
    expectErrors("bad_profile.csv", content, s, expected);
  }

  // ------------------------------------------------------------------ format and file

  // Auto picks the format by extension, case-insensitively; an explicit
  // format reads any extension.
  void formatSelection() {
    const QByteArray asc = kAscHeader + "1 2 3\n4 5 6\n";
    QVERIFY(load(makeSource(write("upper.ASC", asc))).grid);
    QVERIFY(load(makeSource(write("asc.txt", asc), sp::TerrainFormat::Asc)).grid);
    QVERIFY(load(makeSource(write("grid.dat", "1,2\n3,4\n"), sp::TerrainFormat::Csv, 1, 1)).grid);
    QVERIFY(load(makeSource(write("image.PGM", "P2 2 2 1 0 1 1 0"), sp::TerrainFormat::Auto, 1, 1)).grid);
  }

  void fileErrors_data() {
    QTest::addColumn<QString>("name");
    QTest::addColumn<double>("width");
    QTest::addColumn<QString>("expected");
    QTest::newRow("unknown extension")
        << "terrain.txt" << 0.0
        << "{}: error: unknown terrain file extension '.txt'; expected .asc, .pgm "
           "or .csv, or give the format\n";
    QTest::newRow("no extension")
        << "terrain" << 0.0
        << "{}: error: terrain file has no extension; expected .asc, .pgm or .csv, or "
           "give the format\n";
    QTest::newRow("negative width") << "terrain.asc" << -1.0
                                    << "{}: error: width must be >= 0 (0 = from the file), got -1\n";
  }

  // Problems with the file as a whole are reported without a line.
  void fileErrors() {
    QFETCH(QString, name);
    QFETCH(double, width);
    QFETCH(QString, expected);
    expectErrors(name, kAscHeader + "1 2 3\n4 5 6\n", makeSource({}, sp::TerrainFormat::Auto, width, 0),
                 expected);
  }

  // A missing file or a directory cannot be opened.
  void cannotOpen() {
    for (const QString& path : {dir_.filePath("missing.asc"), dir_.path()}) {
      const Loaded r = load(makeSource(path, sp::TerrainFormat::Asc));
      QCOMPARE(r.diagnostics, path + ": error: cannot open terrain file\n");
      QVERIFY(!r.grid);
    }
  }

  // ------------------------------------------------------------------ shipped terrains

  // terrains/bumpy.asc: 81 x 81 samples over 20 m x 20 m, gentle bumps.
  void shippedBumpy() {
    const Loaded r = load(makeSource(QStringLiteral(SP_SOURCE_DIR "/terrains/bumpy.asc")));
    QCOMPARE(r.diagnostics, QString());
    QVERIFY(r.grid);
    QCOMPARE(r.grid->columns, 81);
    QCOMPARE(r.grid->rows, 81);
    QCOMPARE(r.grid->width, 20.0);
    QCOMPARE(r.grid->depth, 20.0);
    QVERIFY(r.grid->minHeight() >= -0.1);
    QVERIFY(r.grid->maxHeight() <= 0.1);
    QVERIFY(r.grid->maxHeight() - r.grid->minHeight() > 0.05);
  }

  // terrains/bumpy_small.pgm: a 16-bit 33 x 33 version of the bumpy field.
  void shippedBumpySmall() {
    sp::TerrainSource s =
        makeSource(QStringLiteral(SP_SOURCE_DIR "/terrains/bumpy_small.pgm"), sp::TerrainFormat::Auto, 8, 8);
    s.minHeight = -0.08;
    s.maxHeight = 0.08;
    const Loaded r = load(s);
    QCOMPARE(r.diagnostics, QString());
    QVERIFY(r.grid);
    QCOMPARE(r.grid->columns, 33);
    QCOMPARE(r.grid->rows, 33);
    QVERIFY(r.grid->minHeight() >= -0.08);
    QVERIFY(r.grid->maxHeight() <= 0.08);
  }

  // terrains/test_track.csv: a 24 m profile (2 m of level snow before the
  // 22 m track) whose highest bump is 0.30 m, flat at both ends.
  void shippedTestTrack() {
    sp::TerrainSource s = makeSource(QStringLiteral(SP_SOURCE_DIR "/terrains/test_track.csv"),
                                     sp::TerrainFormat::Profile, 0, 2);
    const Loaded r = load(s);
    QCOMPARE(r.diagnostics, QString());
    QVERIFY(r.grid);
    QVERIFY(r.grid->width > 23.9 && r.grid->width < 24.1);
    QCOMPARE(r.grid->rows, 41);
    QVERIFY(std::abs(r.grid->maxHeight() - 0.30) < 0.05);
    QCOMPARE(r.grid->heightAt(-r.grid->width / 2, 0), 0.0);
    QCOMPARE(r.grid->heightAt(r.grid->width / 2, 0), 0.0);
  }
};

QTEST_GUILESS_MAIN(TestTerrainLoader)
#include "tst_terrain_loader.moc"
