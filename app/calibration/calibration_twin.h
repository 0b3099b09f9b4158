#pragma once
// The candidate twins of a calibration (calibration.cpp): the telemetry cut
// into segments, each predicted by a twin from its anchor frame, and the
// scaled residuals against the robot's frames.
//
// Thread: pure functions; each run builds its own world.

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/calibration/calibration.h"

namespace sp::calibration_detail {

// What one scaled residual is: a deviation of this size counts 1.
struct ResidualScale {
  double position = 0.01;   // [m]
  double heading = 0.01;    // [rad]
  double wheelTurn = 0.2;   // [rad] a wheel's turn since the anchor (contacts make it chatter by ~0.05)
  double articulation = 0.01;  // [rad]
  double force = 20;           // [N] a wheel's tangential force (the contacts chatter by about this)
};
constexpr ResidualScale kResidualScale;
constexpr int kPerCheckpoint = 8;  // x, y, heading, 4 wheel rates, articulation

/// One stretch of telemetry the twin predicts from its first frame.
struct Segment {
  size_t anchor = 0;                // frame index
  std::vector<size_t> checkpoints;  // frame indices compared
};

/// What every candidate twin of one fit shares.
struct Problem {
  const WorldModel* files = nullptr;
  SimParams profile;
  const std::vector<RobotFrame>* frames = nullptr;
  std::vector<TimedCommand> commands;  // arrival times, in order
  std::vector<Segment> segments;
  std::vector<int> held;     // the full robot's joints held rigid
  std::vector<double> weld;  // where (full robot's joint positions)
  std::array<int, 4> wheels{-1, -1, -1, -1};
  int articulation = -1;
};

/// The fit's problem over `frames` (usable, oldest first): the twin's
/// weld, the commands in order, the driving segments. "" or why not.
std::string makeProblem(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                        const std::vector<TimedCommand>& commands, const CalibrationOptions& o, Problem& pb);

/// The scaled residuals of the twin calibrated by `v` over every segment, or
/// nullopt and `why` when the twin cannot be built or diverges.
/// `turns`, when given, receives each checkpoint's wheel turns since its
/// anchor, (twin, robot), for the motor gain's closed form. `jitter` [m]
/// lifts every anchor by that much: a run from anchors a micrometre off
/// differs from the plain one by the contacts' chaos alone (the noise probe).
/// `forces`, when given, receives each checkpoint's four wheels' tangential
/// forces, twin less robot, at kResidualScale.force (the twin then samples
/// its wheel_force sensors, WorldOptions::wheelForces).
std::optional<std::vector<double>> residuals(const Problem& pb, const CalValues& v, std::string& why,
                                             std::vector<std::pair<double, double>>* turns = nullptr,
                                             double jitter = 0, std::vector<double>* forces = nullptr);

double meanSquare(const std::vector<double>& r);

/// A candidate twin: its values, and the noise probe's jitter (residuals()).
struct Candidate {
  CalValues values;
  double jitter = 0;
  bool forces = false;  ///< its residuals are the wheels' forces (residuals()' `forces`), not the motion's
};

/// Runs the candidates on up to `threads` threads; a failed one is nullopt
/// (`why` says the first failure's reason).
std::vector<std::optional<std::vector<double>>> runAll(const Problem& pb, const std::vector<Candidate>& candidates,
                                                       int threads, std::string& why,
                                                       const std::function<bool()>& abort = {});

/// Each wheel motor's torque limit (CalParam::TorqueFL..RR) fitted to the
/// wheels' tangential forces, the rest of `v` held (calibration_torque.cpp):
/// into `v` and `fit` (value, sigma, observed), those the window never
/// pushed to a limit unobserved at their start. Nothing when the frames
/// report no tangential forces. "" or why the fit is refused.
std::string fitMotorTorques(const Problem& pb, const CalibrationOptions& o, CalValues& v, CalibrationFit& fit,
                            const std::function<double()>& elapsedMs, const std::function<bool()>& abort);

}  // namespace sp::calibration_detail
