#include "ui/live_plots.h"

#include <QSplitter>

#include <QBoxLayout>
#include <QCheckBox>
#include <QColor>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QPainter>
#include <QPen>
#include <QLegend>
#include <QLegendMarker>
#include <QPushButton>
#include <QScrollBar>
#include <QSignalBlocker>
#include <QString>
#include <QtCharts/QChart>
#include <QtCharts/QChartView>
#include <QtCharts/QLegend>
#include <QtCharts/QLineSeries>
#include <QtCharts/QScatterSeries>
#include <QtCharts/QValueAxis>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

#include "app/validation/plot.h"  // plotSeriesColor: the report plots' palette
#include "sim/math.h"
#include "ui/icons.h"

namespace sp {

namespace {

constexpr double kMinWindow = 1;    // [s]
constexpr double kMaxWindow = 600;  // [s]
constexpr double kMinYSpan = 1;     // [N] the y axis never gets flatter than this
constexpr double kYMargin = 0.05;   // of the data's span, above and below

/// A round tick spacing (1, 2 or 5 x 10^n) giving about `ticks` intervals
/// over `span` (> 0).
double tickSpacing(double span, double ticks) {
  const double raw = span / std::max(ticks, 1.0);
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  const double mantissa = raw / decade;
  return decade * (mantissa <= 1 ? 1 : mantissa <= 2 ? 2 : mantissa <= 5 ? 5 : 10);
}

/// Ticks every `step` (at its multiples) with just the decimals it needs,
/// so labels stay short and do not jump in width as the range moves.
void setTickStep(QValueAxis* axis, double step) {
  axis->setTickInterval(step);
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step))));
  axis->setLabelFormat(QStringLiteral("%.%1f").arg(decimals));
}

/// Sets an axis's range [min, max] and tick step (> 0). Of the two orders it
/// takes the one whose state in between has fewer ticks: a 600 s range at
/// the old 1 s step lays out 600 labels (110 ms measured) before the new
/// step cuts them to six.
void setAxis(QValueAxis* axis, double min, double max, double step) {
  if (!(step > 0) || !std::isfinite(step) || !(min < max)) return;
  const double ticksIfRangeFirst = (max - min) / axis->tickInterval();  // inf while no step is set
  const double ticksIfStepFirst = (axis->max() - axis->min()) / step;
  if (ticksIfRangeFirst <= ticksIfStepFirst) {
    axis->setRange(min, max);
    setTickStep(axis, step);
  } else {
    setTickStep(axis, step);
    axis->setRange(min, max);
  }
}

QValueAxis* makeAxis(const QString& title) {
  auto* axis = new QValueAxis;
  axis->setTitleText(title);
  axis->setTickType(QValueAxis::TicksDynamic);
  axis->setTickAnchor(0);
  axis->setGridLineColor(QColor(0xdd, 0xdd, 0xdd));
  axis->setLinePenColor(QColor(0x55, 0x55, 0x55));
  axis->setLabelsColor(Qt::black);
  axis->setTitleBrush(Qt::black);
  // A size smaller than the window's text: a docked plot is short, and
  // labels that do not fit are elided to "...".
  QFont small = axis->labelsFont();
  small.setPointSizeF(small.pointSizeF() * 0.85);
  axis->setLabelsFont(small);
  axis->setTitleFont(small);
  return axis;
}

/// Seconds as whole milliseconds for the history scroll bar, clamped to int.
int toMs(double seconds) {
  return static_cast<int>(std::clamp(std::round(seconds * 1000), 0.0, static_cast<double>(INT_MAX)));
}

}  // namespace

// ---------------------------------------------------------------- LivePlot

