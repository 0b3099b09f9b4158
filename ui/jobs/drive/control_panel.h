#pragma once
// The operator's controls: drive (speed and articulation) by sliders and by
// keyboard, each joint's target by slider and spin box, gait selection and
// stop. The panel only emits commands; the console sends them over the link
// and the robot drawn is the robot as telemetry reports it.
//
// Thread: GUI thread only.

#include <QWidget>

#include <vector>

#include "sim/command.h"
#include "sim/robot_model.h"

class QComboBox;
class QGroupBox;
class QLabel;
class QScrollArea;
class QSlider;
class QTimer;
class QVBoxLayout;

namespace sp {

class LimitSpinBox;

/// Whether `key` is a drive key of ControlPanel::handleKey().
bool isDriveKey(int key);

class ControlPanel : public QWidget {
  Q_OBJECT

 public:
  explicit ControlPanel(QWidget* parent = nullptr);

  /// Builds the controls for `robot`: the drive's limits come from its wheel
  /// actuators and articulation joint, and one row per position-controlled
  /// joint other than the drive's. Resets every control to zero.
  void setRobot(const RobotModel& robot);

  /// Keyboard driving (the console routes these keys here wherever the
  /// focus is, except in text and number fields): Up/Down (W/S) step
  /// the speed by 0.05 m/s, Left/Right (A/D) the articulation by 2 degrees,
  /// Space stops. A key held down (`autoRepeat`) steps faster the longer it
  /// is held, up to four times the step. Returns whether the key was one of these.
  bool handleKey(int key, bool autoRepeat = false);

  /// Shows the measured joint positions (robot.joints order) beside the targets.
  void showMeasured(const std::vector<double>& jointPositions);

  /// Moves the drive controls to `speed` [m/s] and `articulationDeg`
  /// [degree] (clamped to the robot's limits) and sends one drive command.
  void setDrive(double speed, double articulationDeg);

  /// After a stop (e-stop, failsafe, re-arm, release, lost control, gait
  /// end): the controls show what the robot does: speed 0, the articulation
  /// and joint targets where `jointPositions` (robot.joints order, measured)
  /// say they are, no gait. Sends nothing.
  void syncToRobot(const std::vector<double>& jointPositions);
  /// Enables or disables everything that sends commands; `why` becomes their
  /// tooltip while disabled (e.g. "take control first").
  void setControlsEnabled(bool enabled, const QString& why = {});
  bool controlsEnabled() const;
  /// Why the controls are disabled ("" when enabled).
  QString toolTipWhenDisabled() const { return disabledWhy_; }

  double speed() const;         ///< [m/s] the drive's set speed
  double articulation() const;  ///< [rad] the drive's set articulation
  double maxSpeed() const { return maxSpeed_; }

 signals:
  /// A command for the robot (drive, joint target, gait, stop).
  void command(const sp::Command& command);
  /// A typed value was refused (beyond the robot's limits): why, for the operator.
  void refused(const QString& why);

 private:
  struct JointRow {
    int joint = -1;
    double scale = 1;  // display unit per SI unit (degrees or millimetres)
    QSlider* slider = nullptr;
    LimitSpinBox* spin = nullptr;
    QLabel* measured = nullptr;
  };
  void driveChanged();
  void stop();
  void gaitChanged(int index);

  const RobotModel* robot_ = nullptr;
  RobotModel model_;
  int heldKey_ = 0, repeats_ = 0;  // the key held down and its auto-repeats so far
  double maxSpeed_ = 0, maxArticulationDeg_ = 0;
  QSlider* speedSlider_ = nullptr;      // [cm/s]
  LimitSpinBox* speedSpin_ = nullptr;  // [m/s]
  QSlider* articulationSlider_ = nullptr;  // [0.1 degree]
  LimitSpinBox* articulationSpin_ = nullptr;  // [degree]
  QComboBox* gait_ = nullptr;
  QGroupBox* driveBox_ = nullptr;
  QVBoxLayout* jointsLayout_ = nullptr;
  QWidget* jointsHost_ = nullptr;
  QScrollArea* scroll_ = nullptr;
  std::vector<JointRow> rows_;
  std::vector<QWidget*> controlWidgets_;
  QString disabledWhy_;
  QTimer* driveTimer_ = nullptr;  // coalesces slider drags into one drive command per 50 ms
  bool updating_ = false;         // set while controls are moved programmatically
};

}  // namespace sp
