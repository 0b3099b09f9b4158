#pragma once
// The console's calibration while the operator drives: telemetry frames and
// the commands sent (at their estimated arrival) go in from the GUI thread,
// a worker thread fits the newest window (app/calibration/calibration.h)
// every `period` seconds of new telemetry, and the values it applies come
// out as a version the console polls (ConsoleSession hands them to the
// ghost and to the twins it starts).
//
// What the operator can do: freeze (fits go on and are shown, nothing new
// is applied), reset to the files, save (calibrationParamsText). A refused
// fit keeps the values applied and says why (lastRefusal, the history).
//
// Thread: frame(), command(), state(), freeze(), reset() from any thread
// (the GUI's); they copy under a mutex and never wait for a fit. The worker
// runs at nice 10, beside the ghost's threads; the full-physics checks
// (Options::full) on a thread of their own at nice 10, one core, so that
// the fits land every period while a check runs.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/calibration/calibration.h"
#include "app/state/robot_frame.h"
#include "sim/command.h"
#include "sim/params.h"
#include "sim/robot_model.h"

namespace sp {

/// What the console shows of its calibration.
struct CalibrationState {
  int64_t version = 0;      ///< counts changes of `applied` (and fits done)
  CalValues applied{};      ///< what the twins use now: the fits fused, where significant (calibration.h)
  CalValues sigma{};        ///< its deviation (0: the files', or never observed)
  CalFlags observed{};      ///< some fit observed it (else the files' or the start's)
  /// What the full-physics twins (rehearsals, robustness runs, sweeps) use:
  /// `applied`, with each of kFullPhysicsChecked at the files' value until a
  /// full-physics check confirmed it (calibration.h, fullPhysicsValues); a
  /// confirmed motor's limit at the value that check found.
  CalValues fullPhysics{};
  CalFlags confirmed{};     ///< the last full-physics check kept it (a limit: found one, at `checkedValue`)
  CalFlags refused{};       ///< ... put it back to the files' value
  CalValues checkedValue{}; ///< the value the last check gave each of kFullPhysicsChecked
  double checkedAt = -1;    ///< [s] robot time of that check (< 0: none yet)
  bool frozen = false;
  int fits = 0, refusals = 0;
  std::string lastRefusal;  ///< "" or why the last refused fit was
  bool lastRefusalWantsDriving = false;  ///< ... for want of driving only (CalibrationFit::wantsDriving)
  std::vector<CalibrationFit> history;  ///< the fits, oldest first (at most kHistory)
  static constexpr size_t kHistory = 600;
};

class LiveCalibrator {
 public:
  struct Options {
    double period = 3;  ///< [s] of new telemetry between fits
    /// Each fit starts from the last one's values: three Levenberg-Marquardt
    /// steps over the newest 8 s follow the robot (a recursive refinement),
    /// on both cores at nice 10; each after the first only when the last
    /// left time for it within a period, so that a fit lands every period
    /// or so even on a loaded machine. (Three, not two, since the centre of
    /// mass is fitted: docs/performance-log.md, "A third step again".)
    CalibrationOptions fit = [] {
      CalibrationOptions o;
      o.window = 8;
      o.iterations = 3;
      o.threads = 2;
      o.budgetMs = 3000;
      return o;
    }();
    /// Tests: called on the worker between the twin runs of each fit (and
    /// on the checker between those of a check), holding no lock (to prove
    /// the GUI thread never waits on a fit).
    std::function<void()> duringFit;
    /// The console's own physics: when set, the radius splits and motors'
    /// torque limits the fits applied are checked in it (fullPhysicsValues over the newest
    /// `fit.window` s) before the full-physics twins are given them: after
    /// a fit that applied one no check judged, at most every `checkPeriod`
    /// s of robot time; the verdicts again every 4 `checkPeriod`.
    std::optional<SimParams> full;
    double checkPeriod = 12;
  };
  /// Fits the robot of `files` (the console's world, its first robot) with
  /// the physics `profile` (the ghost's: step, iterations, hold) from
  /// `start` (the parameters' calibration.* values).
  LiveCalibrator(WorldModel files, const SimParams& profile, const CalValues& start, const Options& options);
  LiveCalibrator(WorldModel files, const SimParams& profile, const CalValues& start)
      : LiveCalibrator(std::move(files), profile, start, Options{}) {}
  ~LiveCalibrator();
  LiveCalibrator(const LiveCalibrator&) = delete;
  LiveCalibrator& operator=(const LiveCalibrator&) = delete;

  /// A telemetry frame (joints in the model's order). `suspect`: the robot
  /// departs from its twin there (app/ghost/ghost_region.h): the frame and
  /// the window before it are left out, and a fit running over it is
  /// refused in those words; the fits start again on the frames after.
  void frame(const RobotFrame& frame, bool suspect = false);
  /// A command sent, taken to arrive at robot time `arrival`.
  void command(const Command& command, double arrival);
  CalibrationState state() const;
  /// The version alone (cheap to poll).
  int64_t version() const;
  /// What the ghost uses now (state().applied without copying the history).
  CalValues applied() const;
  /// What the full-physics twins use now (state().fullPhysics).
  CalValues fullPhysics() const;
  void freeze(bool frozen);
  /// Back to the files' values; the fits start from them again.
  void reset();

 private:
  void run();
  void runChecks();
  void check(const std::vector<RobotFrame>& frames, const std::vector<TimedCommand>& commands);
  // state_.fullPhysics from state_.applied and the last check (mutex_ held).
  void updateFullPhysics();

  const WorldModel files_;
  const SimParams profile_;
  const CalValues files0_;
  const Options options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::deque<RobotFrame> frames_;
  std::deque<TimedCommand> commands_;
  double lastFitAt_ = -1e300;  // robot time of the newest frame the last fit saw
  double suspectAt_ = -1e300;  // robot time of the newest frame left out for a departure
  CalibrationState state_;
  CalEstimate estimate_;  // state_'s applied, sigma and observed, fused
  std::thread worker_;
  // The full-physics check's request (the window to check) and thread.
  std::condition_variable checkWake_;
  bool checkWanted_ = false, checking_ = false;
  int64_t resets_ = 0;  // reset() calls: a check started before one is void
  std::vector<RobotFrame> checkFrames_;
  std::vector<TimedCommand> checkCommands_;
  std::thread checker_;
};

}  // namespace sp
