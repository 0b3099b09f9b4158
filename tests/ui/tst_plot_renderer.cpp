// Tests of sp::renderPlotPng (ui/plot_renderer.h) and sp::toCsv (app/plot.h).
// Renders into a temporary directory and inspects the PNG's pixels; runs under
// QT_QPA_PLATFORM=offscreen and under xvfb-run alike.

#include <QtTest>

#include <QApplication>
#include <QColor>
#include <QImage>
#include <QProcess>
#include <QProcessEnvironment>
#include <QTemporaryDir>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <thread>

#include "headless_default.h"
#include "app/plot.h"
#include "ui/plot_renderer.h"

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

/// Pixels that are not pure white.
int countNonWhite(const QImage& image) {
  int n = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      if ((image.pixel(x, y) & 0xFFFFFFu) != 0xFFFFFFu) ++n;
    }
  }
  return n;
}

/// Pixels within `tolerance` per channel of the 0xRRGGBB colour `rgb`.
int countColor(const QImage& image, std::uint32_t rgb, int tolerance = 12) {
  const QColor want = QColor::fromRgb(static_cast<QRgb>(rgb));
  int n = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const QColor c = QColor::fromRgb(image.pixel(x, y));
      if (std::abs(c.red() - want.red()) <= tolerance && std::abs(c.green() - want.green()) <= tolerance &&
          std::abs(c.blue() - want.blue()) <= tolerance) {
        ++n;
      }
    }
  }
  return n;
}

}  // namespace

