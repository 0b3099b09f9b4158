#include "ui/jobs/calibration/calibration_job.h"

#include <QFileDialog>
#include <QFileInfo>
#include <QSaveFile>

#include "app/console/console_session.h"
#include "app/log/session_log.h"
#include "sim/file_set.h"
#include "sim/perturbation.h"
#include "ui/jobs/calibration/calibration_panel.h"
#include "ui/robot_feed.h"

namespace sp {

void CalibrationJob::install(ConsoleContext& context) {
  context_ = &context;
  panel_ = new CalibrationPanel;
  context.host().addDock(tr("Calibration"), QStringLiteral("calibrationDock"), panel_, DockPlace::Side, true);
  connect(panel_, &CalibrationPanel::freezeToggled, this, [this](bool frozen) {
    if (LiveCalibrator* c = context_->calibrator()) {
      c->freeze(frozen);
      context_->logEvent(QStringLiteral("calibration"), frozen ? tr("frozen") : tr("unfrozen"));
    }
  });
  connect(panel_, &CalibrationPanel::resetRequested, this, [this] {
    if (LiveCalibrator* c = context_->calibrator()) {
      c->reset();
      context_->event(QStringLiteral("calibration"), tr("Calibration reset to the files' values"));
    }
  });
  connect(panel_, &CalibrationPanel::saveRequested, this, [this] {
    QString filter = tr("Parameters (*.params)");
    const QString path = QFileDialog::getSaveFileName(panel_, tr("Save the calibration"), QStringLiteral("calibrated.params"),
                                                      tr("Parameters (*.params);;Robot file (*.xml)"), &filter);
    if (path.isEmpty()) return;
    QString error;
    const QString said = saveAndSay(path, error);
    if (error.isEmpty()) context_->status(said);
    else context_->showError(tr("Save the calibration"), error);
  });
  connect(&context, &ConsoleContext::panelTick, this, &CalibrationJob::refresh);
  connect(&context, &ConsoleContext::stateChanged, this, &CalibrationJob::refresh);
}

QString CalibrationJob::saveAndSay(const QString& path, QString& error) const {
  error = save(path);
  if (!error.isEmpty()) return {};
  // After a reset the file holds the files' own values: said so, not as if
  // it held a calibration (issue 59).
  const LiveCalibrator* c = context_->session().calibrator();
  if (c && c->fullPhysics() == filesCalValues())
    return tr("Saved to %1: it holds the robot files' own values (nothing is calibrated since the reset)").arg(path);
  return tr("Calibration saved to %1").arg(path);
}

QString CalibrationJob::save(const QString& path) const {
  const LiveCalibrator* c = context_->session().calibrator();
  if (!c) return tr("No calibration runs (it needs the ghost).");
  const CalibrationState s = c->state();
  std::string text;
  if (!path.endsWith(QLatin1String(".xml"), Qt::CaseInsensitive)) {
    // What the full-physics twins use now, as a fit's text: a file stands
    // for the robot, and a split the full physics did not confirm is the
    // ghost's profile speaking, not the robot (calibration.h).
    CalibrationFit fit;
    fit.value = s.fullPhysics;
    fit.sigma = s.sigma;
    fit.observed = s.observed;
    for (size_t i = 0; i < kCalParams; ++i)
      if (s.fullPhysics[i] != s.applied[i]) fit.observed[i] = false;
    if (!s.history.empty()) {
      fit.from = s.history.front().from;
      fit.to = s.history.back().to;
      fit.segments = s.history.back().segments;
    }
    text = calibrationParamsText(fit);
  } else {
    // A robot file: the files' robot with the values written in.
    const WorldModel* world = context_->session().world();
    if (!world || world->robots.empty()) return tr("No robot loaded.");
    const RobotModel& robot = world->robots[0].model;
    const std::optional<std::string> original = readSourceFile(robot.file, nullptr);
    if (!original) return tr("%1: cannot read the robot file").arg(QString::fromStdString(robot.file));
    std::string error;
    std::optional<std::string> calibrated =
        calibratedRobotText(*original, robot, withCalValues(context_->session().params(), s.fullPhysics), error);
    if (!calibrated) return QString::fromStdString(error);
    text = std::move(*calibrated);
  }
  QSaveFile file(path);
  if (!file.open(QIODevice::WriteOnly) || file.write(text.data(), static_cast<qint64>(text.size())) < 0 || !file.commit())
    return tr("%1: %2").arg(path, file.errorString());
  return {};
}

void CalibrationJob::refresh() {
  // A replay shows the log's calibration; the live one comes back after.
  const QString log = context_->state().replaying() ? context_->feeds().current()->logPath() : QString();
  if (log != replayed_) {
    replayed_ = log;
    if (log.isEmpty()) {
      panel_->clearReplayed();
      seen_ = -1;
    } else {
      std::string error;
      std::unique_ptr<SessionLogReader> reader = SessionLogReader::open(log.toStdString(), error);
      panel_->setReplayed(reader ? reader->calibration() : std::vector<LogCalibration>{}, QFileInfo(log).fileName());
    }
  }
  if (!replayed_.isEmpty()) return;
  const LiveCalibrator* c = context_->session().calibrator();
  if (c != calibrator_) {
    calibrator_ = c;
    seen_ = -1;
  }
  if (!c) {
    if (seen_ != 0)
      panel_->setLive(nullptr, context_->session().ghost()
                                   ? tr("Calibration is off.")
                                   : tr("No calibration: it runs with the predictive ghost, which is off or could not be built."));
    seen_ = 0;
    return;
  }
  if (c->version() == seen_) return;
  const CalibrationState s = c->state();
  seen_ = s.version;
  panel_->setLive(&s);
  // Refused fits are said in the panel (its status line) and logged by
  // the session with every fit: the link's event list keeps the link and
  // the safety chain in view (issue 59: it was flooded by calibration).
}

}  // namespace sp
