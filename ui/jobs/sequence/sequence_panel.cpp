#include "ui/jobs/sequence/sequence_panel.h"

#include <QBoxLayout>
#include <QDateTime>
#include <QFileDialog>
#include <QLabel>
#include <QProgressBar>
#include <QPushButton>
#include <QResizeEvent>
#include <QStandardPaths>

#include <cmath>

#include "app/sweep/sweep.h"
#include "ui/jobs/sequence/rehearsal_results.h"
#include "ui/jobs/sequence/relay_buttons.h"
#include "ui/jobs/sequence/sequence_editor.h"

namespace sp {
namespace {

QString seconds(double t) { return QString::number(t, 'f', 2) + " s"; }
QString qs(const std::string& s) { return QString::fromStdString(s); }

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

  editor_ = new SequenceEditor(this);
  layout->addWidget(editor_, 2);
  connect(editor_, &SequenceEditor::checkDue, this, &SequencePanel::checkNow);
  connect(editor_, &SequenceEditor::edited, this, &SequencePanel::updateButtons);

  auto* startRow = new QHBoxLayout;
  startLabel_ = new WrappedLabel(this);
  startLabel_->setWordWrap(true);
  unpinButton_ = new QPushButton(tr("From the robot"), this);
  unpinButton_->setToolTip(tr("Rehearse from the robot's state now again"));
  startRow->addWidget(startLabel_, 1);
  startRow->addWidget(unpinButton_);
  layout->addLayout(startRow);
  connect(unpinButton_, &QPushButton::clicked, this, &SequencePanel::unpinStart);

  buildRunRows(layout);

  results_ = new RehearsalResults(this);
  layout->addWidget(results_, 1);
  connect(results_, &RehearsalResults::scrubbed, this, &SequencePanel::scrubbed);
  // Send and Abort on the Watch row: on a row of their own they fell below
  // the fold of a 1280x800 window (issue 59).
  relayButtons_ = new RelayButtons(this);
  results_->addToWatchRow(relayButtons_);
  connect(relayButtons_, &RelayButtons::sendClicked, this, &SequencePanel::send);
  connect(relayButtons_, &RelayButtons::abortClicked, this, [this] { abort(tr("the operator pressed Abort")); });

