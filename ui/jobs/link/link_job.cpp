#include "ui/jobs/link/link_job.h"

#include <QCommandLineParser>

#include <QAction>
#include <QCoreApplication>
#include <QMenu>
#include <QMessageBox>
#include <QPushButton>

#include "app/console/console_session.h"
#include "app/console/terrain_editor.h"
#include "ui/connect_dialog.h"
#include "ui/link_panel.h"
#include "ui/robot_connection.h"
#include "ui/robot_feed.h"

namespace sp {

namespace {

QString qs(const std::string& s) { return QString::fromStdString(s); }

}  // namespace

QList<QCommandLineOption> LinkJob::commandLineOptions() const {
  return {QCommandLineOption(QStringLiteral("monitor"), tr("Do not take control on connecting."))};
}

QString LinkJob::takeCommandLine(const QCommandLineParser& parser) {
  takeControl_ = !parser.isSet(QStringLiteral("monitor"));
  return {};
}

void LinkJob::install(ConsoleContext& context) {
  context_ = &context;
  panel_ = new LinkPanel;
  context.host().addDock(tr("Link"), QStringLiteral("linkDock"), panel_, DockPlace::Link, false);
  RobotConnection& link = context.connection();
  connect(panel_, &LinkPanel::connectRequested, this, &LinkJob::connectToRobot);
  connect(panel_, &LinkPanel::disconnectRequested, &link, &RobotConnection::close);
  connect(panel_, &LinkPanel::takeControlRequested, &link, &RobotConnection::acquireLease);
  connect(panel_, &LinkPanel::releaseControlRequested, &link, &RobotConnection::releaseLease);
  connect(panel_, &LinkPanel::estopRequested, &context, &ConsoleContext::emergencyStop);
  connect(panel_, &LinkPanel::rearmRequested, this, &LinkJob::rearm);
  connect(&link, &RobotConnection::lease, panel_, &LinkPanel::showLease);
  connect(&link, &RobotConnection::connectionChanged, panel_, &LinkPanel::showConnection);
  connect(context.feeds().live(), &RobotFeed::event, this, [this](const QString& kind, const QString& text) {
    panel_->appendEvent(text);
    if (kind == QLatin1String("refused") || kind == QLatin1String("error")) context_->status(text, 5000);
  });
  connect(&context, &ConsoleContext::eventShown, panel_, &LinkPanel::appendEvent);
  connect(&context, &ConsoleContext::panelTick, this, [this] {
    panel_->showStats(context_->connection().stats());
    // Where the robot is, read at a glance: 3 times a second.
    if (++ticks_ % 3 == 0)
      panel_->showOdometry(qs(context_->state().poseText()), qs(context_->state().motionText()));
  });
  connect(&context, &ConsoleContext::resetRequested, this, &LinkJob::resetRobot);
  connect(&context, &ConsoleContext::sessionChanged, this, [this] {
    panel_->setEndpoint(qs(context_->session().endpoint().label));
    connectToRobot();
  });
  connect(&context, &ConsoleContext::stateChanged, this, [this] {
    const ConsoleState& s = context_->state();
    panel_->showLatches(s.failsafe(), s.estop());
    reconnect_->setEnabled(s.canReconnect());
    disconnect_->setEnabled(s.canDisconnect());
    take_->setEnabled(s.canTakeControl());
    release_->setEnabled(s.canReleaseControl());
    rearm_->setEnabled(s.canRearm());
    reset_->setEnabled(!context_->session().remote());
  });

  const QString robot = tr("&Robot");
  const auto add = [&](const QString& text, auto* receiver, auto slot) {
    auto* action = new QAction(text, context.dialogParent());  // the window owns its menus
    connect(action, &QAction::triggered, receiver, slot);
    context.host().addMenuAction(robot, action);
    return action;
  };
  const auto separator = [&] {
    auto* s = new QAction(context.dialogParent());
    s->setSeparator(true);
    context.host().addMenuAction(robot, s);
  };
  add(tr("&Connect to…"), this, &LinkJob::openConnectDialog);
  reconnect_ = add(tr("&Reconnect"), this, &LinkJob::connectToRobot);
  disconnect_ = add(tr("&Disconnect"), &link, &RobotConnection::close);
  separator();
  take_ = add(tr("&Take control"), &link, &RobotConnection::acquireLease);
  release_ = add(tr("Re&lease control"), &link, &RobotConnection::releaseLease);
  separator();
  // Esc itself is caught by the window's filter; the menu shows the key.
  add(tr("&E-stop\tEsc"), &context, &ConsoleContext::emergencyStop)
      ->setToolTip(tr("Emergency stop of the live robot, whatever the views show"));
  rearm_ = add(tr("Re-&arm…"), this, &LinkJob::rearm);
  separator();
  reset_ = add(tr("Re&set to the start"), this, &LinkJob::resetRobot);
  reset_->setToolTip(tr("Restart the stand-in with the robot where the world file puts it (logged)"));
}

void LinkJob::connectToRobot() {
  const ConsoleSession& session = context_->session();
  const RobotEndpoint& e = session.endpoint();
  if (e.port == 0) return;
  context_->connection().open(
      session.clientConfig(QStringLiteral("console@%1").arg(QCoreApplication::applicationPid()).toStdString()));
  if (takeControl_) context_->connection().acquireLease();
}

void LinkJob::openConnectDialog() {
  ConnectDialog dialog(context_->dialogParent(), [](const QString& hostPort, const QString& token) {
    std::string error;
    return parseEndpoint(hostPort.toStdString(), token.toStdString(), error) ? QString() : qs(error);
  });
  if (dialog.exec() != QDialog::Accepted) return;
  context_->connection().close();
  const std::string error = dialog.standIn() ? context_->useStandIn()
                                             : context_->connectTo(dialog.hostPort().toStdString(), dialog.token().toStdString());
  if (!error.empty()) {
    context_->showError(tr("Cannot connect"), qs(error));
    connectToRobot();  // back to where the console was
    return;
  }
  if (!dialog.standIn()) ConnectDialog::remember(dialog.hostPort());
  context_->event(QStringLiteral("link"), tr("connecting to %1").arg(qs(context_->session().endpoint().label)));
  context_->host().restarted(false);
}

void LinkJob::resetRobot() {
  // The stand-in restarts on the world file's terrain: edits not saved
  // would go without a word (issue 59). Asked first, Cancel the default.
  if (const TerrainEditor* t = context_->terrainEditor(); t && t->unsavedChanges() > 0) {
    if (!context_->confirm(QMessageBox::Warning, tr("Reset to the start"),
                           tr("The terrain has %n edit(s) not saved. Reset restarts the robot on the world file's "
                              "terrain: they would be lost.\n\nSave them first with Terrain ▸ Save as…, or reset "
                              "without them.",
                              nullptr, static_cast<int>(t->unsavedChanges())),
                           QStringLiteral("resetConfirm"), tr("Reset, losing the edits"), QMessageBox::DestructiveRole))
      return;
  }
  context_->connection().close();
  if (const std::string error = context_->resetRobot(); !error.empty()) {
    context_->status(qs(error), 6000);
    connectToRobot();
    return;
  }
  context_->event(QStringLiteral("note"), tr("reset: the robot is back at its start"));
  context_->host().restarted(true);
}

void LinkJob::rearm() {
  // Deliberate: a confirmation whose default is Cancel, so that no stray
  // Enter or Space re-arms a stopped robot.
  if (!context_->confirm(QMessageBox::Question, tr("Re-arm"),
                         tr("Re-arm the robot?\n\nThe latch clears; the robot stays stopped until the next command, "
                            "and the deadman counts from now."),
                         QStringLiteral("rearmConfirm"), tr("Re-arm")))
    return;
  emit context_->robotStopped();
  context_->event(QStringLiteral("rearm"), tr("re-arm sent"));
  context_->connection().rearm();
}

}  // namespace sp
