// Replaying a session log (app/log/log_player.h): a log written by a scripted
// headless run is opened, the logged world rebuilt from the files it stores,
// and the state at any time read from the log: bit for bit what a fresh twin
// running the same commands has at that sample's step (the twin is
// deterministic), and the latest sample at or before the time asked.

#include <QDir>
#include <QFile>
#include <QTemporaryDir>
#include <QTest>

#include <sqlite3.h>

#include <chrono>
#include <filesystem>
#include <sstream>

#include "tests/default_step.h"
#include "app/run/headless_runner.h"
#include "app/console/console_session.h"
#include "app/log/log_player.h"
#include "app/log/session_recorder.h"
#include "app/log/resimulation.h"
#include "app/robot/stand_in.h"
#include "app/log/telemetry_recorder.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/runner.h"
#include "sim/world.h"
#include "tests/test_files.h"

using namespace sp;

class TestLogPlayer : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    QVERIFY(dir_.isValid());
    const QByteArray seq = "0.5 drive 0.6 0\n2.0 drive 0.6 15\n4.0 stop\n";
    commands_ = test::writeFile(dir_, "scripted.seq", seq);
    log_ = dir_.filePath("scripted.splog").toStdString();
    RunOptions o;
    o.worldFile = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    o.commandsFile = commands_;
    o.duration = 5;
    o.realTimeFactor = 0;
    o.logFile = log_;
    o.progressInterval = 0;
    std::ostringstream out, err;
    const auto report = runHeadless(
        o, out, err, [] { return 0.0; }, [](double) {});
    QVERIFY2(report && report->health.healthy(), err.str().c_str());
  }

  // Criterion: at three times (before, during and after the turn) the
  // player's frame is the sample at or before the time (within one log
  // period, 10 ms), and its base pose and joints equal, bit for bit, those
  // of a fresh twin run with the same commands to that sample's time.
  void framesAreTheTwinsState() {
    std::string error;
    auto player = LogPlayer::open(log_, error);
    QVERIFY2(player, error.c_str());
    QCOMPARE(player->startTime(), 0.0);
    QVERIFY(std::abs(player->endTime() - 5.0) < 0.011);
    QCOMPARE(player->world().robots[0].model.name, std::string("workpartner"));

    Diagnostics diag;
    const WorldModel world = *loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    auto twin = World::create(world, SimParams{}, diag);
    Runner runner(*twin);
    runner.schedule(*loadCommandSequence(commands_, diag, &world.robots[0].model));
    for (const double t : {1.234, 2.5, 4.999}) {
      const std::optional<RobotFrame> f = player->frameAt(t);
      QVERIFY(f);
      QVERIFY(f->time <= t && f->time > t - 0.0105);
      runner.advanceToTime(f->time);
      const Pose p = twin->linkPose(0, 0);
      QCOMPARE(f->base.p, p.p);
      QCOMPARE(f->base.q.w, p.q.w);
      QCOMPARE(f->jointPositions.size(), world.robots[0].model.joints.size());
      for (size_t j = 0; j < f->jointPositions.size(); ++j)
        QCOMPARE(f->jointPositions[j], twin->jointPosition(0, static_cast<int>(j)));
    }
    // Before the start: the first sample; seeking back works as forward.
    QCOMPARE(player->frameAt(-3)->time, 0.0);
    QCOMPARE(player->frameAt(2.5)->base.p, player->frameAt(2.5)->base.p);
    QVERIFY(player->frameAt(1.0)->base.p.x < player->frameAt(3.0)->base.p.x);
    QVERIFY(player->laserAt(2.5).has_value());
  }

  // Branch: criterion, the state re-simulated to t = 3 s (from the snapshot
  // at 3 s: hash rows and snapshots come every sim second) has the log's
  // own hash there, bit for bit; a stand-in started from it logs a first
  // snapshot with that same hash at that same step and names its parent.
  // Control: branching at 3.5 s (re-simulated from the snapshot at 3 s)
  // lands on a state whose hash differs from the one at 3 s.
  void branchStartsFromTheLoggedState() {
    std::string error;
    const std::optional<BranchPoint> b = branchAt(log_, 3.0, error);
    QVERIFY2(b, error.c_str());
    QCOMPARE(b->step, sp::test::stepAt(3.0));
    QVERIFY(b->loggedHash.has_value());
    QCOMPARE(b->hash, *b->loggedHash);
    const std::optional<BranchPoint> later = branchAt(log_, 3.5, error);
    QVERIFY(later && later->fromSnapshot == 3000 && later->hash != b->hash && !later->loggedHash);

    StandInOptions o;
    o.worldFile = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    o.port = 0;
    o.startState = b->state;
    o.logPath = dir_.filePath("branch.splog").toStdString();
    o.logMeta = {{"parent_log", log_}, {"parent_time", "3"}};
    Diagnostics diag;
    auto robot = StandInRobot::create(o, diag);
    QVERIFY2(robot, diag.format().c_str());
    QCOMPARE(robot->start(), std::string());
    robot->stop();
    auto branch = SessionLogReader::open(o.logPath, error);
    QVERIFY2(branch, error.c_str());
    QCOMPARE(branch->snapshotSteps().front(), sp::test::stepAt(3.0));
    QCOMPARE(branch->snapshot(3000)->second, b->hash);
    QCOMPARE(branch->meta().at("parent_log"), log_);
    QCOMPARE(branch->meta().at("parent_time"), std::string("3"));
  }

  // A remote robot's log (the console's telemetry recording: no snapshots,
  // samples keyed by robot time) replays the same: the frame at a time is
  // the telemetry frame at or before it, joints mapped by name.
  void telemetryOnlyLogsReplay() {
    Diagnostics diag;
    const WorldModel world = *loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    const RobotModel& robot = world.robots[0].model;
    const std::string path = dir_.filePath("remote.splog").toStdString();
    std::string error;
    {
      auto recorder = TelemetryRecorder::open(path, world, "10.0.0.7:47800", error);
      QVERIFY2(recorder, error.c_str());
      for (int i = 0; i < 5; ++i) {
        net::TelemetryMsg t;
        t.time = 10 + 0.02 * i;
        t.pose = Pose{{1.0 + 0.01 * i, 2.0, 0.8}, {1, 0, 0, 0}};
        t.jointNames = {"knee_fl", "waist_yaw"};
        t.jointPositions = {0.1 * i, -0.2};
        t.jointVelocities = {0, 0};
        recorder->telemetry(t, robot);
      }
    }
    auto player = LogPlayer::open(path, error);
    QVERIFY2(player, error.c_str());
    QCOMPARE(player->startTime(), 10.0);
    QCOMPARE(player->endTime(), 10.08);
    const std::optional<RobotFrame> f = player->frameAt(10.05);
    QVERIFY(f);
    QCOMPARE(f->time, 10.04);
    QCOMPARE(f->base.p.x, 1.02);
    QCOMPARE(f->jointPositions[static_cast<size_t>(robot.findJoint("knee_fl"))], 0.2);
    QCOMPARE(f->jointPositions[static_cast<size_t>(robot.findJoint("waist_yaw"))], -0.2);
    QCOMPARE(f->jointPositions[static_cast<size_t>(robot.findJoint("hip_fl"))], 0.0);  // not reported
  }

  // Branching a telemetry-only log: the scripted drive re-told as a remote
  // robot's telemetry (50 Hz, no base twist, no snapshots) and branched at
  // 3 s, mid-turn at 0.6 m/s. Criteria (before the run): the reconstructed
  // state puts the base where the telemetry frame says (1e-9 m) with the
  // frame's joints; its base velocity, differenced from the frame before,
  // is within 0.05 m/s and 0.05 rad/s of the exact state re-simulated from
  // the full log at the same step; it lands at the logged time (step 3000);
  // a stand-in starts from it. Control: the same state with the twist left
  // at zero misses the exact one by more than 0.3 m/s, so the criterion can fail.
  void telemetryOnlyLogsBranch() {
    std::string error;
    auto full = LogPlayer::open(log_, error);
    QVERIFY2(full, error.c_str());
    const RobotModel& robot = full->world().robots[0].model;
    const std::string path = dir_.filePath("remote-drive.splog").toStdString();
    {
      Diagnostics diag;
      auto recorder = TelemetryRecorder::open(path, *loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag),
                                              "10.0.0.7:47800", error);
      QVERIFY2(recorder, error.c_str());
      for (int i = 0; i <= 200; ++i) {  // 0 to 4 s at 50 Hz
        const RobotFrame f = *full->frameAt(0.02 * i);
        net::TelemetryMsg t;
        t.time = f.time;
        t.pose = f.base;
        for (size_t j = 0; j < robot.joints.size(); ++j) t.jointNames.push_back(robot.joints[j].name);
        t.jointPositions = f.jointPositions;
        t.jointVelocities = f.jointRates;
        recorder->telemetry(t, robot);
      }
    }
    auto remote = LogPlayer::open(path, error);
    QVERIFY2(remote, error.c_str());
    QVERIFY(!remote->hasSnapshots() && full->hasSnapshots());
    const std::optional<BranchPoint> rebuilt = remote->branchAt(3.0, error);
    QVERIFY2(rebuilt, error.c_str());
    QVERIFY(rebuilt->reconstructed);
    QCOMPARE(rebuilt->step, sp::test::stepAt(3.0));
    const std::optional<BranchPoint> exact = full->branchAt(3.0, error);
    QVERIFY2(exact && !exact->reconstructed, error.c_str());

    const BodyState& base = rebuilt->state.bodies[0];
    const RobotFrame logged = *remote->frameAt(3.0);
    QVERIFY(std::abs(base.position[0] - logged.base.p.x) < 1e-9 && std::abs(base.position[1] - logged.base.p.y) < 1e-9);
    const auto gap = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
      return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    };
    const BodyState& truth = exact->state.bodies[0];
    qInfo("reconstructed base velocity off by %.4f m/s, %.4f rad/s (speed %.3f m/s)",
          gap(base.linearVelocity, truth.linearVelocity), gap(base.angularVelocity, truth.angularVelocity),
          gap(truth.linearVelocity, {0, 0, 0}));
    QVERIFY(gap(base.linearVelocity, truth.linearVelocity) < 0.05);
    QVERIFY(gap(base.angularVelocity, truth.angularVelocity) < 0.05);
    QVERIFY(gap({0, 0, 0}, truth.linearVelocity) > 0.3);  // control: a zero twist fails the criterion

    StandInOptions o;
    o.worldFile = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    o.port = 0;
    o.startState = rebuilt->state;
    o.logPath = dir_.filePath("remote-branch.splog").toStdString();
    Diagnostics diag;
    auto standIn = StandInRobot::create(o, diag);
    QVERIFY2(standIn, diag.format().c_str());
    QCOMPARE(standIn->start(), std::string());
    standIn->stop();
    auto branch = SessionLogReader::open(o.logPath, error);
    QVERIFY2(branch, error.c_str());
    QCOMPARE(branch->snapshot(3000)->second, rebuilt->hash);
  }

  // Portable logs: a test-track session logged from the project root
  // re-simulates and replays from a folder where none of its files exist
  // (world, robot and heightfield data all come from the log). Control: the
  // same log with its stored terrain removed cannot be rebuilt there.
  void logsCarryTheirTerrain() {
    RunOptions o;
    o.worldFile = "terrains/test_track.world.xml";  // relative: the paths recorded do not exist elsewhere
    o.duration = 1.2;
    o.realTimeFactor = 0;
    o.logFile = dir_.filePath("track.splog").toStdString();
    o.progressInterval = 0;
    std::ostringstream out, err;
    QVERIFY2(runHeadless(o, out, err, [] { return 0.0; }, [](double) {}), err.str().c_str());
    const QString root = QDir::currentPath();
    QTemporaryDir elsewhere;
    QVERIFY(QDir::setCurrent(elsewhere.path()));
    std::string error;
    const std::optional<ResimReport> resim = resimulate(o.logFile, {}, error);
    auto player = LogPlayer::open(o.logFile, error);
    // The control: without the stored terrain, the same log cannot be rebuilt here.
    const QString stripped = QString::fromStdString(o.logFile) + ".stripped";
    QFile::copy(QString::fromStdString(o.logFile), stripped);
    bool deleted = false;
    {
      sqlite3* db = nullptr;
      if (sqlite3_open(stripped.toUtf8().constData(), &db) == SQLITE_OK)
        deleted = sqlite3_exec(db, "DELETE FROM meta WHERE key LIKE 'terrain_%'", nullptr, nullptr, nullptr) == SQLITE_OK;
      sqlite3_close(db);
    }
    std::string strippedError;
    const bool strippedOpens = LogPlayer::open(stripped.toStdString(), strippedError) != nullptr;
    QVERIFY(QDir::setCurrent(root));
    QVERIFY2(resim && !resim->divergence && resim->hashesCompared > 0, error.c_str());
    QVERIFY2(player, error.c_str());
    QCOMPARE(player->world().terrain.kind, TerrainSpec::Kind::Heightfield);
    QVERIFY(deleted);
    QVERIFY(!strippedOpens);
    qInfo("without the stored terrain: %s", strippedError.c_str());
  }

  // The log folder: listed newest first with sizes (-wal included), other
  // files ignored; log.keep deletes the oldest beyond the newest N when a
  // console session starts, never the current one.
  void logFolderListedAndPruned() {
    namespace fs = std::filesystem;
    QTemporaryDir logs;
    const auto now = fs::file_time_type::clock::now();
    const char* names[] = {"session-a.splog", "session-b.splog", "session-c.splog"};
    for (int i = 0; i < 3; ++i) {
      const std::string p = test::writeFile(logs, names[i], QByteArray(100 * (i + 1), 'x'));
      fs::last_write_time(p, now - std::chrono::hours(3 - i));  // a oldest, c newest
    }
    test::writeFile(logs, "session-c.splog-wal", QByteArray(7, 'w'));
    test::writeFile(logs, "notes.txt", "not a log");
    std::vector<SessionLogFile> list = listSessionLogs(logs.path().toStdString());
    QCOMPARE(list.size(), size_t(3));
    QVERIFY(list[0].path.ends_with("session-c.splog") && list[2].path.ends_with("session-a.splog"));
    QCOMPARE(list[0].bytes, uint64_t(307));
    QVERIFY(list[0].modified > list[1].modified);
    // The oldest is the current one: it stays whatever keep says.
    const std::vector<std::string> gone = pruneSessionLogs(logs.path().toStdString(), 1, list[2].path);
    QCOMPARE(gone.size(), size_t(1));
    QVERIFY(gone[0].ends_with("session-b.splog"));
    QVERIFY(!QFile::exists(logs.filePath("session-b.splog")));

    ConsoleSessionOptions o;
    o.world = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    o.logDir = logs.path().toStdString();
    o.overrides = {"log.keep=2"};
    o.ghost = false;
    {
      ConsoleSession session(o);
      QCOMPARE(session.start(), std::string());
      list = listSessionLogs(logs.path().toStdString());
      QCOMPARE(list.size(), size_t(2));
      QCOMPARE(list[0].path, session.logPath());       // the new one
      QVERIFY(list[1].path.ends_with("session-c.splog"));  // the newest before it
    }
    QCOMPARE(deleteSessionLog(logs.filePath("session-c.splog").toStdString()), std::string());
    QVERIFY(!QFile::exists(logs.filePath("session-c.splog-wal")));
    QVERIFY(!deleteSessionLog(logs.filePath("session-c.splog").toStdString()).empty());
  }

  void notALogIsRefused() {
    const std::string junk = test::writeFile(dir_, "junk.splog", "not sqlite");
    std::string error;
    QVERIFY(!LogPlayer::open(junk, error));
    QVERIFY2(error.find("junk.splog") != std::string::npos, error.c_str());
  }

 private:
  QTemporaryDir dir_;
  std::string commands_, log_;
};

QTEST_GUILESS_MAIN(TestLogPlayer)
#include "tst_log_player.moc"
