#pragma once
// A robot that is not its twin: hidden deviations of a real robot from its
// model files, drawn from a seed within documented ranges, so that what
// predicts or rehearses (the console's twin) can be tested against a robot
// whose physics differs from the files (`simpartner-robot --perturb SEED`).
//
//   sp::Perturbation p = sp::drawPerturbation(seed, world.robots[0].model);
//   sp::WorldModel robotsWorld = sp::perturbWorld(world, p);  // the robot's physics
//   // p.delay and p.rollBias / p.pitchBias are the robot's own (app/robot/twin_host.h)
//
// What is drawn (each uniform in its range, from the seed alone):
//   wheel radius      per wheel (FL FR RL RR), ± 3 %: the tyres' effective radius; the
//                     robot's controller keeps the nominal one (it does not know)
//   link mass         per link, ± 15 %
//   centre of mass    per link, ± 2 cm on each axis (link frame)
//   friction          every contact's mu, ± 30 % (one factor: the ground)
//   torque limit      the wheel motors' torque limit, ± 20 %
//   (not drawn)       a factor per wheel motor's torque limit on top (a weak
//                     motor: `simpartner-robot --weak-motor rl=0.5`); 1 unless set
//   velocity gain     the wheel motors reach gain x the commanded speed, ± 20 %
//   actuator delay    0 – 60 ms between a command's arrival and its effect
//   IMU bias          roll and pitch each ± 1°, in what the robot reports
//
// Thread: pure functions of their arguments.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/math.h"
#include "sim/params.h"
#include "sim/robot_model.h"

namespace sp {

/// The ranges a perturbation is drawn from (the issue's; tests may narrow them).
struct PerturbationRanges {
  double wheelRadius = 0.03;          ///< relative, ±
  double mass = 0.15;                 ///< relative, ±
  double centreOfMass = 0.02;         ///< [m], ± per axis
  double friction = 0.30;             ///< relative, ±
  double torqueLimit = 0.20;          ///< relative, ±
  double velocityGain = 0.20;         ///< relative, ±
  double maxDelay = 0.060;            ///< [s], from 0
  double imuBias = degToRad(1.0);     ///< [rad], ±
};

/// The deviations of one robot from its files.
struct Perturbation {
  uint64_t seed = 0;
  std::array<double, 4> wheelRadius{1, 1, 1, 1};  ///< factor per wheel (FL FR RL RR)
  std::vector<double> linkMass;        ///< factor per link (model order)
  std::vector<Vec3> centreOfMass;      ///< [m] shift per link, link frame
  double friction = 1;                 ///< factor on every contact's mu
  double torqueLimit = 1;              ///< factor on the wheel motors' torque limit
  /// Factor per wheel motor's torque limit (FL FR RL RR) on top of
  /// torqueLimit: not drawn (a seed's robot stays the same), set to make
  /// one motor weak.
  std::array<double, 4> wheelTorque{1, 1, 1, 1};
  double velocityGain = 1;             ///< factor on the wheel motors' speed
  double delay = 0;                    ///< [s] actuator delay
  double rollBias = 0, pitchBias = 0;  ///< [rad] added to the reported roll and pitch

  /// One `key = value` line per deviation (links by name), for reports and
  /// the session log's meta.
  std::string report(const RobotModel& robot) const;
};

/// A robot that changes while it runs: at robot time `at` its contacts'
/// friction is multiplied by `friction` and its commands' delay grows by
/// `delay` (the ground turned wet, a motor's controller slowed). What the
/// console's uncertainty must recover from (issue 61).
struct SuddenChange {
  double at = 0;        ///< [s] robot time
  double friction = 1;  ///< factor on every contact's mu, > 0
  double delay = 0;     ///< [s] added to the actuator delay, >= 0
  /// "friction x0.7, delay +0.1 s at 30 s", for logs and reports.
  std::string describe() const;
  /// "" or what cannot be, naming the field ("friction factor 0: must be > 0").
  std::string check() const;
};
/// Parses `T,FRICTION,DELAY` ("30,0.7,0.1") into `c`: "" or why not,
/// naming the text; `c` is unchanged then.
std::string parseSuddenChange(const std::string& text, SuddenChange& c);

/// The deviations of `robot` drawn from `seed` within `ranges`.
Perturbation drawPerturbation(uint64_t seed, const RobotModel& robot, const PerturbationRanges& ranges = {});

/// Parses a weak motor, `WHEEL=FACTOR` (fl, fr, rl or rr; a factor in
/// (0, 2]), into `p.wheelTorque`: "" or why not, naming the text.
std::string parseWeakMotor(const std::string& text, Perturbation& p);

/// `world` with its first robot's physics perturbed by `p` (wheel geoms'
/// radius, link masses and centres of mass, contact friction, wheel
/// motors); the delay and the IMU bias are applied by the robot's host.
WorldModel perturbWorld(WorldModel world, const Perturbation& p);

/// `world` as a twin calibrated by `params`' calibration.* keys sees it:
/// the first robot's tyres, link masses, contact friction and wheel motors
/// scaled, its links' centres of mass moved (the delay is the caller's: it
/// schedules the commands). `world` itself when the keys are the files'
/// (identity).
WorldModel calibratedWorld(const WorldModel& world, const SimParams& params);

/// The robot file `text` (which loaded as `robot`) with `params`' calibration
/// written in: every link's mass, each wheel's tyre radius and the wheel
/// motors' `velocity_scale`, so that the file alone builds the calibrated
/// robot (its comments and everything else kept). Friction is the ground's
/// (a world's <contact>), the delay the link's, and a robot file places no
/// centre of mass: they stay in the parameters file, and a comment at the
/// top says so with their values.
/// nullopt and `error` when `text` does not parse or does not hold `robot`'s
/// links.
std::optional<std::string> calibratedRobotText(const std::string& text, const RobotModel& robot, const SimParams& params,
                                               std::string& error);

}  // namespace sp
