#include "ui/jobs/drive/control_panel.h"

#include "ui/limit_spin_box.h"

#include "sim/command_check.h"

#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QGridLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QScrollArea>
#include <QScrollBar>
#include <QSlider>
#include <QTimer>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>

namespace sp {

namespace {

constexpr double kSpeedKeyStep = 0.05;        // [m/s]
constexpr double kArticulationKeyStep = 2.0;  // [degree]

/// Slider ticks per displayed unit: sliders are integer, spin boxes are not.
constexpr double kTicks = 10.0;

int toTicks(double value) { return static_cast<int>(std::lround(value * kTicks)); }

}  // namespace

ControlPanel::ControlPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);

  driveBox_ = new QGroupBox(tr("Drive"), this);
  auto* drive = new QGridLayout(driveBox_);
  speedSlider_ = new QSlider(Qt::Horizontal);
  speedSlider_->setMinimumWidth(50);
  speedSpin_ = new LimitSpinBox;
  speedSpin_->setWhat(tr("speed"));
  speedSpin_->setSuffix(tr(" m/s"));
  speedSpin_->setDecimals(2);
  speedSpin_->setSingleStep(kSpeedKeyStep);
  speedSlider_->setToolTip(tr("Speed at the articulation hinge (keys Up/Down or W/S over the 3D view)"));
  articulationSlider_ = new QSlider(Qt::Horizontal);
  articulationSpin_ = new LimitSpinBox;
  articulationSpin_->setWhat(tr("articulation"));
  articulationSpin_->setSuffix(tr(" °"));
  articulationSpin_->setDecimals(1);
  articulationSpin_->setSingleStep(kArticulationKeyStep);
  articulationSlider_->setToolTip(tr("Articulation angle between front and rear body (keys Left/Right or A/D)"));
  drive->addWidget(new QLabel(tr("speed")), 0, 0);
  drive->addWidget(speedSlider_, 0, 1);
  drive->addWidget(speedSpin_, 0, 2);
  drive->addWidget(new QLabel(tr("articulation")), 1, 0);
  drive->addWidget(articulationSlider_, 1, 1);
  drive->addWidget(articulationSpin_, 1, 2);
  drive->setColumnStretch(1, 1);
  layout->addWidget(driveBox_);

  auto* modeRow = new QHBoxLayout;
  gait_ = new QComboBox;
  gait_->addItem(tr("rolling"), static_cast<int>(Gait::Off));
  gait_->addItem(tr("caterpillar"), static_cast<int>(Gait::Caterpillar));
  gait_->addItem(tr("rolking"), static_cast<int>(Gait::Rolking));
  gait_->setToolTip(tr("Locomotion mode: rolling on the wheels (driven by the sliders) or a gait"));
  auto* stopButton = new QPushButton(tr("Stop"));
  // No button takes the keyboard: Space and the arrows are drive keys
  // wherever the focus is, never a click on whatever button had it.
  stopButton->setFocusPolicy(Qt::NoFocus);
  stopButton->setToolTip(tr("Stop driving and any gait (key Space over the 3D view). For an emergency use E-STOP (Esc)."));
  modeRow->addWidget(new QLabel(tr("gait")));
  modeRow->addWidget(gait_, 1);
  modeRow->addWidget(stopButton);
  modeRow->setContentsMargins(0, 0, 0, 0);

  auto* jointsBox = new QGroupBox(tr("Joint targets"), this);
  auto* jointsOuter = new QVBoxLayout(jointsBox);
  scroll_ = new QScrollArea;
  auto* scroll = scroll_;
  scroll->setWidgetResizable(true);
  scroll->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  scroll->setFrameShape(QFrame::NoFrame);
  jointsHost_ = new QWidget;
  jointsLayout_ = new QVBoxLayout(jointsHost_);
  jointsLayout_->setContentsMargins(0, 0, 0, 0);
  scroll->setWidget(jointsHost_);
  jointsOuter->addWidget(scroll);
  layout->addWidget(jointsBox, 1);

  // Everything that sends a command; disabled without the lease.
  auto* gaitRow = new QWidget;
  gaitRow->setLayout(modeRow);
  layout->insertWidget(1, gaitRow);
  controlWidgets_ = {driveBox_, gaitRow, jointsBox};

  driveTimer_ = new QTimer(this);
  driveTimer_->setSingleShot(true);
  driveTimer_->setInterval(50);
  connect(driveTimer_, &QTimer::timeout, this,
          [this] { emit command(DriveCmd{speed(), degToRad(articulationSpin_->value())}); });

  // Slider and spin box mirror each other; either one schedules a command.
  connect(speedSlider_, &QSlider::valueChanged, this, [this](int v) {
    if (updating_) return;
    updating_ = true;
    speedSpin_->setValue(v / (100.0));
    updating_ = false;
    driveChanged();
  });
  connect(speedSpin_, &LimitSpinBox::accepted, this, [this](double v) {
    if (updating_) return;
    updating_ = true;
    speedSlider_->setValue(static_cast<int>(std::lround(v * 100)));
    updating_ = false;
    driveChanged();
  });
  connect(articulationSlider_, &QSlider::valueChanged, this, [this](int v) {
    if (updating_) return;
    updating_ = true;
    articulationSpin_->setValue(v / kTicks);
    updating_ = false;
    driveChanged();
  });
  connect(articulationSpin_, &LimitSpinBox::accepted, this, [this](double v) {
    if (updating_) return;
    updating_ = true;
    articulationSlider_->setValue(toTicks(v));
    updating_ = false;
    driveChanged();
  });
  connect(stopButton, &QPushButton::clicked, this, &ControlPanel::stop);
  for (LimitSpinBox* box : {speedSpin_, articulationSpin_}) connect(box, &LimitSpinBox::refused, this, &ControlPanel::refused);
  connect(gait_, &QComboBox::activated, this, &ControlPanel::gaitChanged);
}

