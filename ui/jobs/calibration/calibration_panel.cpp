#include "ui/jobs/calibration/calibration_panel.h"

#include <QChart>
#include <QChartView>
#include <QComboBox>
#include <QCoreApplication>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineSeries>
#include <QPushButton>
#include <QTabWidget>
#include <QTableWidget>
#include <QValueAxis>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <string_view>
#include <utility>

namespace sp {

namespace {

// A value as shown: factors as such, the delay in milliseconds, the centre
// of mass in millimetres. What a value is multiplied by, and its unit.
std::pair<double, QString> display(size_t param) {
  const std::string_view unit = calParams()[param].unit;
  if (unit == "s") return {1000, QStringLiteral("ms")};
  if (unit == "m") return {1000, QStringLiteral("mm")};
  return {1, QString()};
}

// A value as a cell shows it. A factor says it is one (issue 59: bare
// numbers read as metres), a split (the front, left or diagonal wheels'
// radius over the others') in per cent. `compact` for the files' column,
// whose factors are 1 and splits 0: the parameters' names keep the room.
QString shown(size_t param, double v, bool compact = false) {
  const auto [k, unit] = display(param);
  if (unit.isEmpty()) {
    const bool split = param == static_cast<size_t>(CalParam::WheelRadiusSplit) ||
                       param == static_cast<size_t>(CalParam::WheelRadiusSide) ||
                       param == static_cast<size_t>(CalParam::WheelRadiusDiag);
    if (split) return compact ? QString::number(v * 100, 'g', 3) + QStringLiteral("%") : QString::asprintf("%+.2f%%", v * 100);
    return (compact ? QString::number(v, 'g', 4) : QString::number(v, 'f', 4)) + QStringLiteral("×");
  }
  return QString::number(v * k, 'f', 1) + " " + unit;
}

// The fits a log's rows hold: one time each (a log written before the
// centre of mass was fitted has fewer rows per fit).
qsizetype fitsIn(const std::vector<LogCalibration>& rows) {
  std::vector<double> times;
  for (const LogCalibration& r : rows) times.push_back(r.time);
  std::sort(times.begin(), times.end());
  return std::unique(times.begin(), times.end()) - times.begin();
}

}  // namespace

CalibrationPanel::CalibrationPanel(QWidget* parent) : QWidget(parent), series_(kCalParams) {
  auto* layout = new QVBoxLayout(this);
  table_ = new QTableWidget(kCalParams, 5, this);
  table_->setHorizontalHeaderLabels({tr("Parameter"), tr("Value"), tr("±"), tr("Files"), tr("Rehearsals")});
  table_->horizontalHeaderItem(4)->setToolTip(
      tr("What the rehearsals, robustness runs and sweeps use: the value, except a tyre radius split the "
         "full physics has not confirmed (the fits run in the ghost's coarser physics)"));
  table_->verticalHeader()->hide();
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setSelectionMode(QAbstractItemView::NoSelection);
  table_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
  table_->horizontalHeader()->setSectionResizeMode(0, QHeaderView::Stretch);
  for (int i = 0; i < kCalParams; ++i) {
    const CalParamInfo& p = calParams()[static_cast<size_t>(i)];
    // The brief name: short enough that the side dock (about 370 px at
    // 1280x800) shows it whole beside four columns of numbers; the full
    // name and the key are its tooltip.
    auto* name = new QTableWidgetItem(tr(p.brief));
    name->setToolTip(tr("%1 (%2)").arg(tr(p.label), QString::fromUtf8(p.key)));
    table_->setItem(i, 0, name);
    table_->setItem(i, 3, new QTableWidgetItem(shown(static_cast<size_t>(i), p.files, true)));
    showRow(i, p.files, 0, false, tr("files"));
    table_->setItem(i, 4, new QTableWidgetItem(shown(static_cast<size_t>(i), p.files)));
  }
  table_->resizeColumnsToContents();
  // At least three rows; the rest scroll inside the table (issue 59: the
  // whole table as a minimum pushed the buttons and the status below the
  // fold of a 1280x800 window).
  table_->setMinimumHeight(3 * table_->verticalHeader()->defaultSectionSize() + table_->horizontalHeader()->height() + 4);

  auto* plot = new QWidget;
  auto* plotLayout = new QVBoxLayout(plot);
  plotLayout->setContentsMargins(0, 0, 0, 0);
  auto* plotRow = new QHBoxLayout;
  plotRow->addWidget(new QLabel(tr("Plot:"), plot));
  plotted_ = new QComboBox(plot);
  for (const CalParamInfo& p : calParams()) plotted_->addItem(tr(p.label));
  plotRow->addWidget(plotted_, 1);
  plotLayout->addLayout(plotRow);
  chart_ = new QChart;
  chart_->legend()->hide();
  chart_->setMargins(QMargins(2, 2, 2, 2));
  value_ = new QLineSeries;
  upper_ = new QLineSeries;
  lower_ = new QLineSeries;
  QPen band(Qt::gray);
  band.setStyle(Qt::DashLine);
  upper_->setPen(band);
  lower_->setPen(band);
  axisX_ = new QValueAxis;
  axisX_->setTitleText(tr("robot time [s]"));
  axisY_ = new QValueAxis;
  chart_->addAxis(axisX_, Qt::AlignBottom);
  chart_->addAxis(axisY_, Qt::AlignLeft);
  for (QLineSeries* s : {value_, upper_, lower_}) {
    chart_->addSeries(s);
    s->attachAxis(axisX_);
    s->attachAxis(axisY_);
  }
  view_ = new QChartView(chart_, plot);
  view_->setMinimumHeight(100);
  view_->setRenderHint(QPainter::Antialiasing);
  plotLayout->addWidget(view_, 1);
  connect(plotted_, &QComboBox::currentIndexChanged, this, [this] { replot(); });

  // What the calibration does and the buttons that change it first, always
  // in view; the table and the plot below them, one at a time.
  status_ = new QLabel(this);
  status_->setWordWrap(true);
  layout->addWidget(status_);
  auto* buttons = new QHBoxLayout;
  freeze_ = new QPushButton(tr("Freeze"), this);
  freeze_->setCheckable(true);
  freeze_->setToolTip(tr("Keep the values the twins use now; fits go on and are shown"));
  reset_ = new QPushButton(tr("Reset to files"), this);
  reset_->setToolTip(tr("The twins use the robot and world files' values again"));
  save_ = new QPushButton(tr("Save…"), this);
  save_->setToolTip(tr("Save the values the rehearsals use as a parameters file (calibration.* keys) or as a robot file with them written in"));
  for (QPushButton* b : {freeze_, reset_, save_}) buttons->addWidget(b);
  layout->addLayout(buttons);
  views_ = new QTabWidget(this);
  views_->addTab(table_, tr("Values"));
  views_->addTab(plot, tr("Plot"));
  layout->addWidget(views_, 1);
  // The button says what it is in (issue 59: a pressed Freeze looked as any other).
  connect(freeze_, &QPushButton::toggled, this,
          [this](bool on) { freeze_->setText(on ? tr("Frozen: unfreeze") : tr("Freeze")); });
  connect(freeze_, &QPushButton::toggled, this, &CalibrationPanel::freezeToggled);
  connect(reset_, &QPushButton::clicked, this, &CalibrationPanel::resetRequested);
  connect(save_, &QPushButton::clicked, this, &CalibrationPanel::saveRequested);
}

void CalibrationPanel::showRow(int row, double value, double sigma, bool observed, const QString& status) {
  const size_t p = static_cast<size_t>(row);
  auto* v = new QTableWidgetItem(shown(p, value));
  // A deviation has no sign, and is in the value's unit (the header says ±).
  QString deviation = shown(p, sigma);
  if (deviation.startsWith(QLatin1Char('+'))) deviation.remove(0, 1);
  if (deviation.endsWith(QStringLiteral("×"))) deviation.chop(1);
  auto* s = new QTableWidgetItem(observed ? deviation : status);
  if (!observed) {
    v->setForeground(palette().color(QPalette::Disabled, QPalette::Text));
    s->setForeground(palette().color(QPalette::Disabled, QPalette::Text));
    s->setToolTip(tr("The motion so far cannot tell this parameter: it keeps its value"));
  }
  table_->setItem(row, 1, v);
  table_->setItem(row, 2, s);
}

void CalibrationPanel::setLive(const CalibrationState* state, const QString& why) {
  if (replayed_) return;
  const bool live = state != nullptr;
  for (QPushButton* b : {freeze_, reset_, save_}) b->setEnabled(live);
  if (!state) {
    status_->setText(why);
    return;
  }
  for (int i = 0; i < kCalParams; ++i) {
    const size_t p = static_cast<size_t>(i);
    showRow(i, state->applied[p], state->sigma[p], state->observed[p], tr("unobserved"));
    auto* rehearsed = new QTableWidgetItem(shown(p, state->fullPhysics[p]));
    if (state->fullPhysics[p] != state->applied[p])
      rehearsed->setToolTip(state->refused[p] ? tr("The full physics predicts the robot better with the files' value")
                                              : tr("The files' value until the full physics confirms this one"));
    table_->setItem(i, 4, rehearsed);
  }
  for (auto& s : series_) s.clear();
  for (const CalibrationFit& fit : state->history)
    if (fit.refused.empty())
      for (size_t p = 0; p < kCalParams; ++p)
        if (fit.observed[p]) series_[p].push_back({fit.to, fit.value[p], fit.sigma[p]});
  freeze_->blockSignals(true);
  freeze_->setChecked(state->frozen);
  freeze_->blockSignals(false);
  QString text;
  if (state->history.empty()) {
    text = tr("Drive to calibrate: a fit needs a few seconds of the wheels turning.");
  } else {
    const CalibrationFit& last = state->history.back();
    const QString reason = QString::fromStdString(last.refused);
    if (last.wantsDriving)
      text = tr("Waiting for driving (the values kept): %1").arg(reason);
    else if (!last.refused.empty())
      text = tr("Fit %1 refused, the values kept: %2").arg(state->fits).arg(reason);
    else
      text = tr("Fit %1 at %2 s: %3 segments, cost %4 → %5, %6 ms.")
                 .arg(state->fits)
                 .arg(last.to, 0, 'f', 1)
                 .arg(last.segments)
                 .arg(last.costBefore, 0, 'g', 3)
                 .arg(last.costAfter, 0, 'g', 3)
                 .arg(last.wallMs, 0, 'f', 0);
  }
  if (state->frozen) text += tr(" Frozen: new fits are not applied.");
  status_->setText(text);
  replot();
}

void CalibrationPanel::setReplayed(const std::vector<LogCalibration>& rows, const QString& label) {
  replayed_ = rows;
  for (QPushButton* b : {freeze_, reset_, save_}) b->setEnabled(false);
  for (auto& s : series_) s.clear();
  std::vector<const LogCalibration*> newest(kCalParams, nullptr);
  for (const LogCalibration& r : rows)
    for (size_t p = 0; p < kCalParams; ++p)
      if (r.param == calParams()[p].key) {
        if (r.status.rfind("refused", 0) == 0) continue;
        newest[p] = &r;
        if (r.observed) series_[p].push_back({r.time, r.value, r.sigma});
      }
  for (int i = 0; i < kCalParams; ++i) {
    const size_t p = static_cast<size_t>(i);
    if (newest[p]) showRow(i, newest[p]->value, newest[p]->sigma, newest[p]->observed, tr("unobserved"));
    else showRow(i, calParams()[p].files, 0, false, tr("not in the log"));
    table_->setItem(i, 4, new QTableWidgetItem());  // the log keeps the fits, not what the rehearsals used
  }
  status_->setText(rows.empty() ? tr("The replayed log %1 holds no calibration.").arg(label)
                                : tr("The calibration the console fitted in %1 (%2 fits).")
                                      .arg(label)
                                      .arg(fitsIn(rows)));
  replot();
}

void CalibrationPanel::clearReplayed() { replayed_.reset(); }

int CalibrationPanel::plottedPoints() const { return static_cast<int>(value_->count()); }

void CalibrationPanel::replot() {
  const size_t p = static_cast<size_t>(std::max(0, plotted_->currentIndex()));
  const std::vector<Point>& pts = series_[p];
  const auto [k, unit] = display(p);
  QList<QPointF> v, up, down;
  double lo = calParams()[p].files * k, hi = lo;
  for (const Point& x : pts) {
    v.append({x.time, x.value * k});
    up.append({x.time, (x.value + x.sigma) * k});
    down.append({x.time, (x.value - x.sigma) * k});
    lo = std::min(lo, (x.value - x.sigma) * k);
    hi = std::max(hi, (x.value + x.sigma) * k);
  }
  value_->replace(v);
  upper_->replace(up);
  lower_->replace(down);
  const double pad = std::max(1e-3, (hi - lo) * 0.1);
  axisY_->setRange(lo - pad, hi + pad);
  axisY_->setTitleText(unit.isEmpty() ? tr("× files") : unit);
  if (!pts.empty()) axisX_->setRange(pts.front().time, std::max(pts.back().time, pts.front().time + 1));
}

}  // namespace sp