LivePlot::LivePlot(QWidget* parent) : QWidget(parent) {
  chart_ = new QChart;
  chart_->setTheme(QChart::ChartThemeLight);  // before any series: it recolours them
  // Animations would restart ten times a second and never settle.
  chart_->setAnimationOptions(QChart::NoAnimation);
  chart_->setBackgroundRoundness(0);
  chart_->setDropShadowEnabled(false);
  chart_->setMargins(QMargins(2, 0, 2, 0));
  chart_->legend()->setAlignment(Qt::AlignTop);
  chart_->legend()->setLabelColor(Qt::black);
  QFont titleFont = font();
  titleFont.setBold(true);
  chart_->setTitleFont(titleFont);
  chart_->setTitleBrush(Qt::black);

  auto* view = new QChartView(chart_, this);  // takes the chart
  view->setRenderHint(QPainter::Antialiasing);
  view->setMinimumSize(200, 120);  // small enough for the 3D view to get half the window at 1280x800

  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->setSpacing(2);
  layout->addWidget(view, 1);

  timer_.setInterval(100);
  connect(&timer_, &QTimer::timeout, this, &LivePlot::tick);
  timer_.start();
}

void LivePlot::setReplotInterval(int ms) { timer_.setInterval(std::max(ms, 1)); }

int LivePlot::replotInterval() const { return timer_.interval(); }

void LivePlot::replotNow() {
  dirty_ = false;
  if (replot(true)) ++replots_;
}

void LivePlot::setOwnTimer(bool on) {
  if (on) timer_.start();
  else timer_.stop();
}

void LivePlot::tick() {
  // A hidden plot (another tab, a closed dock) stays dirty and costs nothing
  // until it is shown again.
  if (!dirty_ || !isVisible()) return;
  dirty_ = false;
  if (replot(false)) ++replots_;
}

// ---------------------------------------------------------- WheelForcePlot

WheelForcePlot::WheelForcePlot(QWidget* parent, std::size_t capacity)
    : LivePlot(parent), capacity_(std::max<std::size_t>(capacity, 2)) {
  chart_->setTitle(tr("Wheel normal forces"));
  chart_->legend()->setAlignment(Qt::AlignRight);  // beside the plot: height is what a docked plot lacks
  xAxis_ = makeAxis(tr("robot time [s]"));
  yAxis_ = makeAxis(tr("force [N]"));  // the title says which: a longer one is elided
  chart_->addAxis(xAxis_, Qt::AlignBottom);
  chart_->addAxis(yAxis_, Qt::AlignLeft);
  const std::array<QString, kWheels> names = {tr("FL"), tr("FR"), tr("RL"), tr("RR")};
  for (std::size_t w = 0; w < series_.size(); ++w) {
    auto* series = new QLineSeries;
    series->setName(names[w]);
    series->setPen(QPen(QColor::fromRgb(static_cast<QRgb>(plotSeriesColor(w))), 1.5));
    chart_->addSeries(series);
    series->attachAxis(xAxis_);
    series->attachAxis(yAxis_);
    series_[w] = series;
  }
  setAxis(xAxis_, 0, window_, 1);
  setAxis(yAxis_, 0, 100, 20);

  // Controls under the chart: window, pause/follow, auto y, history.
  auto* label = new QLabel(tr("window [s]"), this);
  windowBox_ = new QDoubleSpinBox(this);
  windowBox_->setObjectName("window");
  windowBox_->setRange(kMinWindow, kMaxWindow);
  windowBox_->setDecimals(1);
  windowBox_->setValue(window_);
  windowBox_->setKeyboardTracking(false);  // typing "60" should not replot at 6 s first
  windowBox_->setToolTip(tr("Length of the time window shown"));
  label->setBuddy(windowBox_);
  pauseButton_ = new QPushButton(actionIcon(QStringLiteral("pause")), tr("Pause"), this);
  pauseButton_->setObjectName("pause");
  pauseButton_->setCheckable(true);
  pauseButton_->setToolTip(tr("Pause: hold the view to read it or scroll back. Follow: show the newest samples"));
  autoYBox_ = new QCheckBox(tr("auto y"), this);
  autoYBox_->setObjectName("autoY");
  autoYBox_->setChecked(true);
  autoYBox_->setToolTip(tr("Fit the force axis to the data shown; untick to hold the current range"));
  history_ = new QScrollBar(Qt::Horizontal, this);
  history_->setObjectName("history");
  history_->setToolTip(tr("Scroll back through the buffered history (pauses)"));
  history_->setRange(0, 0);

  auto* row = new QHBoxLayout;
  row->setContentsMargins(6, 0, 6, 4);
  row->addWidget(label);
  row->addWidget(windowBox_);
  row->addWidget(pauseButton_);
  row->addWidget(autoYBox_);
  row->addWidget(history_, 1);
  qobject_cast<QBoxLayout*>(layout())->addLayout(row);

  connect(windowBox_, &QDoubleSpinBox::valueChanged, this, &WheelForcePlot::onWindowChanged);
  connect(pauseButton_, &QPushButton::toggled, this, &WheelForcePlot::setPaused);
  connect(autoYBox_, &QCheckBox::toggled, this, [this](bool on) {
    if (on) {
      setAutoYRange();
    } else {
      autoY_ = false;  // hold whatever is shown now
    }
  });
  connect(history_, &QScrollBar::valueChanged, this, &WheelForcePlot::onScrolled);
  // A resize changes the tick spacing and the pixel columns for thinning.
  connect(chart_, &QChart::plotAreaChanged, this, [this] {
    viewDirty_ = true;
    markDirty();
  });
}

