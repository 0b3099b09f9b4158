#pragma once
// The Calibration dock: what the console has fitted of the robot from its
// telemetry (app/calibration/live_calibrator.h), each parameter with its
// deviation, the files' value and whether the motion showed it; a plot of
// one parameter over the fits (the two as tabs); Freeze, Reset to files,
// Save parameters above them.
// Shows a replayed log's calibration table instead while a replay is shown.
//
// Thread: GUI thread only.

#include <QWidget>

#include <optional>
#include <vector>

#include "app/calibration/live_calibrator.h"
#include "app/log/session_log.h"

QT_FORWARD_DECLARE_CLASS(QChart)
QT_FORWARD_DECLARE_CLASS(QChartView)
QT_FORWARD_DECLARE_CLASS(QComboBox)
QT_FORWARD_DECLARE_CLASS(QLabel)
QT_FORWARD_DECLARE_CLASS(QLineSeries)
QT_FORWARD_DECLARE_CLASS(QPushButton)
QT_FORWARD_DECLARE_CLASS(QTabWidget)
QT_FORWARD_DECLARE_CLASS(QTableWidget)
QT_FORWARD_DECLARE_CLASS(QValueAxis)

namespace sp {

class CalibrationPanel : public QWidget {
  Q_OBJECT

 public:
  explicit CalibrationPanel(QWidget* parent = nullptr);
  /// The live calibration (null: none, e.g. without a ghost; `why` says so).
  void setLive(const CalibrationState* state, const QString& why = {});
  /// A replayed log's calibration rows (empty: the log has none).
  void setReplayed(const std::vector<LogCalibration>& rows, const QString& label);
  /// Back to the live calibration after a replay.
  void clearReplayed();
  bool showingReplay() const { return replayed_.has_value(); }

  QTableWidget* table() const { return table_; }
  QPushButton* freezeButton() const { return freeze_; }
  QPushButton* resetButton() const { return reset_; }
  QPushButton* saveButton() const { return save_; }
  QLabel* statusLabel() const { return status_; }
  /// Points in the plotted parameter's series (tests).
  int plottedPoints() const;

 signals:
  void freezeToggled(bool frozen);
  void resetRequested();
  void saveRequested();

 private:
  struct Point {
    double time, value, sigma;
  };
  void showRow(int row, double value, double sigma, bool observed, const QString& status);
  void replot();

  QTabWidget* views_ = nullptr;  // the table, the plot
  QTableWidget* table_ = nullptr;
  QComboBox* plotted_ = nullptr;
  QChart* chart_ = nullptr;
  QChartView* view_ = nullptr;
  QLineSeries *value_ = nullptr, *upper_ = nullptr, *lower_ = nullptr;
  QValueAxis *axisX_ = nullptr, *axisY_ = nullptr;
  QPushButton *freeze_ = nullptr, *reset_ = nullptr, *save_ = nullptr;
  QLabel* status_ = nullptr;
  std::vector<std::vector<Point>> series_;  // per parameter: the fits that observed it
  std::optional<std::vector<LogCalibration>> replayed_;
};

}  // namespace sp
