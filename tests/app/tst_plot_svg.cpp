// Tests of sp::renderPlotSvg / writePlotSvg (app/validation/plot_svg.h) and sp::toCsv
// (app/validation/plot.h): the report plots of `simpartner-sim validate`, without Qt.
// The SVG is parsed back with Qt's XML reader to check what it draws.

#include <QTest>

#include <QFile>
#include <QTemporaryDir>
#include <QXmlStreamReader>

#include <limits>
#include <string>

#include "app/validation/plot.h"
#include "app/validation/plot_svg.h"

using sp::PlotSeries;
using sp::PlotSpec;

Q_DECLARE_METATYPE(PlotSpec)

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Two line series, a rising parabola and a falling line, 640 x 360.
PlotSpec twoSeriesPlot() {
  PlotSpec plot;
  plot.title = "Wheel forces";
  plot.xLabel = "time [s]";
  plot.yLabel = "force [N]";
  plot.width = 640;
  plot.height = 360;
  PlotSeries rising{"front left", {}, {}};
  PlotSeries falling{"front right", {}, {}};
  for (int i = 0; i <= 50; ++i) {
    const double t = 0.1 * i;
    rising.x.push_back(t);
    rising.y.push_back(t * t);
    falling.x.push_back(t);
    falling.y.push_back(25.0 - 5.0 * t);
  }
  plot.series = {rising, falling};
  return plot;
}

/// What an SVG draws, read back: its size, polylines (stroke, point count),
/// circles and texts.
struct Drawn {
  QString width, height;
  QList<QPair<QString, int>> polylines;
  int circles = 0;
  QStringList texts;
  bool wellFormed = false;
};

Drawn parse(const std::string& svg) {
  Drawn d;
  QXmlStreamReader xml(QByteArray::fromStdString(svg));
  while (!xml.atEnd()) {
    if (xml.readNext() != QXmlStreamReader::StartElement) continue;
    const auto a = xml.attributes();
    if (xml.name() == u"svg") {
      d.width = a.value("width").toString();
      d.height = a.value("height").toString();
    } else if (xml.name() == u"polyline") {
      d.polylines.append({a.value("stroke").toString(),
                          static_cast<int>(a.value("points").toString().split(' ', Qt::SkipEmptyParts).size())});
    } else if (xml.name() == u"circle") {
      ++d.circles;
    } else if (xml.name() == u"text") {
      d.texts << xml.readElementText();
    }
  }
  d.wellFormed = !xml.hasError();
  return d;
}

}  // namespace

class TestPlotSvg : public QObject {
  Q_OBJECT

 private slots:
  // A two-series plot: the requested size, one polyline per series in the
  // palette's colours with every point, the title, axis titles and legend.
  void twoSeries() {
    std::string error;
    const std::optional<std::string> svg = sp::renderPlotSvg(twoSeriesPlot(), error);
    QVERIFY2(svg, error.c_str());
    const Drawn d = parse(*svg);
    QVERIFY(d.wellFormed);
    QCOMPARE(d.width, QString("640"));
    QCOMPARE(d.height, QString("360"));
    QCOMPARE(d.polylines.size(), 2);
    QCOMPARE(d.polylines[0], qMakePair(QString("#0072b2"), 51));
    QCOMPARE(d.polylines[1], qMakePair(QString("#d55e00"), 51));
    for (const char* text : {"Wheel forces", "time [s]", "force [N]", "front left", "front right"})
      QVERIFY2(d.texts.contains(text), text);
    // Ticks at round 1-2-5 steps: 0, 2, 4 on x (0..5 s), 0, 10, 20 on y (0..25 N).
    for (const char* tick : {"0", "2", "4", "10", "20"}) QVERIFY2(d.texts.contains(tick), tick);
    QVERIFY(!d.texts.contains("1") && !d.texts.contains("5"));
  }

  // Points series become circles; unnamed series get no legend entry.
  void pointsAndNoLegend() {
    PlotSpec plot = twoSeriesPlot();
    plot.series.resize(1);
    plot.series[0].style = PlotSeries::Style::Points;
    plot.series[0].name.clear();
    std::string error;
    const Drawn d = parse(*sp::renderPlotSvg(plot, error));
    QCOMPARE(d.circles, 51);
    QVERIFY(d.polylines.isEmpty());
    QVERIFY(!d.texts.contains("front left"));
  }

  // A legend too long for one row flows into more, all inside the image.
  void legendWraps() {
    PlotSpec plot = twoSeriesPlot();
    for (int i = 0; i < 6; ++i) plot.series.push_back({"a long series name number " + std::to_string(i), {0, 1}, {0, 1}});
    std::string error;
    const std::string svg = *sp::renderPlotSvg(plot, error);
    QXmlStreamReader xml(QByteArray::fromStdString(svg));
    QSet<QString> rows;
    while (!xml.atEnd())
      if (xml.readNext() == QXmlStreamReader::StartElement && xml.name() == u"rect" &&
          xml.attributes().value("width") == u"14") {
        rows.insert(xml.attributes().value("y").toString());
        QVERIFY(xml.attributes().value("x").toDouble() < plot.width);
        QVERIFY(xml.attributes().value("y").toDouble() + 10 <= plot.height);
      }
    QVERIFY2(rows.size() >= 3, qPrintable(QString::number(rows.size())));
  }

