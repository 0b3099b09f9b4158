#pragma once
// The console's third job, first part: replaying a session log. A timeline
// over the log (play, pause, speed 0.1x-10x, step, seek by dragging) with
// the log's events marked on it and listed (a click seeks to one); the
// window's 3D view and plots follow the cursor through the frame and laser
// signals. Reading is app/log_player.h: one indexed row per seek.
//
// Thread: GUI thread.

#include <QElapsedTimer>
#include <QList>
#include <QPointF>
#include <QString>
#include <QWidget>

#include <memory>

#include "app/log_player.h"

class QComboBox;
class QLabel;
class QListWidget;
class QPushButton;
class QSlider;
class QTimer;
QT_FORWARD_DECLARE_CLASS(QChartView)
QT_FORWARD_DECLARE_CLASS(QLineSeries)

namespace sp {

class ReplayPanel : public QWidget {
  Q_OBJECT

 public:
  explicit ReplayPanel(QWidget* parent = nullptr);
  ~ReplayPanel() override;

  /// Opens the log at `path` and shows its start; "" or why not (the
  /// panel keeps what it had).
  QString open(const QString& path);
  void close();
  bool isOpen() const { return player_ != nullptr; }
  const LogPlayer* player() const { return player_.get(); }

  /// The cursor [s, log time] and moving it (clamped to the log).
  double cursor() const { return cursor_; }
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
  void closed();
  /// Simulate from here: branch a new stand-in session from the cursor.
  void branchRequested(double time);
  /// The robot at the cursor, for the views.
  void frame(const sp::RobotFrame& frame);
  void laser(const sp::LaserFrame& scan);

 private:
  void tick();
  void show(double time);

  std::unique_ptr<LogPlayer> player_;
  double cursor_ = 0;
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
