#pragma once
// The console's link to the robot as a job: the Link dock (connection,
// lease, round trip, the event list, E-STOP and Re-arm buttons) and the
// Robot menu (connect to a robot or the stand-in, reconnect, disconnect,
// take and release control, e-stop, re-arm, reset the stand-in). It
// (re)connects whenever the session's endpoint changes
// (ConsoleContext::sessionChanged).
//
// The e-stop itself is the context's (ConsoleContext::emergencyStop): the
// window's Esc key, this dock's button and the menu item send the same one,
// without waiting for any dialog or the log.
//
// Thread: GUI thread only.

#include "ui/console_context.h"

namespace sp {

class LinkPanel;

class LinkJob : public ConsoleJob {
  Q_OBJECT

 public:
  using ConsoleJob::ConsoleJob;
  QString name() const override { return QStringLiteral("link"); }
  /// --monitor: do not ask for the lease on connecting.
  QList<QCommandLineOption> commandLineOptions() const override;
  QString takeCommandLine(const QCommandLineParser& parser) override;
  void install(ConsoleContext& context) override;
  LinkPanel* panel() const { return panel_; }

  /// (Re)connects to the session's endpoint (nothing before it has one).
  void connectToRobot();
  /// Robot ▸ Connect to…: a robot's HOST:PORT and token, or the stand-in.
  void openConnectDialog();
  /// Robot ▸ Reset to the start: restarts the stand-in (logged).
  void resetRobot();
  /// Asks the operator to confirm (default: No), then re-arms.
  void rearm();

 private:
  ConsoleContext* context_ = nullptr;
  LinkPanel* panel_ = nullptr;
  bool takeControl_ = true;  // ask for the lease as soon as connected
  QAction* reconnect_ = nullptr;
  QAction* disconnect_ = nullptr;
  QAction* take_ = nullptr;
  QAction* release_ = nullptr;
  QAction* rearm_ = nullptr;
  QAction* reset_ = nullptr;
  int ticks_ = 0;  // panel ticks seen
};

}  // namespace sp
