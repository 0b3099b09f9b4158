#pragma once
// Calibration from telemetry: the few parameters by which the robot differs
// from its files, fitted to what the robot reported, so that the twins the
// console runs (ghost, rehearsals, sweeps) predict this robot rather than
// the files' one. Qt-free; the console's live fitter is live_calibrator.h,
// `simpartner-sim calibrate LOG` the offline one.
//
// Method (docs/architecture.md, "Calibration"). Three estimators, each
// where the data speaks to it:
//   - Total mass from the wheels' load cells (telemetry `wheel_normal`):
//     the mean of sum N / (g cos roll cos pitch) over the window, against
//     the files' total mass. A velocity-controlled drive hides mass from
//     the motion (the loop supplies the torque), so predictions cannot see
//     it; the loads see it directly.
//   - The centre of mass across the ground from the same loads
//     (comFromLoads): where the loads balance, less the load transfer of
//     the acceleration, against where the files put it in that frame's pose.
//   - Each tyre's radius from rolling without slip (radiiFromRolling): the
//     kinematics of the frames alone, where the wheels roll.
//   - Wheel radius (mean and splits, where a wheel skids), tyre friction, wheel-motor
//     gain and command delay by fitting the twin's own predictions: the
//     window is cut into segments (an anchor frame every `spacing` s, each
//     predicting `horizon` s, as the ghost does: the anchor's state through
//     linkMotions + setRobotMotion, the commands at their arrival times plus
//     the delay), compared with the frames every `checkpoint` s (base x, y,
//     heading, the four wheel rates, the articulation), each residual
//     divided by its scale (kResidualScale). Levenberg-Marquardt on
//     forward differences: one candidate twin per parameter, run from the
//     same anchors, in parallel on `threads`. Why this and not a recursive
//     filter: the twin is the model, with its contacts and its controller;
//     nothing linearised by hand has to agree with it, and a new parameter
//     is one more column.
//   - Each wheel motor's torque limit from the wheels' tangential forces,
//     the twin's against the robot's, the rest held (calibration_torque.cpp):
//     a weak motor is carried along by the others, so the motion hardly
//     shows it; what its wheel pushes does.
//
// Observability. From J'J with each residual at its scale, each
// parameter's standard deviation; a parameter whose deviation exceeds half
// its prior range (CalParamInfo::scale) is unobserved: it is taken out of
// the fit, keeps its previous value and is reported as such (friction while
// driving straight on grip). A fit's first step takes only those within a
// quarter: far from the fit, a step along a weakly pinned direction (the
// tyres' front-rear split) stalls the rest. The deviations a fit reports
// are its residuals' own scatter's, widened by what it held at uncertain
// start values while the data moved with them (consideredVariance).
//
// Refusals: a window without enough driving, a twin that diverges, a fit
// that lands outside a parameter's physical bounds: the previous values are
// kept and CalibrationFit::refused says why.
//
// Thread: pure functions of their arguments; the worlds they build are
// their own (one per candidate and thread).

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "app/state/robot_frame.h"
#include "sim/calibration_table.h"
#include "sim/command.h"
#include "sim/params.h"
#include "sim/robot_model.h"

