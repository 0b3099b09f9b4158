#pragma once
// The Sequence dock's results (ui/jobs/sequence/sequence_panel.h): a
// rehearsal's verdict for every flight rule (failed ones first; a click
// watches its time) and the plot of its stability margin, roll and pitch,
// as tabs; under them the Watch scrubber over the rehearsal, which moves the
// amber robot in the 3D view (`scrubbed`) and marks its time on the plot.
// The Watch row takes the relay's buttons beside it (addToWatchRow).
//
// Thread: GUI thread.

#include <QWidget>

#include <vector>

#include "app/rehearse/rehearsal.h"

class QHBoxLayout;
class QLabel;
class QSlider;
class QTabWidget;
class QTreeWidget;
QT_FORWARD_DECLARE_CLASS(QChartView)
QT_FORWARD_DECLARE_CLASS(QLineSeries)

namespace sp {

class RehearsalResults : public QWidget {
  Q_OBJECT

 public:
  explicit RehearsalResults(QWidget* parent = nullptr);
  /// Shows `result` (null: nothing; it must live until the next call); the
  /// scrubber keeps its place.
  void showResult(const RehearsalResult* result);
  /// Seeks the scrubber to `time` [s from the sequence's start].
  void scrubTo(double time);
  double scrubTime() const;
  QTreeWidget* verdictList() const { return verdicts_; }
  /// Puts `widget` at the end of the Watch row.
  void addToWatchRow(QWidget* widget);

 signals:
  /// The scrubber moved: draw the rehearsed robot here.
  void scrubbed(const sp::Pose& base, const std::vector<double>& jointPositions);

 private:
  void showScrub(int index);

  const RehearsalResult* result_ = nullptr;
  QTabWidget* tabs_ = nullptr;
  QTreeWidget* verdicts_ = nullptr;
  QSlider* scrubber_ = nullptr;
  QLabel* scrubLabel_ = nullptr;
  QHBoxLayout* watchRow_ = nullptr;
  QChartView* chart_ = nullptr;
  QLineSeries* marginSeries_ = nullptr;
  QLineSeries* rollSeries_ = nullptr;
  QLineSeries* pitchSeries_ = nullptr;
  QLineSeries* cursor_ = nullptr;
};

}  // namespace sp
