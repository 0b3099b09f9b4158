#pragma once
// Simulation parameters: a human-readable `key = value` properties file with
// `#` comments. config/defaults.params documents every key.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sim/diagnostics.h"

namespace sp {

enum class Solver { Quick, Exact };

/// Every tunable of the twin, with its default. Plain value type.
struct SimParams {
  // Physics
  double step = 0.001;            ///< fixed step [s]
  Solver solver = Solver::Quick;  ///< quick = dWorldQuickStep, exact = dWorldStep
  int iterations = 60;            ///< quick solver iterations (why 60 at 1 ms: config/defaults.params)
  double erp = 0.5;               ///< error reduction parameter
  double cfm = 1e-6;              ///< constraint force mixing
  double surfaceLayer = 0.001;    ///< contact surface layer [m]
  double maxCorrectingVel = 0.5;  ///< contact max correcting velocity [m/s]
  int maxContacts = 8;            ///< contact points per geom pair
  uint64_t seed = 1;              ///< seed of the world's random engine
  // Pacing
  double realTimeFactor = 1.0;    ///< sim seconds per wall second
  // Rates [Hz]
  double telemetryRate = 50;
  double laserRate = 20;
  double logRate = 100;
  double csvRate = 100;           ///< rows per sim second in `run --csv`
  int logKeep = 0;                ///< session logs kept in the console's log folder (newest first); 0 = all
  // Ports
  int robotPort = 47800;          ///< TCP port of the robot link
  // Robot link timing (docs/protocol.md has settings per link); LAN defaults
  double linkDeadman = 0.2;       ///< [s] robot: longest gap between the holder's keep-alives
  double linkKeepalive = 0.05;    ///< [s] console: keep-alive period (at most a quarter of the deadman)
  double linkCommandExpiry = 0.5; ///< [s] console: how much later than the link's usual delay a command may arrive
  double linkLeaseConfirm = 10;   ///< [s] robot: wait for a new holder's first keep-alive
  int linkMaxConnections = 64;    ///< robot: connections open at once; one more is closed at once
  /// [s] robot: a connection without a good HELLO by then is closed. The
  /// HELLO answers the CHALLENGE, so it arrives a round trip after the
  /// connection opened: 5 s carries the slowest link of docs/protocol.md
  /// (2.2 s) twice over.
  double linkHelloTimeout = 5;
  double consoleStaleAfter = 0.5; ///< [s] console: no telemetry this long => the robot is drawn grey, "no data"
  /// Rehearsals' fast profile (robustness samples, the console's first
  /// verdicts; app/rehearse/rehearsal.h): a coarser step and fewer solver
  /// iterations, the verdicts checked against the full profile's in
  /// bench_rehearsal and tst_rehearsal.
  double rehearsalFastStep = 0.002;
  int rehearsalFastIterations = 40;
  /// The fast profile also welds these joints' subtrees (the drive's
  /// joints turn) while no command or gait moves them: the legs, as the
  /// ghost holds them (app/rehearse/held_twin.h).
  std::string rehearsalFastHold = "hip_fl,hip_fr,hip_rl,hip_rr";
  /// Where the fast profile is not trusted: a fast run that fails a rule,
  /// or comes closer to a rule's limit than its band here, is run again at
  /// full fidelity (RehearsalPlan::refine). A band is 11 times the largest
  /// margin error the fast profile made for that rule over the random
  /// sequences it passed (24 of 40: bench_rehearsal --random 132 40,
  /// docs/performance.md), so the margins it reports stay within 10 % of
  /// the full profile's. In the rule's unit, one per rule of
  /// sim/flight_rules.h but collisions and the twin's health: they have no
  /// distance to a limit, only a failure, which refines.
  double refineStability = 0.015;    ///< [m] of support margin
  double refineRoll = 1.6;           ///< [deg]
  double refinePitch = 1.2;          ///< [deg]
  double refineJointLimit = 2.4;     ///< [deg] from a joint's stop margin
  double refineLiftoff = 0.4;        ///< [s]
  double refineWheelForce = 1150;    ///< [N]
  double refineSpeed = 0.48;         ///< [m/s]
  double refineYawRate = 28;         ///< [deg/s]
  double ghostStep = 0.004;       ///< [s] console's predictive ghost: its physics step
  int ghostIterations = 20;       ///< ghost: quick solver iterations
  double ghostHorizon = 5;        ///< [s] ghost: how far the trail looks ahead of the ghost
  double ghostAnchorRate = 15;    ///< [Hz] ghost: re-anchorings per second at most
  /// Ghost: joints whose subtrees it holds rigid while the robot keeps them
  /// still (comma-separated names, or "none"; the wheels and articulation
  /// keep turning): fewer bodies, faster predictions (sim/rigid.h).
  std::string ghostHold = "waist_yaw,hip_fl,hip_fr,hip_rl,hip_rr";
  // How sure the ghost is (app/ghost/ghost_region.h): its regions' levels,
  // a departure's, and the conformal layer's window and step.
  double ghostRegionInner = 0.5;
  double ghostRegionOuter = 0.9;
  double ghostRegionDeparture = 0.99;
  double ghostRegionHold = 0.5;      ///< [s]
  double ghostRegionWindow = 20;     ///< [s]
  double ghostRegionGamma = 0.005;
  // The twin calibrated to a robot (app/calibration/calibration.h): what
  // the twins the console starts (ghost, rehearsals, sweeps, run) differ
  // from the files by. Factors on the files' values; identity by default.
  // Their keys, bounds and names: sim/calibration_table.h.
  double calWheelRadius = 1;       ///< tyres' effective radius, both axles
  double calWheelRadiusSplit = 0;  ///< front minus rear radius, relative (front x (1 + s/2), rear x (1 - s/2))
  double calWheelRadiusSide = 0;   ///< left minus right radius, relative (left x (1 + s/2), right x (1 - s/2))
  double calWheelRadiusDiag = 0;   ///< one diagonal minus the other, relative (FL, RR x (1 + d/2); FR, RL x (1 - d/2))
  double calFriction = 1;          ///< every contact's mu
  double calMotorGain = 1;         ///< wheel motors reach gain x the commanded speed
  double calDelay = 0;             ///< [s] between a command's arrival and its effect
  double calMass = 1;              ///< every link's mass
  /// [m] the robot's centre of mass moved forward (x) and left (y) of the
  /// files', robot frame at zero pose: every link's centre moved by as much.
  double calComX = 0, calComY = 0;
  /// Each wheel motor's torque limit, a factor (FL FR RL RR): a weak motor.
  double calTorqueFL = 1, calTorqueFR = 1, calTorqueRL = 1, calTorqueRR = 1;
  /// Whether any calibration.* key differs from the files (identity).
  bool calibrated() const;
  // Gaits (sim/gait.h); swings in degrees about the stance pose
  double caterpillarHipSwing = 12;   ///< [deg]
  double caterpillarPhaseTime = 1.0; ///< [s] per half cycle
  double rolkingHipSwing = 12;       ///< [deg]
  double rolkingLegTime = 0.8;       ///< [s] per leg reach
  double rolkingBodyTime = 1.2;      ///< [s] to bring the body forward
  // Health limits (checked every step)
  double maxLinearSpeed = 50;     ///< [m/s]
  double maxAngularSpeed = 200;   ///< [rad/s]
  double maxLinearAcceleration = 5000;     ///< [m/s^2]
  double maxAngularAcceleration = 100000;  ///< [rad/s^2]
  double maxJointError = 0.05;    ///< joint pulled apart [m]
  double maxPenetration = 0.05;   ///< contact depth, or a body below the ground [m]
};

/// Sets one key from its text value. `where`/`line` name the origin for
/// diagnostics (a file and line, or "<command line>" and 0). Returns false and
/// leaves `params` unchanged on an unknown key or a bad value.
bool setParam(SimParams& params, std::string_view key, std::string_view value,
              std::string_view where, int line, Diagnostics& diag);

/// Reads a properties file over `params`. All problems are reported; on any
/// error `params` is left exactly as it was (no half-applied file).
bool loadParams(const std::string& path, SimParams& params, Diagnostics& diag);

/// The same for a properties file held in memory; `path` names it in
/// diagnostics (a session log's stored parameters, say).
bool parseParams(std::string_view contents, std::string_view path, SimParams& params, Diagnostics& diag);

/// Applies a `key=value` override from the command line.
bool applyOverride(SimParams& params, std::string_view assignment, Diagnostics& diag);

/// Every key with its default value text and a one-line description, in the
/// order of config/defaults.params.
struct ParamInfo {
  std::string key;
  std::string defaultValue;
  std::string description;
};
std::vector<ParamInfo> paramTable();

/// The value of `key` in `params` as text (for logs and `--help`).
std::string paramValue(const SimParams& params, std::string_view key);
/// A comma-separated list's items (ghost.hold); none for "none".
std::vector<std::string> splitNames(std::string_view text);

}  // namespace sp
