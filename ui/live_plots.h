#pragma once
// The console's live plots: wheel normal forces against robot time, and the
// latest laser scan seen from above. Telemetry comes at 50-100 Hz, far more
// often than anyone can read a plot, so (as in PlotJuggler) feeding data only
// stores it and marks the plot dirty; a timer redraws at most every
// replotInterval() ms, and only while the widget is visible.
//
// Feeding from the robot link (net/robot_client.h): its callbacks run on the
// client's worker thread, so re-post each message to the GUI thread and call
// addSample()/setScan() there, e.g.
//   plot->addSample(t.time, t.wheelNormal);                  // TelemetryMsg t
//   laserPlot->setScan(l.angleMin, l.angleStep, l.ranges);   // LaserMsg l

#include <QList>
#include <QPointF>
#include <QTimer>
#include <QWidget>

#include <array>
#include <cstddef>
#include <deque>
#include <cstdint>
#include <utility>
#include <vector>

QT_FORWARD_DECLARE_CLASS(QChart)
QT_FORWARD_DECLARE_CLASS(QChartView)
QT_FORWARD_DECLARE_CLASS(QCheckBox)
QT_FORWARD_DECLARE_CLASS(QDoubleSpinBox)
QT_FORWARD_DECLARE_CLASS(QLineSeries)
QT_FORWARD_DECLARE_CLASS(QPushButton)
QT_FORWARD_DECLARE_CLASS(QScatterSeries)
QT_FORWARD_DECLARE_CLASS(QScrollBar)
QT_FORWARD_DECLARE_CLASS(QValueAxis)

namespace sp {

/// What the two live plots share: a Qt Charts view filling the widget (no
/// animation, no OpenGL) and the coalescing replot timer. GUI thread only.
class LivePlot : public QWidget {
  Q_OBJECT

 public:
  /// Redraw at most every `ms` milliseconds (>= 1; smaller values become 1).
  /// Default 100 ms, i.e. 10 Hz.
  void setReplotInterval(int ms);
  int replotInterval() const;

  /// Redraws now, dirty or not, visible or not (e.g. before grab()).
  void replotNow();

  /// One replot tick: redraws if the data changed and the plot is visible.
  /// The plot's own timer calls it; an owner that drives several plots from
  /// one timer (so their repaints reach the screen in one window update,
  /// which software GL composites whole) calls it after setOwnTimer(false).
  void tick();
  /// Whether the plot runs its own replot timer (default) or waits for tick().
  void setOwnTimer(bool on);

  /// Times the chart's contents were updated since construction; each update
  /// is one data pass plus one repaint of the view.
  int64_t replots() const { return replots_; }
  /// Data changed since the last replot: the next tick redraws.
  bool replotPending() const { return dirty_; }

  /// The chart, owned by this widget: to restyle it (title, fonts, legend;
  /// setTheme() would recolour the series) or read its plotArea().
  QChart* chart() const { return chart_; }

 protected:
  explicit LivePlot(QWidget* parent);

  /// Asks for a replot at the next timer tick. Cheap: touches no chart item.
  void markDirty() { dirty_ = true; }

  /// Updates the chart from the stored data; `force` when replotNow() asked.
  /// Returns whether the chart's contents changed (counted in replots()).
  virtual bool replot(bool force) = 0;

  QChart* chart_ = nullptr;  ///< owned by the view, a child of this widget first in its layout

 private:
  QTimer timer_;
  bool dirty_ = false;
  int64_t replots_ = 0;
};

/// Normal force on each wheel (FL, FR, RL, RR) [N] against robot time [s],
/// as a strip chart. Samples go into a bounded ring buffer (the newest
/// `capacity`: 60000 = 10 minutes at 100 Hz by default). The view shows a
/// time window (1-600 s, default 10 s) ending at the newest sample, or
/// starting at the oldest while the buffer holds less than a window. Paused,
/// the view stays put while samples keep arriving, and the scroll bar under
/// the chart moves it through the buffered history (scrolling also pauses);
/// "Follow" returns to the newest. The y axis fits the shown data with a 5%
/// margin (and spans at least 1 N) unless fixed with setYRange() or by
/// unticking "auto y". When a window holds more than 4 samples per pixel
/// column of the plot area, each column is drawn from its first, last,
/// minimum and maximum sample (per wheel), which looks the same and keeps a
/// 600 s window cheap.
///
/// Thread: GUI thread only, like every QWidget.
class WheelForcePlot : public LivePlot {
  Q_OBJECT

