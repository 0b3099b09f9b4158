#include "ui/jobs/replay/replay_panel.h"

#include "ui/background_jobs.h"
#include "ui/icons.h"

#include <QBoxLayout>
#include <QComboBox>
#include <QFile>
#include <QFileDialog>
#include <QMessageBox>
#include <QTextStream>
#include <QtCharts/QChart>
#include <QtCharts/QChartView>
#include <QtCharts/QLineSeries>
#include <QtCharts/QValueAxis>
#include <QFileInfo>
#include <QLabel>
#include <QListWidget>
#include <QMouseEvent>
#include <QPainter>
#include <QProgressBar>
#include <QProxyStyle>
#include <QPushButton>
#include <QSignalBlocker>
#include <QSlider>
#include <QTimer>

#include <algorithm>
#include <cmath>

namespace sp {

// Ticks at the events' times, aligned with the slider above; a click seeks
// to the nearest event.
class ReplayPanel::Marks : public QWidget {
 public:
  explicit Marks(ReplayPanel* panel) : QWidget(panel), panel_(panel) {
    setFixedHeight(10);
    setToolTip(tr("Events of the log; click one to go there"));
  }

 protected:
  void paintEvent(QPaintEvent*) override {
    const LogPlayer* p = panel_->player();
    if (!p || p->endTime() <= p->startTime()) return;
    QPainter painter(this);
    for (const LogEvent& e : p->events()) {
      const int x = xOf(e.time);
      painter.setPen(e.kind == "note" ? QColor(0, 110, 200) : e.kind == "estop" || e.kind == "failsafe" || e.kind == "guard"
                                                              ? QColor(200, 0, 0)
                                                              : QColor(110, 110, 110));
      painter.drawLine(x, 0, x, height());
    }
  }
  void mousePressEvent(QMouseEvent* event) override {
    const LogPlayer* p = panel_->player();
    if (!p) return;
    int best = -1, bestDistance = 8;  // pixels
    for (int i = 0; i < static_cast<int>(p->events().size()); ++i) {
      const int d = std::abs(xOf(p->events()[static_cast<size_t>(i)].time) - static_cast<int>(event->position().x()));
      if (d < bestDistance) {
        best = i;
        bestDistance = d;
      }
    }
    if (best >= 0) panel_->seekToEvent(best);
  }

