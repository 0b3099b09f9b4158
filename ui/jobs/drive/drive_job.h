#pragma once
// The console's first job: driving the robot by hand. The Controls dock
// (speed, articulation, gaits, every joint) and the drive keys (arrows or
// W A S D, Space stops) wherever the focus is in the window, except where
// keys are typed. Commands go through the context's command sink, so the
// lease and the feed shown are checked in one place: while a replay is
// shown the controls are disabled and the keys act on nothing.
//
// Thread: GUI thread only.

#include <optional>

#include "ui/console_context.h"

class QDockWidget;

namespace sp {

class ControlPanel;

class DriveJob : public ConsoleJob {
  Q_OBJECT

 public:
  using ConsoleJob::ConsoleJob;
  ~DriveJob() override;
  QString name() const override { return QStringLiteral("drive"); }
  void install(ConsoleContext& context) override;
  /// --drive SPEED: drive at SPEED m/s once in control (demonstrations, measurements).
  QList<QCommandLineOption> commandLineOptions() const override;
  QString takeCommandLine(const QCommandLineParser& parser) override;
  QString start() override;
  ControlPanel* panel() const { return panel_; }

 protected:
  bool eventFilter(QObject* watched, QEvent* event) override;

 private:
  ConsoleContext* context_ = nullptr;
  ControlPanel* panel_ = nullptr;
  bool measuredDirty_ = false;  // the live robot's joints changed since the panel showed them
  std::optional<double> driveAtStart_;  // [m/s] --drive
};

}  // namespace sp
