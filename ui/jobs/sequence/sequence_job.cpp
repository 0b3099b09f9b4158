#include "ui/jobs/sequence/sequence_job.h"

#include <QCommandLineParser>

#include <utility>

#include "app/data/data_files.h"

#include <algorithm>

#include <QDockWidget>
#include <QFile>
#include <QTimer>

#include "app/console/console_session.h"
#include "sim/diagnostics.h"
#include "ui/jobs/sequence/sequence_panel.h"
#include "ui/robot_feed.h"
#include "ui/scene_view.h"

namespace sp {

QList<QCommandLineOption> SequenceJob::commandLineOptions() const {
  return {QCommandLineOption(QStringLiteral("rules"),
                             tr("Flight rules for rehearsals (default: built-in, see config/flight.rules)."),
                             QStringLiteral("FILE")),
          QCommandLineOption(QStringLiteral("sequence"), tr("Open this command sequence in the Sequence dock."),
                             QStringLiteral("FILE"))};
}

QString SequenceJob::takeCommandLine(const QCommandLineParser& parser) {
  // Named relative to the data folder (terrains/...) they are found there
  // from any working directory (app/data/data_files.h).
  for (const auto& [option, file] : {std::pair{QStringLiteral("rules"), &rules_}, std::pair{QStringLiteral("sequence"), &sequence_}}) {
    if (!parser.isSet(option)) continue;
    std::string error;
    *file = QString::fromStdString(findDataFile(parser.value(option).toStdString(), error));
    if (!error.empty()) return QString::fromStdString(error);  // "FILE: error: not found; looked in ..."
  }
  return {};
}

void SequenceJob::install(ConsoleContext& context) {
  context_ = &context;
  panel_ = new SequencePanel;
  panel_->setBackground(&context.background());
  dock_ = context.host().addDock(tr("Sequence"), QStringLiteral("sequenceDock"), panel_, DockPlace::Side, true);

  // Rehearsals start from the live robot's newest telemetry.
  panel_->setStartProvider([this]() -> std::optional<RehearsalStart> {
    const auto* live = qobject_cast<const LiveLinkFeed*>(context_->feeds().live());
    const RobotModel* robot = context_->session().robot();
    if (!live || !live->lastTelemetry() || !robot) return std::nullopt;
    std::string why;
    std::optional<RehearsalStart> start = startFromTelemetry(*live->lastTelemetry(), *robot, why);
    if (!start) context_->status(tr("Rehearsing from the world's start: %1").arg(QString::fromStdString(why)), 6000);
    return start;
  });

  connect(panel_, &SequencePanel::sendRequested, this, [this](const net::SequenceMsg& m) {
    // Refused here (a replay shown, the lease lost meanwhile): the guard
    // the panel armed for it watches nothing.
    if (const QString why = context_->sendSequence(m); !why.isEmpty()) {
      context_->guard()->reset();
      context_->status(tr("Sequence not sent: %1").arg(why), 5000);
    }
  });
  connect(panel_, &SequencePanel::abortRequested, &context, &ConsoleContext::abortSequence);
  connect(&context, &ConsoleContext::sequenceState, panel_, &SequencePanel::onSequenceState);
  panel_->setGuard(context.guard());
  connect(&context, &ConsoleContext::guardTripped, panel_, &SequencePanel::onGuardTripped);

  SceneView& scene = context.scene();
  connect(panel_, &SequencePanel::scrubbed, &scene, [&scene](const Pose& base, const std::vector<double>& joints) {
    scene.setRehearsalState(base, joints);
    scene.setRehearsalRobotShown(true);
    scene.setRehearsalVisible(true);
  });
  // After the run the amber robot stood where it was last scrubbed, in the
  // follow camera's way: its path stays, the robot goes (scrubbing shows it).
  connect(panel_, &SequencePanel::runEnded, &scene, [&scene] { scene.setRehearsalRobotShown(false); });
  connect(panel_, &SequencePanel::pathChanged, &scene,
          [&scene](const std::vector<Vec3>& path, const std::vector<Vec3>& envelope, const std::vector<double>& band) {
            scene.setRehearsalPath(path);
            scene.setRehearsalEnvelope(envelope);
            scene.setRehearsalBand(band);
            scene.setRehearsalVisible(!path.empty());
          });
  connect(panel_, &SequencePanel::logEvent, this,
          [this](const QString& kind, const QString& text) { context_->logEvent(kind, text); });
  connect(panel_, &SequencePanel::alert, this, [this](const QString& text) {
    context_->event(QStringLiteral("sequence"), text, false);
    context_->status(text, 10000);
    dock_->raise();
  });

  // Shown (its tab raised): room for all its controls without scrolling,
  // taken from the link dock under it (at 1280x800 half the height left
  // Rehearse, the verdicts, Watch and Send below the fold).
  connect(dock_, &QDockWidget::visibilityChanged, this, [this](bool visible) {
    if (visible) QTimer::singleShot(0, dock_, [this] { fitDock(); });
  });
  connect(&context, &ConsoleContext::stateChanged, this,
          [this] { panel_->setLinkReady(context_->state().controlsRefusal().empty()); });
  connect(&context, &ConsoleContext::worldChanged, this, [this](const WorldModel&, bool fresh) {
    // Rehearsals run the twin as calibrated when they start (app/calibration).
    if (fresh)
      panel_->setWorld([this] { return context_->session().world(); }, [this] { return context_->session().twinParams(); },
                       [this] { return context_->session().twinEstimate(); });
  });
  connect(&context, &ConsoleContext::terrainEdited, panel_, [this] { panel_->terrainEdited(); });
  connect(&context, &ConsoleContext::rehearseFrom, this,
          [this](const RehearsalStart& start, const WorldModel& world, const SimParams& params, const QString& label) {
            panel_->pinStart(start, world, params, label);
            dock_->show();
            dock_->raise();
            context_->status(tr("The Sequence dock rehearses from %1 now").arg(label), 8000);
          });
}

void SequenceJob::fitDock() {
  if (!dock_->isVisible() || dock_->isFloating()) return;
  // The panel's least height, its dock's title and the scroll area's frame.
  context_->host().growDock(dock_, panel_->minimumSizeHint().height() + dock_->height() - dock_->widget()->height() + 4,
                            0.7);
}

QString SequenceJob::start() {
  if (!rules_.isEmpty()) {
    FlightRules rules;
    Diagnostics diag;
    if (!loadFlightRules(rules_.toStdString(), rules, diag)) return QString::fromStdString(diag.format()).trimmed();
    panel_->setRules(rules);
  }
  if (!sequence_.isEmpty()) {
    QFile f(sequence_);
    if (!f.open(QIODevice::ReadOnly) || f.size() > 1 << 20)
      return tr("%1: error: cannot read sequence file (or larger than 1 MiB)").arg(sequence_);
    panel_->setText(QString::fromUtf8(f.readAll()));
    // Opened on the command line to be rehearsed: its tab in front, once
    // the window has laid out its docks.
    QTimer::singleShot(0, dock_, [this] {
      dock_->show();
      dock_->raise();
      fitDock();
    });
  }
  return {};
}

}  // namespace sp