  // Text is escaped: a title with markup stays text.
  void textEscaped() {
    PlotSpec plot = twoSeriesPlot();
    plot.title = "a < b & \"c\"";
    std::string error;
    const Drawn d = parse(*sp::renderPlotSvg(plot, error));
    QVERIFY(d.wellFormed);
    QVERIFY(d.texts.contains("a < b & \"c\""));
  }

  // Non-finite points are skipped, not an error, while one is left.
  void nonFinitePointsAreSkipped() {
    PlotSpec plot = twoSeriesPlot();
    plot.series[0].y[3] = kNaN;
    plot.series[1].x[7] = std::numeric_limits<double>::infinity();
    std::string error;
    const std::optional<std::string> svg = sp::renderPlotSvg(plot, error);
    QVERIFY2(svg, error.c_str());
    const Drawn d = parse(*svg);
    QCOMPARE(d.polylines[0].second, 50);
    QCOMPARE(d.polylines[1].second, 50);
    QVERIFY(svg->find("nan") == std::string::npos && svg->find("inf") == std::string::npos);
  }

  void errors_data() {
    QTest::addColumn<PlotSpec>("plot");
    QTest::addColumn<QString>("file");  // relative to the temporary directory
    QTest::addColumn<QString>("message");

    PlotSpec plot = twoSeriesPlot();
    plot.series[1].y.pop_back();
    QTest::newRow("mismatched lengths") << plot << "x.svg"
        << "plot 'Wheel forces': series 'front right': 51 x values but 50 y values";
    plot = twoSeriesPlot();
    plot.series[0].y.assign(plot.series[0].x.size(), kNaN);
    QTest::newRow("all NaN") << plot << "x.svg"
        << "plot 'Wheel forces': series 'front left': no finite point (all 51 skipped)";
    QTest::newRow("unwritable path") << twoSeriesPlot() << "no_such_dir/plot.svg"
        << "plot 'Wheel forces': cannot write '%1/no_such_dir/plot.svg': No such file or directory";
    plot = twoSeriesPlot();
    plot.series.clear();
    QTest::newRow("no series") << plot << "x.svg" << "plot 'Wheel forces': has no series";
    plot = twoSeriesPlot();
    plot.series[1].x.clear();
    plot.series[1].y.clear();
    QTest::newRow("empty series") << plot << "x.svg" << "plot 'Wheel forces': series 'front right': has no points";
    plot = twoSeriesPlot();
    plot.yRange = std::pair{3.0, 3.0};
    QTest::newRow("empty range") << plot << "x.svg" << "plot 'Wheel forces': y range (3, 3) must be finite with min < max";
    plot = twoSeriesPlot();
    plot.series[0].y[0] = -1e308;
    plot.series[0].y[1] = 1e308;
    QTest::newRow("data too wide") << plot << "x.svg"
        << "plot 'Wheel forces': y range (-1.1e+308, 1.1e+308) is wider than a double can hold";
    plot = twoSeriesPlot();
    plot.width = 0;
    QTest::newRow("zero width") << plot << "x.svg" << "plot 'Wheel forces': size 0x360 is outside 1..16384 pixels";
  }

  // Bad input and unwritable paths fail with one line naming the plot and
  // the problem, and leave no file behind.
  void errors() {
    QFETCH(PlotSpec, plot);
    QFETCH(QString, file);
    QFETCH(QString, message);
    QTemporaryDir dir;
    const QString path = dir.filePath(file);
    std::string error;
    QVERIFY(!sp::writePlotSvg(plot, path.toStdString(), error));
    QCOMPARE(QString::fromStdString(error), message.contains("%1") ? message.arg(dir.path()) : message);
    QVERIFY(!QFile::exists(path));
    QVERIFY(!QFile::exists(path + ".part"));
  }

  // writePlotSvg writes exactly what renderPlotSvg returns.
  void writesTheFile() {
    QTemporaryDir dir;
    const QString path = dir.filePath("p.svg");
    std::string error;
    QVERIFY2(sp::writePlotSvg(twoSeriesPlot(), path.toStdString(), error), error.c_str());
    QFile f(path);
    QVERIFY(f.open(QIODevice::ReadOnly));
    QCOMPARE(f.readAll().toStdString(), *sp::renderPlotSvg(twoSeriesPlot(), error));
  }

  // toCsv names the columns after the x label and the series (sanitised,
  // duplicates suffixed) and pads shorter series with empty cells.
  void csvHeaderAndPadding() {
    PlotSpec plot;
    plot.xLabel = "Time [s]";
    plot.series.push_back({"Front left (N)", {0, 0.5, 1}, {10, 12.25, -3}});
    plot.series.push_back({"", {0, 1}, {1e-9, kNaN}});
    plot.series.push_back({"front_left_n", {2}, {std::numeric_limits<double>::infinity()}});
    const std::string expected =
        "time_s,front_left_n,time_s_2,series2,time_s_3,front_left_n_2\n"
        "0,10,0,1e-09,2,inf\n"
        "0.5,12.25,1,nan,,\n"
        "1,-3,,,,\n";
    QCOMPARE(QString::fromStdString(sp::toCsv(plot)), QString::fromStdString(expected));
    QCOMPARE(QString::fromStdString(sp::toCsv(PlotSpec{})), QString());
  }
};

QTEST_GUILESS_MAIN(TestPlotSvg)
#include "tst_plot_svg.moc"