 private:
  int xOf(double t) const {
    const LogPlayer* p = panel_->player();
    const double f = (t - p->startTime()) / (p->endTime() - p->startTime());
    return static_cast<int>(std::lround(std::clamp(f, 0.0, 1.0) * (width() - 1)));
  }
  ReplayPanel* panel_;
};

// A click on the timeline's groove seeks there, as a click on a media
// player's timeline does (QSlider pages a step towards it by default).
class JumpToClick : public QProxyStyle {
 public:
  int styleHint(StyleHint hint, const QStyleOption* option, const QWidget* widget,
                QStyleHintReturn* returned) const override {
    if (hint == QStyle::SH_Slider_AbsoluteSetButtons) return Qt::LeftButton;
    return QProxyStyle::styleHint(hint, option, widget, returned);
  }
};

ReplayPanel::ReplayPanel(QWidget* parent) : QWidget(parent), feed_(new ReplayFeed(this)) {
  setBackground(new BackgroundJobs(this));  // until given the console's
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(4, 4, 4, 4);
  title_ = new QLabel(tr("No log open: File ▸ Open session log…"), this);
  layout->addWidget(title_);
  buildControls(layout);
  buildPlot(layout);
  timer_ = new QTimer(this);
  timer_->setInterval(16);
  connect(timer_, &QTimer::timeout, this, &ReplayPanel::tick);
  connect(slider_, &QSlider::valueChanged, this, [this](int ms) { show(ms / 1000.0); });
  connect(events_, &QListWidget::itemClicked, this, [this](QListWidgetItem* item) { seekToEvent(events_->row(item)); });
  // The timeline, the time and the plot's cursor follow the feed's cursor,
  // whoever moved it.
  connect(feed_, &ReplayFeed::moved, this, &ReplayPanel::showCursor);
  setEnabled(false);  // until a log is open (or opening: Cancel)
}

void ReplayPanel::buildControls(QVBoxLayout* layout) {
  auto* row = new QHBoxLayout;
  auto* back = new QPushButton(actionIcon(QStringLiteral("step-back")), QString(), this);
  back->setToolTip(tr("Step back %1 s").arg(kStep));
  playButton_ = new QPushButton(actionIcon(QStringLiteral("play")), QString(), this);
  playButton_->setToolTip(tr("Play"));
  auto* forward = new QPushButton(actionIcon(QStringLiteral("step-forward")), QString(), this);
  forward->setToolTip(tr("Step forward %1 s").arg(kStep));
  for (QPushButton* b : {back, playButton_, forward}) b->setFocusPolicy(Qt::NoFocus);
  speedBox_ = new QComboBox(this);
  for (double s : {0.1, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0}) speedBox_->addItem(QStringLiteral("%1×").arg(s), s);
  speedBox_->setCurrentIndex(3);
  slider_ = new QSlider(Qt::Horizontal, this);
  auto* jump = new JumpToClick;
  jump->setParent(slider_);
  slider_->setStyle(jump);
  timeLabel_ = new QLabel(this);
  timeLabel_->setMinimumWidth(130);
  row->addWidget(back);
  row->addWidget(playButton_);
  row->addWidget(forward);
  row->addWidget(speedBox_);
  row->addWidget(timeLabel_, 1);
  auto* branch = new QPushButton(tr("Simulate from here"), this);
  branch->setToolTip(tr("A new stand-in session starting from the logged state at the cursor (a new log naming this one)"));
  branch->setFocusPolicy(Qt::NoFocus);
  row->addWidget(branch);
  auto* rehearse = new QPushButton(tr("Rehearse from here"), this);
  rehearse->setToolTip(tr("The Sequence dock rehearses from the logged state at the cursor, in the logged world"));
  auto* verifyButton = new QPushButton(tr("Verify"), this);
  verifyButton->setToolTip(tr("Re-simulate the whole log and compare every logged state hash"));
  for (QPushButton* b : {branch, rehearse, verifyButton}) b->setFocusPolicy(Qt::NoFocus);
  row->addWidget(rehearse);
  row->addWidget(verifyButton);
  layout->addLayout(row);
  connect(rehearse, &QPushButton::clicked, this, [this] { rehearseHere(); });
  connect(verifyButton, &QPushButton::clicked, this, [this] { verify(); });
  // What runs on the worker: what, how far, Cancel. Enabled while the rest
  // of the panel is (a log opening is shown on the disabled panel too).
  progressRow_ = new QWidget(this);
  auto* progressLayout = new QHBoxLayout(progressRow_);
  progressLayout->setContentsMargins(0, 0, 0, 0);
  progressLabel_ = new QLabel(progressRow_);
  progressBar_ = new QProgressBar(progressRow_);
  progressBar_->setRange(0, 1000);
  progressBar_->setTextVisible(false);
  auto* cancelButton = new QPushButton(tr("Cancel"), progressRow_);
  progressLayout->addWidget(progressLabel_);
  progressLayout->addWidget(progressBar_, 1);
  progressLayout->addWidget(cancelButton);
  connect(cancelButton, &QPushButton::clicked, this, [this] { cancel(); });
  layout->addWidget(progressRow_);
  progressRow_->hide();
  // The timeline its own full width, the events ticked under it.
  auto* track = new QVBoxLayout;
  track->setSpacing(0);
  track->addWidget(slider_);
  marks_ = new Marks(this);
  track->addWidget(marks_);
  layout->addLayout(track);
  connect(branch, &QPushButton::clicked, this, [this] { branchHere(); });
  connect(playButton_, &QPushButton::clicked, this, [this] { playing_ ? pause() : play(); });
  connect(back, &QPushButton::clicked, this, [this] { step(-1); });
  connect(forward, &QPushButton::clicked, this, [this] { step(+1); });
  connect(speedBox_, &QComboBox::currentIndexChanged, this, [this](int i) { setSpeed(speedBox_->itemData(i).toDouble()); });
}

void ReplayPanel::buildPlot(QVBoxLayout* layout) {
  auto* plotRow = new QHBoxLayout;
  signalBox_ = new QComboBox(this);
  signalBox_->setToolTip(tr("The logged signal to plot"));
  signalBox_->setMinimumContentsLength(22);
  auto* csv = new QPushButton(tr("CSV…"), this);
  csv->setToolTip(tr("Export the visible range of the plotted signal as CSV"));
  auto* png = new QPushButton(tr("PNG…"), this);
  png->setToolTip(tr("Export the plot as a picture"));
  readout_ = new QLabel(this);
  plotRow->addWidget(signalBox_);
  plotRow->addWidget(csv);
  plotRow->addWidget(png);
  plotRow->addWidget(readout_, 1);
  layout->addLayout(plotRow);
  auto* chart = new QChart;
  chart->setAnimationOptions(QChart::NoAnimation);
  chart->legend()->hide();
  chart->setMargins({2, 2, 2, 2});
  series_ = new QLineSeries;
  cursorLine_ = new QLineSeries;
  chart->addSeries(series_);
  chart->addSeries(cursorLine_);
  chart->createDefaultAxes();
  chart_ = new QChartView(chart, this);
  chart_->setRubberBand(QChartView::HorizontalRubberBand);
  chart_->setMinimumHeight(110);
  // The events beside the plot, not under it: under it the plot got 15 px
  // of a 1280x800 window's dock.
  auto* plotAndEvents = new QHBoxLayout;
  plotAndEvents->addWidget(chart_, 3);
  events_ = new QListWidget(this);
  events_->setMinimumWidth(160);
  plotAndEvents->addWidget(events_, 1);
  layout->addLayout(plotAndEvents, 1);
  replotTimer_ = new QTimer(this);
  replotTimer_->setSingleShot(true);
  replotTimer_->setInterval(100);
  connect(replotTimer_, &QTimer::timeout, this, &ReplayPanel::replot);
  // Zooming changes the time axis: the log is read again for that range.
  connect(static_cast<QValueAxis*>(chart->axes(Qt::Horizontal).front()), &QValueAxis::rangeChanged, this,
          [this] { replotTimer_->start(); });
  connect(signalBox_, &QComboBox::currentIndexChanged, this, [this](int i) { setSignal(i); });
  connect(csv, &QPushButton::clicked, this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, tr("Export CSV"), QString(), tr("CSV (*.csv)"));
    if (const QString e = path.isEmpty() ? QString() : exportCsv(path); !e.isEmpty()) QMessageBox::warning(this, tr("Export CSV"), e);
  });
  connect(png, &QPushButton::clicked, this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, tr("Export PNG"), QString(), tr("PNG (*.png)"));
    if (const QString e = path.isEmpty() ? QString() : exportPng(path); !e.isEmpty()) QMessageBox::warning(this, tr("Export PNG"), e);
  });
}

