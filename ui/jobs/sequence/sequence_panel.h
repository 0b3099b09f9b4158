#pragma once
// The console's first job: a command sequence is written here, rehearsed on
// the console's own twin from the robot's current state, and only a sequence
// that passed is sent to the robot, unchanged. While it runs on board, the
// guard compares telemetry with the rehearsal and aborts it when the robot
// departs.
//
//   editor      the `.seq` text; errors inline as you type (the line
//               underlined, the message below), a template per command,
//               open and save;
//   rehearse    on a worker thread, with progress and cancel; the verdict of
//               every flight rule (a failed one seeks the scrubber to its
//               time); the rehearsed path and an amber robot in the 3D view;
//               a scrubber over the rehearsal and a plot of its stability
//               margin, roll and pitch with the scrubber's time marked;
//   robustness  rules' robust.samples perturbed rehearsals on both cores:
//               success probability and the spread of the end positions
//               (their hull drawn with the path); "On cluster…" writes the
//               same rehearsals as a sweep folder and submits it to Slurm
//               (app/sweep/sweep.h, docs/sweeps.md);
//   relay       Send (only after a pass, with the text unchanged since),
//               the robot's progress, Abort.
//
// The panel holds no link: it asks for the start state and sends through
// the callbacks and signals MainWindow connects (app/rehearse/sequence_relay.h does
// the protocol's side). Its parts: the editor (sequence_editor.h), the
// results (rehearsal_results.h) and the relay's buttons (relay_buttons.h);
// what may be rehearsed, checked or sent, and why not, is the Qt-free
// SequenceWorkflow's (app/rehearse/sequence_workflow.h).
//
// Thread: GUI thread. Rehearsals, robustness checks and submissions run on
// a BackgroundJobs runner (the console's, ui/background_jobs.h), one at a
// time; Cancel stops one and shows what it did so far; a task still running
// when the panel goes is stopped and its result dropped.

#include <QCoreApplication>
#include <QString>
#include <QStringList>
#include <QWidget>

#include <atomic>
#include <functional>
#include <memory>
#include <optional>

#include "app/rehearse/rehearsal.h"
#include "app/rehearse/sequence_guard.h"
#include "app/rehearse/sequence_workflow.h"
#include "net/message.h"
#include "ui/background_jobs.h"

class QLabel;
class QProgressBar;
class QPushButton;
class QTreeWidget;
class QVBoxLayout;

namespace sp {

class RehearsalResults;
class RelayButtons;
class SequenceEditor;

class SequencePanel : public QWidget {
  Q_OBJECT

 public:
  explicit SequencePanel(QWidget* parent = nullptr);
  /// Cancels and joins a rehearsal in progress.
  ~SequencePanel() override;

  /// The world rehearsals run on, read when needed (robots[0] is the
  /// robot; its terrain as edited: the console's one terrain, no copy kept
  /// here), null without one; and the parameters, read at each rehearsal
  /// (the console's calibration moves on). Re-checks the text. Drops the
  /// last rehearsal.
  /// `estimate`, when given, is what robustness runs draw the robot from
  /// (RehearsalPlan::estimate); else the rules' fixed ranges.
  void setWorld(std::function<const WorldModel*()> world, std::function<SimParams()> params,
                std::function<std::optional<RobotEstimate>()> estimate = {});
  void setRules(const FlightRules& rules);
  const FlightRules& rules() const { return rules_; }
  /// Where a rehearsal starts: the robot's state now (nullopt = not known:
  /// then the world's own start). Called when Rehearse is pressed.
  void setStartProvider(std::function<std::optional<RehearsalStart>()> provider);
  /// Rehearse from a logged moment (Replay ▸ Rehearse from here): until
  /// unpinned, rehearsals start from `start` in the logged `world` with its
  /// `params` instead of the robot's state now. Such a rehearsal is a
  /// what-if: it cannot be sent (the robot is not there).
  void pinStart(const RehearsalStart& start, const WorldModel& world, const SimParams& params, const QString& label);
  void unpinStart();
  /// "" while rehearsals start from the robot; else where they start.
  QString pinnedStart() const {
    return workflow_.pinned() ? QString::fromStdString(workflow_.pinned()->label) : QString();
  }
  /// The terrain was edited: the next rehearsal runs on the edited heights
  /// (the world's), and the last one (on the old heights) cannot be sent
  /// until rehearsed again.
  void terrainEdited();
  /// Whether a sequence may go to the robot now (connected, holding the
  /// lease, nothing latched).
  void setLinkReady(bool ready);

  void setText(const QString& text);
  QString text() const;
  /// The text's problems, "line N: message" each; empty when it parses and
  /// passes the robot's limits. Up to date after checkNow().
  QStringList errors() const;
  /// Checks the text now (typing checks it 150 ms after the last key).
  void checkNow();
  /// The lines marked in the editor.
  QList<int> markedLines() const;
  /// The sequence's way from text to robot (what the panel shows).
  const SequenceWorkflow& workflow() const { return workflow_; }