void WheelForcePlot::addSample(double time, const std::array<double, kWheels>& normal) {
  ++samplesReceived_;
  if (!std::isfinite(time)) return;
  if (size_ > 0 && time < at(size_ - 1).time) clear();  // robot time restarted
  if (size_ < capacity_) {
    buffer_.push_back({time, normal});  // not yet full: start_ is 0
    ++size_;
  } else {
    buffer_[start_] = {time, normal};
    start_ = (start_ + 1) % capacity_;
  }
  // Paused, the view stays put; only the scroll bar's range grows.
  if (!paused_) viewDirty_ = true;
  markDirty();
}

void WheelForcePlot::clear() {
  buffer_.clear();
  start_ = 0;
  size_ = 0;
  setPaused(false);
  viewDirty_ = true;
  markDirty();
}

void WheelForcePlot::setWindow(double seconds) {
  if (std::isnan(seconds)) return;
  windowBox_->setValue(std::clamp(seconds, kMinWindow, kMaxWindow));  // calls onWindowChanged
}

void WheelForcePlot::onWindowChanged(double seconds) {
  window_ = seconds;
  viewDirty_ = true;
  markDirty();
}

void WheelForcePlot::setPaused(bool paused) {
  if (paused != paused_) {
    // Hold what the operator sees now, not what newer samples would show.
    if (paused) pausedEnd_ = xAxis_->max();
    paused_ = paused;
    viewDirty_ = true;
    markDirty();
  }
  const QSignalBlocker block(pauseButton_);
  pauseButton_->setChecked(paused);
  pauseButton_->setText(paused ? tr("Follow") : tr("Pause"));
}

bool WheelForcePlot::setYRange(double min, double max) {
  if (!std::isfinite(min) || !std::isfinite(max) || !(min < max) || !std::isfinite(max - min)) return false;
  autoY_ = false;
  {
    const QSignalBlocker block(autoYBox_);
    autoYBox_->setChecked(false);
  }
  setYAxis(min, max);
  return true;
}

void WheelForcePlot::setAutoYRange() {
  autoY_ = true;
  {
    const QSignalBlocker block(autoYBox_);
    autoYBox_->setChecked(true);
  }
  viewDirty_ = true;
  markDirty();
}

std::pair<double, double> WheelForcePlot::xRange() const { return {xAxis_->min(), xAxis_->max()}; }

std::pair<double, double> WheelForcePlot::yRange() const { return {yAxis_->min(), yAxis_->max()}; }

QList<QPointF> WheelForcePlot::shownPoints(int wheel) const {
  if (wheel < 0 || wheel >= kWheels) return {};
  QList<QPointF> out = series_[static_cast<std::size_t>(wheel)]->points();
  for (QLineSeries* more : gapSeries_[static_cast<std::size_t>(wheel)]) out += more->points();
  return out;
}

int WheelForcePlot::shownSegments(int wheel) const {
  if (wheel < 0 || wheel >= kWheels) return 0;
  const auto w = static_cast<std::size_t>(wheel);
  int n = series_[w]->count() > 0 ? 1 : 0;
  for (QLineSeries* more : gapSeries_[w]) n += more->count() > 0 ? 1 : 0;
  return n;
}

