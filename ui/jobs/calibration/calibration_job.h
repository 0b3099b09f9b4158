#pragma once
// The console's calibration job: the Calibration dock (ui/jobs/calibration/
// calibration_panel.h) over the session's live calibrator (app/calibration/
// live_calibrator.h): shows each fit, says a refused one in the event list,
// freezes, resets to the files, saves a parameters file. While a replay is
// shown, the replayed log's calibration table.
//
// Thread: GUI thread only.

#include <cstdint>
#include <string>

#include "ui/console_context.h"

namespace sp {

class CalibrationPanel;

class CalibrationJob : public ConsoleJob {
  Q_OBJECT

 public:
  using ConsoleJob::ConsoleJob;
  QString name() const override { return QStringLiteral("calibration"); }
  void install(ConsoleContext& context) override;
  CalibrationPanel* panel() const { return panel_; }
  /// Writes the values the twins use now as a parameters file: "" or why not.
  QString save(const QString& path) const;
  /// save(), then what the status bar says of it: where, and whether the
  /// file holds a calibration or (after a reset) the files' own values.
  /// Empty `error` on success; else it is why not.
  QString saveAndSay(const QString& path, QString& error) const;

 private:
  void refresh();

  ConsoleContext* context_ = nullptr;
  CalibrationPanel* panel_ = nullptr;
  int64_t seen_ = -1;       // the calibrator's version shown
  const void* calibrator_ = nullptr;  // the one seen_ counts (a new world makes another)
  QString replayed_;        // the log shown, "" when live
};

}  // namespace sp
