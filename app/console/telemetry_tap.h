#pragma once
// Telemetry's one way in. On the link's worker thread (net::RobotClient's
// callbacks, after the sequence guard), each frame is turned into a
// RobotFrame once and handed on, in this order, to the session log, the
// ghost's anchor and the calibration: none of them waits on the GUI, the
// disk or a fit (each copies under a short lock of its own). The GUI is
// given the frame to draw and relays it nowhere, so a window that stalls
// (a modal dialog, a loaded machine) stalls neither the log, nor the
// ghost's re-anchoring, nor the fits.
//
//   worker:  SequenceGuard -> TelemetryTap::telemetry() -> the GUI draws the frame
//                              |-> TelemetryRecorder (a remote robot's log)
//                              |-> Ghost::anchor()  (and the prediction's log row)
//                              `-> LiveCalibrator::frame()
//
// ConsoleSession owns the parts and binds them here; it unbinds them before
// it replaces or destroys any, and unbind() returns only once no frame is
// being handed to them.
//
// Thread: telemetry() and laser() from one thread at a time (the link's
// worker); bind(), unbind() and the readers from any other (the GUI's). The
// mutex is held while one frame is handed on (microseconds), never while
// waiting for anything.

#include <cstdint>
#include <mutex>
#include <optional>

#include "app/ghost/prediction_record.h"
#include "app/state/robot_frame.h"
#include "net/message.h"
#include "sim/robot_model.h"

namespace sp {

class Ghost;
class LiveCalibrator;
class StandInRobot;
class TelemetryRecorder;

class TelemetryTap {
 public:
  /// What the frames are handed to; each may be null.
  struct Parts {
    const RobotModel* robot = nullptr;  ///< the drawn world's robot: the frames' joint order
    Ghost* ghost = nullptr;
    LiveCalibrator* calibrator = nullptr;
    TelemetryRecorder* recorder = nullptr;  ///< the console's log of a remote robot
    StandInRobot* standIn = nullptr;        ///< whose log takes the ghost's predictions otherwise
  };
  /// A frame as it was handed on.
  struct Tapped {
    RobotFrame frame;  ///< to draw (joints in the robot's order)
    /// The frame against what the ghost had shown for its time, if it showed something then.
    std::optional<GhostError> prediction;
  };

  /// Hands the frames from now on to `parts`; forgets the last robot's
  /// joint mapping, rate and prediction.
  void bind(const Parts& parts);
  /// Hands them to nothing; returns once no frame is being handed on.
  void unbind() { bind(Parts{}); }

  /// A telemetry frame arrived at wall time `wall` [s]; `roundTrip` [s] is
  /// the link's as the client measures it (0 = not yet: the robot's own
  /// figure in the message is used).
  Tapped telemetry(const net::TelemetryMsg& message, double wall, double roundTrip);
  /// A laser scan arrived: into a remote robot's log.
  void laser(const net::LaserMsg& message);

  /// The newest frame's prediction (Tapped::prediction).
  std::optional<GhostError> lastPrediction() const;
  /// The robot's real-time factor over the last second of telemetry.
  double realTimeFactor() const;
  /// Frames handed on since the last bind().
  uint64_t frames() const;

 private:
  void logPrediction(const GhostError& error);  // under mutex_
  void logDeparture();  // the ghost's newest departure began or ended (under mutex_)

  mutable std::mutex mutex_;
  Parts parts_;
  JointNameMap positions_, rates_;
  RateMeter rate_;
  std::optional<GhostError> lastPrediction_;
  uint64_t frames_ = 0;
};

}  // namespace sp