class TestPlotRenderer : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    QVERIFY(dir_.isValid());
    qInfo("platform plugin: %s%s", qPrintable(QGuiApplication::platformName()),
          sp::test::kHeadlessDefault ? " (no display: chosen by this test)" : "");
  }

  // A two-series plot becomes a PNG of the requested size with the plot drawn
  // on it: many non-white pixels and both series' colours present.
  void twoSeriesRenderToRequestedSize() {
    const PlotSpec plot = twoSeriesPlot();
    const QString path = dir_.filePath("two_series.png");
    std::string error;
    QVERIFY2(sp::renderPlotPng(plot, path.toStdString(), error), error.c_str());
    QVERIFY(error.empty());

    QImage image(path);
    QVERIFY(!image.isNull());
    QCOMPARE(image.size(), QSize(640, 360));
    QCOMPARE(image.pixel(0, 0) & 0xFFFFFFu, 0xFFFFFFu);  // white background
    QVERIFY2(countNonWhite(image) > 5000, qPrintable(QString::number(countNonWhite(image))));
    // Each 2 px line runs well over 300 px across the plot area.
    QVERIFY2(countColor(image, sp::plotSeriesColor(0)) > 300,
             qPrintable(QString::number(countColor(image, sp::plotSeriesColor(0)))));
    QVERIFY2(countColor(image, sp::plotSeriesColor(1)) > 300,
             qPrintable(QString::number(countColor(image, sp::plotSeriesColor(1)))));
    // A colour no series has is absent (the check above is not vacuous).
    QCOMPARE(countColor(image, sp::plotSeriesColor(2), 4), 0);
  }

  // A Points series draws its markers: 20 points of 7 px give hundreds of
  // pixels in its colour, and the image differs from the same data as a line.
  void pointsSeriesRenders() {
    PlotSpec plot;
    plot.title = "Contacts";
    plot.width = 400;
    plot.height = 300;
    PlotSeries dots{"contacts", {}, {}, PlotSeries::Style::Points};
    for (int i = 0; i < 20; ++i) {
      dots.x.push_back(i);
      dots.y.push_back((i * 7) % 11);
    }
    plot.series = {dots};
    const QString pointsPath = dir_.filePath("points.png");
    std::string error;
    QVERIFY2(sp::renderPlotPng(plot, pointsPath.toStdString(), error), error.c_str());
    const QImage points(pointsPath);
    QCOMPARE(points.size(), QSize(400, 300));
    const int colored = countColor(points, sp::plotSeriesColor(0));
    QVERIFY2(colored > 20 * 20, qPrintable(QString::number(colored)));

    plot.series[0].style = PlotSeries::Style::Line;
    const QString linePath = dir_.filePath("points_as_line.png");
    QVERIFY2(sp::renderPlotPng(plot, linePath.toStdString(), error), error.c_str());
    QVERIFY(QImage(linePath) != points);
  }

  // The title is drawn: changing only its text changes the image.
  void titleChangesImage() {
    PlotSpec plot = twoSeriesPlot();
    std::string error;
    plot.title = "A";
    QVERIFY2(sp::renderPlotPng(plot, dir_.filePath("title_a.png").toStdString(), error), error.c_str());
    plot.title = "Something else entirely";
    QVERIFY2(sp::renderPlotPng(plot, dir_.filePath("title_b.png").toStdString(), error), error.c_str());
    const QImage a(dir_.filePath("title_a.png"));
    const QImage b(dir_.filePath("title_b.png"));
    QCOMPARE(a.size(), b.size());
    QVERIFY(a != b);
    // ...and the same title again gives the same pixels (rendering is repeatable).
    plot.title = "A";
    QVERIFY2(sp::renderPlotPng(plot, dir_.filePath("title_a2.png").toStdString(), error), error.c_str());
    QCOMPARE(QImage(dir_.filePath("title_a2.png")), a);
  }

  // Non-finite points are skipped, not an error, as long as one is left; the
  // default range then fits the finite points only.
  void nonFinitePointsAreSkipped() {
    PlotSpec plot = twoSeriesPlot();
    plot.series[0].y[3] = kNaN;
    plot.series[1].x[7] = std::numeric_limits<double>::infinity();
    std::string error;
    QVERIFY2(sp::renderPlotPng(plot, dir_.filePath("with_nan.png").toStdString(), error), error.c_str());
    QVERIFY(countColor(QImage(dir_.filePath("with_nan.png")), sp::plotSeriesColor(0)) > 300);
  }

  void errors_data() {
    QTest::addColumn<PlotSpec>("plot");
    QTest::addColumn<QString>("file");  // relative to the temporary directory
    QTest::addColumn<QString>("message");

    PlotSpec plot = twoSeriesPlot();
    plot.series[1].y.pop_back();
    QTest::newRow("mismatched lengths") << plot << "x.png"
        << "plot 'Wheel forces': series 'front right': 51 x values but 50 y values";

    plot = twoSeriesPlot();
    plot.series[0].y.assign(plot.series[0].x.size(), kNaN);
    QTest::newRow("all NaN") << plot << "x.png"
        << "plot 'Wheel forces': series 'front left': no finite point (all 51 skipped)";

    QTest::newRow("unwritable path") << twoSeriesPlot() << "no_such_dir/plot.png"
        << "plot 'Wheel forces': cannot write '%1/no_such_dir/plot.png': No such file or directory";

    plot = twoSeriesPlot();
    plot.series.clear();
    QTest::newRow("no series") << plot << "x.png" << "plot 'Wheel forces': has no series";

    plot = twoSeriesPlot();
    plot.series[1].x.clear();
    plot.series[1].y.clear();
    QTest::newRow("empty series") << plot << "x.png" << "plot 'Wheel forces': series 'front right': has no points";

    plot = twoSeriesPlot();
    plot.yRange = std::pair{3.0, 3.0};
    QTest::newRow("empty range") << plot << "x.png"
        << "plot 'Wheel forces': y range (3, 3) must be finite with min < max";

    plot = twoSeriesPlot();
    plot.series[0].y[0] = -1e308;
    plot.series[0].y[1] = 1e308;
    QTest::newRow("data too wide") << plot << "x.png"
        << "plot 'Wheel forces': y range (-1.1e+308, 1.1e+308) is wider than a double can hold";

    plot = twoSeriesPlot();
    plot.width = 0;
    QTest::newRow("zero width") << plot << "x.png"
        << "plot 'Wheel forces': size 0x360 is outside 1..16384 pixels";
  }

  // Bad input and unwritable paths fail with one line naming the plot and the
  // problem, and leave no file behind.
  void errors() {
    QFETCH(PlotSpec, plot);
    QFETCH(QString, file);
    QFETCH(QString, message);
    const QString path = dir_.filePath(file);
    std::string error;
    QVERIFY(!sp::renderPlotPng(plot, path.toStdString(), error));
    QCOMPARE(QString::fromStdString(error), message.contains("%1") ? message.arg(dir_.path()) : message);
    QVERIFY(!QFile::exists(path));
  }

  // Calls from a thread other than the GUI thread are refused, not run.
  void otherThreadIsRefused() {
    bool ok = true;
    std::string error;
    std::thread worker([&] { ok = sp::renderPlotPng(twoSeriesPlot(), dir_.filePath("t.png").toStdString(), error); });
    worker.join();
    QVERIFY(!ok);
    QCOMPARE(QString::fromStdString(error), QString("plot 'Wheel forces': must be rendered on the GUI thread"));
    QVERIFY(!QFile::exists(dir_.filePath("t.png")));
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

  void cleanExit_data() {
    QTest::addColumn<QString>("mode");
    QTest::addColumn<bool>("headless");  // DISPLAY, WAYLAND_DISPLAY, QT_QPA_PLATFORM removed
    QTest::addColumn<QString>("platform");  // expected plugin; "" = whatever the parent has

    QTest::newRow("renderer's own app, headless") << "auto" << true << "offscreen";
    QTest::newRow("renderer's own app, parent env") << "auto" << false << "";
    QTest::newRow("caller's app, parent env") << "own" << false << "";
  }

  // A program that renders and then exits ends normally with status 0,
  // whether renderPlotPng made the QApplication (kept to the end) or main owned
  // one (destroyed before Qt's statics); without a display it picks offscreen.
  void cleanExit() {
    QFETCH(QString, mode);
    QFETCH(bool, headless);
    QFETCH(QString, platform);
    QProcess child;
    QProcessEnvironment env = QProcessEnvironment::systemEnvironment();
    if (headless) {
      env.remove("DISPLAY");
      env.remove("WAYLAND_DISPLAY");
      env.remove("QT_QPA_PLATFORM");
    }
    child.setProcessEnvironment(env);
    const QString png = dir_.filePath("exit_" + mode + (headless ? "_headless" : "") + ".png");
    child.start(SP_PLOT_RENDER_ONCE, {mode, png});
    QVERIFY(child.waitForFinished(60000));
    const QByteArray stderrText = child.readAllStandardError();
    QVERIFY2(child.exitStatus() == QProcess::NormalExit, stderrText.constData());
    QVERIFY2(child.exitCode() == 0, stderrText.constData());
    const QString used = QString::fromUtf8(child.readAllStandardOutput()).trimmed();
    QCOMPARE(used, platform.isEmpty() ? QGuiApplication::platformName() : platform);
    QCOMPARE(QImage(png).size(), QSize(320, 200));
  }

 private:
  QTemporaryDir dir_;
};

QTEST_MAIN(TestPlotRenderer)
#include "tst_plot_renderer.moc"
