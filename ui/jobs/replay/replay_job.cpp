#include "ui/jobs/replay/replay_job.h"

#include <QCommandLineParser>

#include <algorithm>

#include <QAction>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QKeySequence>
#include <QMenu>
#include <QSettings>
#include <QTimer>

#include "app/console/console_session.h"
#include "ui/jobs/replay/replay_feed.h"
#include "ui/jobs/replay/replay_panel.h"
#include "ui/jobs/replay/session_logs_dialog.h"
#include "ui/robot_feed.h"

namespace sp {

QList<QCommandLineOption> ReplayJob::commandLineOptions() const {
  return {QCommandLineOption(QStringLiteral("replay"), tr("Open this session log in the Replay dock."), QStringLiteral("LOG"))};
}

QString ReplayJob::takeCommandLine(const QCommandLineParser& parser) {
  replay_ = parser.value(QStringLiteral("replay"));
  return {};
}

void ReplayJob::install(ConsoleContext& context) {
  context_ = &context;
  logDir_ = QString::fromStdString(context.session().logDir());
  panel_ = new ReplayPanel;
  panel_->setBackground(&context.background());
  feed_ = panel_->feed();
  dock_ = context.host().addDock(tr("Replay"), QStringLiteral("replayDock"), panel_, DockPlace::Bottom, true);
  dock_->hide();  // until a log is opened

  connect(panel_, &ReplayPanel::opened, this, &ReplayJob::opened);
  connect(panel_, &ReplayPanel::closed, this, &ReplayJob::closed);
  connect(panel_, &ReplayPanel::branchReady, this, [this](const QString& log, std::shared_ptr<const BranchPoint> point) {
    // The branch runs live now: the replay it came from closes, saying so
    // (it closed without a word) and how to see it again.
    if (!context_->host().startBranch(log, *point, false).isEmpty()) return;
    panel_->close();
    const QString text = tr("Simulating from %1 s of %2 in a new stand-in session; the replay closed "
                            "(File ▸ Open session log… shows it again)")
                             .arg(static_cast<double>(point->step) * point->logged.params.step, 0, 'f', 1)
                             .arg(QFileInfo(log).fileName());
    context_->event(QStringLiteral("replay"), text, false);
    context_->status(text, 10000);
  });
  connect(panel_, &ReplayPanel::failed, this, [this](const QString& message) {
    if (!panel_->isOpen()) dock_->hide();  // a log that did not open
    context_->status(message, 10000);
    if (message != tr("Cancelled.")) context_->showError(tr("Replay"), message);
  });
  connect(panel_, &ReplayPanel::rehearsalStart, &context, &ConsoleContext::rehearseFrom);
  connect(panel_, &ReplayPanel::verified, this,
          [this](bool, const QString& verdict) { context_->status(verdict, 15000); });
  // The dock is shown only while a log is open (its tab costs the view).
  connect(&context, &ConsoleContext::layoutReset, this, [this] {
    dock_->setVisible(panel_->isOpen());
    if (panel_->isOpen()) dock_->raise();
  });

  QAction* open = new QAction(tr("Open session &log…"), context.dialogParent());
  open->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_L));
  connect(open, &QAction::triggered, this, [this] {
    const QString path = QFileDialog::getOpenFileName(context_->dialogParent(), tr("Open session log"), logDir_,
                                                      tr("Session logs (*.splog);;All files (*)"));
    if (!path.isEmpty()) openLogInBackground(path);
  });
  // The last logs replayed, newest first (settings "replay/recent"); a
  // file gone since is left out when the menu opens.
  auto* recent = new QMenu(tr("&Recent session logs"), context.dialogParent());
  connect(recent, &QMenu::aboutToShow, this, [this, recent] {
    recent->clear();
    for (const QString& path : recentLogs())
      recent->addAction(QFileInfo(path).fileName(), this, [this, path] { openLogInBackground(path); })->setToolTip(path);
    if (recent->isEmpty()) recent->addAction(tr("(none yet)"))->setEnabled(false);
  });
  recent->setToolTipsVisible(true);
  QAction* logs = new QAction(tr("Session &logs…"), context.dialogParent());
  connect(logs, &QAction::triggered, this, &ReplayJob::showSessionLogs);
  QAction* close = new QAction(tr("Close replay"), context.dialogParent());
  connect(close, &QAction::triggered, panel_, &ReplayPanel::close);
  for (QAction* a : {open, recent->menuAction(), logs, close}) context.host().addMenuAction(tr("&File"), a);
}

QString ReplayJob::start() { return replay_.isEmpty() ? QString() : openLog(replay_, true); }

void ReplayJob::opened() {
  QStringList recent = recentLogs();
  const QString path = QFileInfo(QString::fromStdString(panel_->player()->path())).absoluteFilePath();
  recent.removeAll(path);
  recent.prepend(path);
  QSettings().setValue(QStringLiteral("replay/recent"), recent.mid(0, kRecent));
  context_->feeds().show(feed_);
  // Room for the timeline, the plot and the events without scrolling: the
  // default bottom dock (the live plots') is too low for them.
  // (After the window has laid out its docks: a log opened at start-up
  // would be laid out again.)
  QTimer::singleShot(0, dock_, [this] {
    // At least two fifths of the window, more if the panel needs it.
    context_->host().growDock(
        dock_, std::max(panel_->minimumSizeHint().height() + 40, context_->dialogParent()->height() * 2 / 5), 1.0);
  });
  context_->status(tr("Replaying %1: the live robot goes on unseen; close the replay to see it again")
                       .arg(QFileInfo(path).fileName()),
                   0);
}

void ReplayJob::closed() {
  dock_->hide();
  context_->feeds().show(nullptr);
  context_->status({}, 0);
}

QString ReplayJob::openLog(const QString& path, bool quiet) {
  const QString error = panel_->open(path);
  if (!error.isEmpty()) {
    if (!quiet) context_->showError(tr("Open session log"), error);
    return error;
  }
  dock_->show();
  dock_->raise();
  return {};
}

void ReplayJob::openLogInBackground(const QString& path) {
  dock_->show();  // its progress row shows the opening, with Cancel
  dock_->raise();
  panel_->openInBackground(path);
}

void ReplayJob::showSessionLogs() {
  SessionLogsDialog dialog(logDir_, QString::fromStdString(context_->session().logPath()), context_->dialogParent());
  connect(&dialog, &SessionLogsDialog::replayRequested, this, &ReplayJob::openLogInBackground);
  dialog.exec();
}

QStringList ReplayJob::recentLogs() const {
  QStringList logs;
  for (const QString& path : QSettings().value(QStringLiteral("replay/recent")).toStringList())
    if (QFileInfo::exists(path)) logs << path;
  return logs;
}

}  // namespace sp
