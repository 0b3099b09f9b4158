#include "app/log/session_log.h"

#include "app/state/robot_shapes.h"

#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "app/log/snapshot_codec.h"

namespace sp {
namespace {

const char* const kSchema = R"sql(
CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE commands(step INTEGER, time REAL, source TEXT, text TEXT);
CREATE TABLE samples(step INTEGER PRIMARY KEY, time REAL, base_x REAL, base_y REAL, base_z REAL,
                     qw REAL, qx REAL, qy REAL, qz REAL, joints BLOB, wheel_normal BLOB,
                     roll REAL, pitch REAL);
CREATE INDEX samples_time ON samples(time);
CREATE TABLE laser(step INTEGER PRIMARY KEY, time REAL, angle_min REAL, angle_step REAL, ranges BLOB);
CREATE INDEX laser_time ON laser(time);
CREATE TABLE events(step INTEGER, time REAL, kind TEXT, text TEXT);
CREATE TABLE snapshots(step INTEGER PRIMARY KEY, time REAL, hash INTEGER, data BLOB);
CREATE TABLE hashes(step INTEGER PRIMARY KEY, hash INTEGER);
CREATE TABLE predictions(time REAL, made REAL, base_x REAL, base_y REAL, base_z REAL,
                         qw REAL, qx REAL, qy REAL, qz REAL, error_position REAL, error_heading REAL);
CREATE INDEX predictions_time ON predictions(time);
CREATE TABLE calibration(time REAL, param TEXT, value REAL, sigma REAL, observed INTEGER, status TEXT);
)sql";

const char* const kStreams[] = {"meta",   "commands", "samples",     "laser",      "events",
                                 "snapshots", "hashes", "predictions", "calibration"};

// Doubles as little-endian bytes, and back.
std::vector<uint8_t> packDoubles(const double* values, std::size_t n) {
  std::vector<uint8_t> out(n * 8);
  for (std::size_t i = 0; i < n; ++i) {
    uint64_t bits = 0;
    std::memcpy(&bits, &values[i], 8);
    for (std::size_t b = 0; b < 8; ++b) out[i * 8 + b] = static_cast<uint8_t>(bits >> (8 * b));
  }
  return out;
}

std::vector<double> unpackDoubles(const void* blob, int bytes) {
  const auto* p = static_cast<const uint8_t*>(blob);
  std::vector<double> out(static_cast<std::size_t>(bytes > 0 ? bytes : 0) / 8);
  for (std::size_t i = 0; i < out.size(); ++i) {
    uint64_t bits = 0;
    for (std::size_t b = 0; b < 8; ++b) bits |= static_cast<uint64_t>(p[i * 8 + b]) << (8 * b);
    std::memcpy(&out[i], &bits, 8);
  }
  return out;
}

std::string isoUtcNow() {
  std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// A prepared statement, finalized on destruction.
class Stmt {
 public:
  Stmt(sqlite3* db, const char* sql) { sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr); }
  ~Stmt() { sqlite3_finalize(stmt_); }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;
  sqlite3_stmt* get() const { return stmt_; }
  explicit operator bool() const { return stmt_ != nullptr; }
  void bind(int i, int64_t v) { sqlite3_bind_int64(stmt_, i, v); }
  void bind(int i, double v) { sqlite3_bind_double(stmt_, i, v); }
  void bind(int i, const std::string& v) {
    sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
  }
  void bind(int i, const std::vector<uint8_t>& v) {
    sqlite3_bind_blob(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
  }
  // Steps once and resets; returns the sqlite result code of the step.
  int exec() {
    int rc = sqlite3_step(stmt_);
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
    return rc;
  }
  bool row() { return sqlite3_step(stmt_) == SQLITE_ROW; }
  int64_t i64(int c) const { return sqlite3_column_int64(stmt_, c); }
  double f64(int c) const { return sqlite3_column_double(stmt_, c); }
  std::string text(int c) const {
    const unsigned char* t = sqlite3_column_text(stmt_, c);
    return t ? std::string(reinterpret_cast<const char*>(t), static_cast<std::size_t>(sqlite3_column_bytes(stmt_, c)))
             : std::string();
  }
  std::vector<double> doubles(int c) const {
    return unpackDoubles(sqlite3_column_blob(stmt_, c), sqlite3_column_bytes(stmt_, c));
  }
  std::vector<uint8_t> bytes(int c) const {
    const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, c));
    return p ? std::vector<uint8_t>(p, p + sqlite3_column_bytes(stmt_, c)) : std::vector<uint8_t>();
  }