  status_ = new WrappedLabel(this);
  status_->hide();
  layout->addWidget(status_);
  updateButtons();
}

void SequencePanel::buildRunRows(QVBoxLayout* layout) {
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
}

SequencePanel::~SequencePanel() {
  *cancel_ = true;  // a task still running stops; its result goes nowhere
}

QPushButton* SequencePanel::sendButton() const { return relayButtons_->sendButton(); }
QPushButton* SequencePanel::abortButton() const { return relayButtons_->abortButton(); }
QTreeWidget* SequencePanel::verdictList() const { return results_->verdictList(); }
QStringList SequencePanel::errors() const { return editor_->problemTexts(); }

void SequencePanel::setBackground(BackgroundJobs* jobs) {
  if (busy_ || !jobs || jobs == jobs_) return;
  if (jobs_) disconnect(jobs_, nullptr, this, nullptr);
  jobs_ = jobs;
  connect(jobs_, &BackgroundJobs::progressed, this, [this](int id, double f) {
    if (id == job_) progress_->setValue(static_cast<int>(f * 1000));
  });
}

void SequencePanel::setWorld(std::function<const WorldModel*()> world, std::function<SimParams()> params,
                             std::function<std::optional<RobotEstimate>()> estimate) {
  estimate_ = std::move(estimate);
  world_ = std::move(world);
  params_ = std::move(params);
  workflow_.forget();
  showResult();
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
  workflow_.pin({start, world, params, label.toStdString()});
  updateButtons();
}

void SequencePanel::unpinStart() {
  workflow_.unpin();
  updateButtons();
}

void SequencePanel::setLinkReady(bool ready) {
  linkReady_ = ready;
  updateButtons();
}

void SequencePanel::setText(const QString& text) {
  editor_->setText(text);
  checkNow();
}

QString SequencePanel::text() const { return editor_->text(); }

QList<int> SequencePanel::markedLines() const { return editor_->markedLines(); }

void SequencePanel::checkNow() {
  editor_->checkStarted();
  workflow_.check(text().toStdString(), world_ ? world_() : nullptr);
  editor_->showProblems(workflow_.problems());
  updateButtons();
}

bool SequencePanel::rehearsalCurrent() const { return workflow_.current(text().toStdString()); }

void SequencePanel::terrainEdited() {
  if (workflow_.terrainEdited()) {
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
  if (!errors().isEmpty()) {
    setStatus(tr("Fix the sequence first: %1").arg(errors().front()));
    return false;
  }
  std::string why;
  std::optional<RehearsalPlan> plan = workflow_.plan(text().toStdString(), world_ ? world_() : nullptr,
                                                     params_ ? params_() : SimParams{}, rules_,
                                                     startProvider_ ? startProvider_() : std::nullopt, why);
  if (plan && !workflow_.pinned() && estimate_) plan->estimate = estimate_();
  if (!plan) {
    QString said = qs(why);
    said[0] = said[0].toUpper();
    setStatus(said + ".");
    return false;
  }
  const QString text = this->text();
  const bool pinned = workflow_.pinned().has_value();
  setStatus(pinned       ? tr("Rehearsing from %1…").arg(pinnedStart())
            : plan->start ? tr("Rehearsing from the robot's state now…")
                          : tr("Rehearsing from the world's start…"));
  runTask(tr("Rehearsing"), [this, plan = std::move(*plan), text, pinned, cancel = freshCancel()](
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
    return [this, done, r, text, pinned] { rehearsalDone(std::move(*done), std::move(*r), text, pinned); };
  });
  return true;
}

void SequencePanel::showResult() {
  results_->showResult(workflow_.result() ? &*workflow_.result() : nullptr);
  emit pathChanged(workflow_.path(), workflow_.envelope(), workflow_.band());
  updateButtons();
}

void SequencePanel::previewDone(RehearsalPlan plan, RehearsalResult result) {
  if (!busy_) return;  // the full rehearsal came first (or was cancelled): nothing to preview
  workflow_.previewed(std::move(plan), std::move(result));
  const RehearsalResult& r = *workflow_.result();
  preview_ = qs(r.summary());
  setStatus(tr("Preview (fast profile, %1 s): %2. The full-fidelity rehearsal, the one Send relays, is running…")
                .arg(r.wallSeconds, 0, 'f', 2)
                .arg(r.passed ? tr("passed") : preview_));
  showResult();
  emit previewed(r.passed);
}

void SequencePanel::rehearsalDone(RehearsalPlan plan, RehearsalResult result, const QString& text, bool pinned) {
  busy_ = false;
  progress_->setValue(1000);
  workflow_.rehearsed(std::move(plan), std::move(result), text.toStdString(), pinned);
  const RehearsalResult& r = *workflow_.result();
  const QString verdict = qs(r.summary());
  // Said when the preview told otherwise: the operator looked at it.
  const QString differs = !preview_.isEmpty() && preview_ != verdict
                              ? tr(" (the fast preview had: %1)").arg(preview_)
                              : QString();
  preview_.clear();
  setStatus(tr("Rehearsal %1 (%2 simulated in %3 s): %4%5")
                .arg(r.passed ? tr("passed") : tr("failed"), seconds(r.duration))
                .arg(r.wallSeconds, 0, 'f', 2)
                .arg(verdict, differs));
  emit logEvent("rehearsal", qs(workflow_.rehearsalLogLine()));
  showResult();
  emit rehearsed(r.passed);
}

bool SequencePanel::checkRobustness() {
  if (busy_ || !rehearsalCurrent()) {
    setStatus(tr("Rehearse the sequence first."));
    return false;
  }
  RehearsalPlan plan = *workflow_.rehearsedPlan();
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
  if (busy_ || !rehearsalCurrent()) {
    setStatus(tr("Rehearse the sequence first."));
    return false;
  }
  const RehearsalPlan& plan = *workflow_.rehearsedPlan();
  std::string error;
  if (!createSweepFromPlan(dir.toStdString(), plan, 1, error)) {
    setStatus(tr("Robustness on cluster: %1").arg(QString::fromStdString(error)));
    return false;
  }
  const int samples = plan.rules.robustSamples;
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

void SequencePanel::robustnessFinished(RobustnessResult result) {
  busy_ = false;
  progress_->setValue(1000);
  workflow_.robustnessDone(std::move(result));
  const RobustnessResult& r = *workflow_.robustness();
  QString worst;
  for (int i = 0; i < r.samples && worst.isEmpty(); ++i)
    if (!r.samplePassed[i]) worst = qs(r.failures[i]);
  setStatus(tr("Robustness: %1 (%2 %), every end within %3 m of their mean%4%5")
                .arg(qs(r.verdict()))
                .arg(100 * r.probability(), 0, 'f', 0)
                .arg(r.spread, 0, 'f', 3)
                .arg(worst.isEmpty() ? QString() : tr("; e.g. %1").arg(worst))
                .arg(r.refined ? tr("; %1 near a limit or failing run again at full fidelity").arg(r.refined)
                               : QString()));
  emit logEvent("rehearsal", qs(workflow_.robustnessLogLine()));
  emit pathChanged(workflow_.path(), workflow_.envelope(), workflow_.band());
  updateButtons();
  emit robustnessDone();
}

void SequencePanel::scrubTo(double time) { results_->scrubTo(time); }

double SequencePanel::scrubTime() const { return results_->scrubTime(); }

bool SequencePanel::send() {
  std::string why = workflow_.sendRefusal(text().toStdString(), linkReady_);
  std::optional<net::SequenceMsg> msg;
  if (why.empty()) msg = workflow_.message(why);
  if (!msg) {
    setStatus(tr("Not sent: %1").arg(qs(why)));
    return false;
  }
  const RehearsalPlan& plan = *workflow_.rehearsedPlan();
  guard_->relayed(*msg, *workflow_.result(), plan.rules, plan.world.robots[0].model);
  emit logEvent("relay", QStringLiteral("sent %1 (%2 commands)").arg(qs(msg->hash)).arg(relay().count()));
  emit sendRequested(*msg);
  setStatus(tr("Sent %1 to the robot; waiting for its answer…").arg(qs(msg->hash)));
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
  emit abortRequested(qs(r.hash()), reason);
  emit logEvent("relay", QStringLiteral("abort %1: %2").arg(qs(r.hash()), reason));
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
  const bool fine = errors().isEmpty();
  const std::optional<RehearsalResult>& result = workflow_.result();
  rehearseButton_->setEnabled(!busy_ && fine);
  robustButton_->setEnabled(!busy_ && current);
  clusterButton_->setEnabled(!busy_ && current);
  cancelButton_->setEnabled(busy_);
  relayButtons_->setStates(!busy_ && linkReady_ && current && result->passed && !workflow_.rehearsedFromPin(), running);
  QString why;
  if (busy_) why.clear();
  else if (!fine) why = tr("Rehearse waits for the sequence to be fixed: %1").arg(errors().front());
  else if (text().trimmed().isEmpty()) why = tr("Write or open a sequence to rehearse.");
  else if (!current)
    why = tr("Send needs a rehearsal of this text%1.").arg(workflow_.terrainEditedSince() ? tr(" since the terrain edit") : QString());
  else if (!result->passed) why = tr("Send: the rehearsal failed (%1).").arg(qs(result->summary()));
  else if (workflow_.rehearsedFromPin()) why = tr("Send: a what-if from a pinned start cannot be sent.");
  else if (!linkReady_) why = tr("Send: take control of the robot first.");
  whyLabel_->setText(why);
  whyLabel_->setVisible(!why.isEmpty());
  progressRow_->setVisible(busy_);
  startLabel_->setText(workflow_.pinned() ? tr("Start: %1 (a what-if: it cannot be sent)").arg(pinnedStart())
                                          : tr("Start: the robot's state when Rehearse is pressed"));
  unpinButton_->setVisible(workflow_.pinned().has_value());
}

}  // namespace sp