QLineSeries* WheelForcePlot::segmentSeries(std::size_t wheel, std::size_t k) {
  if (k == 0) return series_[wheel];
  std::vector<QLineSeries*>& more = gapSeries_[wheel];
  while (more.size() < k) {
    // Same colour, no legend entry: one wheel, drawn in pieces.
    auto* series = new QLineSeries;
    series->setPen(series_[wheel]->pen());
    chart_->addSeries(series);
    series->attachAxis(xAxis_);
    series->attachAxis(yAxis_);
    for (QLegendMarker* marker : chart_->legend()->markers(series)) marker->setVisible(false);
    more.push_back(series);
  }
  return more[k - 1];
}

std::size_t WheelForcePlot::firstIndex(double t, bool after) const {
  std::size_t lo = 0;
  std::size_t hi = size_;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    const double m = at(mid).time;
    if (after ? m <= t : m < t) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo;
}

std::pair<double, double> WheelForcePlot::viewSpan() const {
  if (paused_) return {pausedEnd_ - window_, pausedEnd_};
  if (size_ == 0) return {0, window_};
  const double oldest = at(0).time;
  const double newest = at(size_ - 1).time;
  // Until a window is full, fill it from the left, as an oscilloscope's first
  // sweep, rather than showing empty negative time.
  if (newest - oldest < window_) return {oldest, oldest + window_};
  return {newest - window_, newest};
}

void WheelForcePlot::appendPoints(int wheel, std::size_t i0, std::size_t i1, std::pair<double, double> span,
                                  int columns, QList<QPointF>& out) const {
  const auto w = static_cast<std::size_t>(wheel);
  const std::size_t perColumn = 4;
  if (i1 - i0 <= perColumn * static_cast<std::size_t>(columns)) {
    out.reserve(static_cast<qsizetype>(i1 - i0));
    for (std::size_t i = i0; i < i1; ++i) {
      const Sample& s = at(i);
      if (std::isfinite(s.normal[w])) out.append(QPointF(s.time, s.normal[w]));
    }
    return;
  }
  // More samples than pixels: per pixel column keep the first, lowest,
  // highest and last sample (in time order). The drawn line covers the
  // same pixels as with every sample, at a fraction of the cost.
  out.reserve(static_cast<qsizetype>(perColumn) * columns);
  const double columnsPerSecond = columns / (span.second - span.first);
  long column = -1;
  std::array<std::size_t, 4> keep{};  // first, lowest, highest, last
  auto flush = [&] {
    if (column < 0) return;
    std::array<std::size_t, 4> order = keep;
    std::sort(order.begin(), order.end());
    for (std::size_t k = 0; k < order.size(); ++k) {
      if (k > 0 && order[k] == order[k - 1]) continue;
      out.append(QPointF(at(order[k]).time, at(order[k]).normal[w]));
    }
  };
  for (std::size_t i = i0; i < i1; ++i) {
    const double v = at(i).normal[w];
    if (!std::isfinite(v)) continue;
    const long c = std::min(static_cast<long>((at(i).time - span.first) * columnsPerSecond), long{columns} - 1);
    if (c != column) {
      flush();
      column = c;
      keep = {i, i, i, i};
    }
    if (v < at(keep[1]).normal[w]) keep[1] = i;
    if (v > at(keep[2]).normal[w]) keep[2] = i;
    keep[3] = i;
  }
  flush();
}

std::pair<double, double> WheelForcePlot::fittedYRange(const std::array<QList<QPointF>, kWheels>& points) const {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (const QList<QPointF>& list : points) {
    for (const QPointF& p : list) {
      lo = std::min(lo, p.y());
      hi = std::max(hi, p.y());
    }
  }
  if (!(lo <= hi) || !std::isfinite(hi - lo)) return yRange();  // nothing (sane) shown: keep the range
  const double mid = lo + (hi - lo) / 2;
  // A flat signal still gets a readable axis; relative to |mid| too, so
  // mid +- half the span stays distinct from mid in doubles.
  const double minSpan = std::max(kMinYSpan, 1e-9 * std::abs(mid));
  if (hi - lo < minSpan) {
    lo = mid - minSpan / 2;
    hi = mid + minSpan / 2;
  }
  const double pad = kYMargin * (hi - lo);
  return {lo - pad, hi + pad};
}