 private:
  sqlite3_stmt* stmt_ = nullptr;
};

bool execSql(sqlite3* db, const std::string& sql, std::string& error) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message) == SQLITE_OK) return true;
  error = message ? message : sqlite3_errmsg(db);
  sqlite3_free(message);
  return false;
}

}  // namespace

LogSample makeLogSample(const World& world, int robot) { return sampleFromReadout(readRobot(world, robot)); }

std::optional<LogLaser> makeLogLaser(const SensorSample& sample) {
  const auto* l = std::get_if<LaserReading>(&sample.value);
  if (!l) return std::nullopt;
  return LogLaser{sample.step, sample.time, l->angleMin, l->angleStep, l->ranges};
}

struct SessionLogWriter::Statements {
  explicit Statements(sqlite3* db)
      : command(db, "INSERT INTO commands VALUES(?,?,?,?)"),
        sample(db, "INSERT OR REPLACE INTO samples VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?)"),
        laser(db, "INSERT OR REPLACE INTO laser VALUES(?,?,?,?,?)"),
        event(db, "INSERT INTO events VALUES(?,?,?,?)"),
        snapshot(db, "INSERT OR REPLACE INTO snapshots VALUES(?,?,?,?)"),
        hash(db, "INSERT OR REPLACE INTO hashes VALUES(?,?)"),
        prediction(db, "INSERT INTO predictions VALUES(?,?,?,?,?,?,?,?,?,?,?)"),
        calibration(db, "INSERT INTO calibration VALUES(?,?,?,?,?,?)") {}
  bool ok() const { return command && sample && laser && event && snapshot && hash && prediction && calibration; }
  Stmt command, sample, laser, event, snapshot, hash, prediction, calibration;
};

SessionLogWriter::SessionLogWriter(std::string path, const SessionLogOptions& options)
    : path_(std::move(path)), options_(options) {}

std::unique_ptr<SessionLogWriter> SessionLogWriter::open(const std::string& path, const SessionInfo& info,
                                                         std::string& error, const SessionLogOptions& options) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    error = path + ": already exists";
    return nullptr;
  }
  std::unique_ptr<SessionLogWriter> w(new SessionLogWriter(path, options));
  if (sqlite3_open_v2(path.c_str(), &w->db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    error = path + ": cannot create the session log: " + (w->db_ ? sqlite3_errmsg(w->db_) : "out of memory");
    return nullptr;
  }
  std::string sqlError;
  std::string pragmas = "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;";
  if (options.maxPageCount > 0) pragmas += " PRAGMA max_page_count=" + std::to_string(options.maxPageCount) + ";";
  bool ok = execSql(w->db_, pragmas, sqlError) && execSql(w->db_, "BEGIN", sqlError) &&
            execSql(w->db_, kSchema, sqlError);
  if (ok) {
    Stmt meta(w->db_, "INSERT INTO meta VALUES(?,?)");
    auto put = [&](const std::string& key, const std::string& value) {
      meta.bind(1, key);
      meta.bind(2, value);
      if (meta.exec() != SQLITE_DONE) ok = false;
    };
    put("format_version", std::to_string(kSessionLogFormatVersion));
    put("program_version", info.programVersion);
    put("start_time", info.startTime.empty() ? isoUtcNow() : info.startTime);
    put("snapshot_codec_version", std::to_string(kSnapshotCodecVersion));
    for (const SessionFile& f : info.files) {
      put(f.role + "_file", f.name);
      put(f.role + "_contents", f.contents);
      put(f.role + "_fnv1a64", hex64(fnv1a64(f.contents)));
    }
    for (const auto& [key, value] : info.extraMeta) put(key, value);
    if (!ok) sqlError = sqlite3_errmsg(w->db_);
  }
  ok = ok && execSql(w->db_, "COMMIT", sqlError);
  if (ok) {
    w->statements_ = std::make_unique<Statements>(w->db_);
    if (!w->statements_->ok()) {
      ok = false;
      sqlError = sqlite3_errmsg(w->db_);
    }
  }
  if (!ok) {
    error = path + ": cannot create the session log: " + sqlError;
    w->statements_.reset();
    sqlite3_close(w->db_);
    w->db_ = nullptr;
    std::filesystem::remove(path, ec);
    return nullptr;
  }
  w->thread_ = std::thread([raw = w.get()] { raw->run(); });
  return w;
}