void ControlPanel::setRobot(const RobotModel& robot) {
  model_ = robot;
  robot_ = &model_;
  maxSpeed_ = 0;
  maxArticulationDeg_ = 0;
  if (model_.drive) {
    // The drive is as fast as its slowest wheel allows (what the robot checks).
    const double top = driveSpeedLimit(model_);
    maxSpeed_ = std::isfinite(top) ? top : 0;
    if (model_.drive->articulation >= 0) {
      const JointSpec& j = model_.joints[static_cast<size_t>(model_.drive->articulation)];
      maxArticulationDeg_ = j.limited ? radToDeg(std::min(std::abs(j.lower), std::abs(j.upper))) : 45.0;
    }
  }
  // Ranges in whole display steps inside the limits; the epsilon keeps a
  // limit of 30 degrees (0.5236 rad = 29.99999 degrees) at 30.
  const double speedCm = std::floor(maxSpeed_ * 100 + 1e-6);
  const double articulationDeg = std::floor(maxArticulationDeg_ + 1e-6);
  updating_ = true;
  speedSlider_->setRange(-static_cast<int>(speedCm), static_cast<int>(speedCm));
  speedSpin_->setLimits(-speedCm / 100, speedCm / 100);
  articulationSlider_->setRange(-toTicks(articulationDeg), toTicks(articulationDeg));
  articulationSpin_->setLimits(-articulationDeg, articulationDeg);
  speedSlider_->setValue(0);
  speedSpin_->setValue(0);
  articulationSlider_->setValue(0);
  articulationSpin_->setValue(0);
  gait_->setCurrentIndex(0);
  updating_ = false;
  driveBox_->setEnabled(model_.drive.has_value());

  // One row per joint the operator positions: those with a position
  // controller, except the drive's own joints.
  while (QLayoutItem* item = jointsLayout_->takeAt(0)) {
    delete item->widget();
    delete item;
  }
  rows_.clear();
  auto* grid = new QWidget;
  auto* gl = new QGridLayout(grid);
  gl->setContentsMargins(0, 0, 0, 0);
  for (const ActuatorSpec& act : model_.actuators) {
    if (!act.hasPid || act.joint < 0) continue;
    if (model_.drive && (act.joint == model_.drive->articulation ||
                         std::find(model_.drive->wheels.begin(), model_.drive->wheels.end(), act.joint) !=
                             model_.drive->wheels.end()))
      continue;
    const JointSpec& joint = model_.joints[static_cast<size_t>(act.joint)];
    JointRow row;
    row.joint = act.joint;
    const bool slider = joint.type == JointType::Slider;
    row.scale = slider ? 1000.0 : radToDeg(1.0);
    const double lo = joint.limited ? joint.lower * row.scale : (slider ? -1000.0 : -180.0);
    const double hi = joint.limited ? joint.upper * row.scale : (slider ? 1000.0 : 180.0);
    row.slider = new QSlider(Qt::Horizontal);
    row.slider->setRange(toTicks(lo), toTicks(hi));
    row.slider->setMinimumWidth(50);
    row.spin = new LimitSpinBox;
    row.spin->setLimits(lo, hi);
    row.spin->setWhat(tr("%1 target").arg(QString::fromStdString(joint.name)));
    row.spin->setDecimals(1);
    row.spin->setSuffix(slider ? tr(" mm") : tr(" °"));
    const double initial = std::clamp(act.initialTarget * row.scale, lo, hi);
    row.slider->setValue(toTicks(initial));
    row.spin->setValue(initial);
    // Named by joint, for tests and style sheets.
    row.slider->setObjectName(QStringLiteral("slider_") + QString::fromStdString(joint.name));
    row.spin->setObjectName(QStringLiteral("target_") + QString::fromStdString(joint.name));
    row.measured = new QLabel(QStringLiteral("–"));
    row.measured->setObjectName(QStringLiteral("measured_") + QString::fromStdString(joint.name));
    row.measured->setMinimumWidth(row.measured->fontMetrics().horizontalAdvance(QStringLiteral("-000.0 mm")));
    row.measured->setToolTip(tr("Measured position (telemetry)"));
    auto* name = new QLabel(QString::fromStdString(joint.name));
    const int r = static_cast<int>(rows_.size());
    gl->addWidget(name, r, 0);
    gl->addWidget(row.slider, r, 1);
    gl->addWidget(row.spin, r, 2);
    gl->addWidget(row.measured, r, 3);
    const size_t index = rows_.size();
    // A slider sends when released (or on a key step), the spin box on each
    // committed value: the robot gets targets, not every pixel of a drag.
    connect(row.slider, &QSlider::valueChanged, this, [this, index](int v) {
      JointRow& rw = rows_[index];
      const QSignalBlocker block(rw.spin);
      rw.spin->setValue(v / kTicks);
      if (!rw.slider->isSliderDown() && !updating_)
        emit command(JointTargetCmd{model_.joints[static_cast<size_t>(rw.joint)].name, rw.spin->value() / rw.scale});
    });
    connect(row.slider, &QSlider::sliderReleased, this, [this, index] {
      JointRow& rw = rows_[index];
      emit command(JointTargetCmd{model_.joints[static_cast<size_t>(rw.joint)].name, rw.spin->value() / rw.scale});
    });
    connect(row.spin, &LimitSpinBox::refused, this, &ControlPanel::refused);
    connect(row.spin, &LimitSpinBox::accepted, this, [this, index](double v) {
      JointRow& rw = rows_[index];
      const QSignalBlocker block(rw.slider);
      rw.slider->setValue(toTicks(v));
      if (!updating_) emit command(JointTargetCmd{model_.joints[static_cast<size_t>(rw.joint)].name, v / rw.scale});
    });
    rows_.push_back(row);
  }
  gl->setColumnStretch(1, 1);
  jointsLayout_->addWidget(grid);
  // Rows scroll vertically only: the area is as wide as a row.
  scroll_->setMinimumWidth(grid->minimumSizeHint().width() + scroll_->verticalScrollBar()->sizeHint().width() + 4);
  jointsLayout_->addStretch(1);
}