void WheelForcePlot::setYAxis(double min, double max) {
  // Before the first layout the plot area is empty: assume a few hundred pixels.
  const double height = chart_->plotArea().height() >= 1 ? chart_->plotArea().height() : 300;
  // A tick every ~35 px, and at least three intervals in a short dock.
  setAxis(yAxis_, min, max, tickSpacing(max - min, std::max(3.0, height / 35)));
}

void WheelForcePlot::updateScrollBar() {
  // Positions are the view's right edge in ms after the oldest sample.
  const QSignalBlocker block(history_);
  if (size_ == 0) {
    history_->setRange(0, 0);
    return;
  }
  const double oldest = at(0).time;
  const double span = at(size_ - 1).time - oldest;
  history_->setRange(toMs(window_), toMs(std::max(span, window_)));
  history_->setPageStep(toMs(window_));
  history_->setSingleStep(std::max(1, toMs(window_ / 10)));
  history_->setValue(toMs(viewSpan().second - oldest));
}

void WheelForcePlot::onScrolled(int value) {
  if (size_ == 0) return;
  setPaused(true);  // scrolling back means the operator wants to look, not follow
  pausedEnd_ = at(0).time + value / 1000.0;
  viewDirty_ = true;
  markDirty();
}

bool WheelForcePlot::replot(bool force) {
  if (paused_ && !viewDirty_ && !force) {
    updateScrollBar();
    return false;
  }
  viewDirty_ = false;
  const std::pair<double, double> span = viewSpan();
  const std::size_t i0 = firstIndex(span.first, false);
  const std::size_t i1 = std::max(i0, firstIndex(span.second, true));
  // Before the first layout the plot area is empty: use the widget's size.
  const QRectF area = chart_->plotArea();
  const double areaWidth = area.width() >= 1 ? area.width() : width();
  const int columns = std::max(1, static_cast<int>(areaWidth));

  std::array<QList<QPointF>, kWheels> points;
  for (int w = 0; w < kWheels; ++w) appendPoints(w, i0, i1, span, columns, points[static_cast<std::size_t>(w)]);
  // Empty the series first: each axis change makes every series recompute
  // its geometry, which for the old points is wasted (half the cost of a
  // replot at 4 x 1000 points, measured).
  for (QLineSeries* series : series_) series->clear();
  for (auto& more : gapSeries_)
    for (QLineSeries* series : more) series->clear();
  setAxis(xAxis_, span.first, span.second, tickSpacing(window_, areaWidth / 100));
  const std::pair<double, double> y = autoY_ ? fittedYRange(points) : yRange();
  setYAxis(y.first, y.second);  // also when fixed: the plot's height may have changed
  // Where telemetry stopped for a while the line breaks: a straight line
  // across the silence would show forces nobody measured. A gap is a step
  // in robot time above kGap, or above two pixel columns when thinned.
  const double gap = std::max(kGap, 2.0 * (span.second - span.first) / columns);
  for (std::size_t w = 0; w < series_.size(); ++w) {
    const QList<QPointF>& all = points[w];
    std::size_t segment = 0;
    qsizetype start = 0;
    for (qsizetype i = 1; i <= all.size(); ++i)
      if (i == all.size() || all[i].x() - all[i - 1].x() > gap) {
        segmentSeries(w, segment++)->replace(all.mid(start, i - start));
        start = i;
      }
  }
  updateScrollBar();
  return true;
}

// --------------------------------------------------------------- LaserPlot