ReplayPanel::~ReplayPanel() {
  if (job_) jobs_->cancel(job_);  // its result goes nowhere now
}

void ReplayPanel::setBackground(BackgroundJobs* jobs) {
  if (job_ || !jobs || jobs == jobs_) return;
  if (jobs_) disconnect(jobs_, nullptr, this, nullptr);
  jobs_ = jobs;
  connect(jobs_, &BackgroundJobs::progressed, this, [this](int id, double f) {
    if (id == job_) progressBar_->setValue(static_cast<int>(f * 1000));
  });
  connect(jobs_, &BackgroundJobs::finished, this, [this](int id, bool cancelled) {
    if (id != job_) return;
    finishBackground();
    if (cancelled) emit failed(tr("Cancelled."));
  });
}

QString ReplayPanel::open(const QString& path) {
  std::string error;
  std::unique_ptr<LogPlayer> player = LogPlayer::open(path.toStdString(), error);
  if (!player) return QString::fromStdString(error);
  adopt(std::move(player), path, std::nullopt);
  return {};
}

void ReplayPanel::openInBackground(const QString& path) {
  runInBackground(tr("Opening %1").arg(QFileInfo(path).fileName()),
                  [this, path](const std::function<bool(double)>& progress) -> std::function<void()> {
                    std::string error;
                    // Held by a shared pointer: std::function needs a copyable closure.
                    auto player = std::make_shared<std::unique_ptr<LogPlayer>>(LogPlayer::open(path.toStdString(), error));
                    if (!*player) return [this, e = QString::fromStdString(error)] { emit failed(e); };
                    if (!progress(0.5)) return {};
                    // The first plot: 1500 seeks, a second or more on a cold disk.
                    const LogPlayer& p = **player;
                    auto points = p.signal(kFirstSignal, p.startTime(), p.endTime(), kPlotPoints);
                    return [this, player, path, points = std::move(points)] {
                      // The player moves to the GUI thread now; the worker has let go of it.
                      adopt(std::move(*player), path, points);
                    };
                  });
}

