#include "ui/plot_renderer.h"

#include <QApplication>
#include <QByteArray>
#include <QFont>
#include <QGraphicsLayout>
#include <QGraphicsScene>
#include <QImage>
#include <QList>
#include <QPainter>
#include <QPen>
#include <QPointF>
#include <QSaveFile>
#include <QString>
#include <QThread>
#include <QtCharts/QChart>
#include <QtCharts/QLegend>
#include <QtCharts/QLegendMarker>
#include <QtCharts/QLineSeries>
#include <QtCharts/QScatterSeries>
#include <QtCharts/QValueAxis>
#include <QtCharts/QXYSeries>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>
#include <vector>

namespace sp {

namespace {

constexpr int kMaxSide = 16384;  // [px]; a 16k x 16k ARGB image is 1 GiB

/// A finite interval, grown from points.
struct Extent {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  void add(double v) {
    min = std::min(min, v);
    max = std::max(max, v);
  }
  /// The interval widened by 5% of its span on each side; a single value
  /// gets +-5% of its magnitude (or +-1 at zero). Stays finite.
  std::pair<double, double> withMargin() const {
    constexpr double kMax = std::numeric_limits<double>::max();
    const double pad = max > min ? 0.05 * max - 0.05 * min : (min != 0 ? 0.05 * std::abs(min) : 1.0);
    return {std::max(min - pad, -kMax), std::min(max + pad, kMax)};
  }
};

/// "plot 'Title': " so every message names the plot.
std::string prefix(const PlotSpec& plot) { return "plot '" + plot.title + "': "; }

/// "(min, max)" with up to 6 significant digits.
std::string formatRange(const std::pair<double, double>& r) {
  char text[64];
  std::snprintf(text, sizeof text, "(%g, %g)", r.first, r.second);
  return text;
}

/// Checks an axis range, given or fitted; returns "" or the problem.
std::string rangeProblem(const char* axis, const std::pair<double, double>& r) {
  if (!std::isfinite(r.first) || !std::isfinite(r.second) || !(r.first < r.second)) {
    return std::string(axis) + " range " + formatRange(r) + " must be finite with min < max";
  }
  if (!std::isfinite(r.second - r.first)) {
    return std::string(axis) + " range " + formatRange(r) + " is wider than a double can hold";
  }
  return {};
}

/// The QApplication to render with, created if there is none (see the
/// header). Returns nullptr and sets `problem` if it cannot be used.
QApplication* application(std::string& problem) {
  QCoreApplication* instance = QCoreApplication::instance();
  if (instance == nullptr) {
    // Headless: no display server to talk to, so draw with the offscreen
    // platform plugin instead of letting xcb abort the process.
    if (qEnvironmentVariableIsEmpty("DISPLAY") && qEnvironmentVariableIsEmpty("WAYLAND_DISPLAY") &&
        !qEnvironmentVariableIsSet("QT_QPA_PLATFORM")) {
      qputenv("QT_QPA_PLATFORM", QByteArrayLiteral("offscreen"));
    }
    // QApplication keeps references to argc and argv for its lifetime.
    static int argc = 1;
    static char name[] = "simpartner-plot";
    static char* argv[] = {name, nullptr};
    // Deliberately never deleted. Qt does not support destroying the
    // application after main has returned (its globals may be gone), and a
    // leaked one runs no code at exit; the OS reclaims it.
    instance = new QApplication(argc, argv);
  }
  auto* app = qobject_cast<QApplication*>(instance);
  if (app == nullptr) {
    problem = "needs a QApplication, but the application object is a " +
              std::string(instance->metaObject()->className());
    return nullptr;
  }
  if (QThread::currentThread() != app->thread()) {
    problem = "must be rendered on the GUI thread";
    return nullptr;
  }
  return app;
}

/// The 1, 2 or 5 times a power of ten nearest above `raw` (> 0).
double niceStep(double raw) {
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * decade >= raw) return m * decade;
  }
  return 10 * decade;
}

/// An axis over `range` with ticks at round multiples of 1, 2 or 5 x 10^n,
/// about one per `pixelsPerTick` of its `lengthPx`.
QValueAxis* makeAxis(const std::string& title, std::pair<double, double> range, QFont font, int lengthPx,
                     int pixelsPerTick) {
  auto* axis = new QValueAxis;
  axis->setTitleText(QString::fromStdString(title));
  font.setBold(false);
  axis->setTitleFont(font);
  axis->setRange(range.first, range.second);
  const double wanted = std::max(2.0, static_cast<double>(lengthPx) / pixelsPerTick);
  axis->setTickType(QValueAxis::TicksDynamic);
  axis->setTickAnchor(0);
  axis->setTickInterval(niceStep((range.second - range.first) / wanted));
  axis->setLabelFormat(QStringLiteral("%.4g"));
  axis->setGridLineColor(QColor(0xdd, 0xdd, 0xdd));
  axis->setLinePenColor(QColor(0x55, 0x55, 0x55));
  axis->setLabelsColor(Qt::black);
  axis->setTitleBrush(Qt::black);
  return axis;
}

}  // namespace

std::uint32_t plotSeriesColor(std::size_t index) {
  // Okabe-Ito without black (it would look like the axes): blue, vermillion,
  // bluish green, orange, reddish purple, sky blue, yellow, grey.
  static constexpr std::array<std::uint32_t, 8> kPalette = {
      0x0072B2, 0xD55E00, 0x009E73, 0xE69F00, 0xCC79A7, 0x56B4E9, 0xF0E442, 0x666666};
  return kPalette[index % kPalette.size()];
}

