#pragma once
// What the ghost showed for which robot time, and each telemetry frame
// against it: the ghost's prediction error (horizontal distance and yaw
// difference), and its median over the last kErrorWindow of robot time.
//
// Thread: a plain value; its owner guards it (the Ghost's mutex).

#include <deque>
#include <optional>
#include <utility>

#include "app/ghost/ghost_region.h"
#include "app/state/robot_frame.h"
#include "sim/math.h"

namespace sp {

/// A telemetry frame against what the ghost had shown for its time.
struct GhostError {
  double time = 0;      ///< [s] robot time of the frame
  double made = 0;      ///< [s] robot time of the telemetry the prediction ran from
  Pose predicted;       ///< the ghost's base then
  double position = 0;  ///< [m] horizontal distance to the frame's base
  double heading = 0;   ///< [rad] absolute yaw difference
  /// How sure the ghost was (app/ghost/ghost_region.h): the prediction's
  /// error scale, and its regions' radii when telemetry judged it (0: the
  /// ghost gave none).
  double scale = 0;     ///< [m]
  ErrorSources sources;  ///< what the scale was made of (the nearer shown state's)
  double inner = 0, outer = 0, limit = 0;  ///< [m] the inner, outer and departure regions
  /// The twin's wheels' clearances over the map then (ghost_region.h
  /// wheelClearances(); NaN where not shown).
  WheelClearances clearance{kNoClearance, kNoClearance, kNoClearance, kNoClearance};
  double vertical = 0;       ///< [m] the ground's discrepancy under the wheels (ghost_region.h groundDiscrepancy())
  double verticalLimit = 0;  ///< [m] its departure region
  /// +1: this frame announced a departure; -1: it cleared one; 0: neither.
  int departure = 0;
  /// In a departure under the wheels (Departure::ground): not the files'
  /// world there, so the calibration leaves it out. A departure of the base
  /// alone is the robot, which the calibration is for: not suspect.
  bool suspect = false;
};

class PredictionRecord {
 public:
  static constexpr double kShownWindow = 20;   ///< [s] of robot time remembered for comparisons
  static constexpr double kErrorWindow = 10;   ///< [s] of robot time the median is over
  static constexpr double kMatchWindow = 0.1;  ///< [s] a shown state this close in time counts

  /// The ghost showed `base` for robot time `time`, predicted from the
  /// telemetry of robot time `made`. A later prediction for the same or an
  /// earlier time supersedes what was shown from then on.
  /// `scale` [m]: its error scale (ghost_region.h; 0: none), made of `sources`.
  /// `clearance`: the twin's wheels' (wheelClearances()).
  void shown(double time, double made, const Pose& base, double scale = 0, const ErrorSources& sources = {},
             const WheelClearances& clearance = {kNoClearance, kNoClearance, kNoClearance, kNoClearance});
  /// `frame` against what was shown for its time (interpolated between the
  /// two shown states around it), recorded; nullopt when nothing was shown
  /// within kMatchWindow of it.
  std::optional<GhostError> compare(const RobotFrame& frame);
  /// Median position and heading errors over the last kErrorWindow; nullopt before the first.
  std::optional<std::pair<double, double>> median() const;
  /// [m] the largest position error over the same window (a median hides
  /// a jump of a metre); nullopt before the first.
  std::optional<double> worstPosition() const;
  /// Forgets everything (the robot was reset).
  void clear();

 private:
  struct Shown {
    double time, made;  // robot time shown; of the telemetry it ran from
    Pose base;
    double scale;
    ErrorSources sources;
    WheelClearances clearance;
  };
  std::deque<Shown> shown_;
  std::deque<GhostError> errors_;
};

}  // namespace sp