void ReplayPanel::adopt(std::unique_ptr<LogPlayer> log, const QString& path,
                        std::optional<std::vector<std::pair<double, double>>> firstPlot) {
  pause();
  feed_->adopt(std::move(log));
  lastResult_.clear();
  setEnabled(true);
  title_->setText(tr("%1: %2 s, %3 events%4")
                      .arg(QFileInfo(path).fileName())
                      .arg(player()->endTime() - player()->startTime(), 0, 'f', 1)
                      .arg(player()->events().size())
                      .arg(player()->hasSnapshots() ? QString() : tr(" (telemetry only)")));
  events_->clear();
  for (const LogEvent& e : player()->events())
    events_->addItem(QStringLiteral("%1 s  %2: %3")
                         .arg(e.time, 0, 'f', 2)
                         .arg(QString::fromStdString(e.kind), QString::fromStdString(e.text)));
  {
    const QSignalBlocker block(slider_);
    slider_->setRange(static_cast<int>(std::floor(player()->startTime() * 1000)),
                      static_cast<int>(std::ceil(player()->endTime() * 1000)));
  }
  emit opened(player()->world());
  {
    const QSignalBlocker block(signalBox_);
    signalBox_->clear();
    for (const std::string& name : player()->signalNames()) signalBox_->addItem(QString::fromStdString(name));
    signalBox_->setCurrentIndex(kFirstSignal);
  }
  if (firstPlot) {
    {
      const QSignalBlocker block(chart_->chart()->axes(Qt::Horizontal).front());  // no re-read: the points are here
      setVisibleRange(player()->startTime(), player()->endTime());
    }
    plot(*firstPlot);
  } else {
    setSignal(signalBox_->currentIndex());
  }
  show(cursor());
  marks_->update();
}

bool ReplayPanel::runInBackground(
    const QString& what, std::function<std::function<void()>(const std::function<bool(double)>& progress)> work) {
  if (job_) {
    emit failed(tr("%1: wait for \"%2\" to end, or cancel it").arg(what, progressLabel_->text()));
    return false;
  }
  progressLabel_->setText(what + QStringLiteral("…"));
  progressBar_->setValue(0);
  progressRow_->show();
  setEnabled(true);  // for Cancel; every control checks for a player
  job_ = jobs_->run(this, what, std::move(work));
  return true;
}

void ReplayPanel::finishBackground() {
  job_ = 0;
  progressRow_->hide();
  progressLabel_->clear();
  setEnabled(player() != nullptr);
}

void ReplayPanel::cancel() {
  if (job_) jobs_->cancel(job_);
}

QString ReplayPanel::progressText() const { return job_ ? progressLabel_->text() : QString(); }

void ReplayPanel::branchHere() {
  if (!player()) return;
  pause();
  const QString path = QString::fromStdString(player()->path());
  const double at = cursor();
  if (!player()->hasSnapshots()) {
    // Reconstructed from one sample: no re-simulation, nothing to wait for.
    std::string error;
    std::optional<BranchPoint> b = player()->branchAt(at, error);
    if (!b) emit failed(QString::fromStdString(error));
    else emit branchReady(path, std::make_shared<const BranchPoint>(std::move(*b)));
    return;
  }
  runInBackground(tr("Re-simulating to t = %1 s").arg(at, 0, 'f', 3),
                  [this, path, at](const std::function<bool(double)>& progress) -> std::function<void()> {
                    std::string error;
                    std::optional<BranchPoint> b = sp::branchAt(path.toStdString(), at, error, progress);
                    if (!b) return [this, e = QString::fromStdString(error)] { emit failed(e); };
                    auto point = std::make_shared<const BranchPoint>(std::move(*b));
                    return [this, path, point] { emit branchReady(path, point); };
                  });
}