SessionLogWriter::~SessionLogWriter() { close(); }

void SessionLogWriter::close() {
  {
    std::lock_guard lock(mutex_);
    if (closing_ && !thread_.joinable()) return;
    closing_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
  statements_.reset();
  if (db_) {
    sqlite3_close(db_);
    db_ = nullptr;
  }
}

bool SessionLogWriter::push(Item item) {
  std::size_t size = 0;
  {
    std::lock_guard lock(mutex_);
    if (closing_ || queue_.size() >= options_.queueCapacity) {
      dropped_.fetch_add(1);
      return false;
    }
    queue_.push_back(std::move(item));
    size = queue_.size();
  }
  if (size == options_.batchItems) wake_.notify_one();
  return true;
}

bool SessionLogWriter::logCommand(int64_t step, double time, const std::string& source, const Command& command,
                                  const RobotModel* robot) {
  return push(LogCommand{step, time, source, toText(command, robot)});
}
bool SessionLogWriter::logSample(LogSample sample) { return push(std::move(sample)); }
bool SessionLogWriter::logLaser(LogLaser scan) { return push(std::move(scan)); }
bool SessionLogWriter::logPrediction(const LogPrediction& prediction) { return push(prediction); }

bool SessionLogWriter::logCalibration(LogCalibration row) { return push(std::move(row)); }
bool SessionLogWriter::logEvent(int64_t step, double time, std::string kind, std::string text) {
  return push(LogEvent{step, time, std::move(kind), std::move(text)});
}
bool SessionLogWriter::logSnapshot(Snapshot snapshot, double time, uint64_t hash) {
  return push(SnapshotItem{std::move(snapshot), time, hash});
}
bool SessionLogWriter::logHash(int64_t step, uint64_t hash) { return push(HashItem{step, hash}); }

std::string SessionLogWriter::errorMessage() const {
  std::lock_guard lock(mutex_);
  return error_;
}

void SessionLogWriter::fail(const std::string& message) {
  {
    std::lock_guard lock(mutex_);
    if (error_.empty()) error_ = path_ + ": " + message;
  }
  failed_.store(true);
}

void SessionLogWriter::run() {
  std::deque<Item> batch;
  for (;;) {
    bool last = false;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, std::chrono::milliseconds(options_.batchMillis),
                     [this] { return closing_ || queue_.size() >= options_.batchItems; });
      batch.swap(queue_);
      last = closing_;
    }
    if (!batch.empty()) {
      if (failed_.load() || !writeBatch(batch)) dropped_.fetch_add(static_cast<int64_t>(batch.size()));
      batch.clear();
    }
    if (last) {
      std::lock_guard lock(mutex_);
      if (queue_.empty()) return;
    }
  }
}

