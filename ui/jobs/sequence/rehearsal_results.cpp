#include "ui/jobs/sequence/rehearsal_results.h"

#include <QBoxLayout>
#include <QLabel>
#include <QSlider>
#include <QTabWidget>
#include <QTreeWidget>
#include <QtCharts/QChart>
#include <QtCharts/QChartView>
#include <QtCharts/QLineSeries>
#include <QtCharts/QValueAxis>

#include <algorithm>
#include <cmath>

namespace sp {

namespace {

QString seconds(double t) { return QString::number(t, 'f', 2) + " s"; }

}  // namespace

RehearsalResults::RehearsalResults(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->setSpacing(3);
  verdicts_ = new QTreeWidget(this);
  verdicts_->setColumnCount(2);
  verdicts_->setHeaderLabels({tr("Rule"), tr("Verdict")});
  verdicts_->setRootIsDecorated(false);
  verdicts_->setMinimumHeight(60);
  // A failed rule's explanation wraps in its row rather than being elided
  // (issue 59: clipped top and bottom); failed rules come first.
  verdicts_->setWordWrap(true);
  verdicts_->setUniformRowHeights(false);
  verdicts_->setTextElideMode(Qt::ElideNone);
  // The verdicts and the margins' plot share one place, as tabs: stacked,
  // they pushed Watch and Send below the fold of a 1280x800 window.
  tabs_ = new QTabWidget(this);
  tabs_->addTab(verdicts_, tr("Verdicts"));
  layout->addWidget(tabs_, 1);
  connect(verdicts_, &QTreeWidget::itemClicked, this, [this](QTreeWidgetItem* item) {
    const QVariant t = item->data(0, Qt::UserRole);
    if (t.isValid()) scrubTo(t.toDouble());
  });

  watchRow_ = new QHBoxLayout;
  scrubber_ = new QSlider(Qt::Horizontal, this);
  scrubber_->setRange(0, 0);
  scrubLabel_ = new QLabel(this);
  scrubLabel_->setMinimumWidth(60);
  watchRow_->addWidget(new QLabel(tr("Watch"), this));
  watchRow_->addWidget(scrubber_, 1);
  watchRow_->addWidget(scrubLabel_);
  layout->addLayout(watchRow_);
  connect(scrubber_, &QSlider::valueChanged, this, &RehearsalResults::showScrub);

  auto* chart = new QChart;
  chart->setAnimationOptions(QChart::NoAnimation);
  chart->setMargins({2, 2, 2, 2});
  marginSeries_ = new QLineSeries;
  marginSeries_->setName(tr("stability margin [cm]"));
  rollSeries_ = new QLineSeries;
  rollSeries_->setName(tr("roll [deg]"));
  pitchSeries_ = new QLineSeries;
  pitchSeries_->setName(tr("pitch [deg]"));
  cursor_ = new QLineSeries;
  cursor_->setName(tr("watched"));
  for (QLineSeries* s : {marginSeries_, rollSeries_, pitchSeries_, cursor_}) chart->addSeries(s);
  chart->createDefaultAxes();
  chart_ = new QChartView(chart, this);
  chart_->setMinimumHeight(60);
  tabs_->addTab(chart_, tr("Margins"));
}

void RehearsalResults::addToWatchRow(QWidget* widget) { watchRow_->addWidget(widget); }

void RehearsalResults::showResult(const RehearsalResult* result) {
  result_ = result;
  verdicts_->clear();
  marginSeries_->clear();
  rollSeries_->clear();
  pitchSeries_->clear();
  cursor_->clear();
  if (!result_) {
    scrubber_->setRange(0, 0);
    return;
  }
  if (!result_->error.empty()) new QTreeWidgetItem(verdicts_, {tr("rehearsal"), QString::fromStdString(result_->error)});
  std::vector<const RuleVerdict*> ordered;
  for (const RuleVerdict& v : result_->verdicts) ordered.push_back(&v);
  std::stable_partition(ordered.begin(), ordered.end(), [](const RuleVerdict* v) { return !v->passed; });
  for (const RuleVerdict* p : ordered) {
    const RuleVerdict& v = *p;
    // The message without its leading "rule: ", which the first column shows.
    QString text = QString::fromStdString(v.message());
    const QString prefix = QString::fromUtf8(toString(v.rule)) + QStringLiteral(": ");
    if (text.startsWith(prefix)) text.remove(0, prefix.size());
    auto* item = new QTreeWidgetItem(verdicts_, {QString::fromUtf8(toString(v.rule)), text});
    item->setForeground(0, v.passed ? QColor(0, 120, 0) : QColor(190, 0, 0));
    item->setToolTip(1, item->text(1));
    item->setData(0, Qt::UserRole, v.passed ? v.worstTime : v.time);
  }
  verdicts_->resizeColumnToContents(0);
  // Each row as tall as its explanation wraps to in the verdict column
  // (the view does not measure wrapped rows against the column's width).
  const int textWidth = std::max(80, verdicts_->viewport()->width() - verdicts_->columnWidth(0) - 10);
  for (int i = 0; i < verdicts_->topLevelItemCount(); ++i) {
    QTreeWidgetItem* item = verdicts_->topLevelItem(i);
    const int h = verdicts_->fontMetrics().boundingRect(QRect(0, 0, textWidth, 10000), Qt::TextWordWrap, item->text(1)).height();
    item->setSizeHint(1, QSize(textWidth, h + 4));
  }
  double top = 0, bottom = 0;
  for (const RehearsalSample& s : result_->path) {
    const double margin = std::isfinite(s.margin) ? std::clamp(s.margin * 100, -100.0, 100.0) : -100.0;
    marginSeries_->append(s.time, margin);
    rollSeries_->append(s.time, radToDeg(s.roll));
    pitchSeries_->append(s.time, radToDeg(s.pitch));
    top = std::max({top, margin, radToDeg(s.roll), radToDeg(s.pitch)});
    bottom = std::min({bottom, margin, radToDeg(s.roll), radToDeg(s.pitch)});
  }
  const auto axes = chart_->chart()->axes();
  if (axes.size() >= 2) {
    axes[0]->setRange(0, std::max(1.0, result_->duration));
    axes[1]->setRange(bottom - 1, top + 1);
  }
  scrubber_->setRange(0, std::max(0, static_cast<int>(result_->path.size()) - 1));
  showScrub(scrubber_->value());
}

void RehearsalResults::scrubTo(double time) {
  if (!result_ || result_->path.empty()) return;
  scrubber_->setValue(static_cast<int>(std::lround(time / RehearsalResult::kSampleInterval)));
}

double RehearsalResults::scrubTime() const {
  if (!result_ || result_->path.empty()) return 0;
  return result_->path[std::min<size_t>(static_cast<size_t>(scrubber_->value()), result_->path.size() - 1)].time;
}

void RehearsalResults::showScrub(int index) {
  if (!result_ || result_->path.empty()) {
    scrubLabel_->clear();
    return;
  }
  const RehearsalSample& s = result_->path[std::min<size_t>(static_cast<size_t>(std::max(0, index)), result_->path.size() - 1)];
  scrubLabel_->setText(seconds(s.time));
  cursor_->clear();
  const auto axes = chart_->chart()->axes();
  if (axes.size() >= 2) {
    const auto* y = static_cast<QValueAxis*>(axes[1]);
    cursor_->append(s.time, y->min());
    cursor_->append(s.time, y->max());
  }
  emit scrubbed(s.base, s.jointPositions);
}

}  // namespace sp
