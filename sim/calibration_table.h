#pragma once
// The twins' calibration.* parameters, listed once: the SimParams field,
// the key, the names people read, the unit, the physical bounds and what
// a fit judges them against. The keys' parsing and descriptions
// (sim/params.cpp), SimParams::calibrated(), the calibration's fits
// (app/calibration/) and the Calibration dock all read this table.

#include <array>

#include "sim/params.h"

namespace sp {

/// The fitted parameters, in the order of calParams().
enum class CalParam : int {
  WheelRadius, WheelRadiusSplit, WheelRadiusSide, WheelRadiusDiag, Friction, MotorGain, Delay, Mass, ComX, ComY,
  TorqueFL, TorqueFR, TorqueRL, TorqueRR  ///< each wheel motor's torque limit (FL FR RL RR), from the wheels' forces
};
constexpr int kCalParams = 14;

/// [m] about what the load fit of the centre of mass reads of a robot that
/// is its twin: 0.3-0.5 mm on flat ground (tst_calibration
/// centreOfMassFromLoads, 10 s), -2.3 and -1.3 mm on the test track's bumps
/// (bench_calibration's control, fused over 30 s: kept at the files' by the
/// two deviations this sets). Each fit's deviation is at least this, and no
/// fusing of fits goes below it (CalParamInfo::floor).
constexpr double kComBias = 0.002;

struct CalParamInfo {
  CalParam id;
  double SimParams::*field;
  const char* key;          ///< its SimParams key (calibration.wheel_radius)
  const char* label;        ///< for people ("wheel radius")
  const char* brief;        ///< a table cell's name ("radius")
  const char* description;  ///< the key's, without its bounds (--help, defaults.params)
  const char* unit;         ///< "" for a factor or a relative split, else the unit ("s")
  double files;             ///< the files' value (identity)
  double lower, upper;      ///< physical bounds: a value beyond is an error, a fit beyond is refused
  /// Prior half range: what "observed" is judged against; the ranges of a
  /// real robot's deviations (sim/perturbation.h), so that "observed" means
  /// "pinned well inside what a robot may differ by".
  double scale;
  double probe;  ///< the fits' finite-difference step (0: not fitted through the twin)
  /// A deviation no fusing of fits goes below: the estimator's own bias,
  /// which every window shares (0: none known).
  double floor;
};
const std::array<CalParamInfo, kCalParams>& calParams();
inline const CalParamInfo& calParam(CalParam p) { return calParams()[static_cast<size_t>(p)]; }

}  // namespace sp
