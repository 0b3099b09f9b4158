#pragma once
// The console's session log when it is connected to a robot it does not run
// (`simpartner --connect`): what the link showed and what the operator did,
// in the session-log format (docs/session-format.md) so the same reader,
// export and replay read it. It holds no snapshots or state hashes (the
// robot's physics is not here), so it cannot be re-simulated; meta key
// `log_source` is `telemetry` and `robot_endpoint` names the robot.
//
// Steps: the robot's own step is not on the link; rows carry the robot's
// time in milliseconds as their step.
//
// Thread: telemetry() and laser() from one thread (the link's worker,
// through app/console/telemetry_tap.h), the rest from one other (the GUI's);
// nothing blocks on the disk (SessionLogWriter queues, under its own lock).

#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "app/state/robot_frame.h"
#include "app/log/session_log.h"
#include "net/message.h"
#include "sim/robot_model.h"

namespace sp {

class TelemetryRecorder {
 public:
  /// Creates the log at `path` (must not exist) with the world file the
  /// console draws (its robot file too) in the meta. nullptr and `error`
  /// when it cannot be created.
  static std::unique_ptr<TelemetryRecorder> open(const std::string& path, const WorldModel& world,
                                                 const std::string& endpoint, std::string& error);

  /// A state sample; joint values are stored in `robot`'s joint order
  /// (telemetry names mapped; joints the robot did not report are zero).
  void telemetry(const net::TelemetryMsg& message, const RobotModel& robot);
  void laser(const net::LaserMsg& message);
  /// A command the operator sent (source "operator"), at the robot time it
  /// is expected to take effect (`arrival`: the ghost's clock estimate,
  /// app/ghost/ghost_clock.h), or without one at the latest telemetry's.
  void command(const Command& command, const RobotModel* robot, std::optional<double> arrival = std::nullopt);
  /// An event ("link", "estop", "note", ...) at the latest robot time.
  void event(const std::string& kind, const std::string& text);
  /// What the console's ghost predicted for a frame (app/ghost/ghost.h).
  void prediction(const LogPrediction& prediction) { writer_->logPrediction(prediction); }
  /// A calibration fit's row (app/calibration).
  void calibration(const LogCalibration& row) { writer_->logCalibration(row); }

  const SessionLogWriter& writer() const { return *writer_; }
  const std::string& path() const { return writer_->path(); }

 private:
  explicit TelemetryRecorder(std::unique_ptr<SessionLogWriter> writer) : writer_(std::move(writer)) {}
  /// The row key of the latest telemetry: robot time in whole milliseconds
  /// (the robot's own step count is not on the link).
  int64_t rowKey() const;

  std::unique_ptr<SessionLogWriter> writer_;
  std::atomic<double> time_{0};  // robot time of the latest telemetry [s]: written by telemetry(), read by the rest
  JointNameMap joints_;  // telemetry joint names -> the robot's order
};

}  // namespace sp
