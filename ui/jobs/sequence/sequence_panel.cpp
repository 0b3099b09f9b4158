#include "ui/jobs/sequence/sequence_panel.h"

#include <QBoxLayout>
#include <QCoreApplication>
#include <QDateTime>
#include <QFile>
#include <QFileDialog>
#include <QFontDatabase>
#include <QLabel>
#include <QListWidget>
#include <QMenu>
#include <QMessageBox>
#include <QPlainTextEdit>
#include <QProgressBar>
#include <QStandardPaths>
#include <QPushButton>
#include <QResizeEvent>
#include <QSlider>
#include <QTabWidget>
#include <QTextBlock>
#include <QTimer>
#include <QToolButton>
#include <QTreeWidget>
#include <QtCharts/QChart>
#include <QtCharts/QChartView>
#include <QtCharts/QLineSeries>
#include <QtCharts/QValueAxis>

#include <cmath>

#include "app/sweep/sweep.h"
#include "sim/command_file.h"
#include "sim/terrain_brush.h"

namespace sp {
namespace {

// One line per command of docs/formats.md, with what its numbers mean.
struct Template {
  const char* label;
  const char* text;  // after the time
};
constexpr Template kTemplates[] = {
    {"drive: roll with the hinge at an angle", "drive 0.5 0        # speed [m/s], articulation [deg]"},
    {"turn: roll at a yaw rate", "turn 0.5 10        # speed [m/s], yaw rate [deg/s], > 0 left"},
    {"wheels: four wheel speeds", "wheels 2 2 2 2     # FL FR RL RR [rad/s]"},
    {"target: a joint to an angle", "target waist_yaw 0 # joint, angle [deg] (slider: [m])"},
    {"velocity: a joint at a speed", "velocity waist_yaw 10  # joint, [deg/s] (slider: [m/s])"},
    {"torque: a joint's torque", "torque waist_yaw 0 # joint, [N m] (slider: [N])"},
    {"mode: switch a joint's mode", "mode waist_yaw position  # velocity, position, torque, free"},
    {"gait: caterpillar, rolking or off", "gait caterpillar"},
    {"stop: brake and hold", "stop"},
};

QString seconds(double t) { return QString::number(t, 'f', 2) + " s"; }

// A word-wrapped label that does not ask for height for its width: one
// that does makes the dock's scroll area size the whole panel by its
// preferred heights (593 px where 317 are enough). Its minimum is the
// height its text takes at its present width: squeezed to one line, a
// two-line reason was cut in half (issue 59).
class WrappedLabel : public QLabel {
 public:
  explicit WrappedLabel(QWidget* parent) : QLabel(parent) {
    setWordWrap(true);
    setMinimumHeight(fontMetrics().lineSpacing());
  }
  bool hasHeightForWidth() const override { return false; }
  // The height its text takes at its present width (not a guessed one).
  QSize sizeHint() const override {
    const QSize hint = QLabel::sizeHint();
    return {hint.width(), QLabel::heightForWidth(width() > 50 ? width() : hint.width())};
  }
  QSize minimumSizeHint() const override {
    const QSize least = QLabel::minimumSizeHint();
    if (width() <= 50 || text().isEmpty()) return {least.width(), fontMetrics().lineSpacing()};
    return {least.width(), std::max(fontMetrics().lineSpacing(), QLabel::heightForWidth(width()))};
  }