namespace sp {

/// The fitted parameters: CalParam, calParams() (sim/calibration_table.h).
using CalValues = std::array<double, kCalParams>;
using CalFlags = std::array<bool, kCalParams>;

/// The calibration.* values of `params`, and `params` with `values` set.
CalValues calValues(const SimParams& params);
SimParams withCalValues(SimParams params, const CalValues& values);
/// The files' values (identity).
CalValues filesCalValues();
/// Why a fit whose `value` of `info` lies beyond its physical bounds is
/// refused, in words and units ("the command delay came out at -0.297 s,
/// outside what the robot can have (0 to 0.5 s; calibration.delay)").
std::string boundsRefusal(const CalParamInfo& info, double value);

struct CalibrationOptions {
  double window = 10;        ///< [s] of the newest telemetry fitted; <= 0: all of it
  double spacing = 1;        ///< [s] between segment anchors
  double horizon = 2;        ///< [s] each segment predicts
  double checkpoint = 0.25;  ///< [s] between compared frames
  int iterations = 5;        ///< Levenberg-Marquardt iterations per fit
  /// [ms] of wall time: a further iteration starts only when the last one's
  /// duration still fits in it (the first always runs); 0 = no limit. The
  /// console's fits land on time on a loaded machine this way.
  double budgetMs = 0;
  int threads = 1;           ///< candidate twins run at once
  int minSegments = 3;       ///< fewer driving segments: refused (not enough motion)
  /// Parameters held at their start values whatever the data says (the
  /// operator's choice, or a test fitting one).
  CalFlags fixed{};
  /// The start values' deviations where known (a fused estimate's sigma);
  /// 0 where never observed: the parameter's scale. A parameter the window
  /// moves but cannot pin is held at its start, and what that start may be
  /// off by widens the deviations of those fitted with it (fitCalibration).
  CalValues startSigma{};
};

/// One fit over a window of telemetry.
struct CalibrationFit {
  CalValues value{};      ///< the fitted values (the start's where unobserved, fixed or refused)
  CalValues sigma{};      ///< one standard deviation; 0 where unobserved
  CalFlags observed{};    ///< the data pinned it (else it kept its start value)
  double from = 0, to = 0;  ///< [s] robot time fitted
  int segments = 0;       ///< driving segments used
  int residuals = 0;
  int iterations = 0;     ///< Levenberg-Marquardt steps taken
  int twinRuns = 0;       ///< candidate twins run (each over every segment)
  double costBefore = 0;  ///< mean squared scaled residual at the start values
  double costAfter = 0;   ///< ... at the fitted ones
  double wallMs = 0;
  /// "" when accepted; else why it was refused (value = the start's).
  std::string refused;
  /// Refused only for want of driving (the robot stood, or walked): not a
  /// fault, nothing to fit yet. The console says it waits, not that it refused.
  bool wantsDriving = false;
};

/// Fits the calibration of the robot that reported `frames` (oldest first;
/// joints in `files`' first robot's order) under `commands` (each at the
/// robot time it arrived), starting from `start`. `profile` is the twin's
/// physics (step, iterations, ghost.hold: the ghost's own profile for the
/// console); its calibration.* keys are ignored. `abort` is asked between
/// twin runs: true stops the fit (refused "cancelled").
CalibrationFit fitCalibration(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                              const std::vector<TimedCommand>& commands, const CalValues& start,
                              const CalibrationOptions& options = {}, const std::function<bool()>& abort = {});

/// Consider covariance (Schmidt): the variance, in scaled units, that the
/// parameters `on` owe to those `held` at their start values while the data
/// moves with them. `jac` holds each parameter's column of scaled residual
/// derivatives (d r / d (value / scale)); fitting `on` alone puts a held
/// one's error into them by -H_oo^-1 H_ou per unit, and `heldVariance` is
/// each held one's scaled variance about its start. Why: a first window too
/// short to pin the tyres' diagonal split fitted the mean radius with the
/// split held at 0, said it was pinned when it was 2.2 % off, and outweighed
/// the later windows that fitted both (the test track, docs/performance.md).
std::vector<double> consideredVariance(const std::vector<std::vector<double>>& jac, const std::vector<int>& on,
                                       const std::vector<int>& held, const CalValues& heldVariance);

/// What the console holds of the robot across fits: one window's fit is
/// noisy (the contacts, a window of a few turns), so fits are fused.
struct CalEstimate {
  CalValues value = {};  ///< what the twins use
  CalValues sigma = {};  ///< one standard deviation; 0 where never observed
  CalFlags observed{};   ///< some fit observed it
  double time = 0;       ///< [s] robot time of the newest fit fused
};
/// The files' values, none observed.
CalEstimate filesEstimate();
/// fitCalibration from a fused estimate: its values are the start, its
/// deviations the start's (`options.startSigma`, set here).
CalibrationFit fitCalibration(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                              const std::vector<TimedCommand>& commands, const CalEstimate& from,
                              CalibrationOptions options = {}, const std::function<bool()>& abort = {});
/// `prior` updated by `fit` (accepted): each parameter the fit observed is
/// fused by inverse-variance weighting (a Kalman update of a constant),
/// its prior deviation first grown by kDrift per second since the prior's
/// time (a robot's tyres and loads do change, slowly), the result never
/// below the parameter's floor (a bias all windows share); the rest are kept.
/// (A fading memory, the prior's variance grown to the difference where a
/// fit lies beyond the deviations, was measured and left out: the track's
/// ghost 1.16x the matched twin's error against 1.12x, radius error up to
/// 0.89 % against 0.44 %; docs/performance-log.md, "Honest deviations".)
/// `overlap`: how many fits each frame is in (window over period: the live
/// fitter's 8 s every 3 s is 2.7); the fit's variances are multiplied by
/// it, so that overlapping windows are not counted as independent.
CalEstimate fuse(const CalEstimate& prior, const CalibrationFit& fit, double overlap = 1);
/// The drift: a share of each parameter's scale per square-root second.
constexpr double kDrift = 0.005;
/// What the twins are given of `estimate`: each parameter where it differs
/// from the files' value by more than kSignificance deviations, else the
/// files' (a robot that is its twin keeps its twin: the fits' noise is not
/// applied).
CalValues significantValues(const CalEstimate& estimate);
/// Two deviations, the usual test, now that the deviations are the fits'
/// own scatter's (at half a deviation of the old, floored ones a robot
/// that is its twin kept its twin; at none it got a spurious 1.9 %
/// diagonal split on flat ground). docs/performance-log.md, "Honest deviations".
constexpr double kSignificance = 2;

/// How far the twin calibrated by `values` lands from the robot `horizon`
/// seconds after each anchor (every `spacing` s along the driving parts of
/// `frames`), as the ghost predicts over a link: the benchmark's measure.
struct PredictionCheck {
  std::vector<double> time;      ///< [s] each anchor's robot time
  std::vector<double> position;  ///< [m] horizontal error at anchor + horizon
  std::vector<double> heading;   ///< [rad] absolute heading error there
  std::string problem;           ///< "" or why there are none
};
PredictionCheck checkPredictions(const WorldModel& files, const SimParams& profile, const std::vector<RobotFrame>& frames,
                                 const std::vector<TimedCommand>& commands, const CalValues& values, double horizon,
                                 double spacing);

/// Each tyre's rolling radius from rolling without slip, against the files'
/// (a factor, FL FR RL RR): for every frame with the wheel turning, the
/// hub's speed across its axle over the wheel's spin about the axle (both
/// from the frame's base twist and joint rates through the kinematics, no
/// twin run), least squares over the frames. Frames where the wheel slips
/// (the ratio more than 5 % from the wheel's median) are left out.
///
/// A wheel that slips all the time tells nothing of its radius: four
/// driven wheels whose radii differ fight, and a stiff velocity loop makes
/// the odd one skid (a robot with one tyre 4 % smaller than the rest: it
/// was dragged in every frame, its ratio the others' radius, its own seen
/// only in a few frames where it gripped). Its friction is then at its
/// limit whatever its radius, so the motion does not show the radius
/// either; what shows the skid is the share of frames off the median.
struct RollingRadii {
  std::array<double, 4> factor{1, 1, 1, 1};
  std::array<double, 4> sigma{};     ///< one deviation; 0 where not enough rolling
  std::array<int, 4> frames{};       ///< frames used per wheel
  std::array<double, 4> slipping{};  ///< share of the wheel's turning frames left out
  /// Every wheel rolled in enough frames and slipped in at most kSlipping
  /// of them: the radii stand for the robot's.
  bool rolled() const {
    for (size_t w = 0; w < 4; ++w)
      if (!(sigma[w] > 0) || slipping[w] > kSlipping) return false;
    return true;
  }
  /// Over 30 s of the benchmark's flat drives (21 robots, 84 wheels):
  /// wheels whose ratio came within 0.2 % of their radius left out 0-6.6 %
  /// of their frames (turns begun, stops), those 0.4-1.1 % off 4.7-7.7 %,
  /// the three that skid all the time (2-4 % off) 13-14 %: the skids that
  /// matter are told apart; a few windows rolling would have measured go to
  /// the twin's fit (docs/performance.md).
  static constexpr double kSlipping = 0.05;
};
RollingRadii radiiFromRolling(const WorldModel& files, const std::vector<RobotFrame>& frames);
/// How far the robot's centre of mass lies forward and left of the files'
/// (calibration.com_x, com_y: robot frame at zero pose, metres) from the
/// wheels' loads: in each frame the loads' balance point (the contacts under
/// the hubs, along the ground's normal where the world is a heightfield,
/// weighted by the loads' vertical parts) moved by h a / g (the
/// acceleration's load transfer, h the centre's height over the contacts),
/// less the centre the files put at that frame's pose (the kinematics), in
/// the robot's heading; least squares over the frames of that against what
/// the parameter moves the centre by at each frame's pose. Statics, and the
/// mean of the body's rocking: what is left is the contacts' real spread
/// under a tyre, a bias kComBias measures.
struct LoadCentre {
  double forward = 0, left = 0;    ///< [m]
  double sigmaForward = 0, sigmaLeft = 0;  ///< the frames' scatter only (one sample per 10 frames)
  int frames = 0;
};
/// nullopt without 50 frames with loads.
std::optional<LoadCentre> comFromLoads(const WorldModel& files, const std::vector<RobotFrame>& frames);
/// What calibration.com_x, com_y would make the files' robot's centre of mass
/// follow `robot`'s (the same links with other masses or centres) over the
/// poses of `frames`, least squares as comFromLoads: the value a perfect
/// comFromLoads finds (the benchmark's and tests' truth; a robot whose links'
/// centres moved every which way is no uniform shift, and bent legs turn
/// theirs). nullopt without 50 frames, or when the links differ.
std::optional<LoadCentre> centreShift(const RobotModel& files, const RobotModel& robot, const std::vector<RobotFrame>& frames);
/// kComBias (sim/calibration_table.h) is about what it reads of a robot that is its twin.

/// The wheel radius and its front-rear, left-right and diagonal splits of
/// four tyre radius factors (FL FR RL RR): the inverse of the product the
/// twins apply (calibratedWorld), to first order (as the radii differ by a
/// few percent, to 0.02 %). In CalParam order, WheelRadius first.
std::array<double, 4> radiusValues(const std::array<double, 4>& factors);

/// The parameters the full-physics twins (rehearsals, robustness runs,
/// sweeps) are given. The fits run in the ghost's coarser profile, and a
/// weakly pinned parameter soaks up that profile's own bias: on a robot
/// that is its twin the diagonal radius split was fitted at -1.46 % (hidden
/// 0), which helps the ghost and moved a full-physics rehearsal's end from
/// 0.2 to 9.4 cm. So each of kFullPhysicsChecked that `applied` moved from
/// the files' is put back to the files' value unless the twin at `full`
/// physics predicts the newest `window` seconds of telemetry better with
/// it: the splits on the motion (with the motors' limits at the files'),
/// then the motors' limits on the wheels' forces (with the splits as
/// judged), each at the value of kLimitSteps + 1 from the applied one to
/// the files' that predicts the forces best. A limit fitted in the ghost's
/// fits to the forces of wheels a spurious split made fight is refused
/// there with the split.
struct FullPhysicsCheck {
  CalValues values{};       ///< `applied`, less what the full physics refused (a limit may land between the two)
  double cost = 0;          ///< the motion's mean squared scaled residual with `applied` (the limits at the files'); 0: no split checked
  double forceCost = 0;     ///< the wheels' forces' with `values`' splits and `applied`'s limits; 0: no limit checked
  CalValues costWithout{};  ///< ... with each checked one at the files' (0: not tried)
  double wallMs = 0;
  std::string problem;      ///< "" or why nothing was checked (values = applied)
};
inline constexpr CalParam kFullPhysicsChecked[] = {CalParam::WheelRadiusSplit, CalParam::WheelRadiusSide,
                                                   CalParam::WheelRadiusDiag,  CalParam::TorqueFL,
                                                   CalParam::TorqueFR,         CalParam::TorqueRL,
                                                   CalParam::TorqueRR};
inline constexpr int kLimitSteps = 3;
/// One of the wheel motors' torque limits (judged on the forces).
constexpr bool isTorqueLimit(CalParam p) { return p >= CalParam::TorqueFL && p <= CalParam::TorqueRR; }
FullPhysicsCheck fullPhysicsValues(const WorldModel& files, const SimParams& full, const std::vector<RobotFrame>& frames,
                                   const std::vector<TimedCommand>& commands, const CalValues& applied, double window,
                                   int threads = 1, const std::function<bool()>& abort = {});

/// What a session log (a robot's own, or a console's telemetry log) holds
/// for calibration: the files' world, the frames and the commands.
struct CalibrationInput {
  WorldModel world;  ///< as the files say (not a perturbed robot's physics)
  SimParams params;  ///< the log's
  std::vector<RobotFrame> frames;
  std::vector<TimedCommand> commands;
  std::string source;  ///< the log's meta log_source ("" for a robot's own)
  std::string robotText;  ///< the robot file as logged (calibratedRobotText writes a calibrated one)
};
/// nullopt and `error` (naming `path`) when the log cannot be read.
std::optional<CalibrationInput> calibrationInput(const std::string& path, std::string& error);

/// `values` as a parameters file (calibration.* keys, with a comment line
/// per parameter: its deviation, or "unobserved").
std::string calibrationParamsText(const CalibrationFit& fit);

}  // namespace sp