LaserPlot::LaserPlot(QWidget* parent) : LivePlot(parent), farthest_(std::numeric_limits<double>::infinity()) {
  // The frame in the tooltip: a docked plot is narrow, and the title
  // "Laser scan (sensor frame)" came out elided at 1280 px.
  chart_->setTitle(tr("Laser scan"));
  // No legend: a docked plot is short, and dots and a triangle say enough.
  chart_->legend()->hide();
  setToolTip(tr("Laser scan in the sensor's frame. Dots: laser hits; triangle: the sensor, pointing forward"));
  leftAxis_ = makeAxis(tr("y, left [m]"));
  leftAxis_->setReverse(true);  // seen from above with x up, +y is to the left
  forwardAxis_ = makeAxis(tr("x, forward [m]"));
  chart_->addAxis(leftAxis_, Qt::AlignBottom);
  chart_->addAxis(forwardAxis_, Qt::AlignLeft);

  hits_ = new QScatterSeries;
  hits_->setName(tr("hits"));
  hits_->setMarkerShape(QScatterSeries::MarkerShapeCircle);
  hits_->setMarkerSize(5);
  hits_->setBrush(QColor::fromRgb(static_cast<QRgb>(plotSeriesColor(0))));
  hits_->setPen(Qt::NoPen);
  sensor_ = new QScatterSeries;
  sensor_->setName(tr("sensor"));
  sensor_->setMarkerShape(QScatterSeries::MarkerShapeTriangle);  // points up: forward
  sensor_->setMarkerSize(12);
  sensor_->setBrush(QColor(0x33, 0x33, 0x33));
  sensor_->setPen(Qt::NoPen);
  sensor_->append(0, 0);
  for (QScatterSeries* series : {hits_, sensor_}) {
    chart_->addSeries(series);
    series->attachAxis(leftAxis_);
    series->attachAxis(forwardAxis_);
  }
  // Any resize changes the plot area; keep metres per pixel equal on both axes.
  connect(chart_, &QChart::plotAreaChanged, this, &LaserPlot::fitAspect);
  fitAspect();
}

void LaserPlot::setScan(double angleMin, double angleStep, const std::vector<double>& ranges) {
  ++scansReceived_;
  angleMin_ = angleMin;
  angleStep_ = angleStep;
  ranges_.assign(ranges.begin(), ranges.end());  // reuses the capacity
  markDirty();
}

void LaserPlot::clear() {
  ranges_.clear();
  markDirty();
}

bool LaserPlot::setRangeLimits(double nearest, double farthest) {
  if (!std::isfinite(nearest) || !(nearest >= 0) || !(nearest <= farthest)) return false;
  nearest_ = nearest;
  farthest_ = farthest;
  markDirty();
  return true;
}

void LaserPlot::setMaxRange(double metres) {
  if (!std::isfinite(metres) || !(metres > 0)) return;
  maxRange_ = metres;
  fitAspect();
}

std::pair<double, double> LaserPlot::forwardRange() const { return {forwardAxis_->min(), forwardAxis_->max()}; }

std::pair<double, double> LaserPlot::leftRange() const { return {leftAxis_->min(), leftAxis_->max()}; }

QList<QPointF> LaserPlot::shownPoints() const {
  // The series holds (y, x): sensor y runs along the horizontal axis.
  QList<QPointF> points = hits_->points();
  for (QPointF& p : points) p = QPointF(p.y(), p.x());
  return points;
}

void LaserPlot::fitAspect() {
  const QRectF area = chart_->plotArea();
  const double w = area.width() >= 1 ? area.width() : 1;
  const double h = area.height() >= 1 ? area.height() : 1;
  const double shorter = std::min(w, h);
  // The same tick step on both axes, so the grid is square.
  const double step = tickSpacing(2 * maxRange_, shorter / 70);
  for (const auto& [axis, length] : {std::pair{leftAxis_, w}, std::pair{forwardAxis_, h}}) {
    const double half = maxRange_ * length / shorter;
    // Setting an unchanged range would relayout and come back here.
    const bool same = std::abs(axis->max() - half) <= 1e-9 * half && std::abs(axis->min() + half) <= 1e-9 * half;
    setAxis(axis, same ? axis->min() : -half, same ? axis->max() : half, step);
  }
}

bool LaserPlot::replot(bool /*force*/) {
  QList<QPointF> points;
  if (std::isfinite(angleMin_) && std::isfinite(angleStep_)) {
    points.reserve(static_cast<qsizetype>(ranges_.size()));
    for (std::size_t i = 0; i < ranges_.size(); ++i) {
      const double r = ranges_[i];
      if (!std::isfinite(r) || r < nearest_ || r > farthest_) continue;  // no return, invalid, out of limits
      const double a = angleMin_ + static_cast<double>(i) * angleStep_;
      points.append(QPointF(r * std::sin(a), r * std::cos(a)));  // (y, x)
    }
  }
  hits_->replace(points);
  return true;
}