bool ReplayPanel::rehearseHere() {
  if (!player()) return false;
  pause();
  const std::optional<RehearsalStart> start = player()->startAt(cursor());
  if (!start) {
    emit failed(tr("No sample at t = %1 s to rehearse from").arg(cursor(), 0, 'f', 3));
    return false;
  }
  emit rehearsalStart(*start, player()->world(), player()->params(),
                      tr("%1 at t = %2 s").arg(QFileInfo(QString::fromStdString(player()->path())).fileName())
                          .arg(cursor(), 0, 'f', 2));
  return true;
}

void ReplayPanel::verify() {
  if (!player()) return;
  if (!player()->hasSnapshots()) {
    lastResult_ = tr("A telemetry-only log holds no snapshots or hashes: there is nothing to re-simulate.");
    readout_->setText(lastResult_);
    emit verified(false, lastResult_);
    return;
  }
  const QString path = QString::fromStdString(player()->path());
  runInBackground(tr("Verifying %1 (re-simulating it)").arg(QFileInfo(path).fileName()),
                  [this, path](const std::function<bool(double)>& progress) -> std::function<void()> {
                    std::string error;
                    const std::optional<ResimReport> r = resimulate(path.toStdString(), {.from = 0, .progress = progress}, error);
                    QString verdict;
                    bool passed = false;
                    if (!r) {
                      verdict = QString::fromStdString(error);
                    } else if (r->divergence) {
                      verdict = tr("Diverges at t = %1 s (step %2): logged hash %3, re-simulated %4")
                                    .arg(r->divergence->time, 0, 'f', 3)
                                    .arg(r->divergence->step)
                                    .arg(QString::fromStdString(hashHex(r->divergence->expected)),
                                         QString::fromStdString(hashHex(r->divergence->actual)));
                    } else {
                      passed = r->hashesCompared > 0;
                      verdict = tr("Reproduced: %1 logged hashes match, %2 commands re-applied")
                                    .arg(r->hashesCompared)
                                    .arg(r->commandsApplied);
                    }
                    return [this, passed, verdict] {
                      lastResult_ = verdict;
                      title_->setToolTip(verdict);
                      readout_->setText(verdict);
                      emit verified(passed, verdict);
                    };
                  });
}

void ReplayPanel::close() {
  pause();
  feed_->adopt(nullptr);
  events_->clear();
  series_->clear();
  cursorLine_->clear();
  readout_->clear();
  {
    const QSignalBlocker block(signalBox_);
    signalBox_->clear();
  }
  title_->setText(tr("No log open: File ▸ Open session log…"));
  setEnabled(false);
  emit closed();
}

void ReplayPanel::seek(double time) { show(time); }

void ReplayPanel::play() {
  if (!player()) return;
  if (cursor() >= player()->endTime()) show(player()->startTime());  // from the start again
  playing_ = true;
  playButton_->setIcon(actionIcon(QStringLiteral("pause")));
  playButton_->setToolTip(tr("Pause"));
  wall_.start();
  timer_->start();
}

void ReplayPanel::pause() {
  playing_ = false;
  timer_->stop();
  playButton_->setIcon(actionIcon(QStringLiteral("play")));
  playButton_->setToolTip(tr("Play"));
}

void ReplayPanel::setSpeed(double factor) {
  speed_ = std::clamp(factor, 0.1, 10.0);
  const int i = speedBox_->findData(speed_);
  if (i >= 0 && i != speedBox_->currentIndex()) {
    const QSignalBlocker block(speedBox_);
    speedBox_->setCurrentIndex(i);
  }
}

void ReplayPanel::step(int direction) {
  pause();
  show(cursor() + direction * kStep);
}

void ReplayPanel::seekToEvent(int index) {
  if (!player() || index < 0 || index >= static_cast<int>(player()->events().size())) return;
  pause();
  show(player()->events()[static_cast<size_t>(index)].time);
}

