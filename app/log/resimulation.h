#pragma once
// Re-simulation of a session log (app/log/session_log.h): rebuilds the world from
// the files stored in the log, restores a logged snapshot, applies the logged
// commands at their steps and compares the state hash at every logged hash
// step, reporting the first divergence (box2d's recording replay).
//
// The world is rebuilt from the logged file *contents*, never from the paths
// on disk: the contents are held in memory (sim/file_set.h) under their
// recorded paths, so a log still re-simulates after the files on disk were
// edited or moved, and nothing is written; a heightfield's data file is
// stored too (`terrain_*`; older logs read it from beside the recorded world
// file). Parameter overrides come from the log's "param_override" events.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include <map>

#include "sim/params.h"
#include "sim/perturbation.h"
#include "sim/robot_model.h"
#include "sim/world.h"

namespace sp {

class SessionLogReader;

/// The world and parameters a log was recorded with, rebuilt from the files
/// it stores (see above) and its parameter overrides.
struct LoggedWorld {
  WorldModel world;   ///< as the files say
  SimParams params;
  /// The logged robot's hidden deviations (meta `perturbation_seed`), if it
  /// was a robot that is not its twin: its physics is physicsWorld().
  std::optional<Perturbation> perturbation;
  /// The world the logged robot's physics ran: world calibrated by the
  /// parameters' calibration.* keys, perturbed if it was.
  WorldModel physicsWorld() const {
    const WorldModel calibrated = calibratedWorld(world, params);
    return perturbation ? perturbWorld(calibrated, *perturbation) : calibrated;
  }
};
/// nullopt and `error` (naming `path`) when the log holds no files or they
/// do not load.
std::optional<LoggedWorld> loggedWorld(const SessionLogReader& reader, const std::string& path, std::string& error);

struct ResimOptions {
  double from = 0;  ///< start at the latest snapshot at or before this sim time [s]
  /// Called with the fraction done about every 1 % of the steps; returning
  /// false stops the re-simulation (ResimReport::cancelled).
  std::function<bool(double)> progress;
};

/// The first logged hash that the re-simulation did not reproduce.
struct ResimDivergence {
  int64_t step = 0;
  double time = 0;         ///< [s]
  uint64_t expected = 0;   ///< the logged hash
  uint64_t actual = 0;     ///< the re-simulation's
};

struct ResimReport {
  int64_t startStep = 0;     ///< the step of the snapshot restored
  int64_t endStep = 0;       ///< the last step simulated
  int hashesCompared = 0;
  int commandsApplied = 0;
  std::optional<ResimDivergence> divergence;  ///< nullopt: every hash matched
  std::string healthMessage;  ///< the twin diverged physically while re-simulating, else ""
  bool cancelled = false;     ///< stopped by ResimOptions::progress before the end
};

/// A moment of a log to branch a new simulation from: the state there,
/// re-simulated from the nearest snapshot before it.
struct BranchPoint {
  LoggedWorld logged;
  Snapshot state;             ///< at `step`
  uint64_t hash = 0;          ///< World::stateHash() of `state`
  std::optional<uint64_t> loggedHash;  ///< the log's own hash at `step`, if it has one
  int64_t step = 0;
  int64_t fromSnapshot = 0;   ///< the snapshot's step it was re-simulated from
  std::map<std::string, std::string> meta;  ///< the log's meta (its files)
  /// Not re-simulated but rebuilt from a telemetry-only log's sample
  /// (LogPlayer::branchAt): the pose and joints are the logged ones, what
  /// telemetry does not carry (contact state, controllers' integrators) is not.
  bool reconstructed = false;
};
/// The state at `time` [s] (the step nearest it) of the log at `path`;
/// nullopt and `error` when the log cannot be re-simulated there.
/// `progress(fraction)` while re-simulating; returning false cancels
/// (nullopt, `error` says so). Thread: any.
std::optional<BranchPoint> branchAt(const std::string& path, double time, std::string& error,
                                    const std::function<bool(double)>& progress = {});

/// Re-simulates the log at `path`. Returns nullopt and sets `error` when the
/// log cannot be read or the world cannot be rebuilt. Thread: any; the
/// calling thread owns the rebuilt world for the whole call.
std::optional<ResimReport> resimulate(const std::string& path, const ResimOptions& options, std::string& error);

/// One-line hex form of a state hash ("%016llx").
std::string hashHex(uint64_t hash);

}  // namespace sp