bool isDriveKey(int key) {
  switch (key) {
    case Qt::Key_Up: case Qt::Key_W: case Qt::Key_Down: case Qt::Key_S:
    case Qt::Key_Left: case Qt::Key_A: case Qt::Key_Right: case Qt::Key_D:
    case Qt::Key_Space: return true;
    default: return false;
  }
}

bool ControlPanel::handleKey(int key, bool autoRepeat) {
  if (!model_.drive) return false;
  // Held down, a key steps faster the longer it is held (0.6 m/s took 12
  // presses): once per auto-repeat, up to four steps at a time. A press
  // of its own is always one step.
  repeats_ = autoRepeat && key == heldKey_ ? repeats_ + 1 : 0;
  heldKey_ = key;
  const double times = std::min(4.0, 1.0 + repeats_ / 8.0);
  switch (key) {
    case Qt::Key_Up:
    case Qt::Key_W: setDrive(speed() + times * kSpeedKeyStep, articulationSpin_->value()); return true;
    case Qt::Key_Down:
    case Qt::Key_S: setDrive(speed() - times * kSpeedKeyStep, articulationSpin_->value()); return true;
    case Qt::Key_Left:
    case Qt::Key_A: setDrive(speed(), articulationSpin_->value() + times * kArticulationKeyStep); return true;
    case Qt::Key_Right:
    case Qt::Key_D: setDrive(speed(), articulationSpin_->value() - times * kArticulationKeyStep); return true;
    case Qt::Key_Space: stop(); return true;
    default: return false;
  }
}

