#pragma once
// What a running twin writes into its session log (docs/session-format.md),
// shared by the headless runner (`simpartner-sim run --log`) and the
// stand-in robot's TwinHost: the meta with the files the session was built
// from, then from the physics loop the initial state, samples at the logging
// rate, laser scans, and a snapshot and state hash every sim second.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "app/log/session_log.h"
#include "sim/world.h"

namespace sp {

/// The files a session was built from, by the names given to the program.
struct SessionSources {
  std::string worldFile;
  std::string robotFile;               ///< the robot file the world refers to (RobotModel::file)
  std::string paramsFile;              ///< "" = built-in defaults (not stored)
  /// The heightfield's data file (TerrainSpec::file, as the world resolved
  /// it; "" for a plane): stored so that the log re-simulates and replays
  /// anywhere, without the project's files.
  std::string terrainFile = {};
  std::string commandsFile;            ///< "" = none (not stored)
  std::vector<std::string> overrides;  ///< key=value, logged as param_override events at step 0
  /// When the operator opened `robotFile` in place of the world's own robot:
  /// the file the world refers to ("" = none). Re-simulation lays the logged
  /// robot out under this name, so the logged world loads the robot used.
  std::string replacedRobotFile;
  /// Further meta keys (a branched session's `parent_log`, `parent_time`).
  std::map<std::string, std::string> extraMeta = {};
};

/// The bytes of the file at `path` ("" if it cannot be read), for the meta.
std::string readWholeFile(const std::string& path);
/// FNV-1a 64 of a file's bytes as 16 hex digits (as the log's meta and
/// WELCOME carry it); "" when the file cannot be read.
std::string fileHash(const std::string& path);

/// Creates the session log at `path` (an existing file is an error): meta
/// with this program's version and each source file's name, whole contents
/// and hash, and the overrides as events. Returns nullptr and sets `error`
/// when the file cannot be created. Thread: any.
std::unique_ptr<SessionLogWriter> openSessionLog(const std::string& path, const SessionSources& sources,
                                                 std::string& error, const SessionLogOptions& options = {});

/// A new log file name in `dir` (created if missing):
/// `session-YYYYMMDD-HHMMSS.splog` in local time, `-2`, `-3`, ... appended
/// when taken. "" and `error` set when the folder cannot be made. The stand-in
/// robot and the console's log of a remote robot name their files so.
std::string newSessionLogPath(const std::string& dir, std::string& error);

/// A session log in a folder.
struct SessionLogFile {
  std::string path;
  uint64_t bytes = 0;     ///< the file with its -wal and -shm companions
  int64_t modified = 0;   ///< [s] since the epoch
};
/// The `*.splog` files of `dir`, newest first (by modification time, then
/// name); none when the folder is missing.
std::vector<SessionLogFile> listSessionLogs(const std::string& dir);
/// Deletes a log and its -wal/-shm companions; "" or why not.
std::string deleteSessionLog(const std::string& path);
/// Deletes the logs of `dir` beyond the `keep` newest (`keep` <= 0: none),
/// never `current`; returns the paths deleted.
std::vector<std::string> pruneSessionLogs(const std::string& dir, int keep, const std::string& current);

/// Feeds a session log from a physics loop: start() once before the first
/// step, stepped() after every step. Owns the writer.
///
/// Thread: the thread that steps the World calls start(), stepped() and
/// finish(); writer() and failed() may be read from any thread (the writer's
/// flags are atomic).
class SessionRecorder {
 public:
  /// `world` gives the logging rate (rate.log) and the step; the recorder
  /// keeps no reference to it.
  SessionRecorder(std::unique_ptr<SessionLogWriter> writer, const World& world);

  SessionLogWriter& writer() { return *writer_; }
  const SessionLogWriter& writer() const { return *writer_; }

  /// The state at the start: snapshot, hash and first sample.
  void start(const World& world);
  /// After each step: the sample when due, robot 0's new laser scans, the
  /// snapshot and hash at each whole sim second.
  void stepped(const World& world);
  /// At the end of the session: a last snapshot and hash unless this step
  /// has them already, so that re-simulation covers the whole session.
  void finish(const World& world);
  /// True exactly once: at the first call after the writer failed (so that
  /// the caller tells the operator once).
  bool newlyFailed();

 private:
  void snapshot(const World& world);

  std::unique_ptr<SessionLogWriter> writer_;
  int64_t sampleEvery_;
  int64_t snapshotEvery_;
  int64_t lastSnapshot_ = -1;
  bool toldFailure_ = false;
};

}  // namespace sp