bool SessionLogWriter::writeBatch(std::deque<Item>& batch) {
  std::string error;
  if (!execSql(db_, "BEGIN", error)) {
    fail(error);
    return false;
  }
  Statements& s = *statements_;
  int rc = SQLITE_DONE;
  for (const Item& item : batch) {
    if (const auto* c = std::get_if<LogCommand>(&item)) {
      s.command.bind(1, c->step); s.command.bind(2, c->time);
      s.command.bind(3, c->source); s.command.bind(4, c->text);
      rc = s.command.exec();
    } else if (const auto* m = std::get_if<LogSample>(&item)) {
      Stmt& st = s.sample;
      st.bind(1, m->step); st.bind(2, m->time);
      for (int i = 0; i < 3; ++i) st.bind(3 + i, m->base[static_cast<std::size_t>(i)]);
      for (int i = 0; i < 4; ++i) st.bind(6 + i, m->quat[static_cast<std::size_t>(i)]);
      st.bind(10, packDoubles(m->joints.data(), m->joints.size()));
      // The normal forces, then the tangential ones: a reader of the older
      // four-value column reads the normals as before.
      std::array<double, 8> wheels{};
      std::copy(m->wheelNormal.begin(), m->wheelNormal.end(), wheels.begin());
      std::copy(m->wheelTangential.begin(), m->wheelTangential.end(), wheels.begin() + 4);
      st.bind(11, packDoubles(wheels.data(), wheels.size()));
      st.bind(12, m->roll); st.bind(13, m->pitch);
      rc = st.exec();
    } else if (const auto* l = std::get_if<LogLaser>(&item)) {
      s.laser.bind(1, l->step); s.laser.bind(2, l->time);
      s.laser.bind(3, l->angleMin); s.laser.bind(4, l->angleStep);
      s.laser.bind(5, packDoubles(l->ranges.data(), l->ranges.size()));
      rc = s.laser.exec();
    } else if (const auto* e = std::get_if<LogEvent>(&item)) {
      s.event.bind(1, e->step); s.event.bind(2, e->time);
      s.event.bind(3, e->kind); s.event.bind(4, e->text);
      rc = s.event.exec();
    } else if (const auto* n = std::get_if<SnapshotItem>(&item)) {
      s.snapshot.bind(1, n->snapshot.step); s.snapshot.bind(2, n->time);
      s.snapshot.bind(3, static_cast<int64_t>(n->hash));
      s.snapshot.bind(4, encodeSnapshot(n->snapshot));
      rc = s.snapshot.exec();
    } else if (const auto* h = std::get_if<HashItem>(&item)) {
      s.hash.bind(1, h->step); s.hash.bind(2, static_cast<int64_t>(h->hash));
      rc = s.hash.exec();
    } else if (const auto* p = std::get_if<LogPrediction>(&item)) {
      Stmt& st = s.prediction;
      st.bind(1, p->time); st.bind(2, p->made);
      for (int i = 0; i < 3; ++i) st.bind(3 + i, p->base[static_cast<std::size_t>(i)]);
      for (int i = 0; i < 4; ++i) st.bind(6 + i, p->quat[static_cast<std::size_t>(i)]);
      st.bind(10, p->positionError); st.bind(11, p->headingError);
      rc = st.exec();
    } else if (const auto* k = std::get_if<LogCalibration>(&item)) {
      Stmt& st = s.calibration;
      st.bind(1, k->time); st.bind(2, k->param); st.bind(3, k->value); st.bind(4, k->sigma);
      st.bind(5, static_cast<int64_t>(k->observed ? 1 : 0)); st.bind(6, k->status);
      rc = st.exec();
    }
    if (rc != SQLITE_DONE) break;
  }
  if (rc != SQLITE_DONE) {
    fail(sqlite3_errstr(rc));
    execSql(db_, "ROLLBACK", error);
    return false;
  }
  if (!execSql(db_, "COMMIT", error)) {
    fail(error);
    execSql(db_, "ROLLBACK", error);
    return false;
  }
  return true;
}

// Reader.

