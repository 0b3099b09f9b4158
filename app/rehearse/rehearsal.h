#pragma once
// Rehearsal: a command sequence run on the console's own twin, from the
// robot's current state, faster than real time, with the flight rules
// (sim/flight_rules.h) checked after every step. Only a sequence that passed
// is relayed to the robot (app/rehearse/sequence_relay.h), unchanged: the hash of its
// canonical text names it on both ends.
//
//   sp::RehearsalPlan plan{world, params, rules, commands, start};
//   sp::RehearsalResult r = sp::rehearse(plan, [&](double f) { bar(f); return !cancelled; });
//   if (r.passed) relay(plan.commands, r);
//
// Time: a sequence's command times count from its start (t = 0 when the
// rehearsal, or the robot's run, begins).
//
// Thread: any; rehearse() builds and steps its own World on the calling
// thread (the console runs it on a worker). robustness() uses `threads`
// threads of its own.

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sim/calibration_table.h"
#include "app/rehearse/held_twin.h"
#include "sim/command.h"
#include "sim/flight_rules.h"
#include "sim/math.h"
#include "sim/params.h"
#include "sim/robot_model.h"

namespace sp {

/// What to rehearse.
/// What the console knows of the robot, for robustness draws: each
/// calibration.* parameter (sim/calibration_table.h) about the plan's
/// params' value, with its deviation where a fit observed it, else over its
/// prior range (CalParamInfo::scale: what a robot may differ by).
struct RobotEstimate {
  std::array<double, kCalParams> sigma{};
  std::array<bool, kCalParams> observed{};
};

struct RehearsalPlan {
  WorldModel world;  ///< robots[0] is the robot
  SimParams params;
  FlightRules rules;
  std::vector<TimedCommand> commands;  ///< times from the start, non-decreasing
  /// nullopt = the world's own initial state, settled first
  /// (settleWorldStart; RehearsalResult::settled says how long).
  std::optional<RehearsalStart> start;
  /// Hold rigid the joints no command of the sequence moves (whole
  /// subtrees without drive joints: an arm, the head; sim/rigid.h), for
  /// speed: fewer bodies, the same mass and centre of mass.
  bool holdUnmoved = true;
  /// The fast profile: params' rehearsal.fast_step and
  /// rehearsal.fast_iterations instead of physics.step and .iterations
  /// (about 2x faster; its verdicts against the full profile's:
  /// docs/performance.md). A fast result is never relayed (sequenceMessage).
  bool fast = false;
  /// Stop at the first failed rule (the verdict is known; the other rules
  /// are judged only up to then).
  bool stopAtFirstFailure = false;
  /// With `fast`: where the fast profile is not to be trusted (a rule
  /// failed, or a margin is within params' rehearsal.refine.* band of its
  /// limit, untrusted()), run again at full fidelity and return that
  /// (RehearsalResult::refined says why). Off for a preview that the full
  /// rehearsal follows anyway (the console's first verdicts).
  bool refine = true;
  /// Robustness samples draw the robot from this (perturbed()) instead of
  /// the rules' fixed friction and mass ranges; nullopt: the ranges.
  std::optional<RobotEstimate> estimate = std::nullopt;
};

/// A world's start settled: the robot let down onto the ground (worlds
/// place it a little above) until it touches it and its base stays within
/// kSettleDrift over kSettleStill, at most kSettleLimit of sim time.
struct SettledStart {
  RehearsalStart state;
  double seconds = 0;  ///< [s] sim time it took
};
constexpr double kSettleLimit = 5;      ///< [s] a robot still moving then is its own verdict
constexpr double kSettleStill = 0.5;    ///< [s] the window the base must stay within kSettleDrift over
constexpr double kSettleDrift = 0.003;  ///< [m]
/// nullopt and `why` (off the ground, or how fast the base still moves)
/// when it does not settle, or the twin diverges.
std::optional<SettledStart> settleWorldStart(const WorldModel& world, const SimParams& params, std::string& why);

/// The joints `commands` leave alone, as held subtrees: every joint whose
/// subtree holds no commanded joint and no drive joint, outermost first.
std::vector<int> unmovedJoints(const RobotModel& robot, const std::vector<TimedCommand>& commands);

/// The robot's state every RehearsalResult::kSampleInterval.
struct RehearsalSample {
  double time = 0;  ///< [s] from the start
  Pose base;
  std::vector<double> jointPositions;  ///< model joint order
  double roll = 0, pitch = 0;          ///< [rad]
  double margin = 0;                   ///< [m] stability margin
  double speed = 0;                    ///< [m/s] base over ground
};

struct RehearsalResult {
  static constexpr double kSampleInterval = 0.05;  ///< [s]
  bool passed = false;
  std::string error;       ///< why it could not run ("" if it ran)
  bool cancelled = false;  ///< stopped by the progress callback
  std::vector<RuleVerdict> verdicts;  ///< one per Rule
  std::vector<RehearsalSample> path;
  double duration = 0;     ///< [s] simulated: last command's time + rules.settle
  double wallSeconds = 0;  ///< what it took
  uint64_t endHash = 0;    ///< World::stateHash() at the end
  int heldJoints = 0;      ///< joints held rigid throughout (plan.holdUnmoved)
  int switches = 0;        ///< times the twin welded or freed joints mid-run (app/rehearse/held_twin.h)
  bool fast = false;       ///< run in the fast profile (plan.fast; false once refined)
  /// Why a fast run was run again at full fidelity (plan.refine), "" if it
  /// was not; wallSeconds then counts both runs.
  std::string refined;
  bool stoppedEarly = false;  ///< a rule failed and plan.stopAtFirstFailure stopped the run there
  /// [s] how long the robot settled from the world's start before t = 0
  /// (0 when the plan gave a start).
  double settled = 0;
  /// Commands the twin refused when due ("line N at T s: why"): a
  /// rehearsal with any does not pass (the robot would refuse them too).
  std::vector<std::string> refused;
  /// The first failed rule's one-line message, or "passed".
  std::string summary() const;
  /// The rehearsed state at `time` [s from the start], interpolated
  /// between samples (base position linearly, heading by the shorter way);
  /// nullopt outside the path.
  std::optional<RehearsalSample> at(double time) const;
};

/// Runs the plan. `progress(fraction)` is called about every 1 % of the
/// simulated time; returning false cancels. Never throws for bad input: a
/// world that cannot be built or a start that does not fit is `error`.
RehearsalResult rehearse(const RehearsalPlan& plan, const std::function<bool(double)>& progress = {});

/// The margin [the rule's unit] within which the fast profile is not
/// trusted for `rule` (params' rehearsal.refine.*; 0 for twin health).
double refineBand(Rule rule, const SimParams& params);
/// Why a fast run's verdicts are not to be trusted ("" when they are): a
/// refused command, a failed rule, or a margin within refineBand().
std::string untrusted(const RehearsalResult& fast, const SimParams& params);

/// A rule's margin: the distance of its closest approach from its limit,
/// on the safe side positive, beyond the limit negative (signed rules
/// bound |value|).
double ruleMargin(const RuleVerdict& verdict);

/// How a rehearsal in another profile (the fast one) agrees with a
/// reference (the full one), rule by rule: each ruleMargin()'s change,
/// relative to the reference's margin (at least 1 % of the limit, so a
/// margin near zero does not divide by nothing).
struct ProfileAgreement {
  bool sameVerdicts = true;       ///< every rule passes or fails in both
  double largestChange = 0;       ///< the largest margin change (0.1 = 10 %)
  std::string largestRule;        ///< whose it is
  std::string differ;             ///< "stability: passed, failed; ..." ("" when the same)
  bool within(double tolerance) const { return sameVerdicts && largestChange <= tolerance; }
};
/// Rules compared over the part both judged: a run stopped at its first
/// failure compares its verdicts only (margins of unfinished runs are partial).
ProfileAgreement compareProfiles(const RehearsalResult& reference, const RehearsalResult& other);

/// The canonical text of a sequence (`TIME COMMAND` per line, shortest
/// times, toText() commands: what SEQUENCE carries) and its hash
/// (FNV-1a 64, 16 hex digits).
std::string sequenceText(const std::vector<TimedCommand>& commands, const RobotModel* robot);
std::string sequenceHash(const std::string& canonicalText);

/// The plan with its parameters drawn for one robustness sample (seeded,
/// reproducible): the robot from plan.estimate where given (each
/// calibration.* parameter normal about its value with its deviation where
/// observed, uniform over its prior range where not, within its bounds),
/// else every contact's friction and every link's mass scaled within the
/// rules' ranges; heightfield samples moved, the start shifted.
RehearsalPlan perturbed(const RehearsalPlan& plan, uint64_t seed);

/// N perturbed rehearsals, each in the plan's profile (the console and
/// `rehearse --robust` run them fast and stopped at their first failed
/// rule; a sweep's samples, the same draws, at full fidelity to the end).
struct RobustnessResult {
  int samples = 0, passed = 0;
  int refined = 0;  ///< fast samples run again at full fidelity (RehearsalPlan::refine)
  double probability() const { return samples ? static_cast<double>(passed) / samples : 0; }
  std::vector<Pose> endPoses;         ///< per sample
  std::vector<uint64_t> endHashes;    ///< per sample: World::stateHash() at its end (a sweep's `hash`)
  std::vector<bool> samplePassed;     ///< per sample
  std::vector<std::string> failures;  ///< per sample: summary() ("passed" if it did)
  /// Per sample, its base's position every RehearsalResult::kSampleInterval
  /// up to where it ended (the rehearsed path's band, SequenceWorkflow::band()).
  std::vector<std::vector<Vec3>> paths;
  /// [m] largest distance of an end position from their mean, over the
  /// samples that ran to the end (a failed one stops where it failed)
  double spread = 0;
  /// [m] 90 % of those ends lie within this of their mean (the 90th
  /// percentile of their distances); none with fewer than two
  std::optional<double> within90;
  bool fromEstimate = false;  ///< drawn from what the console knows of the robot (RehearsalPlan::estimate)
  double wallSeconds = 0;
  /// The verdict for people: "passes in 16 of 16 draws of what the console
  /// knows of the robot; 90 % of the ends within 12 cm" (or "... of 16
  /// perturbed rehearsals" without an estimate).
  std::string verdict() const;
};
/// rules.robustSamples rehearsals of perturbed(plan, seed + i) on `threads`
/// threads; `progress(done, total)` after each (from the worker threads; false cancels).
RobustnessResult robustness(const RehearsalPlan& plan, uint64_t seed, int threads,
                            const std::function<bool(int, int)>& progress = {});

}  // namespace sp
