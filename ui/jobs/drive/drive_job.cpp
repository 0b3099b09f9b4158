#include "ui/jobs/drive/drive_job.h"

#include <QAbstractSpinBox>
#include <QCommandLineParser>
#include <QApplication>
#include <QDockWidget>
#include <QKeyEvent>
#include <QLineEdit>
#include <QMessageBox>
#include <QAction>
#include <QPlainTextEdit>
#include <QTextEdit>
#include <QTimer>

#include <cmath>

#include "sim/robot_model.h"
#include "ui/jobs/drive/control_panel.h"
#include "ui/robot_feed.h"

namespace sp {

DriveJob::~DriveJob() {
  // A console that stops before its window (a bad command line) drops its
  // jobs after the application.
  if (qApp) qApp->removeEventFilter(this);
}

QList<QCommandLineOption> DriveJob::commandLineOptions() const {
  return {QCommandLineOption(QStringLiteral("drive"), tr("Drive at SPEED m/s once in control (for demonstrations)."),
                             QStringLiteral("SPEED"))};
}

QString DriveJob::takeCommandLine(const QCommandLineParser& parser) {
  if (!parser.isSet(QStringLiteral("drive"))) return {};
  bool ok = false;
  const QString text = parser.value(QStringLiteral("drive"));
  const double speed = text.toDouble(&ok);
  if (!ok || !(std::abs(speed) <= 10))
    return QStringLiteral("<command line>: error: --drive: expected a number in [-10, 10], got '%1'").arg(text);
  driveAtStart_ = speed;
  return {};
}

QString DriveJob::start() {
  if (!driveAtStart_) return {};
  // Once the lease is ours: it arrives over the link, so the state is polled.
  auto* poll = new QTimer(this);
  connect(poll, &QTimer::timeout, this, [this, poll] {
    if (!context_->state().leaseHeld()) return;
    panel_->setDrive(*driveAtStart_, 0.0);
    poll->stop();
  });
  poll->start(100);
  return {};
}

void DriveJob::install(ConsoleContext& context) {
  context_ = &context;
  panel_ = new ControlPanel;
  connect(panel_, &ControlPanel::command, this, [this](const Command& c) { context_->sendCommand(c); });
  connect(panel_, &ControlPanel::refused, this, [this](const QString& why) {
    context_->status(why, 6000);
    context_->event(QStringLiteral("refused"), why, false);
  });
  panel_->setControlsEnabled(false, tr("Take control first (Robot ▸ Take control)"));
  context.host().addDock(tr("Controls"), QStringLiteral("controlsDock"), panel_, DockPlace::Side, false);

  connect(&context, &ConsoleContext::worldChanged, this, [this](const WorldModel& world) {
    if (!world.robots.empty()) panel_->setRobot(world.robots[0].model);
  });
  connect(&context, &ConsoleContext::stateChanged, this, [this] {
    const QString why = QString::fromStdString(context_->state().controlsRefusal());
    panel_->setControlsEnabled(why.isEmpty(), why);
  });
  connect(&context, &ConsoleContext::robotStopped, this,
          [this] { panel_->syncToRobot(context_->measuredPositions()); });
  // The measured values are the live robot's, whatever the views show.
  connect(context.feeds().live(), &RobotFeed::frame, this, [this] { measuredDirty_ = true; });
  connect(&context, &ConsoleContext::panelTick, this, [this] {
    if (!measuredDirty_) return;
    panel_->showMeasured(context_->measuredPositions());
    measuredDirty_ = false;
  });
  auto* keys = new QAction(tr("&Keys"), context.dialogParent());
  connect(keys, &QAction::triggered, this, [this] {
    QMessageBox::information(context_->dialogParent(), tr("Keys"),
                             tr("Esc\temergency stop (anywhere; an open menu closes too, an open list only closes)\n"
                                "Up/Down, W/S\tspeed ± 0.05 m/s (held: faster)\n"
                                "Left/Right, A/D\tarticulation ± 2°\n"
                                "Space\tstop driving\n"
                                "F\tfollow the robot (3D view focused)\nHome\treset the view\n"
                                "Ctrl+N\tnote in the session log"));
  });
  context.host().addMenuAction(tr("&Help"), keys);
  // Drive keys wherever the focus is in this window: an application-wide
  // filter sees them before a focused button or slider can.
  qApp->installEventFilter(this);
}

bool DriveJob::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() != QEvent::KeyPress || !panel_) return false;
  auto* key = static_cast<QKeyEvent*>(event);
  if (key->modifiers() != Qt::NoModifier || !isDriveKey(key->key())) return false;
  // Not where keys are typed (a number box, a text field), and only in the
  // console's window: no button or slider with the focus ever turns Space
  // into a click or an arrow into a step.
  auto* widget = qobject_cast<QWidget*>(watched);
  const auto* line = qobject_cast<QLineEdit*>(watched);
  const auto* plain = qobject_cast<QPlainTextEdit*>(watched);
  const auto* rich = qobject_cast<QTextEdit*>(watched);
  const bool typing = qobject_cast<QAbstractSpinBox*>(watched) || (line && !line->isReadOnly()) ||
                      (plain && !plain->isReadOnly()) || (rich && !rich->isReadOnly());
  if (!widget || widget->window() != context_->dialogParent() || typing || QApplication::activePopupWidget()) return false;
  if (panel_->controlsEnabled()) panel_->handleKey(key->key(), key->isAutoRepeat());
  else if (!key->isAutoRepeat()) context_->status(panel_->toolTipWhenDisabled(), 3000);
  return true;
}

}  // namespace sp
