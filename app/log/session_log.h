#pragma once
// The session log: one SQLite file per session (schema in
// docs/session-format.md, format version 1). SessionLogWriter takes plain
// values from the physics thread into a bounded queue and a writer thread
// batches them into transactions; SessionLogReader reads a finished (or
// crashed) log back.
//
// Tables: meta(key, value); commands(step, time, source, text);
// samples(step, time, base_x/y/z, qw/qx/qy/qz, joints BLOB, wheel_normal
// BLOB, roll, pitch); laser(step, time, angle_min, angle_step, ranges BLOB);
// events(step, time, kind, text); snapshots(step, time, hash, data BLOB);
// hashes(step, hash). BLOBs of doubles are little-endian IEEE 754; 64-bit
// hashes are stored as INTEGER with the same bits (so may read negative).

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include "app/state/log_sample.h"
#include "sim/command.h"
#include "sim/hash.h"
#include "sim/readout.h"  // fnv1a64: the hash of each logged file's contents
#include "sim/world.h"

struct sqlite3;

namespace sp {

inline constexpr int kSessionLogFormatVersion = 1;


/// A file the session was built from, stored whole in the log's meta table.
struct SessionFile {
  std::string role;      ///< "robot", "world", "params", ...: the meta key prefix
  std::string name;      ///< as given to the program
  std::string contents;  ///< the file's bytes
};

/// What the meta table records about a session.
struct SessionInfo {
  std::string programVersion;
  std::string startTime;  ///< ISO-8601 UTC; "" = now
  std::vector<SessionFile> files;
  std::map<std::string, std::string> extraMeta;  ///< further meta keys (docs/session-format.md)
};

/// One laser scan.
struct LogLaser {
  int64_t step = 0;
  double time = 0;        ///< [s]
  double angleMin = 0;    ///< [rad]
  double angleStep = 0;   ///< [rad]
  std::vector<double> ranges;  ///< [m]
  friend bool operator==(const LogLaser&, const LogLaser&) = default;
};

/// What the predictive ghost had shown for robot time `time` (app/ghost/ghost.h),
/// and how far the robot turned out to be from it when its telemetry for
/// that time arrived.
struct LogPrediction {
  double time = 0;  ///< [s] robot time predicted for
  double made = 0;  ///< [s] robot time of the telemetry the prediction ran from
  std::array<double, 3> base{};            ///< predicted base position, world [m]
  std::array<double, 4> quat{1, 0, 0, 0};  ///< predicted base orientation w, x, y, z
  double positionError = 0;  ///< [m] horizontal, against the telemetry
  double headingError = 0;   ///< [rad] absolute yaw difference
  friend bool operator==(const LogPrediction&, const LogPrediction&) = default;
};

/// One parameter of a calibration fit the console made (app/calibration):
/// one row per parameter per fit.
struct LogCalibration {
  double time = 0;     ///< [s] robot time of the newest telemetry fitted
  std::string param;   ///< its key (calibration.wheel_radius)
  double value = 0;    ///< fitted (or kept, when unobserved or refused)
  double sigma = 0;    ///< one standard deviation; 0 when unobserved
  bool observed = false;
  std::string status;  ///< "applied", "frozen" (fitted, not applied), "reset", or "refused: why"
  friend bool operator==(const LogCalibration&, const LogCalibration&) = default;
};

/// A command as applied: its step, its source ("operator", "sequence",
/// "rehearsal") and its sequence-file text (sp::toText).
struct LogCommand {
  int64_t step = 0;
  double time = 0;
  std::string source;
  std::string text;
  friend bool operator==(const LogCommand&, const LogCommand&) = default;
};

/// Something that happened: kind "health", "link", "estop", "note", ...
struct LogEvent {
  int64_t step = 0;
  double time = 0;
  std::string kind;
  std::string text;
  friend bool operator==(const LogEvent&, const LogEvent&) = default;
};

/// A read-out as logged: the base pose, every joint's position then rate,
/// the wheel normal forces, roll and pitch (sim/readout.h).
/// The row of readRobot(world, robot) (app/state/robot_shapes.h:
/// sampleFromReadout). Thread: the World's.
LogSample makeLogSample(const World& world, int robot = 0);

/// A laser reading as logged; nullopt if `sample` is not a laser scan.
std::optional<LogLaser> makeLogLaser(const SensorSample& sample);

/// Tuning of the writer.
struct SessionLogOptions {
  std::size_t queueCapacity = 1 << 16;  ///< items queued before new ones are dropped
  int batchMillis = 25;                 ///< longest wait between transactions [ms]; 25 keeps a kill's loss well under 100 ms
  std::size_t batchItems = 500;         ///< queue length that wakes the writer early
  int64_t maxPageCount = 0;             ///< > 0: SQLite page limit (tests: a full disk)
};

/// Writes one session's log.
///
/// Threads: the log* methods, dropped(), failed() and errorMessage() may be
/// called from any one thread at a time (the physics thread); they only
/// queue values and never wait on the disk. An internal writer thread owns
/// the database. close() (or the destructor) flushes what is queued.
class SessionLogWriter {
 public:
  /// Creates `path` (replacing nothing: an existing file is an error),
  /// writes the schema and the meta table and starts the writer thread.
  /// Returns nullptr and sets `error` when the file cannot be created.
  static std::unique_ptr<SessionLogWriter> open(const std::string& path, const SessionInfo& info,
                                                std::string& error, const SessionLogOptions& options = {});
  ~SessionLogWriter();
  SessionLogWriter(const SessionLogWriter&) = delete;
  SessionLogWriter& operator=(const SessionLogWriter&) = delete;