  /// Starts a rehearsal of the text (false, and the reason in status(), if
  /// it has errors or one runs). `rehearsed` is emitted when it ends.
  bool rehearse();
  /// Starts the robustness rehearsals (needs a passed rehearsal).
  bool checkRobustness();
  /// The same robustness rehearsals as a sweep in `dir` (app/sweep/sweep.h:
  /// sample i equals the local robustness's sample i), submitted with
  /// sbatch when this machine has it; status() says where and what next.
  bool robustnessOnCluster(const QString& dir);
  /// The simpartner-sim a cluster's tasks run (default: beside this program).
  void setSimBinary(const QString& path) { simBinary_ = path; }
  bool busy() const { return busy_; }
  /// Runs rehearsals on `jobs` (the console's runner; it must outlive the
  /// panel) instead of a runner of its own. Not while one runs.
  void setBackground(BackgroundJobs* jobs);
  /// The last rehearsal, if any (and whether the text is still what it rehearsed).
  const std::optional<RehearsalResult>& result() const { return workflow_.result(); }
  const std::optional<RobustnessResult>& robustnessResult() const { return workflow_.robustness(); }
  bool rehearsalCurrent() const;
  /// Sends the rehearsed sequence (false and status() says why if it
  /// cannot go: not passed, edited since, link not ready).
  bool send();
  /// Asks the robot to abort the running sequence.
  void abort(const QString& reason);
  /// The guard the link's worker feeds (RobotConnection::guard()); the
  /// panel arms it on Send and shows its state.
  void setGuard(std::shared_ptr<SequenceGuard> guard);
  /// Where the relayed sequence stands.
  SequenceGuard::Status relay() const { return guard_->status(); }
  QString status() const;
  /// Seeks the scrubber to `time` [s from the sequence's start].
  void scrubTo(double time);
  double scrubTime() const;

  QPushButton* rehearseButton() const { return rehearseButton_; }
  QPushButton* sendButton() const;
  QPushButton* abortButton() const;
  QTreeWidget* verdictList() const;

 public slots:
  /// The robot's SEQUENCE_STATE (after the guard has taken it).
  void onSequenceState(const sp::net::SequenceStateMsg& state);
  /// The guard tripped; its ABORT has gone out already.
  void onGuardTripped(const QString& hash, const sp::GuardDeparture& departure);

 signals:
  void rehearsed(bool passed);
  /// Rehearse's first verdicts are in: the fast profile's preview, while
  /// the full-fidelity rehearsal (the one Send relays) still runs.
  void previewed(bool passed);
  void robustnessDone();
  /// Send this SEQUENCE to the robot.
  void sendRequested(const sp::net::SequenceMsg& message);
  /// Send ABORT for `hash` (the operator's Abort).
  void abortRequested(const QString& hash, const QString& reason);
  /// The scrubber moved: draw the rehearsed robot here.
  void scrubbed(const sp::Pose& base, const std::vector<double>& jointPositions);
  /// The sent sequence ended on the robot (done, aborted or refused): the
  /// rehearsed robot is not needed in the view any more.
  void runEnded();
  /// A new rehearsal path (base positions on the ground) and the robustness
  /// envelope (hull of end positions; empty for none).
  void pathChanged(const std::vector<sp::Vec3>& path, const std::vector<sp::Vec3>& envelope, const std::vector<double>& band);
  /// Something for the session log: kind "rehearsal", "relay" or "guard".
  void logEvent(const QString& kind, const QString& text);
  /// The operator must know now (the guard tripped, the robot refused).
  void alert(const QString& text);

 private:
  void buildRunRows(QVBoxLayout* layout);
  /// A new Cancel flag for the next task (the last one's stays with it).
  std::shared_ptr<std::atomic<bool>> freshCancel();
  /// Runs `work` on the runner: busy, progress, Cancel until its result runs.
  void runTask(const QString& what, BackgroundJobs::Work work);
  void rehearsalDone(RehearsalPlan plan, RehearsalResult result, const QString& text, bool pinned);
  void previewDone(RehearsalPlan plan, RehearsalResult result);
  /// The verdicts, the path in the view and the buttons for the workflow's result.
  void showResult();
  void robustnessFinished(RobustnessResult result);
  void updateButtons();
  void setStatus(const QString& text);

  std::function<const WorldModel*()> world_;  // the console's world (and terrain) now
  std::function<SimParams()> params_;
  std::function<std::optional<RobotEstimate>()> estimate_;
  FlightRules rules_;
  std::function<std::optional<RehearsalStart>()> startProvider_;
  bool linkReady_ = false;
  QString preview_;  // the last preview's verdict, to say when the full one differs
  SequenceWorkflow workflow_;

  SequenceEditor* editor_ = nullptr;
  RehearsalResults* results_ = nullptr;
  RelayButtons* relayButtons_ = nullptr;
  QPushButton* rehearseButton_ = nullptr;
  QPushButton* robustButton_ = nullptr;
  QPushButton* clusterButton_ = nullptr;
  QString simBinary_ = QCoreApplication::applicationDirPath() + "/simpartner-sim";
  QPushButton* cancelButton_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QLabel* status_ = nullptr;
  QLabel* whyLabel_ = nullptr;       // why Rehearse or Send is disabled, beside them
  QWidget* progressRow_ = nullptr;   // the progress and Cancel, shown while busy
  QLabel* startLabel_ = nullptr;
  QPushButton* unpinButton_ = nullptr;

  bool busy_ = false;
  BackgroundJobs* jobs_ = nullptr;  // the console's runner, or the panel's own
  int job_ = 0;                     // the task running (for its progress)
  std::shared_ptr<std::atomic<bool>> cancel_ = std::make_shared<std::atomic<bool>>(false);  // the task's
  std::shared_ptr<SequenceGuard> guard_ = std::make_shared<SequenceGuard>();
  SequenceRelay::Phase shownPhase_ = SequenceRelay::Phase::Idle;
};

}  // namespace sp