void ControlPanel::showMeasured(const std::vector<double>& jointPositions) {
  for (JointRow& row : rows_) {
    const auto j = static_cast<size_t>(row.joint);
    if (j >= jointPositions.size()) continue;
    row.measured->setText(formatFixed(jointPositions[j] * row.scale, 1) + row.spin->suffix());
  }
}

double ControlPanel::speed() const { return speedSpin_->value(); }
double ControlPanel::articulation() const { return degToRad(articulationSpin_->value()); }

void ControlPanel::setDrive(double newSpeed, double articulationDeg) {
  // Clamped to the robot's limits: a key never asks for more.
  speedSpin_->setValue(std::clamp(newSpeed, speedSpin_->lower(), speedSpin_->upper()));
  articulationSpin_->setValue(std::clamp(articulationDeg, articulationSpin_->lower(), articulationSpin_->upper()));
}

void ControlPanel::syncToRobot(const std::vector<double>& jointPositions) {
  driveTimer_->stop();
  updating_ = true;
  speedSpin_->setValue(0);
  speedSlider_->setValue(0);
  // The articulation and the joints hold where they are after a stop: the
  // controls show that, so that the next key press starts from it.
  double articulationDeg = 0;
  if (model_.drive && static_cast<size_t>(model_.drive->articulation) < jointPositions.size())
    articulationDeg = radToDeg(jointPositions[static_cast<size_t>(model_.drive->articulation)]);
  articulationDeg = std::clamp(articulationDeg, articulationSpin_->lower(), articulationSpin_->upper());
  articulationSpin_->setValue(articulationDeg);
  articulationSlider_->setValue(toTicks(articulationDeg));
  for (JointRow& row : rows_) {
    const auto j = static_cast<size_t>(row.joint);
    if (j >= jointPositions.size()) continue;
    const double v = std::clamp(jointPositions[j] * row.scale, row.spin->lower(), row.spin->upper());
    const QSignalBlocker blockSpin(row.spin), blockSlider(row.slider);
    row.spin->setValue(v);
    row.slider->setValue(toTicks(v));
  }
  {
    const QSignalBlocker block(gait_);
    gait_->setCurrentIndex(0);
  }
  updating_ = false;
}

void ControlPanel::setControlsEnabled(bool enabled, const QString& why) {
  disabledWhy_ = enabled ? QString() : why;
  for (QWidget* w : controlWidgets_) {
    w->setEnabled(enabled);
    w->setToolTip(enabled ? QString() : why);
  }
  if (!enabled) driveTimer_->stop();
}

bool ControlPanel::controlsEnabled() const { return controlWidgets_.empty() || controlWidgets_.front()->isEnabled(); }

void ControlPanel::driveChanged() {
  if (gait_->currentIndex() != 0) {
    // Driving ends a gait on the robot: show it.
    const QSignalBlocker block(gait_);
    gait_->setCurrentIndex(0);
  }
  if (!driveTimer_->isActive()) driveTimer_->start();
}

void ControlPanel::stop() {
  driveTimer_->stop();
  updating_ = true;
  speedSpin_->setValue(0);
  speedSlider_->setValue(0);
  updating_ = false;
  const QSignalBlocker block(gait_);
  gait_->setCurrentIndex(0);
  emit command(StopCmd{});
}

void ControlPanel::gaitChanged(int index) {
  const auto gait = static_cast<Gait>(gait_->itemData(index).toInt());
  driveTimer_->stop();
  updating_ = true;
  speedSpin_->setValue(0);
  speedSlider_->setValue(0);
  updating_ = false;
  emit command(GaitCmd{gait});
}

}  // namespace sp