  // Each queues one item; false when the queue was full and it was dropped.
  /// The command's text is toText(command, robot) (slider values in metres
  /// need the robot; see sim/command.h).
  bool logCommand(int64_t step, double time, const std::string& source, const Command& command,
                  const RobotModel* robot = nullptr);
  bool logSample(LogSample sample);
  bool logLaser(LogLaser scan);
  /// Safe from any thread (the console's, while the physics thread logs).
  bool logPrediction(const LogPrediction& prediction);
  bool logCalibration(LogCalibration row);
  bool logEvent(int64_t step, double time, std::string kind, std::string text);
  /// A snapshot (encoded by the writer thread) with its World::stateHash().
  bool logSnapshot(Snapshot snapshot, double time, uint64_t hash);
  bool logHash(int64_t step, uint64_t hash);

  /// Writes what is queued and closes the file; idempotent.
  void close();

  /// Items dropped: the queue was full, or the disk had failed.
  int64_t dropped() const { return dropped_.load(); }
  /// True once a write failed (disk full, I/O error): later items are
  /// dropped, the file holds everything committed before.
  bool failed() const { return failed_.load(); }
  /// Why it failed, or "".
  std::string errorMessage() const;
  const std::string& path() const { return path_; }

 private:
  struct SnapshotItem {
    Snapshot snapshot;
    double time = 0;
    uint64_t hash = 0;
  };
  struct HashItem {
    int64_t step = 0;
    uint64_t hash = 0;
  };
  using Item = std::variant<LogCommand, LogSample, LogLaser, LogEvent, SnapshotItem, HashItem, LogPrediction, LogCalibration>;
  struct Statements;

  SessionLogWriter(std::string path, const SessionLogOptions& options);
  bool push(Item item);
  void run();
  bool writeBatch(std::deque<Item>& batch);
  void fail(const std::string& message);

  std::string path_;
  SessionLogOptions options_;
  sqlite3* db_ = nullptr;
  std::unique_ptr<Statements> statements_;

  mutable std::mutex mutex_;  // guards queue_, closing_, error_
  std::condition_variable wake_;
  std::deque<Item> queue_;
  bool closing_ = false;
  std::string error_;
  std::atomic<int64_t> dropped_{0};
  std::atomic<bool> failed_{false};
  std::thread thread_;
};

/// Reads a session log. Thread: one thread at a time.
/// Opens the session log at `path` read-only without leaving files beside
/// it: a log whose writer closed it (no -wal) is opened immutable, so no
/// -wal or -shm is created; one with a -wal (live, or a killed writer's) as
/// it is. Returns SQLite's result code; `*db` as sqlite3_open_v2 sets it.
int openSessionLogReadOnly(const std::string& path, sqlite3** db);

class SessionLogReader {
 public:
  /// Opens read-only. Returns nullptr and sets `error` to a message naming
  /// the file when it is not a SimPartner log or of another format version.
  static std::unique_ptr<SessionLogReader> open(const std::string& path, std::string& error);
  ~SessionLogReader();
  SessionLogReader(const SessionLogReader&) = delete;
  SessionLogReader& operator=(const SessionLogReader&) = delete;

  std::map<std::string, std::string> meta() const;
  /// Each table (stream) with its row count, in schema order.
  std::vector<std::pair<std::string, int64_t>> streams() const;
  /// Samples with t0 <= time <= t1 [s], in step order (uses the time index).
  std::vector<LogSample> samplesBetween(double t0, double t1) const;
  /// The latest sample at or before `time` (one row from the time index);
  /// nullopt before the first.
  std::optional<LogSample> sampleAt(double time) const;
  /// The latest laser scan at or before `time` (one row); nullopt before the first.
  std::optional<LogLaser> laserAt(double time) const;
  /// The first and last sample times; nullopt without samples.
  std::optional<std::pair<double, double>> sampleTimeRange() const;
  /// Laser scans with t0 <= time <= t1 [s], in step order (uses the time
  /// index where the log has one: logs since laser_time was added).
  std::vector<LogLaser> laserBetween(double t0, double t1) const;
  /// The ghost's predictions for robot times in [t0, t1]; none in a log
  /// written before they were logged.
  std::vector<LogPrediction> predictionsBetween(double t0, double t1) const;
  std::vector<LogCommand> commands() const;
  /// The console's calibration fits, oldest first (none in older logs).
  std::vector<LogCalibration> calibration() const;
  std::vector<LogEvent> events() const;
  /// (step, hash) of the periodic state hashes, in step order.
  std::vector<std::pair<int64_t, uint64_t>> hashes() const;
  /// Steps that have a snapshot, ascending.
  std::vector<int64_t> snapshotSteps() const;
  /// The snapshot at `step` and its state hash; nullopt (with `error`) if
  /// there is none or it does not decode.
  std::optional<std::pair<Snapshot, uint64_t>> snapshot(int64_t step, std::string* error = nullptr) const;

 private:
  explicit SessionLogReader(sqlite3* db) : db_(db) {}
  sqlite3* db_ = nullptr;
};

}  // namespace sp