PredictionErrorPlot::PredictionErrorPlot(QWidget* parent) : LivePlot(parent) {
  chart_->setTitle(tr("Ghost prediction error"));
  // No legend (a docked plot has no width to spare): each axis title is in
  // its line's colour.
  chart_->legend()->hide();
  xAxis_ = makeAxis(tr("robot time [s]"));
  positionAxis_ = makeAxis(tr("position [cm]"));
  headingAxis_ = makeAxis(tr("heading [°]"));
  chart_->addAxis(xAxis_, Qt::AlignBottom);
  chart_->addAxis(positionAxis_, Qt::AlignLeft);
  chart_->addAxis(headingAxis_, Qt::AlignRight);
  position_ = new QLineSeries;
  position_->setName(tr("position"));
  position_->setPen(QPen(QColor::fromRgb(static_cast<QRgb>(plotSeriesColor(0))), 1.5));
  heading_ = new QLineSeries;
  heading_->setName(tr("heading"));
  heading_->setPen(QPen(QColor::fromRgb(static_cast<QRgb>(plotSeriesColor(1))), 1.5));
  for (QLineSeries* s : {position_, heading_}) {
    chart_->addSeries(s);
    s->attachAxis(xAxis_);
  }
  positionAxis_->setTitleBrush(QColor::fromRgb(static_cast<QRgb>(plotSeriesColor(0))));
  headingAxis_->setTitleBrush(QColor::fromRgb(static_cast<QRgb>(plotSeriesColor(1))));
  position_->attachAxis(positionAxis_);
  heading_->attachAxis(headingAxis_);
  setAxis(xAxis_, 0, kWindow, 10);
  setAxis(positionAxis_, 0, 5, 1);
  setAxis(headingAxis_, 0, 1, 0.2);
}

void PredictionErrorPlot::addSample(double time, double position, double heading) {
  ++received_;
  if (!std::isfinite(time) || !std::isfinite(position) || !std::isfinite(heading)) return;
  if (!samples_.empty() && time < samples_.back().time) samples_.clear();  // the robot restarted
  // One point per kBin of robot time, the bin's worst: 300 points for the
  // window instead of 1500 at 50 Hz (a chart's repaint under software GL
  // costs by the point), and no spike is lost.
  const double bin = std::floor(time / kBin) * kBin;
  if (!samples_.empty() && samples_.back().time == bin) {
    Sample& s = samples_.back();
    if (position <= s.position && heading <= s.heading) return;
    s.position = std::max(s.position, position);
    s.heading = std::max(s.heading, heading);
  } else {
    samples_.push_back({bin, position, heading});
    while (samples_.front().time < bin - kWindow) samples_.pop_front();
  }
  markDirty();
}

void PredictionErrorPlot::clear() {
  samples_.clear();
  markDirty();
}

int PredictionErrorPlot::shownPoints() const { return static_cast<int>(position_->count()); }

bool PredictionErrorPlot::replot(bool) {
  QList<QPointF> position, heading;
  double maxPosition = 0, maxHeading = 0;
  const double end = samples_.empty() ? 0 : samples_.back().time;
  for (const Sample& s : samples_) {
    position.append({s.time, s.position * 100});
    heading.append({s.time, radToDeg(s.heading)});
    maxPosition = std::max(maxPosition, s.position * 100);
    maxHeading = std::max(maxHeading, radToDeg(s.heading));
  }
  position_->replace(position);
  heading_->replace(heading);
  const double start = std::max(0.0, end - kWindow);
  setAxis(xAxis_, start, start + kWindow, 10);
  // At least 5 cm and 1 deg tall: a good prediction reads as good.
  const double pTop = std::max(5.0, maxPosition * 1.1), hTop = std::max(1.0, maxHeading * 1.1);
  setAxis(positionAxis_, 0, pTop, tickSpacing(pTop, 4));
  setAxis(headingAxis_, 0, hTop, tickSpacing(hTop, 4));
  return true;
}

QWidget* plotRow(const std::vector<std::pair<LivePlot*, int>>& plots) {
  auto* row = new QSplitter(Qt::Horizontal);
  for (const auto& [plot, stretch] : plots) {
    plot->setOwnTimer(false);
    row->addWidget(plot);
    row->setStretchFactor(row->count() - 1, stretch);
  }
  return row;
}

}  // namespace sp