 protected:
  void resizeEvent(QResizeEvent* event) override {
    QLabel::resizeEvent(event);
    if (event->size().width() != event->oldSize().width()) updateGeometry();
  }
};

}  // namespace

SequencePanel::SequencePanel(QWidget* parent) : QWidget(parent) {
  setBackground(new BackgroundJobs(this));  // until given the console's
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(4, 4, 4, 4);
  layout->setSpacing(3);  // at 1280x800 every row must fit the tab's ~340 px

  auto* fileRow = new QHBoxLayout;
  auto* open = new QPushButton(tr("Open…"), this);
  auto* save = new QPushButton(tr("Save…"), this);
  auto* insert = new QToolButton(this);
  insert->setText(tr("Insert"));
  insert->setToolTip(tr("Insert a command at the cursor, with what its numbers mean"));
  buildTemplateMenu(insert);
  fileRow->addWidget(open);
  fileRow->addWidget(save);
  fileRow->addWidget(insert);
  fileRow->addStretch();
  layout->addLayout(fileRow);
  connect(open, &QPushButton::clicked, this, &SequencePanel::openFile);
  connect(save, &QPushButton::clicked, this, &SequencePanel::saveFile);

  editor_ = new QPlainTextEdit(this);
  editor_->setFont(QFontDatabase::systemFont(QFontDatabase::FixedFont));
  editor_->setPlaceholderText(tr("# time [s]  command  arguments\n1.0  drive 0.5 0\n5.0  stop"));
  editor_->setLineWrapMode(QPlainTextEdit::NoWrap);
  editor_->setMinimumHeight(48);
  layout->addWidget(editor_, 2);
  errorList_ = new QListWidget(this);
  errorList_->setMaximumHeight(70);
  errorList_->hide();
  layout->addWidget(errorList_);
  // Checked 150 ms after the last key, not on every key.
  checkTimer_ = new QTimer(this);
  checkTimer_->setSingleShot(true);
  checkTimer_->setInterval(150);
  connect(checkTimer_, &QTimer::timeout, this, &SequencePanel::checkNow);
  connect(editor_, &QPlainTextEdit::textChanged, this, [this] {
    checkTimer_->start();
    updateButtons();
  });
  connect(errorList_, &QListWidget::itemActivated, this, [this](QListWidgetItem* item) {
    const int line = item->data(Qt::UserRole).toInt();
    const QTextBlock block = editor_->document()->findBlockByNumber(line - 1);
    if (!block.isValid()) return;
    QTextCursor c(block);
    editor_->setTextCursor(c);
    editor_->setFocus();
  });

  auto* startRow = new QHBoxLayout;
  startLabel_ = new WrappedLabel(this);
  startLabel_->setWordWrap(true);
  unpinButton_ = new QPushButton(tr("From the robot"), this);
  unpinButton_->setToolTip(tr("Rehearse from the robot's state now again"));
  startRow->addWidget(startLabel_, 1);
  startRow->addWidget(unpinButton_);
  layout->addLayout(startRow);
  connect(unpinButton_, &QPushButton::clicked, this, &SequencePanel::unpinStart);

  auto* runRow = new QHBoxLayout;
  rehearseButton_ = new QPushButton(tr("Rehearse"), this);
  rehearseButton_->setToolTip(tr("Run the sequence on the console's twin from the robot's state now"));
  robustButton_ = new QPushButton(tr("Robustness"), this);
  robustButton_->setToolTip(tr("Rehearse it again with friction, masses, terrain and start perturbed"));
  clusterButton_ = new QPushButton(tr("On cluster…"), this);
  clusterButton_->setToolTip(tr("The same robustness rehearsals as a sweep folder, submitted to a Slurm cluster "
                                "that shares it (docs/sweeps.md)"));
  cancelButton_ = new QPushButton(tr("Cancel"), this);
  progress_ = new QProgressBar(this);
  progress_->setRange(0, 1000);
  progress_->setTextVisible(false);
  // Two rows: in one the dock's width (370 px at 1280x800) scrolled
  // sideways and cut the buttons' names.
  runRow->addWidget(rehearseButton_);
  runRow->addWidget(robustButton_);
  runRow->addWidget(clusterButton_);
  runRow->addStretch();
  layout->addLayout(runRow);
  // The progress and Cancel only while something runs.
  progressRow_ = new QWidget(this);
  auto* progressRow = new QHBoxLayout(progressRow_);
  progressRow->setContentsMargins(0, 0, 0, 0);
  progressRow->addWidget(progress_, 1);
  progressRow->addWidget(cancelButton_);
  layout->addWidget(progressRow_);
  // Why a button is disabled, beside it (not a status line out of view).
  whyLabel_ = new WrappedLabel(this);
  whyLabel_->setObjectName(QStringLiteral("sequenceWhy"));
  whyLabel_->setStyleSheet(QStringLiteral("color: #8a6d00"));
  layout->addWidget(whyLabel_);
  connect(rehearseButton_, &QPushButton::clicked, this, &SequencePanel::rehearse);
  connect(robustButton_, &QPushButton::clicked, this, &SequencePanel::checkRobustness);
  connect(clusterButton_, &QPushButton::clicked, this, [this] {
    const QString folder = QFileDialog::getExistingDirectory(this, tr("Folder for the sweep (shared with the cluster)"));
    if (!folder.isEmpty())
      robustnessOnCluster(folder + "/robustness-" + QDateTime::currentDateTime().toString("yyyyMMdd-hhmmss"));
  });
  // Cancel stops the task; what it did so far is shown (a rehearsal's
  // samples up to there), so the panel keeps its own flag rather than the
  // runner's, which would drop the result.
  connect(cancelButton_, &QPushButton::clicked, this, [this] { *cancel_ = true; });

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
  results_ = new QTabWidget(this);
  results_->addTab(verdicts_, tr("Verdicts"));
  layout->addWidget(results_, 1);
  connect(verdicts_, &QTreeWidget::itemClicked, this, [this](QTreeWidgetItem* item) {
    const QVariant t = item->data(0, Qt::UserRole);
    if (t.isValid()) scrubTo(t.toDouble());
  });

  auto* scrubRow = new QHBoxLayout;
  scrubber_ = new QSlider(Qt::Horizontal, this);
  scrubber_->setRange(0, 0);
  scrubLabel_ = new QLabel(this);
  scrubLabel_->setMinimumWidth(60);
  scrubRow->addWidget(new QLabel(tr("Watch"), this));
  scrubRow->addWidget(scrubber_, 1);
  scrubRow->addWidget(scrubLabel_);
  layout->addLayout(scrubRow);
  // Send and Abort on the Watch row: on a row of their own they fell below
  // the fold of a 1280x800 window (issue 59).
  connect(scrubber_, &QSlider::valueChanged, this, &SequencePanel::showScrub);

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
  results_->addTab(chart_, tr("Margins"));

  sendButton_ = new QPushButton(tr("Send to robot"), this);
  sendButton_->setToolTip(tr("Only a sequence that passed its rehearsal, unchanged since"));
  abortButton_ = new QPushButton(tr("Abort"), this);
  abortButton_->setToolTip(tr("Stop the sequence on the robot (the robot stops)"));
  scrubRow->addWidget(sendButton_);
  scrubRow->addWidget(abortButton_);
  connect(sendButton_, &QPushButton::clicked, this, &SequencePanel::send);
  connect(abortButton_, &QPushButton::clicked, this, [this] { abort(tr("the operator pressed Abort")); });

  status_ = new WrappedLabel(this);
  status_->hide();
  layout->addWidget(status_);
  updateButtons();
}

SequencePanel::~SequencePanel() {
  *cancel_ = true;  // a task still running stops; its result goes nowhere
}

void SequencePanel::setBackground(BackgroundJobs* jobs) {
  if (busy_ || !jobs || jobs == jobs_) return;
  if (jobs_) disconnect(jobs_, nullptr, this, nullptr);
  jobs_ = jobs;
  connect(jobs_, &BackgroundJobs::progressed, this, [this](int id, double f) {
    if (id == job_) progress_->setValue(static_cast<int>(f * 1000));
  });
}

void SequencePanel::buildTemplateMenu(QToolButton* button) {
  auto* menu = new QMenu(button);
  for (const Template& t : kTemplates) {
    menu->addAction(QString::fromUtf8(t.label), this, [this, text = QString::fromUtf8(t.text)] {
      // At the line after the cursor's, a second after the last time above it.
      double last = -1;
      const int here = editor_->textCursor().blockNumber();
      for (QTextBlock b = editor_->document()->begin(); b.isValid() && b.blockNumber() <= here; b = b.next()) {
        bool ok = false;
        const double t0 = b.text().section(' ', 0, 0, QString::SectionSkipEmpty).toDouble(&ok);
        if (ok) last = t0;
      }
      QTextCursor c = editor_->textCursor();
      c.movePosition(QTextCursor::EndOfBlock);
      const QString line = QString::number(last < 0 ? 0.0 : last + 1.0, 'f', 1) + "  " + text;
      c.insertText(editor_->document()->isEmpty() ? line : "\n" + line);
      editor_->setTextCursor(c);
    });
  }
  button->setMenu(menu);
  button->setPopupMode(QToolButton::InstantPopup);
}

void SequencePanel::setWorld(std::function<const WorldModel*()> world, std::function<SimParams()> params) {
  world_ = std::move(world);
  params_ = std::move(params);
  plan_.reset();
  result_.reset();
  robust_.reset();
  showVerdicts();
  emit pathChanged({}, {});
  checkNow();
}

void SequencePanel::setRules(const FlightRules& rules) {
  rules_ = rules;
  updateButtons();
}

void SequencePanel::setStartProvider(std::function<std::optional<RehearsalStart>()> provider) {
  startProvider_ = std::move(provider);
}

void SequencePanel::pinStart(const RehearsalStart& start, const WorldModel& world, const SimParams& params,
                             const QString& label) {
  pinned_ = Pinned{start, world, params, label};
  updateButtons();
}

void SequencePanel::unpinStart() {
  pinned_.reset();
  updateButtons();
}

void SequencePanel::setLinkReady(bool ready) {
  linkReady_ = ready;
  updateButtons();
}

void SequencePanel::setText(const QString& text) {
  editor_->setPlainText(text);
  checkNow();
}

QString SequencePanel::text() const { return editor_->toPlainText(); }

QList<int> SequencePanel::markedLines() const { return marked_; }

void SequencePanel::checkNow() {
  checkTimer_->stop();
  errors_.clear();
  marked_.clear();
  errorList_->clear();
  QList<QTextEdit::ExtraSelection> marks;
  if (const WorldModel* world = world_ ? world_() : nullptr; world && !world->robots.empty()) {
    const RobotModel& robot = world->robots[0].model;
    const std::string text = editor_->toPlainText().toStdString();
    Diagnostics diag;
    const auto commands = parseCommandSequence(text, "sequence", diag, &robot);
    if (commands) checkCommands(*commands, *world, "sequence", diag);  // terrain edits against its grid
    for (const Diagnostic& d : diag.items()) {
      if (d.severity != Severity::Error) continue;
      const QString message = QString::fromStdString(d.message);
      errors_ << QStringLiteral("line %1: %2").arg(d.line).arg(message);
      auto* item = new QListWidgetItem(errors_.back(), errorList_);
      item->setData(Qt::UserRole, d.line);
      item->setForeground(QColor(170, 0, 0));
      if (d.line <= 0 || marked_.contains(d.line)) continue;
      marked_ << d.line;
      QTextEdit::ExtraSelection mark;
      mark.cursor = QTextCursor(editor_->document()->findBlockByNumber(d.line - 1));
      mark.format.setBackground(QColor(255, 225, 225));
      mark.format.setUnderlineStyle(QTextCharFormat::WaveUnderline);
      mark.format.setUnderlineColor(Qt::red);
      mark.format.setProperty(QTextFormat::FullWidthSelection, true);
      mark.format.setToolTip(message);
      marks << mark;
    }
  }
  editor_->setExtraSelections(marks);
  errorList_->setVisible(!errors_.isEmpty());
  // As tall as its lines, three at most: 70 px for one error squeezed the
  // editor to two lines (issue 59).
  if (errorList_->count() > 0)
    errorList_->setFixedHeight(std::min(3, errorList_->count()) * errorList_->sizeHintForRow(0) +
                               2 * errorList_->frameWidth());
  updateButtons();
}

bool SequencePanel::rehearsalCurrent() const {
  return result_ && rehearsedText_ == editor_->toPlainText() && !terrainEditedSince_;
}

void SequencePanel::terrainEdited() {
  if (result_ && !terrainEditedSince_) {
    terrainEditedSince_ = true;
    setStatus(tr("The terrain was edited since the rehearsal: rehearse again before sending."));
    updateButtons();
  }
}

std::shared_ptr<std::atomic<bool>> SequencePanel::freshCancel() {
  cancel_ = std::make_shared<std::atomic<bool>>(false);
  return cancel_;
}

void SequencePanel::runTask(const QString& what, BackgroundJobs::Work work) {
  busy_ = true;
  progress_->setValue(0);
  updateButtons();
  job_ = jobs_->run(this, what, std::move(work));
}

bool SequencePanel::rehearse() {
  checkNow();
  if (busy_) return false;
  const WorldModel* world = pinned_ ? &pinned_->world : world_ ? world_() : nullptr;
  if (!world || world->robots.empty()) {
    setStatus(tr("No world with a robot to rehearse on."));
    return false;
  }
  if (!errors_.isEmpty()) {
    setStatus(tr("Fix the sequence first: %1").arg(errors_.front()));
    return false;
  }
  Diagnostics diag;
  const RobotModel& robot = world->robots[0].model;
  auto commands = parseCommandSequence(editor_->toPlainText().toStdString(), "sequence", diag, &robot);
  if (!commands || commands->empty()) {
    setStatus(tr("The sequence has no command."));
    return false;
  }
  RehearsalPlan plan{*world, pinned_ ? pinned_->params : params_ ? params_() : SimParams{}, rules_, std::move(*commands),
                     pinned_                ? std::optional(pinned_->start)
                     : startProvider_ ? startProvider_()
                                      : std::nullopt};
  const QString text = editor_->toPlainText();
  const bool pinned = pinned_.has_value();
  setStatus(pinned       ? tr("Rehearsing from %1…").arg(pinned_->label)
            : plan.start ? tr("Rehearsing from the robot's state now…")
                         : tr("Rehearsing from the world's start…"));
  runTask(tr("Rehearsing"), [this, plan = std::move(plan), text, pinned, cancel = freshCancel()](
                                const BackgroundJobs::Progress& progress) mutable -> std::function<void()> {
    // First the fast profile, stopped at its first failure: its verdicts
    // show within a fraction of the time while the full-fidelity rehearsal,
    // the one Send relays, runs (issue 32).
    auto preview = std::make_shared<RehearsalPlan>(plan);
    preview->fast = preview->stopAtFirstFailure = true;
    preview->refine = false;  // the full rehearsal follows anyway
    auto first = std::make_shared<RehearsalResult>(
        sp::rehearse(*preview, [&](double f) { return progress(0.25 * f) && !cancel->load(); }));
    if (!first->cancelled)
      QMetaObject::invokeMethod(
          this, [this, preview, first] { previewDone(std::move(*preview), std::move(*first)); }, Qt::QueuedConnection);
    auto r = std::make_shared<RehearsalResult>(
        sp::rehearse(plan, [&](double f) { return progress(0.25 + 0.75 * f) && !cancel->load(); }));
    auto done = std::make_shared<RehearsalPlan>(std::move(plan));
    return [this, done, r, text, pinned] {
      rehearsedText_ = text;
      planPinned_ = pinned;
      terrainEditedSince_ = false;
      rehearsalDone(std::move(*done), std::move(*r));
    };
  });
  return true;
}

void SequencePanel::showResult() {
  showVerdicts();
  std::vector<Vec3> path;
  for (const RehearsalSample& s : result_->path) path.push_back(s.base.p);
  emit pathChanged(path, {});
  updateButtons();
}

void SequencePanel::previewDone(RehearsalPlan plan, RehearsalResult result) {
  if (!busy_) return;  // the full rehearsal came first (or was cancelled): nothing to preview
  plan_ = std::move(plan);
  result_ = std::move(result);
  robust_.reset();
  preview_ = QString::fromStdString(result_->summary());
  setStatus(tr("Preview (fast profile, %1 s): %2. The full-fidelity rehearsal, the one Send relays, is running…")
                .arg(result_->wallSeconds, 0, 'f', 2)
                .arg(result_->passed ? tr("passed") : preview_));
  showResult();
  emit previewed(result_->passed);
}

void SequencePanel::rehearsalDone(RehearsalPlan plan, RehearsalResult result) {
  busy_ = false;
  progress_->setValue(1000);
  plan_ = std::move(plan);
  result_ = std::move(result);
  robust_.reset();
  const RobotModel& robot = plan_->world.robots[0].model;
  const QString hash = QString::fromStdString(sequenceHash(sequenceText(plan_->commands, &robot)));
  const QString verdict = QString::fromStdString(result_->summary());
  // Said when the preview told otherwise: the operator looked at it.
  const QString differs = !preview_.isEmpty() && preview_ != verdict
                              ? tr(" (the fast preview had: %1)").arg(preview_)
                              : QString();
  preview_.clear();
  setStatus(tr("Rehearsal %1 (%2 simulated in %3 s): %4%5")
                .arg(result_->passed ? tr("passed") : tr("failed"), seconds(result_->duration))
                .arg(result_->wallSeconds, 0, 'f', 2)
                .arg(verdict, differs));
  emit logEvent("rehearsal", QStringLiteral("%1 %2 (%3 commands, %4 s simulated): %5")
                                 .arg(hash, result_->passed ? "passed" : "failed")
                                 .arg(plan_->commands.size())
                                 .arg(result_->duration)
                                 .arg(verdict));
  showResult();
  emit rehearsed(result_->passed);
}

bool SequencePanel::checkRobustness() {
  if (busy_ || !plan_ || !rehearsalCurrent()) {
    setStatus(tr("Rehearse the sequence first."));
    return false;
  }
  RehearsalPlan plan = *plan_;
  plan.fast = plan.stopAtFirstFailure = true;  // a statistical check: its gate is the full rehearsal (issue 32)
  setStatus(tr("Robustness: %1 perturbed rehearsals on 2 threads (fast profile)…").arg(plan.rules.robustSamples));
  runTask(tr("Robustness"), [this, plan, cancel = freshCancel()](const BackgroundJobs::Progress& progress) -> std::function<void()> {
    auto r = std::make_shared<RobustnessResult>(robustness(plan, 1, 2, [&](int done, int total) {
      return progress(static_cast<double>(done) / std::max(1, total)) && !cancel->load();
    }));
    return [this, r] { robustnessFinished(std::move(*r)); };
  });
  return true;
}

bool SequencePanel::robustnessOnCluster(const QString& dir) {
  if (busy_ || !plan_ || !rehearsalCurrent()) {
    setStatus(tr("Rehearse the sequence first."));
    return false;
  }
  std::string error;
  if (!createSweepFromPlan(dir.toStdString(), *plan_, 1, error)) {
    setStatus(tr("Robustness on cluster: %1").arg(QString::fromStdString(error)));
    return false;
  }
  const int samples = plan_->rules.robustSamples;
  const QString later = QStringLiteral("simpartner-sim collect %1").arg(dir);
  if (QStandardPaths::findExecutable("sbatch").isEmpty()) {
    setStatus(tr("Robustness on cluster: %1 samples written to %2 (no sbatch here); on a machine of the cluster that "
                 "shares it: simpartner-sim sweep --resume %2 --slurm, then %3")
                  .arg(samples)
                  .arg(dir, later));
  } else {
    // sbatch may wait for a slow controller: on the worker, never the GUI.
    setStatus(tr("Robustness on cluster: %1 samples written to %2; submitting…").arg(samples).arg(dir));
    runTask(tr("Submitting"), [this, dir, samples, later, sim = simBinary_.toStdString()](
                                  const BackgroundJobs::Progress&) -> std::function<void()> {
      std::string why;
      const std::string job = submitSlurm(dir.toStdString(), {}, sim, {}, why);
      return [this, dir, samples, later, job, why] {
        busy_ = false;
        updateButtons();
        if (job.empty())
          setStatus(tr("Robustness on cluster: %1 samples written to %2; %3")
                        .arg(samples)
                        .arg(dir, QString::fromStdString(why)));
        else
          setStatus(tr("Robustness on cluster: job array %1, %2 samples in %3; when it is done: %4")
                        .arg(QString::fromStdString(job))
                        .arg(samples)
                        .arg(dir, later));
      };
    });
  }
  emit logEvent("rehearsal", QStringLiteral("robustness on cluster: %1 samples in %2").arg(samples).arg(dir));
  return true;
}

void SequencePanel::robustnessFinished(RobustnessResult r) {
  busy_ = false;
  progress_->setValue(1000);
  robust_ = std::move(r);
  QString worst;
  for (int i = 0; i < robust_->samples && worst.isEmpty(); ++i)
    if (!robust_->samplePassed[i]) worst = QString::fromStdString(robust_->failures[i]);
  setStatus(tr("Robustness: %1 of %2 passed (%3 %), end positions within %4 m of their mean%5%6")
                .arg(robust_->passed)
                .arg(robust_->samples)
                .arg(100 * robust_->probability(), 0, 'f', 0)
                .arg(robust_->spread, 0, 'f', 3)
                .arg(worst.isEmpty() ? QString() : tr("; e.g. %1").arg(worst))
                .arg(robust_->refined ? tr("; %1 near a limit or failing run again at full fidelity").arg(robust_->refined)
                                      : QString()));
  emit logEvent("rehearsal", QStringLiteral("robustness: %1 of %2 passed, end spread %3 m")
                                 .arg(robust_->passed)
                                 .arg(robust_->samples)
                                 .arg(robust_->spread));
  std::vector<Vec3> ends;
  for (const Pose& p : robust_->endPoses) ends.push_back(p.p);
  std::vector<Vec3> hull = convexHullXY(ends);
  if (!hull.empty()) hull.push_back(hull.front());  // closed
  std::vector<Vec3> path;
  for (const RehearsalSample& s : result_->path) path.push_back(s.base.p);
  emit pathChanged(path, hull);
  updateButtons();
  emit robustnessDone();
}

void SequencePanel::showVerdicts() {
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

void SequencePanel::scrubTo(double time) {
  if (!result_ || result_->path.empty()) return;
  scrubber_->setValue(static_cast<int>(std::lround(time / RehearsalResult::kSampleInterval)));
}

double SequencePanel::scrubTime() const {
  if (!result_ || result_->path.empty()) return 0;
  return result_->path[std::min<size_t>(static_cast<size_t>(scrubber_->value()), result_->path.size() - 1)].time;
}

void SequencePanel::showScrub(int index) {
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

bool SequencePanel::send() {
  std::string why;
  if (!plan_ || !result_) why = "rehearse the sequence first";
  else if (!rehearsalCurrent()) why = "the sequence changed since its rehearsal: rehearse it again";
  else if (terrainEditedSince_) why = "the terrain was edited since the rehearsal: rehearse it again";
  else if (planPinned_) why = "it was rehearsed from a logged moment, not from the robot's state: rehearse it from the robot";
  else if (!linkReady_) why = "the robot cannot take a sequence now (not connected, no lease, or latched)";
  std::optional<net::SequenceMsg> msg;
  if (why.empty()) msg = sequenceMessage(*plan_, *result_, why);
  if (!msg) {
    setStatus(tr("Not sent: %1").arg(QString::fromStdString(why)));
    return false;
  }
  guard_->relayed(*msg, *result_, plan_->rules, plan_->world.robots[0].model);
  emit logEvent("relay", QStringLiteral("sent %1 (%2 commands)").arg(QString::fromStdString(msg->hash)).arg(relay().count()));
  emit sendRequested(*msg);
  setStatus(tr("Sent %1 to the robot; waiting for its answer…").arg(QString::fromStdString(msg->hash)));
  updateButtons();
  return true;
}

void SequencePanel::setGuard(std::shared_ptr<SequenceGuard> guard) {
  guard_ = std::move(guard);
  updateButtons();
}

void SequencePanel::abort(const QString& reason) {
  const SequenceGuard::Status r = relay();
  if (r.phase() != SequenceRelay::Phase::Running && r.phase() != SequenceRelay::Phase::Sent) return;
  emit abortRequested(QString::fromStdString(r.hash()), reason);
  emit logEvent("relay", QStringLiteral("abort %1: %2").arg(QString::fromStdString(r.hash()), reason));
  setStatus(tr("Abort sent: %1").arg(reason));
}

void SequencePanel::onSequenceState(const net::SequenceStateMsg& state) {
  const SequenceGuard::Status r = relay();
  if (state.hash != r.hash()) return;
  const QString hash = QString::fromStdString(r.hash());
  switch (r.phase()) {
    case SequenceRelay::Phase::Running:
      setStatus(tr("Running %1 on the robot: %2 of %3 commands applied").arg(hash).arg(r.index()).arg(r.count()));
      break;
    case SequenceRelay::Phase::Done: setStatus(tr("%1 done on the robot; the guard watches to the rehearsal's end").arg(hash)); break;
    case SequenceRelay::Phase::Refused:
    case SequenceRelay::Phase::Aborted: {
      const QString what = r.phase() == SequenceRelay::Phase::Refused ? tr("refused") : tr("aborted");
      const QString text = tr("The robot %1 %2: %3").arg(what, hash, QString::fromStdString(r.reason()));
      setStatus(text);
      if (shownPhase_ != r.phase()) emit alert(text);
      break;
    }
    default: break;
  }
  const bool ended = r.phase() == SequenceRelay::Phase::Done || r.phase() == SequenceRelay::Phase::Aborted ||
                     r.phase() == SequenceRelay::Phase::Refused;
  if (ended && shownPhase_ != r.phase()) emit runEnded();
  shownPhase_ = r.phase();
  updateButtons();
}

void SequencePanel::onGuardTripped(const QString& hash, const GuardDeparture& d) {
  const QString why = QString::fromStdString("guard: " + d.message());
  emit logEvent("guard", QStringLiteral("%1 (sequence %2) at (%3, %4), rehearsed (%5, %6): ABORT sent")
                             .arg(why, hash)
                             .arg(d.reported.p.x, 0, 'f', 2)
                             .arg(d.reported.p.y, 0, 'f', 2)
                             .arg(d.rehearsed.p.x, 0, 'f', 2)
                             .arg(d.rehearsed.p.y, 0, 'f', 2));
  scrubTo(d.time);
  const QString text = tr("Aborted by the guard: %1. The amber robot shows where the rehearsal was.").arg(why);
  setStatus(text);
  emit alert(text);
}

QString SequencePanel::status() const { return status_->text(); }

void SequencePanel::setStatus(const QString& text) {
  status_->setText(text);
  status_->setVisible(!text.isEmpty());
}

void SequencePanel::updateButtons() {
  const SequenceRelay::Phase phase = relay().phase();
  const bool running = phase == SequenceRelay::Phase::Running || phase == SequenceRelay::Phase::Sent;
  const bool current = rehearsalCurrent();
  rehearseButton_->setEnabled(!busy_ && errors_.isEmpty());
  robustButton_->setEnabled(!busy_ && current);
  clusterButton_->setEnabled(!busy_ && current);
  cancelButton_->setEnabled(busy_);
  sendButton_->setEnabled(!busy_ && linkReady_ && current && result_->passed && !running && !planPinned_);
  QString why;
  if (busy_) why.clear();
  else if (!errors_.isEmpty()) why = tr("Rehearse waits for the sequence to be fixed: %1").arg(errors_.front());
  else if (editor_->toPlainText().trimmed().isEmpty()) why = tr("Write or open a sequence to rehearse.");
  else if (!current) why = tr("Send needs a rehearsal of this text%1.").arg(terrainEditedSince_ ? tr(" since the terrain edit") : QString());
  else if (!result_->passed) why = tr("Send: the rehearsal failed (%1).").arg(QString::fromStdString(result_->summary()));
  else if (planPinned_) why = tr("Send: a what-if from a pinned start cannot be sent.");
  else if (!linkReady_) why = tr("Send: take control of the robot first.");
  whyLabel_->setText(why);
  whyLabel_->setVisible(!why.isEmpty());
  progressRow_->setVisible(busy_);
  startLabel_->setText(pinned_ ? tr("Start: %1 (a what-if: it cannot be sent)").arg(pinned_->label)
                               : tr("Start: the robot's state when Rehearse is pressed"));
  unpinButton_->setVisible(pinned_.has_value());
  abortButton_->setEnabled(running);
}

void SequencePanel::openFile() {
  const QString path = QFileDialog::getOpenFileName(this, tr("Open sequence"), QString(), tr("Sequences (*.seq);;All files (*)"));
  if (path.isEmpty()) return;
  QFile f(path);
  if (!f.open(QIODevice::ReadOnly) || f.size() > 1 << 20) {
    QMessageBox::warning(this, tr("Open sequence"), tr("%1: cannot read (or larger than 1 MiB)").arg(path));
    return;
  }
  setText(QString::fromUtf8(f.readAll()));
}

void SequencePanel::saveFile() {
  const QString path = QFileDialog::getSaveFileName(this, tr("Save sequence"), QString(), tr("Sequences (*.seq)"));
  if (path.isEmpty()) return;
  QFile f(path);
  if (!f.open(QIODevice::WriteOnly | QIODevice::Truncate) || f.write(editor_->toPlainText().toUtf8()) < 0 ||
      !f.flush()) {
    QMessageBox::warning(this, tr("Save sequence"), tr("%1: %2").arg(path, f.errorString()));
  }
}

}  // namespace sp
