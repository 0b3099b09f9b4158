#pragma once
// The console's third job: replaying a session log. A timeline over the log
// (play, pause, speed 0.1x-10x, step, seek by dragging) with the log's
// events marked on it and listed (a click seeks to one); the window's 3D
// view and plots follow the cursor through the frame and laser signals.
// Reading is app/log/log_player.h: one indexed row per seek.
//
// What may take long runs on a worker thread with progress and Cancel, the
// window staying responsive: opening a log (reading it, rebuilding its
// world, the first plot), "Simulate from here" (re-simulating from the
// snapshot before the cursor), "Verify" (re-simulating the whole log
// against its hashes).
//
// Thread: GUI thread; one task at a time on a BackgroundJobs runner (the
// console's, ui/background_jobs.h), its result dropped if the panel is gone
// first. The task never touches the open player: it opens its own.

#include <QElapsedTimer>
#include <QList>
#include <QPointF>
#include <QString>
#include <QWidget>

#include <functional>
#include <memory>

#include "app/log/log_player.h"
#include "ui/jobs/replay/replay_feed.h"

class QComboBox;
class QLabel;
class QVBoxLayout;
class QListWidget;
class QProgressBar;
class QPushButton;
class QSlider;
class QTimer;
QT_FORWARD_DECLARE_CLASS(QChartView)
QT_FORWARD_DECLARE_CLASS(QLineSeries)

namespace sp {

class BackgroundJobs;

class ReplayPanel : public QWidget {
  Q_OBJECT

 public:
  explicit ReplayPanel(QWidget* parent = nullptr);
  ~ReplayPanel() override;

  /// Opens the log at `path` and shows its start; "" or why not (the
  /// panel keeps what it had). Blocks until read.
  QString open(const QString& path);
  /// The same on the worker, with progress: `opened` or `openFailed` follow.
  void openInBackground(const QString& path);
  /// Simulate from here, on the worker with progress: the state at the
  /// cursor (re-simulated, or reconstructed from a telemetry-only log);
  /// `branchReady` or `failed` follow.
  void branchHere();
  /// Rehearse from here: the sample at the cursor as a rehearsal's start
  /// (`rehearsalStart`); false (and `failed`) without one.
  bool rehearseHere();
  /// Verify: re-simulates the whole log on the worker and compares every
  /// logged hash; the verdict is shown and `verified` emitted.
  void verify();
  /// A worker task is running (opening, branching, verifying).
  bool busy() const { return job_ != 0; }
  /// Runs its long tasks on `jobs` (the console's runner; it must outlive
  /// the panel) instead of a runner of its own. Not while one runs.
  void setBackground(BackgroundJobs* jobs);
  /// Stops the worker's task (its result is dropped).
  void cancel();
  /// What the progress row says ("" when idle), and the last task's verdict.
  QString progressText() const;
  QString lastResult() const { return lastResult_; }
  void close();
  bool isOpen() const { return player() != nullptr; }
  const LogPlayer* player() const { return feed_->player(); }
  /// The log as a feed: it owns the player and the cursor (replay_feed.h).
  ReplayFeed* feed() const { return feed_; }

  /// The cursor [s, log time] and moving it (clamped to the log).
  double cursor() const { return feed_->cursor(); }
  void seek(double time);
  void play();
  void pause();
  bool playing() const { return playing_; }
  /// Playback speed, 0.1 to 10 (robot seconds per wall second).
  void setSpeed(double factor);
  double speed() const { return speed_; }
  /// One step of 0.1 s back (-1) or forward (+1).
  void step(int direction);
  /// Seeks to event `index` of player()->events().
  void seekToEvent(int index);

  /// The plot: signal `index` of player()->signalNames() over the visible
  /// range (the whole log until zoomed: drag a rectangle to zoom, right
  /// click to zoom out), about kPlotPoints points read from the log.
  void setSignal(int index);
  int signalIndex() const;
  void setVisibleRange(double t0, double t1);
  QList<QPointF> plotted() const;
  /// "t = 2.500 s: knee_fl position [deg] = 12.3" at the cursor.
  QString readout() const;
  /// The plotted points of the visible range as CSV (time, value, with a
  /// header naming the signal and units), or the chart as PNG; "" or why not.
  QString exportCsv(const QString& path) const;
  QString exportPng(const QString& path) const;
  static constexpr int kPlotPoints = 1500;
  static constexpr double kStep = 0.1;

 signals:
  void opened(const sp::WorldModel& world);
  /// A background task failed or was cancelled (the message says which).
  void failed(const QString& message);
  /// The branch point at the cursor of log `path` is ready to start from.
  void branchReady(const QString& path, std::shared_ptr<const sp::BranchPoint> point);
  /// Rehearse from here: start, and the logged world and parameters.
  void rehearsalStart(const sp::RehearsalStart& start, const sp::WorldModel& world, const sp::SimParams& params,
                      const QString& label);
  /// Verify ended: passed = every logged hash reproduced.
  void verified(bool passed, const QString& verdict);
  void closed();

 private:
  // The constructor's parts: the transport row, the progress row and the
  // timeline; the signal's plot beside the events.
  void buildControls(QVBoxLayout* layout);
  void buildPlot(QVBoxLayout* layout);
  void tick();
  /// Seeks the feed (the frame there follows, then showCursor).
  void show(double time);
  /// The cursor moved to `at`: the slider, the time and the plot's cursor.
  void showCursor(double at);
  /// Shows a player opened (on the worker or here); `firstPlot`: the
  /// default signal over the whole log, read already (else read here).
  void adopt(std::unique_ptr<LogPlayer> log, const QString& path,
             std::optional<std::vector<std::pair<double, double>>> firstPlot);
  void plot(const std::vector<std::pair<double, double>>& points);
  static constexpr int kFirstSignal = 6;  // wheel FL normal force
  /// Runs `work(progress)` on the worker with the progress row showing
  /// `what`; `work` returns what to do back on the GUI thread (dropped when
  /// cancelled). Returns false if a task runs.
  bool runInBackground(const QString& what,
                       std::function<std::function<void()>(const std::function<bool(double)>& progress)> work);
  void finishBackground();

  BackgroundJobs* jobs_ = nullptr;  // the console's runner, or the panel's own
  int job_ = 0;                     // the task running, 0 = none
  QString lastResult_;
  QWidget* progressRow_ = nullptr;
  QLabel* progressLabel_ = nullptr;
  QProgressBar* progressBar_ = nullptr;

  ReplayFeed* feed_ = nullptr;  // the log shown: its player and cursor (a child)
  double speed_ = 1;
  bool playing_ = false;
  QElapsedTimer wall_;  // since the last tick while playing
  QTimer* timer_ = nullptr;
  QLabel* title_ = nullptr;
  QPushButton* playButton_ = nullptr;
  QSlider* slider_ = nullptr;  // milliseconds of log time
  QLabel* timeLabel_ = nullptr;
  QComboBox* speedBox_ = nullptr;
  QListWidget* events_ = nullptr;
  class Marks;  // event ticks under the slider
  Marks* marks_ = nullptr;
  void replot();
  void moveCursorLine();
  QComboBox* signalBox_ = nullptr;
  QLabel* readout_ = nullptr;
  QChartView* chart_ = nullptr;
  QLineSeries* series_ = nullptr;
  QLineSeries* cursorLine_ = nullptr;
  QTimer* replotTimer_ = nullptr;
};

}  // namespace sp
