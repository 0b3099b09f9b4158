// The session log: a real run written and read back, the reader's refusals,
// the snapshot codec's exact round trip, and a writer that never blocks.

#include <sqlite3.h>

#include <QElapsedTimer>
#include <QTemporaryDir>
#include <QTest>

#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "tests/default_step.h"
#include "app/run/headless_runner.h"
#include "app/log/session_log.h"
#include "app/log/snapshot_codec.h"
#include "sim/model_loader.h"
#include "sim/world.h"

using namespace sp;

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string sourcePath(const std::string& relative) { return std::string(SP_SOURCE_DIR) + "/" + relative; }

std::unique_ptr<World> makeWorld(const std::string& worldFile) {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(sourcePath(worldFile), diag);
  if (!model) return nullptr;
  return World::create(*model, SimParams{}, diag);
}

// Sets meta.format_version of an existing log.
void setFormatVersion(const std::string& path, const std::string& version) {
  sqlite3* db = nullptr;
  QCOMPARE(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  std::string sql = "UPDATE meta SET value='" + version + "' WHERE key='format_version'";
  QCOMPARE(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
}

// `decoded` restored into a fresh world of `worldFile` has `world`'s state
// hash, now and after 100 more steps of both.
void verifyRestoresLike(World& world, const Snapshot& decoded, const std::string& worldFile) {
  std::unique_ptr<World> fresh = makeWorld(worldFile);
  QVERIFY(fresh);
  QCOMPARE(fresh->restore(decoded), std::string());
  QCOMPARE(fresh->stateHash(), world.stateHash());
  for (int i = 0; i < 100; ++i) {
    QVERIFY(world.step());
    QVERIFY(fresh->step());
  }
  QCOMPARE(fresh->stateHash(), world.stateHash());
}

}  // namespace

class TestSessionLog : public QObject {
  Q_OBJECT

 private slots:
  // A 2 s drive on flat ground logged at 1 kHz (samples), 20 Hz (laser) and
  // 1 Hz (snapshots, hashes) reads back complete and bit for bit.
  void realRunReadsBack() {
    QTemporaryDir dir;
    QVERIFY(dir.isValid());
    const std::string path = dir.filePath("session.sqlite").toStdString();
    const std::string worldFile = "terrains/flat.world.xml";
    std::unique_ptr<World> world = makeWorld(worldFile);
    QVERIFY(world);
    QCOMPARE(world->params().step, sp::test::defaultStep());

    SessionInfo info;
    info.programVersion = "test";
    info.startTime = "2026-01-02T03:04:05Z";
    info.files.push_back({"world", worldFile, readFile(sourcePath(worldFile))});
    std::string error;
    std::unique_ptr<SessionLogWriter> log = SessionLogWriter::open(path, info, error);
    QVERIFY2(log, error.c_str());

    const Command drive = DriveCmd{0.5, 0.1};
    QCOMPARE(world->submit(drive), std::string());
    log->logSnapshot(world->snapshot(), world->time(), world->stateHash());
    log->logCommand(world->stepCount(), world->time(), "sequence", drive);
    log->logEvent(0, 0, "note", "start");
    std::vector<LogSample> samples;
    std::vector<LogLaser> scans;
    uint64_t hashAt1s = 0;
    for (int i = 0; i < 2000; ++i) {
      QVERIFY(world->step());
      samples.push_back(makeLogSample(*world));
      QVERIFY(log->logSample(samples.back()));
      for (auto [robot, sensor] : world->sampledLastStep()) {
        if (auto scan = makeLogLaser(world->sensorSample(robot, sensor))) {
          scans.push_back(*scan);
          QVERIFY(log->logLaser(*scan));
        }
      }
      if (world->stepCount() % 1000 == 0) {
        if (world->stepCount() == 1000) hashAt1s = world->stateHash();
        log->logSnapshot(world->snapshot(), world->time(), world->stateHash());
        log->logHash(world->stepCount(), world->stateHash());
      }
    }
    // The ghost's predictions come from another thread than the samples'.
    const std::vector<LogPrediction> predictions = {{1.25, 0.5, {1, 2, 0.3}, {0.6, 0, 0, 0.8}, 0.04, 0.01},
                                                    {2.5, 1.5, {3, 4, 0.3}, {1, 0, 0, 0}, 0.02, 0.003}};
    std::thread([&] {
      for (const LogPrediction& p : predictions) QVERIFY(log->logPrediction(p));
    }).join();
    // A calibration fit's rows (app/calibration), one applied and one refused.
    const std::vector<LogCalibration> calibration = {{4.0, "calibration.wheel_radius", 0.98, 0.002, true, "applied"},
                                                     {7.0, "calibration.friction", 1.0, 0, false, "refused: not enough driving"}};
    for (const LogCalibration& c : calibration) QVERIFY(log->logCalibration(c));
    log->close();
    QCOMPARE(log->dropped(), int64_t{0});
    QVERIFY(!log->failed());
    QCOMPARE(scans.size(), std::size_t{40});

    std::unique_ptr<SessionLogReader> reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    std::map<std::string, std::string> meta = reader->meta();
    QCOMPARE(meta["format_version"], std::string("1"));
    QCOMPARE(meta["program_version"], std::string("test"));
    QCOMPARE(meta["start_time"], std::string("2026-01-02T03:04:05Z"));
    QCOMPARE(meta["world_file"], worldFile);
    QCOMPARE(meta["world_contents"], readFile(sourcePath(worldFile)));
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx",
                  static_cast<unsigned long long>(fnv1a64(readFile(sourcePath(worldFile)))));
    QCOMPARE(meta["world_fnv1a64"], std::string(hex));

    const std::vector<std::pair<std::string, int64_t>> expected = {
        {"meta", static_cast<int64_t>(meta.size())}, {"commands", 1}, {"samples", 2000}, {"laser", 40},
        {"events", 1}, {"snapshots", 3}, {"hashes", 2}, {"predictions", 2}, {"calibration", 2}};
    QCOMPARE(reader->streams(), expected);
    QCOMPARE(reader->calibration(), calibration);

    QCOMPARE(reader->commands(), (std::vector<LogCommand>{{0, 0.0, "sequence", toText(drive)}}));
    QCOMPARE(reader->events(), (std::vector<LogEvent>{{0, 0.0, "note", "start"}}));
    QCOMPARE(reader->samplesBetween(0, 10), samples);
    // Samples of steps 500..600 (times are multiples of the step, compared with a margin).
    std::vector<LogSample> window = reader->samplesBetween(0.4995, 0.6005);
    QCOMPARE(window.size(), std::size_t{101});
    QCOMPARE(window.front(), samples[499]);
    QCOMPARE(window.back(), samples[599]);
    QVERIFY(window.back().base[0] > samples.front().base[0]);  // it drove forwards
    QCOMPARE(reader->laserBetween(0, 10), scans);
    QCOMPARE(reader->predictionsBetween(0, 10), predictions);
    QCOMPARE(reader->predictionsBetween(2, 3), std::vector<LogPrediction>{predictions[1]});
    QCOMPARE(reader->snapshotSteps(), (std::vector<int64_t>{0, 1000, 2000}));
    QCOMPARE(reader->hashes().front(), (std::pair<int64_t, uint64_t>{1000, hashAt1s}));

    // The snapshot at 1 s restores into a fresh world with the logged hash.
    auto snap = reader->snapshot(1000, &error);
    QVERIFY2(snap, error.c_str());
    QCOMPARE(snap->second, hashAt1s);
    std::unique_ptr<World> fresh = makeWorld(worldFile);
    QCOMPARE(fresh->restore(snap->first), std::string());
    QCOMPARE(fresh->stateHash(), hashAt1s);
    QVERIFY(!reader->snapshot(999, &error));
    QCOMPARE(error, std::string("no snapshot at step 999"));
  }

  void codecRoundTrip_data() {
    QTest::addColumn<QString>("worldFile");
    QTest::newRow("plane") << "terrains/flat.world.xml";
    QTest::newRow("heightfield") << "terrains/bumpy.world.xml";
  }
  // A snapshot with a pending command (and terrain heights, when the world
  // has a heightfield) encodes, decodes and restores bit-exactly.
  void codecRoundTrip() {
    QFETCH(QString, worldFile);
    std::unique_ptr<World> world = makeWorld(worldFile.toStdString());
    QVERIFY(world);
    QCOMPARE(world->submit(DriveCmd{0.3, 0}), std::string());
    for (int i = 0; i < 300; ++i) QVERIFY(world->step());
    QCOMPARE(world->submit(JointTargetCmd{"waist_yaw", 0.2}), std::string());
    const Snapshot original = world->snapshot();
    const std::vector<uint8_t> bytes = encodeSnapshot(original);
    std::string error;
    std::optional<Snapshot> decoded = decodeSnapshot(bytes, &error);
    QVERIFY2(decoded, error.c_str());
    QCOMPARE(encodeSnapshot(*decoded), bytes);
    QCOMPARE(decoded->pending, original.pending);
    QCOMPARE(decoded->terrain != nullptr, original.terrain != nullptr);
    if (original.terrain) QCOMPARE(decoded->terrain->heights, original.terrain->heights);

    verifyRestoresLike(*world, *decoded, worldFile.toStdString());
    if (QTest::currentTestFailed()) return;

    // Truncated data and another version are refused.
    std::vector<uint8_t> cut(bytes.begin(), bytes.end() - 3);
    QVERIFY(!decodeSnapshot(cut, &error));
    QCOMPARE(error, std::string("truncated snapshot data"));
    std::vector<uint8_t> v4 = bytes;
    v4[4] = 4;
    QVERIFY(!decodeSnapshot(v4, &error));
    QCOMPARE(error, std::string("snapshot format version 4 is not supported (expected 3)"));
  }

  // Logs written before motion resistance (snapshot format version 1: no
  // resistance per link) or before its hold (2) still restore and
  // re-simulate exactly: the older bytes are these without those fields.
  void versions1And2StillRead() {
    std::unique_ptr<World> world = makeWorld("terrains/flat.world.xml");
    QVERIFY(world);
    QCOMPARE(world->submit(DriveCmd{0.3, 0}), std::string());
    for (int i = 0; i < 300; ++i) QVERIFY(world->step());
    const Snapshot original = world->snapshot();
    QCOMPARE(original.robots.size(), size_t{1});
    std::vector<uint8_t> bytes = encodeSnapshot(original);
    // magic, version, modelKey, step, stepSize, bodies; robots: count, then
    // actuators (count, 33 bytes each) and the drive and gait fields (44).
    const size_t robot = 4 + 4 + 8 + 8 + 8 + 8 + original.bodies.size() * 13 * 8 + 8;
    const size_t block = robot + 8 + original.robots[0].actuators.size() * 33 + 44;
    const size_t links = original.robots[0].resistance.size();
    QCOMPARE(links, world->robotModel(0).links.size());
    uint64_t count = 0;
    std::memcpy(&count, bytes.data() + block, 8);
    QCOMPARE(count, uint64_t{links});  // found the block
    // Version 2: each link's force and share without the hold.
    std::vector<uint8_t> v2 = bytes;
    for (size_t l = links; l-- > 0;) {
      const size_t hold = block + 8 + l * 24 + 16;
      v2.erase(v2.begin() + static_cast<std::ptrdiff_t>(hold), v2.begin() + static_cast<std::ptrdiff_t>(hold + 8));
    }
    v2[4] = 2;
    std::string error2;
    std::optional<Snapshot> decoded2 = decodeSnapshot(v2, &error2);
    QVERIFY2(decoded2, error2.c_str());
    QCOMPARE(decoded2->robots[0].resistance, original.robots[0].resistance);
    QCOMPARE(decoded2->robots[0].resistanceHold, std::vector<double>(links, 0.0));
    {
      std::unique_ptr<World> reference = makeWorld("terrains/flat.world.xml");  // `world` goes on below
      QVERIFY(reference);
      QCOMPARE(reference->restore(original), std::string());
      verifyRestoresLike(*reference, *decoded2, "terrains/flat.world.xml");
    }
    // Version 1: no resistance block at all.
    bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(block),
                bytes.begin() + static_cast<std::ptrdiff_t>(block + 8 + links * 24));
    bytes[4] = 1;
    std::string error;
    std::optional<Snapshot> decoded = decodeSnapshot(bytes, &error);
    QVERIFY2(decoded, error.c_str());
    QVERIFY(decoded->robots[0].resistance.empty());
    verifyRestoresLike(*world, *decoded, "terrains/flat.world.xml");
  }

  // The reader refuses another format version, a database without meta and
  // a file that is not SQLite, naming the file.
  void readerRejects() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("v2.sqlite").toStdString();
    std::string error;
    {
      auto log = SessionLogWriter::open(path, SessionInfo{}, error);
      QVERIFY2(log, error.c_str());
    }
    setFormatVersion(path, "2");
    QVERIFY(!SessionLogReader::open(path, error));
    QCOMPARE(error, path + ": session log format version 2 is not supported (this program reads version 1)");

    const std::string empty = dir.filePath("empty.sqlite").toStdString();
    sqlite3* db = nullptr;
    QCOMPARE(sqlite3_open(empty.c_str(), &db), SQLITE_OK);
    QCOMPARE(sqlite3_exec(db, "CREATE TABLE t(x)", nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(db);
    QVERIFY(!SessionLogReader::open(empty, error));
    QCOMPARE(error, empty + ": not a session log (no meta table)");

    const std::string text = dir.filePath("notes.txt").toStdString();
    std::ofstream(text) << std::string(2048, 'x');
    QVERIFY(!SessionLogReader::open(text, error));
    QCOMPARE(error, text + ": not a session log (not an SQLite database)");

    const std::string missing = dir.filePath("missing.sqlite").toStdString();
    QVERIFY(!SessionLogReader::open(missing, error));
    QCOMPARE(error, missing + ": cannot open the session log: unable to open database file");
  }

  // The writer refuses a path it cannot create, and an existing file.
  void writerRejectsPath() {
    QTemporaryDir dir;
    std::string error;
    const std::string bad = dir.filePath("no/such/dir/log.sqlite").toStdString();
    QVERIFY(!SessionLogWriter::open(bad, SessionInfo{}, error));
    QCOMPARE(error, bad + ": cannot create the session log: unable to open database file");
    const std::string existing = dir.filePath("x.sqlite").toStdString();
    std::ofstream(existing) << "x";
    QVERIFY(!SessionLogWriter::open(existing, SessionInfo{}, error));
    QCOMPARE(error, existing + ": already exists");
  }

  // A full queue drops and counts instead of waiting for the writer.
  void overflowDropsWithoutBlocking() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("tiny.sqlite").toStdString();
    SessionLogOptions options;
    options.queueCapacity = 4;
    options.batchMillis = 5000;  // the writer sleeps through the burst
    std::string error;
    auto log = SessionLogWriter::open(path, SessionInfo{}, error, options);
    QVERIFY2(log, error.c_str());
    QElapsedTimer timer;
    timer.start();
    int accepted = 0;
    for (int i = 0; i < 100; ++i) accepted += log->logEvent(i, i * 0.001, "note", "n") ? 1 : 0;
    QVERIFY(timer.elapsed() < 1000);
    QCOMPARE(accepted, 4);
    QCOMPARE(log->dropped(), int64_t{96});
    log->close();
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    QCOMPARE(reader->events().size(), std::size_t{4});
  }

  // A full disk is reported, later items are dropped, and the file keeps
  // what was committed before.
  void diskFullIsReported() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("full.sqlite").toStdString();
    SessionLogOptions options;
    options.maxPageCount = 64;
    std::string error;
    auto log = SessionLogWriter::open(path, SessionInfo{}, error, options);
    QVERIFY2(log, error.c_str());
    QVERIFY(log->logEvent(0, 0, "note", "before"));
    QTest::qWait(200);  // committed
    QVERIFY(!log->failed());
    for (int i = 1; i <= 100 && !log->failed(); ++i) {
      log->logLaser(LogLaser{i, i * 0.05, 0, 0.01, std::vector<double>(4000, 1.0)});
      QTest::qWait(10);
    }
    QTRY_VERIFY_WITH_TIMEOUT(log->failed(), 2000);
    QCOMPARE(log->errorMessage(), path + ": database or disk is full");
    log->close();
    QVERIFY(log->dropped() > 0);
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    QCOMPARE(reader->events(), (std::vector<LogEvent>{{0, 0.0, "note", "before"}}));
  }

  // `run --log`: the runner logs files, the initial snapshot, sequence
  // commands, samples at rate.log, laser scans and a snapshot per second,
  // and its final state hash is the last one logged.
  void runnerWritesLog() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("run.sqlite").toStdString();
    const std::string commands = dir.filePath("drive.seq").toStdString();
    std::ofstream(commands) << "0 drive 0.5 0\n0.5 stop\n";
    RunOptions o;
    o.worldFile = sourcePath("terrains/flat.world.xml");
    o.commandsFile = commands;
    o.duration = 2;
    o.realTimeFactor = 0;
    o.progressInterval = 0;
    o.logFile = path;
    std::ostringstream out, err;
    double fakeClock = 0;
    auto report = runHeadless(o, out, err, [&] { return fakeClock += 1e-4; }, [](double) {});
    QVERIFY2(report, err.str().c_str());
    QCOMPARE(err.str(), std::string());
    QVERIFY2(out.str().find("logging the session at 100.0 Hz to " + path) != std::string::npos, out.str().c_str());
    QCOMPARE(report->logDropped, int64_t{0});

    std::string error;
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    std::map<std::string, std::string> meta = reader->meta();
    QCOMPARE(meta["world_contents"], readFile(o.worldFile));
    QCOMPARE(meta["commands_contents"], readFile(commands));
    QVERIFY(meta["robot_contents"].find("<sensor name=\"laser\"") != std::string::npos);
    const std::vector<LogCommand> logged = reader->commands();
    QCOMPARE(logged.size(), std::size_t{2});
    QCOMPARE(logged[0].step, int64_t{0});
    QCOMPARE(logged[0].source, std::string("sequence"));
    QCOMPARE(logged[1].step, sp::test::stepAt(0.5));
    QCOMPARE(logged[1].text, std::string("stop"));
    QCOMPARE(reader->samplesBetween(0, 10).size(), std::size_t{201});
    QCOMPARE(reader->laserBetween(0, 10).size(), std::size_t{40});
    QCOMPARE(reader->snapshotSteps(), (std::vector<int64_t>{0, 1000, 2000}));
    QCOMPARE(reader->hashes().back(), (std::pair<int64_t, uint64_t>{2000, report->stateHash}));

    // A second run refuses to overwrite the log.
    std::ostringstream out2, err2;
    QVERIFY(!runHeadless(o, out2, err2, [&] { return fakeClock += 1e-4; }, [](double) {}));
    QCOMPARE(err2.str(), path + ": already exists\n");
  }

  // Seeking by time uses the time indexes of samples and laser scans (a
  // one-hour 1 kHz log seeks in ~ms with them, bench_log --hour; a scan
  // reads the whole table): the plans of time-range queries search
  // samples_time and laser_time, and the reader's seeks answer.
  void seekUsesTimeIndex() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("seek.splog").toStdString();
    std::string error;
    auto writer = SessionLogWriter::open(path, SessionInfo{}, error);
    QVERIFY2(writer, error.c_str());
    for (int64_t step = 0; step < 2000; ++step) {
      LogSample s;
      s.step = step;
      s.time = static_cast<double>(step) * 1e-3;
      QVERIFY(writer->logSample(s));
      if (step % 50 == 0) QVERIFY(writer->logLaser(LogLaser{step, s.time, 0, 0.01, {1.0, 2.0}}));
    }
    writer->close();

    sqlite3* db = nullptr;
    QCOMPARE(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
    auto plan = [db](const char* sql) {
      sqlite3_stmt* q = nullptr;
      std::string out;
      if (sqlite3_prepare_v2(db, (std::string("EXPLAIN QUERY PLAN ") + sql).c_str(), -1, &q, nullptr) != SQLITE_OK)
        return std::string(sqlite3_errmsg(db));
      while (sqlite3_step(q) == SQLITE_ROW) out += reinterpret_cast<const char*>(sqlite3_column_text(q, 3)) + std::string("\n");
      sqlite3_finalize(q);
      return out;
    };
    const std::string samplesPlan = plan("SELECT * FROM samples WHERE time >= 1.0 AND time <= 1.1 ORDER BY time, step");
    const std::string laserPlan = plan("SELECT * FROM laser WHERE time >= 1.0 AND time <= 1.1 ORDER BY step");
    sqlite3_close(db);
    QVERIFY2(samplesPlan.find("SEARCH samples USING INDEX samples_time") != std::string::npos, samplesPlan.c_str());
    QVERIFY2(laserPlan.find("SEARCH laser USING INDEX laser_time") != std::string::npos, laserPlan.c_str());

    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    const std::vector<LogSample> found = reader->samplesBetween(1.0, 1.0999);
    QCOMPARE(found.size(), std::size_t{100});
    QCOMPARE(found.front().step, sp::test::stepAt(1.0));
    QCOMPARE(reader->laserBetween(1.0, 1.0999).size(), std::size_t{2});
  }
};

QTEST_GUILESS_MAIN(TestSessionLog)
#include "tst_session_log.moc"