int openSessionLogReadOnly(const std::string& path, sqlite3** db) {
  // A log its writer closed has no -wal file (the writer checkpoints it
  // away); a plain read-only connection would create -wal and -shm beside
  // it and leave them there. Nobody writes such a log any more, so it is
  // opened as immutable, which creates nothing. A log with a -wal (being
  // written, or left by a killed writer) is opened read-only as it is.
  std::error_code ec;
  if (std::filesystem::exists(path + "-wal", ec) || ec) return sqlite3_open_v2(path.c_str(), db, SQLITE_OPEN_READONLY, nullptr);
  std::string uri = "file:";
  for (const char c : std::filesystem::absolute(path, ec).string()) {
    if (c == '%' || c == '?' || c == '#') {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", static_cast<unsigned char>(c));
      uri += hex;
    } else {
      uri += c;
    }
  }
  uri += "?immutable=1";
  return sqlite3_open_v2(uri.c_str(), db, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
}

std::unique_ptr<SessionLogReader> SessionLogReader::open(const std::string& path, std::string& error) {
  sqlite3* db = nullptr;
  if (openSessionLogReadOnly(path, &db) != SQLITE_OK) {
    error = path + ": cannot open the session log: " + (db ? sqlite3_errmsg(db) : "out of memory");
    sqlite3_close(db);
    return nullptr;
  }
  std::unique_ptr<SessionLogReader> r(new SessionLogReader(db));
  std::string version;
  bool found = false;
  {
    Stmt q(db, "SELECT value FROM meta WHERE key='format_version'");
    if (!q) {
      std::string why = sqlite3_errmsg(db);
      if (sqlite3_errcode(db) == SQLITE_NOTADB)
        error = path + ": not a session log (not an SQLite database)";
      else if (why.rfind("no such table", 0) == 0)
        error = path + ": not a session log (no meta table)";
      else
        error = path + ": cannot read the session log: " + why;
      return nullptr;
    }
    if (q.row()) {
      found = true;
      version = q.text(0);
    }
  }
  if (!found) {
    error = path + ": not a session log (no format_version in meta)";
    return nullptr;
  }
  if (version != std::to_string(kSessionLogFormatVersion)) {
    error = path + ": session log format version " + version + " is not supported (this program reads version " +
            std::to_string(kSessionLogFormatVersion) + ")";
    return nullptr;
  }
  return r;
}

SessionLogReader::~SessionLogReader() { sqlite3_close(db_); }

std::map<std::string, std::string> SessionLogReader::meta() const {
  std::map<std::string, std::string> out;
  Stmt q(db_, "SELECT key, value FROM meta");
  while (q && q.row()) out[q.text(0)] = q.text(1);
  return out;
}

std::vector<std::pair<std::string, int64_t>> SessionLogReader::streams() const {
  std::vector<std::pair<std::string, int64_t>> out;
  for (const char* table : kStreams) {
    Stmt q(db_, (std::string("SELECT count(*) FROM ") + table).c_str());
    out.emplace_back(table, q && q.row() ? q.i64(0) : 0);
  }
  return out;
}

namespace {

constexpr const char* kSampleColumns =
    "SELECT step, time, base_x, base_y, base_z, qw, qx, qy, qz, joints, wheel_normal, roll, pitch FROM samples ";

LogSample readSample(Stmt& q) {
  LogSample s;
  s.step = q.i64(0);
  s.time = q.f64(1);
  for (int i = 0; i < 3; ++i) s.base[static_cast<std::size_t>(i)] = q.f64(2 + i);
  for (int i = 0; i < 4; ++i) s.quat[static_cast<std::size_t>(i)] = q.f64(5 + i);
  s.joints = q.doubles(9);
  std::vector<double> wheels = q.doubles(10);
  for (std::size_t i = 0; i < 4 && i < wheels.size(); ++i) s.wheelNormal[i] = wheels[i];
  for (std::size_t i = 0; i < 4 && i + 4 < wheels.size(); ++i) s.wheelTangential[i] = wheels[i + 4];
  s.roll = q.f64(11);
  s.pitch = q.f64(12);
  return s;
}

}  // namespace

std::vector<LogSample> SessionLogReader::samplesBetween(double t0, double t1) const {
  std::vector<LogSample> out;
  Stmt q(db_, (std::string(kSampleColumns) + "INDEXED BY samples_time WHERE time >= ? AND time <= ? ORDER BY time, step")
                  .c_str());
  if (!q) return out;
  q.bind(1, t0);
  q.bind(2, t1);
  while (q.row()) out.push_back(readSample(q));
  return out;
}

std::optional<LogSample> SessionLogReader::sampleAt(double time) const {
  // One row from the time index, whatever the log's length.
  Stmt q(db_,
         (std::string(kSampleColumns) + "INDEXED BY samples_time WHERE time <= ? ORDER BY time DESC, step DESC LIMIT 1")
             .c_str());
  if (!q) return std::nullopt;
  q.bind(1, time);
  if (!q.row()) return std::nullopt;
  return readSample(q);
}

std::optional<std::pair<double, double>> SessionLogReader::sampleTimeRange() const {
  Stmt q(db_, "SELECT MIN(time), MAX(time), COUNT(*) > 0 FROM samples");
  if (!q || !q.row() || q.i64(2) == 0) return std::nullopt;
  return std::pair{q.f64(0), q.f64(1)};
}

std::optional<LogLaser> SessionLogReader::laserAt(double time) const {
  Stmt q(db_, "SELECT step, time, angle_min, angle_step, ranges FROM laser WHERE time <= ? ORDER BY time DESC, step DESC LIMIT 1");
  if (!q) return std::nullopt;
  q.bind(1, time);
  if (!q.row()) return std::nullopt;
  return LogLaser{q.i64(0), q.f64(1), q.f64(2), q.f64(3), q.doubles(4)};
}

std::vector<LogLaser> SessionLogReader::laserBetween(double t0, double t1) const {
  std::vector<LogLaser> out;
  // Not INDEXED BY: logs written before laser_time existed read the same
  // (by a scan).
  Stmt q(db_, "SELECT step, time, angle_min, angle_step, ranges FROM laser WHERE time >= ? AND time <= ? ORDER BY step");
  if (!q) return out;
  q.bind(1, t0);
  q.bind(2, t1);
  while (q.row()) out.push_back(LogLaser{q.i64(0), q.f64(1), q.f64(2), q.f64(3), q.doubles(4)});
  return out;
}

std::vector<LogPrediction> SessionLogReader::predictionsBetween(double t0, double t1) const {
  std::vector<LogPrediction> out;
  Stmt q(db_,
         "SELECT time, made, base_x, base_y, base_z, qw, qx, qy, qz, error_position, error_heading "
         "FROM predictions WHERE time >= ? AND time <= ? ORDER BY time, rowid");
  if (!q) return out;  // a log from before predictions were logged
  q.bind(1, t0);
  q.bind(2, t1);
  while (q.row()) {
    LogPrediction p;
    p.time = q.f64(0);
    p.made = q.f64(1);
    for (int i = 0; i < 3; ++i) p.base[static_cast<std::size_t>(i)] = q.f64(2 + i);
    for (int i = 0; i < 4; ++i) p.quat[static_cast<std::size_t>(i)] = q.f64(5 + i);
    p.positionError = q.f64(9);
    p.headingError = q.f64(10);
    out.push_back(p);
  }
  return out;
}

std::vector<LogCalibration> SessionLogReader::calibration() const {
  std::vector<LogCalibration> out;
  Stmt q(db_, "SELECT time, param, value, sigma, observed, status FROM calibration ORDER BY time, rowid");
  // A log from before calibration was logged has no such table.
  while (q && q.row()) out.push_back(LogCalibration{q.f64(0), q.text(1), q.f64(2), q.f64(3), q.i64(4) != 0, q.text(5)});
  return out;
}

std::vector<LogCommand> SessionLogReader::commands() const {
  std::vector<LogCommand> out;
  Stmt q(db_, "SELECT step, time, source, text FROM commands ORDER BY step, rowid");
  while (q && q.row()) out.push_back(LogCommand{q.i64(0), q.f64(1), q.text(2), q.text(3)});
  return out;
}

std::vector<LogEvent> SessionLogReader::events() const {
  std::vector<LogEvent> out;
  Stmt q(db_, "SELECT step, time, kind, text FROM events ORDER BY step, rowid");
  while (q && q.row()) out.push_back(LogEvent{q.i64(0), q.f64(1), q.text(2), q.text(3)});
  return out;
}

std::vector<std::pair<int64_t, uint64_t>> SessionLogReader::hashes() const {
  std::vector<std::pair<int64_t, uint64_t>> out;
  Stmt q(db_, "SELECT step, hash FROM hashes ORDER BY step");
  while (q && q.row()) out.emplace_back(q.i64(0), static_cast<uint64_t>(q.i64(1)));
  return out;
}

std::vector<int64_t> SessionLogReader::snapshotSteps() const {
  std::vector<int64_t> out;
  Stmt q(db_, "SELECT step FROM snapshots ORDER BY step");
  while (q && q.row()) out.push_back(q.i64(0));
  return out;
}

std::optional<std::pair<Snapshot, uint64_t>> SessionLogReader::snapshot(int64_t step, std::string* error) const {
  Stmt q(db_, "SELECT hash, data FROM snapshots WHERE step = ?");
  if (!q) {
    if (error) *error = sqlite3_errmsg(db_);
    return std::nullopt;
  }
  q.bind(1, step);
  if (!q.row()) {
    if (error) *error = "no snapshot at step " + std::to_string(step);
    return std::nullopt;
  }
  auto hash = static_cast<uint64_t>(q.i64(0));
  std::optional<Snapshot> s = decodeSnapshot(q.bytes(1), error);
  if (!s) return std::nullopt;
  return std::make_pair(std::move(*s), hash);
}

}  // namespace sp
