#pragma once
// Sweeps: many rehearsals of one command sequence, each with its own
// parameters and seed (Monte-Carlo robustness before a risky drive, or a
// parameter sweep for model identification), run as independent tasks so
// that one machine's cores or a cluster's job array can share them.
//
// A sweep is a folder:
//   manifest.txt   the spec (files, --set for all, the varied keys) and one
//                  line per sample: INDEX SEED --set KEY=VALUE ...
//   results/N.tsv  one task's outcome (key<TAB>value lines), written whole
//   status/N       "ok", or "error: why" when the task could not run
//   results.csv, report.md, end_positions.svg, margins.svg   by collectSweep()
// A task reads only the manifest and writes only its own two files, so a
// task is the same on any machine that sees the folder (a shared
// filesystem on a cluster) and a rerun of some tasks touches nothing else.
// Sample i's draws come from the sweep's seed and i alone: a sample gives
// the same result (the same end hash) wherever and whenever it runs.
//
//   sp::SweepSpec spec = ...;            // files, vary, samples, seed
//   std::string error;
//   sp::createSweep(dir, spec, error);    // draws the samples, writes the manifest
//   sp::runSweepLocal(dir, {}, 2, error); // or a job array: runSweepTask(dir, i)
//   sp::SweepSummary s = sp::collectSweep(dir, error);
//
// Thread: createSweep/collectSweep on any one thread; runSweepLocal runs
// tasks on `threads` threads of its own; runSweepTask on any thread.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "app/rehearse/rehearsal.h"

namespace sp {

/// A parameter drawn uniformly in [lo, hi] for every sample.
struct SweepVary {
  std::string key;  ///< a parameter key (simpartner-sim params)
  double lo = 0, hi = 0;
};

struct SweepSpec {
  std::string world, commands;  ///< files (absolute paths in the manifest)
  std::string rules, params;    ///< optional files ("" = defaults)
  std::vector<std::string> overrides;  ///< KEY=VALUE for every sample
  std::vector<SweepVary> vary;
  int samples = 0;
  uint64_t seed = 1;
  /// Each sample also perturbs friction, masses, terrain and the start
  /// within the rules' robustness ranges, seeded by its own seed.
  bool perturb = true;
  /// The robot's state to start from (the console's: where the robot is
  /// now); nullopt = the world's own start.
  std::optional<RehearsalStart> start;
  /// Sample i's seed is seed + i, as robustness() numbers them (the
  /// console's cluster robustness equals its local one sample for sample);
  /// otherwise drawn from the seed and i (splitmix64).
  bool consecutiveSeeds = false;
  /// With `perturb`: each sample draws the robot from what the console
  /// knows of it (RehearsalPlan::estimate) instead of the rules' ranges.
  std::optional<RobotEstimate> estimate;
};

/// One sample of the manifest.
struct SweepSample {
  int index = 0;
  uint64_t seed = 0;
  std::vector<std::string> sets;  ///< KEY=VALUE drawn for it
};

/// "KEY=LO:HI" as a SweepVary; "" or why not.
std::string parseVary(const std::string& text, SweepVary& out);

/// Checks the spec (files load, keys exist and take the drawn values,
/// samples 1..100000), draws the samples and writes `dir`/manifest.txt
/// (creating `dir`; an existing manifest is not overwritten). False and
/// `error` (naming the file or option) otherwise.
bool createSweep(const std::string& dir, const SweepSpec& spec, std::string& error);

/// The console's "Robustness on cluster": writes the plan's sequence,
/// rules, parameters and (for a heightfield, with any edits) world and
/// terrain into `dir`, then a sweep of plan.rules.robustSamples samples
/// from the plan's start with robustness()'s seeds (seed + i): sample i
/// equals robustness(plan, seed)'s sample i.
bool createSweepFromPlan(const std::string& dir, const RehearsalPlan& plan, uint64_t seed, std::string& error);

/// Reads `dir`/manifest.txt; false and `error` naming its line otherwise.
bool readSweep(const std::string& dir, SweepSpec& spec, std::vector<SweepSample>& samples, std::string& error);

/// Runs sample `index` of the sweep in `dir` and writes its result and
/// status files. False (and the status file says why) when it could not run.
bool runSweepTask(const std::string& dir, int index, std::string& error);

/// The samples with no "ok" status: not run yet, or failed to run.
std::vector<int> pendingTasks(const std::string& dir, std::string& error);

/// Runs `indices` (all pending when empty) on `threads` threads. False when
/// the manifest cannot be read; tasks that fail are left in their status.
bool runSweepLocal(const std::string& dir, std::vector<int> indices, int threads, std::string& error);

/// `indices` as a Slurm --array list, runs joined: "0-7,9,12-13".
std::string slurmArrayList(std::vector<int> indices);

/// Writes `dir`/sweep.sbatch: a job array script that runs
/// `simBinary sweep-task DIR` (the task reads SLURM_ARRAY_TASK_ID), logs in
/// `dir`/logs. It runs unchanged on any Slurm cluster that shares `dir`
/// and the binary's path with its nodes.
bool writeSlurmScript(const std::string& dir, const std::string& simBinary, std::string& error);

/// Submits `indices` (all pending when empty) of the sweep as a job array
/// with sbatch (`sbatchArgs` passed before the script: --partition=...).
/// The job id, or "" and `error`.
std::string submitSlurm(const std::string& dir, std::vector<int> indices, const std::string& simBinary,
                        const std::vector<std::string>& sbatchArgs, std::string& error);

struct SweepSummary {
  int samples = 0, done = 0, passed = 0;
  std::vector<int> failed;   ///< tasks that could not run (status "error: ...")
  std::vector<int> missing;  ///< tasks with no status at all
};

/// Gathers the results into `dir`/results.csv (one row per sample: index,
/// seed, the varied values, passed, summary, end pose, minimum stability
/// margin, health, end hash, wall time) and `dir`/report.md with plots of
/// the end positions and the margins, naming failed and missing tasks.
SweepSummary collectSweep(const std::string& dir, std::string& error);

}  // namespace sp