void ReplayPanel::setSignal(int index) {
  if (!player() || index < 0 || index >= signalBox_->count()) return;
  if (signalBox_->currentIndex() != index) {
    const QSignalBlocker block(signalBox_);
    signalBox_->setCurrentIndex(index);
  }
  setVisibleRange(player()->startTime(), player()->endTime());
  replot();
}

int ReplayPanel::signalIndex() const { return signalBox_->currentIndex(); }

void ReplayPanel::setVisibleRange(double t0, double t1) {
  auto* x = static_cast<QValueAxis*>(chart_->chart()->axes(Qt::Horizontal).front());
  x->setRange(t0, std::max(t1, t0 + 1e-3));
}

void ReplayPanel::replot() {
  replotTimer_->stop();
  if (!player()) return;
  auto* x = static_cast<QValueAxis*>(chart_->chart()->axes(Qt::Horizontal).front());
  plot(player()->signal(signalBox_->currentIndex(), x->min(), x->max(), kPlotPoints));
}

void ReplayPanel::plot(const std::vector<std::pair<double, double>>& points) {
  auto* y = static_cast<QValueAxis*>(chart_->chart()->axes(Qt::Vertical).front());
  QList<QPointF> list;
  double lo = 0, hi = 0;
  for (const auto& [t, v] : points) {
    if (list.isEmpty()) lo = hi = v;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    list.append({t, v});
  }
  series_->replace(list);
  const double pad = std::max(1e-6, 0.05 * (hi - lo));
  y->setRange(lo - pad, hi + pad);
  y->setTitleText(signalBox_->currentText());
  moveCursorLine();
}

void ReplayPanel::moveCursorLine() {
  auto* y = static_cast<QValueAxis*>(chart_->chart()->axes(Qt::Vertical).front());
  cursorLine_->replace(QList<QPointF>{{cursor(), y->min()}, {cursor(), y->max()}});
  readout_->setText(readout());
}

QList<QPointF> ReplayPanel::plotted() const { return series_->points(); }

QString ReplayPanel::readout() const {
  const QList<QPointF> p = series_->points();
  if (p.isEmpty()) return {};
  // The plotted point at or before the cursor.
  auto it = std::upper_bound(p.begin(), p.end(), cursor(), [](double t, const QPointF& q) { return t < q.x(); });
  const QPointF at = it == p.begin() ? p.front() : *(it - 1);
  return tr("t = %1 s: %2 = %3").arg(cursor(), 0, 'f', 3).arg(signalBox_->currentText()).arg(at.y(), 0, 'g', 6);
}

QString ReplayPanel::exportCsv(const QString& path) const {
  QFile f(path);
  if (!f.open(QIODevice::WriteOnly | QIODevice::Truncate | QIODevice::Text)) return path + ": " + f.errorString();
  QTextStream out(&f);
  out << "time [s]," << signalBox_->currentText() << "\n";
  auto* x = static_cast<QValueAxis*>(chart_->chart()->axes(Qt::Horizontal).front());
  for (const QPointF& p : series_->points())
    if (p.x() >= x->min() && p.x() <= x->max()) out << QString::number(p.x(), 'g', 17) << ',' << QString::number(p.y(), 'g', 17) << "\n";
  out.flush();
  if (out.status() != QTextStream::Ok || !f.flush()) return path + ": " + f.errorString();
  return {};
}

QString ReplayPanel::exportPng(const QString& path) const {
  const QPixmap picture = chart_->grab();
  return picture.save(path, "PNG") ? QString() : path + tr(": cannot write the picture");
}

void ReplayPanel::tick() {
  // Wall time since the last tick, not the timer's nominal period: the pace
  // holds when ticks come late.
  const double dt = static_cast<double>(wall_.nsecsElapsed()) * 1e-9;
  wall_.start();
  show(cursor() + dt * speed_);
  if (cursor() >= player()->endTime()) pause();
}

void ReplayPanel::show(double time) { feed_->seek(time); }

void ReplayPanel::showCursor(double at) {
  {
    const QSignalBlocker block(slider_);
    slider_->setValue(static_cast<int>(std::lround(at * 1000)));
  }
  timeLabel_->setText(tr("%1 / %2 s").arg(at, 0, 'f', 2).arg(player()->endTime(), 0, 'f', 1));
  moveCursorLine();
}

}  // namespace sp
