#pragma once
// The console's second job: rehearsing a command sequence on the twin
// before relaying exactly what passed (the Sequence dock, ui/jobs/sequence/
// sequence_panel.h). It rehearses from the live robot's newest telemetry,
// draws the rehearsed path and phantom in the 3D view, relays over the
// link, and is pinned to a replayed log's moment by the Replay job
// (ConsoleContext::rehearseFrom).
//
// Thread: GUI thread only.

#include "ui/console_context.h"

class QDockWidget;

namespace sp {

class SequencePanel;

class SequenceJob : public ConsoleJob {
  Q_OBJECT

 public:
  using ConsoleJob::ConsoleJob;
  QString name() const override { return QStringLiteral("sequence"); }
  /// --rules FILE (flight rules; the built-in defaults without), --sequence
  /// FILE (opened at the start), each found in the data folder too.
  QList<QCommandLineOption> commandLineOptions() const override;
  QString takeCommandLine(const QCommandLineParser& parser) override;
  void install(ConsoleContext& context) override;
  QString start() override;
  SequencePanel* panel() const { return panel_; }

 private:
  /// Grows the dock, when shown, to what its panel needs without scrolling.
  void fitDock();
  ConsoleContext* context_ = nullptr;
  SequencePanel* panel_ = nullptr;
  QDockWidget* dock_ = nullptr;
  QString rules_, sequence_;  // files; "" = the built-in rules, no sequence
};

}  // namespace sp
