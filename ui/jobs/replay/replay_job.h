#pragma once
// The console's third job: replaying session logs. The Replay dock (shown
// while a log is open), File ▸ Open session log, Recent session logs,
// Session logs… and Close replay. An open log is a feed (ReplayFeed): the
// job shows it through the feed switch, so the 3D view and plots follow the
// replay's cursor, and the context's state says a replay is shown, which
// disables driving the live robot until the replay closes.
//
// Thread: GUI thread only.

#include <QStringList>

#include "ui/console_context.h"

class QDockWidget;

namespace sp {

class ReplayFeed;
class ReplayPanel;

class ReplayJob : public ConsoleJob {
  Q_OBJECT

 public:
  using ConsoleJob::ConsoleJob;
  QString name() const override { return QStringLiteral("replay"); }
  /// --replay LOG: a session log to open at the start.
  QList<QCommandLineOption> commandLineOptions() const override;
  QString takeCommandLine(const QCommandLineParser& parser) override;
  void install(ConsoleContext& context) override;
  QString start() override;

  ReplayPanel* panel() const { return panel_; }
  ReplayFeed* feed() const { return feed_; }
  /// Opens `path` and shows it (blocking): "" or why not (in a dialog unless `quiet`).
  QString openLog(const QString& path, bool quiet);
  /// Opens `path` on a worker, with progress and Cancel in the dock.
  void openLogInBackground(const QString& path);
  /// The session logs dialog (modal).
  void showSessionLogs();
  /// The last kRecent logs opened for replay that still exist, newest first.
  QStringList recentLogs() const;
  static constexpr int kRecent = 8;

 private:
  void opened();
  void closed();

  ConsoleContext* context_ = nullptr;
  ReplayPanel* panel_ = nullptr;
  ReplayFeed* feed_ = nullptr;
  QDockWidget* dock_ = nullptr;
  QString logDir_;  // where the session logs are: the session's
  QString replay_;  // a log to open at the start; "" = none
};

}  // namespace sp