 public:
  static constexpr int kWheels = 4;
  static constexpr std::size_t kDefaultCapacity = 60000;  ///< samples: 10 min at 100 Hz

  /// `capacity` >= 2 samples (smaller values become 2).
  explicit WheelForcePlot(QWidget* parent = nullptr, std::size_t capacity = kDefaultCapacity);

  /// Appends one sample: robot time [s] and the normal force on each wheel
  /// [N], in the order FL, FR, RL, RR (TelemetryMsg::wheelNormal). Does not
  /// touch the chart. A non-finite time drops the sample; a time earlier than
  /// the newest sample's means the robot restarted, and the buffer is
  /// cleared first. Non-finite forces are stored but not drawn.
  void addSample(double time, const std::array<double, kWheels>& normal);

  /// Empties the buffer and follows again (a new session). The counters and
  /// the window, y-range and replot settings stay.
  void clear();

  /// The window [s], clamped to 1..600 and rounded to 0.1 s, as the
  /// "window [s]" box (which sets it too) shows it.
  void setWindow(double seconds);
  double window() const { return window_; }

  /// Paused: the view stops following the newest sample (the button does
  /// the same). Unpausing follows the newest again.
  void setPaused(bool paused);
  bool isPaused() const { return paused_; }

  /// Fixes the y axis to [min, max] N (finite, min < max; otherwise returns
  /// false and changes nothing) and unticks "auto y".
  bool setYRange(double min, double max);
  /// Lets the y axis fit the data again (ticks "auto y").
  void setAutoYRange();
  bool isAutoYRange() const { return autoY_; }

  /// The axes' current ranges: x [s], y [N].
  std::pair<double, double> xRange() const;
  std::pair<double, double> yRange() const;

  /// addSample() calls since construction, including dropped ones.
  int64_t samplesReceived() const { return samplesReceived_; }
  /// Samples in the ring buffer now.
  std::size_t bufferedSamples() const { return size_; }
  /// What the series of `wheel` (0..3: FL, FR, RL, RR) shows now, as
  /// (time [s], force [N]); empty for another index.
  QList<QPointF> shownPoints(int wheel) const;
  /// Pieces the line of `wheel` is drawn in: more than one where telemetry
  /// stopped for longer than kGap of robot time.
  int shownSegments(int wheel) const;
  static constexpr double kGap = 0.25;  ///< [s] of robot time without samples that breaks the line

 protected:
  bool replot(bool force) override;

 private:
  struct Sample {
    double time = 0;
    std::array<double, kWheels> normal{};
  };

  const Sample& at(std::size_t i) const { return buffer_[(start_ + i) % capacity_]; }
  /// First buffered index whose time is >= t (or > t with `after`).
  std::size_t firstIndex(double t, bool after) const;
  /// The time span [t0, t1] the view shows now.
  std::pair<double, double> viewSpan() const;
  void appendPoints(int wheel, std::size_t i0, std::size_t i1, std::pair<double, double> span, int columns,
                    QList<QPointF>& out) const;
  /// The y range that fits `points` (with margin and a minimum height), or
  /// the current one if none is finite.
  std::pair<double, double> fittedYRange(const std::array<QList<QPointF>, kWheels>& points) const;
  /// Sets the y axis with a tick about every 50 px.
  void setYAxis(double min, double max);
  void updateScrollBar();
  void onScrolled(int value);
  void onWindowChanged(double seconds);

  std::vector<Sample> buffer_;
  std::size_t capacity_;
  std::size_t start_ = 0;  ///< physical index of the oldest sample
  std::size_t size_ = 0;
  int64_t samplesReceived_ = 0;

  double window_ = 10;   ///< [s]
  bool paused_ = false;
  double pausedEnd_ = 0;  ///< [s] right edge of the view while paused
  bool autoY_ = true;
  bool viewDirty_ = true;  ///< the shown span or data changed (not just the history)