bool renderPlotPng(const PlotSpec& plot, const std::string& path, std::string& error) {
  // Check everything before touching Qt or the file.
  if (plot.series.empty()) {
    error = prefix(plot) + "has no series";
    return false;
  }
  if (plot.width < 1 || plot.width > kMaxSide || plot.height < 1 || plot.height > kMaxSide) {
    error = prefix(plot) + "size " + std::to_string(plot.width) + "x" + std::to_string(plot.height) +
            " is outside 1.." + std::to_string(kMaxSide) + " pixels";
    return false;
  }
  Extent xExtent, yExtent;
  std::vector<QList<QPointF>> points(plot.series.size());
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    const std::string where = prefix(plot) + "series '" + s.name + "': ";
    if (s.x.empty() && s.y.empty()) {
      error = where + "has no points";
      return false;
    }
    if (s.x.size() != s.y.size()) {
      error = where + std::to_string(s.x.size()) + " x values but " + std::to_string(s.y.size()) + " y values";
      return false;
    }
    points[i].reserve(static_cast<qsizetype>(s.x.size()));
    for (std::size_t k = 0; k < s.x.size(); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      points[i].append(QPointF(s.x[k], s.y[k]));
      xExtent.add(s.x[k]);
      yExtent.add(s.y[k]);
    }
    if (points[i].isEmpty()) {
      error = where + "no finite point (all " + std::to_string(s.x.size()) + " skipped)";
      return false;
    }
  }

  const std::pair<double, double> xRange = plot.xRange.value_or(xExtent.withMargin());
  const std::pair<double, double> yRange = plot.yRange.value_or(yExtent.withMargin());
  for (const auto& [axis, range] : {std::pair{"x", xRange}, std::pair{"y", yRange}}) {
    if (std::string p = rangeProblem(axis, range); !p.empty()) {
      error = prefix(plot) + p;
      return false;
    }
  }

  std::string problem;
  QApplication* app = application(problem);
  if (app == nullptr) {
    error = prefix(plot) + problem;
    return false;
  }

  // The chart, inside a scene that owns it (and it its series and axes).
  // No view, no window: the scene paints straight into an image.
  QGraphicsScene scene;
  auto* chart = new QChart;
  scene.addItem(chart);
  chart->setAnimationOptions(QChart::NoAnimation);
  chart->setTheme(QChart::ChartThemeLight);
  chart->setBackgroundBrush(Qt::white);
  chart->setBackgroundPen(Qt::NoPen);
  chart->setBackgroundRoundness(0);
  chart->setDropShadowEnabled(false);
  QFont titleFont = app->font();
  titleFont.setPointSizeF(titleFont.pointSizeF() * 1.3);
  titleFont.setBold(true);
  chart->setTitleFont(titleFont);
  chart->setTitleBrush(Qt::black);
  chart->setTitle(QString::fromStdString(plot.title));

  QValueAxis* xAxis =
      makeAxis(plot.xLabel, xRange, app->font(), plot.width, 100);
  QValueAxis* yAxis =
      makeAxis(plot.yLabel, yRange, app->font(), plot.height, 60);
  chart->addAxis(xAxis, Qt::AlignBottom);
  chart->addAxis(yAxis, Qt::AlignLeft);

  bool anyName = false;
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    const QColor color = QColor::fromRgb(static_cast<QRgb>(plotSeriesColor(i)));
    QXYSeries* series = nullptr;
    if (s.style == PlotSeries::Style::Points) {
      auto* scatter = new QScatterSeries;
      scatter->setMarkerShape(QScatterSeries::MarkerShapeCircle);
      scatter->setMarkerSize(7);
      scatter->setBrush(color);
      scatter->setPen(QPen(color.darker(130), 1));
      series = scatter;
    } else {
      auto* line = new QLineSeries;
      QPen pen(color, 2);
      pen.setCapStyle(Qt::RoundCap);
      pen.setJoinStyle(Qt::RoundJoin);
      line->setPen(pen);
      series = line;
    }
    series->setName(QString::fromStdString(s.name));
    anyName = anyName || !s.name.empty();
    series->replace(points[i]);
    chart->addSeries(series);
    series->attachAxis(xAxis);
    series->attachAxis(yAxis);
  }
  chart->legend()->setVisible(anyName);
  chart->legend()->setAlignment(Qt::AlignBottom);
  chart->legend()->setLabelColor(Qt::black);
  // Unnamed series get no legend entry.
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    if (plot.series[i].name.empty()) {
      const auto markers = chart->legend()->markers(chart->series().at(static_cast<qsizetype>(i)));
      for (QLegendMarker* marker : markers) marker->setVisible(false);
    }
  }

  // Lay out now, without an event loop. setGeometry already does (the image
  // was identical without activate()); activate() makes sure nothing waits
  // for a posted LayoutRequest that no event loop would deliver.
  const QRectF rect(0, 0, plot.width, plot.height);
  chart->setGeometry(rect);
  chart->layout()->activate();
  scene.setSceneRect(rect);

  QImage image(plot.width, plot.height, QImage::Format_ARGB32);
  image.fill(Qt::white);
  {
    QPainter painter(&image);
    painter.setRenderHint(QPainter::Antialiasing);
    painter.setRenderHint(QPainter::TextAntialiasing);
    scene.render(&painter, rect, rect);
  }

  // Written to a temporary file and renamed, so a report never holds half a PNG.
  QSaveFile file(QString::fromStdString(path));
  if (!file.open(QIODevice::WriteOnly)) {
    error = prefix(plot) + "cannot write '" + path + "': " + file.errorString().toStdString();
    return false;
  }
  if (!image.save(&file, "PNG") || !file.commit()) {
    error = prefix(plot) + "cannot write '" + path + "': " + file.errorString().toStdString();
    return false;
  }
  return true;
}

}  // namespace sp