  std::array<QLineSeries*, kWheels> series_{};
  /// Further pieces of each wheel's line after gaps (made on demand).
  std::array<std::vector<QLineSeries*>, kWheels> gapSeries_{};
  /// The series drawing piece `k` of `wheel`'s line (0: series_[wheel]).
  QLineSeries* segmentSeries(std::size_t wheel, std::size_t k);
  QValueAxis* xAxis_ = nullptr;
  QValueAxis* yAxis_ = nullptr;
  QDoubleSpinBox* windowBox_ = nullptr;
  QPushButton* pauseButton_ = nullptr;
  QCheckBox* autoYBox_ = nullptr;
  QScrollBar* history_ = nullptr;
};

/// The latest laser scan, top-down in the sensor frame: x forward (up on
/// screen), y to the left (the horizontal axis grows leftwards), in metres.
/// Hits (finite ranges within the range limits) are dots; a triangle marks
/// the sensor at the origin. The scale is the same on both axes: the shorter
/// side of the plot spans exactly +-maxRange(), the longer one more.
///
/// Thread: GUI thread only, like every QWidget.
class LaserPlot : public LivePlot {
  Q_OBJECT

 public:
  explicit LaserPlot(QWidget* parent = nullptr);

  /// Stores a copy of the scan and marks the plot dirty; does not touch the
  /// chart. Beam i points at angleMin + i * angleStep [rad], counter-clockwise
  /// from x; ranges [m] as in LaserMsg (inf = no return, NaN = invalid). A
  /// non-finite angle draws no hits.
  void setScan(double angleMin, double angleStep, const std::vector<double>& ranges);
  /// Removes the scan (nothing shown until the next).
  void clear();

  /// Ranges outside [nearest, farthest] m are not drawn (the scanner's
  /// minRange and maxRange). Default [0, inf]. Returns false and changes
  /// nothing unless 0 <= nearest <= farthest (farthest may be inf).
  bool setRangeLimits(double nearest, double farthest);

  /// Half the extent of the plot's shorter side [m] (> 0 and finite, else
  /// ignored). Default 10 m.
  void setMaxRange(double metres);
  double maxRange() const { return maxRange_; }

  /// The axes' current ranges [m]: sensor x (forward, vertical axis) and
  /// sensor y (left, horizontal axis).
  std::pair<double, double> forwardRange() const;
  std::pair<double, double> leftRange() const;

  /// setScan() calls since construction.
  int64_t scansReceived() const { return scansReceived_; }
  /// The hits shown now, in the sensor frame: (x forward, y left) [m].
  QList<QPointF> shownPoints() const;

 protected:
  bool replot(bool force) override;

 private:
  void fitAspect();

  double angleMin_ = 0;
  double angleStep_ = 0;
  std::vector<double> ranges_;
  double nearest_ = 0;  ///< [m] scanner limits
  double farthest_;
  double maxRange_ = 10;  ///< [m] view
  int64_t scansReceived_ = 0;

  QScatterSeries* hits_ = nullptr;
  QScatterSeries* sensor_ = nullptr;
  QValueAxis* leftAxis_ = nullptr;     ///< horizontal, reversed: sensor y
  QValueAxis* forwardAxis_ = nullptr;  ///< vertical: sensor x
};

/// The predictive ghost's error (app/ghost/ghost.h): for each telemetry frame,
/// how far the robot was from where the ghost had shown it for that time,
/// in position [cm] (left axis) and heading [deg] (right axis), over the
/// last 30 s of robot time (the status bar gives the median of 10 s).
///
/// Thread: GUI thread only, like every QWidget.
class PredictionErrorPlot : public LivePlot {
  Q_OBJECT

 public:
  static constexpr double kWindow = 30;  ///< [s] of robot time shown
  static constexpr double kBin = 0.1;    ///< [s] one point per bin: the bin's largest errors

  explicit PredictionErrorPlot(QWidget* parent = nullptr);
  /// One comparison: robot time [s], position error [m], heading error
  /// [rad]. Non-finite values are dropped; a time earlier than the newest
  /// means the robot restarted, and the plot starts over.
  void addSample(double time, double position, double heading);
  void clear();
  /// Samples received (kept or not).
  int64_t samplesReceived() const { return received_; }
  /// The points shown after the last replot (position series): one per
  /// 0.1 s of robot time that had samples.
  int shownPoints() const;

 protected:
  bool replot(bool force) override;

 private:
  struct Sample {
    double time, position, heading;
  };
  std::deque<Sample> samples_;
  int64_t received_ = 0;
  QLineSeries* position_ = nullptr;
  QLineSeries* heading_ = nullptr;
  QValueAxis* xAxis_ = nullptr;
  QValueAxis* positionAxis_ = nullptr;
  QValueAxis* headingAxis_ = nullptr;
};

/// The plots side by side in a splitter, each with its stretch factor,
/// replotted by their owner's tick() rather than their own timers.
QWidget* plotRow(const std::vector<std::pair<LivePlot*, int>>& plots);

}  // namespace sp
