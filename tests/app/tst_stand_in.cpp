// The stand-in robot as one object (app/robot/stand_in.h): a console client drives
// it over loopback, and its session log then holds the files, the operator's
// commands, samples, link and e-stop events and snapshots, and re-simulates
// without divergence. Also: telemetry carries the world's dynamic objects,
// where logs go, and what create() and start() refuse.

#include <QRegularExpression>
#include <QTemporaryDir>
#include <QTest>


#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "tests/default_step.h"
#include "app/log/resimulation.h"
#include "app/log/session_log.h"
#include "app/robot/stand_in.h"
#include "net/robot_client.h"
#include "tests/app/shared_state.h"
#include "sim/model_loader.h"
#include "sim/perturbation.h"

#include <sqlite3.h>

using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

std::string sourcePath(const std::string& relative) { return std::string(SP_SOURCE_DIR) + "/" + relative; }

StandInOptions options(const std::string& logPath) {
  StandInOptions o;
  o.worldFile = sourcePath("terrains/flat.world.xml");
  o.port = 0;
  o.token = kToken;
  o.logPath = logPath;
  o.log = !logPath.empty();
  return o;
}

// What a client's callbacks report (on its thread), for the test's thread.
struct Seen : sp::test::SharedState {
  bool ready = false, lease = false;
  std::vector<ReplyMsg> replies;
  std::vector<EventKind> events;

  RobotClientCallbacks callbacks() {
    RobotClientCallbacks cb;
    cb.connection = [this](ConnectionState s, const std::string&) { add([&] { ready = s == ConnectionState::Ready; }); };
    cb.lease = [this](const LeaseStateMsg& m) { add([&] { lease = m.yours; }); };
    cb.reply = [this](const ReplyMsg& m) { add([&] { replies.push_back(m); }); };
    cb.event = [this](const EventMsg& m) { add([&] { events.push_back(m.kind); }); };
    return cb;
  }
  bool replied(uint64_t seq, ReplyStatus status) {
    return waitFor([&] {
      return std::any_of(replies.begin(), replies.end(), [&](const ReplyMsg& r) { return r.seq == seq && r.status == status; });
    });
  }
  bool got(EventKind kind) {
    return waitFor([&] { return std::find(events.begin(), events.end(), kind) != events.end(); });
  }
};

bool hasEvent(const std::vector<LogEvent>& events, const std::string& kind, const std::string& part) {
  return std::any_of(events.begin(), events.end(),
                     [&](const LogEvent& e) { return e.kind == kind && e.text.find(part) != std::string::npos; });
}

std::string eventList(const std::vector<LogEvent>& events) {
  std::string out;
  for (const LogEvent& e : events) out += std::to_string(e.step) + " " + e.kind + ": " + e.text + "\n";
  return out;
}

}  // namespace

class TestStandIn : public QObject {
  Q_OBJECT

 private slots:
  // A client takes the lease, drives, e-stops and re-arms; the log then
  // holds all of it, and re-simulates hash for hash.
  void sessionIsLoggedAndResimulates() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("session.splog").toStdString();
    std::vector<std::string> lines;
    std::mutex linesMutex;
    StandInOptions o = options(path);
    o.lineLog = [&](const std::string& line) {
      std::lock_guard lock(linesMutex);
      lines.push_back(line);
    };
    Diagnostics diag;
    auto robot = StandInRobot::create(o, diag);
    QVERIFY2(robot, diag.format().c_str());
    QCOMPARE(robot->start(), std::string());
    QVERIFY(robot->port() != 0);
    QCOMPARE(robot->logPath(), path);
    QCOMPARE(robot->token(), kToken);
    QCOMPARE(robot->world().robots.size(), size_t{1});

    Seen seen;
    RobotClientConfig config;
    config.port = robot->port();
    config.token = robot->token();
    config.name = "tester";
    {
      RobotClient client(config, seen.callbacks());
      client.start();
      QVERIFY(seen.waitFor([&] { return seen.ready; }));
      client.acquireLease();
      QVERIFY(seen.waitFor([&] { return seen.lease; }));
      QVERIFY(seen.replied(client.sendCommandText("drive 0.5 10"), ReplyStatus::Ok));
      std::this_thread::sleep_for(1200ms);  // past a periodic snapshot
      client.estop("test");
      QVERIFY(seen.got(EventKind::Estop));
      client.rearm();
      QVERIFY(seen.got(EventKind::Rearmed));
      robot->addNote("operator note from the test");
      client.releaseLease();
      QVERIFY(seen.waitFor([&] { return !seen.lease; }));
      client.stop();
    }
    // The server notices the disconnection (its line goes to the log too).
    auto disconnected = [&] {
      std::lock_guard lock(linesMutex);
      return std::find(lines.begin(), lines.end(), "client 1 disconnected") != lines.end();
    };
    for (int i = 0; i < 500 && !disconnected(); ++i) std::this_thread::sleep_for(10ms);
    QVERIFY(disconnected());
    robot->stop();
    QVERIFY2(!robot->logFailed(), robot->logError().c_str());
    QCOMPARE(robot->logDropped(), int64_t{0});
    QCOMPARE(robot->stats().clientsAccepted, uint64_t{1});
    {
      std::lock_guard lock(linesMutex);
      QVERIFY(std::any_of(lines.begin(), lines.end(), [](const std::string& l) { return l.find("connected") != std::string::npos; }));
      QVERIFY(std::any_of(lines.begin(), lines.end(), [](const std::string& l) { return l.rfind("estop: ", 0) == 0; }));
    }

    std::string error;
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    const auto meta = reader->meta();
    QCOMPARE(meta.at("world_file"), o.worldFile);
    QVERIFY(meta.at("world_contents").find("<world") != std::string::npos);
    QVERIFY(meta.at("robot_contents").find("<robot") != std::string::npos);
    QCOMPARE(meta.at("robot_fnv1a64").size(), size_t{16});

    // The drive as the operator sent it, then the e-stop's and the
    // release's stops, all from the link.
    const std::vector<LogCommand> commands = reader->commands();
    std::string commandList;
    for (const LogCommand& c : commands) commandList += std::to_string(c.step) + " " + c.source + ": " + c.text + "\n";
    QVERIFY2(commands.size() >= 3, (commandList + eventList(reader->events())).c_str());
    QCOMPARE(commands.front().text.rfind("drive 0.5", 0), size_t{0});
    for (const LogCommand& c : commands) QCOMPARE(c.source, std::string("operator"));
    QCOMPARE(commands[1].text, std::string("stop"));
    QVERIFY(commands[1].step > commands[0].step);

    const std::vector<LogEvent> events = reader->events();
    QVERIFY2(hasEvent(events, "link", "client 1 connected from 127.0.0.1"), eventList(events).c_str());
    QVERIFY2(hasEvent(events, "link", "'tester' (client 1) authenticated as control"), eventList(events).c_str());
    QVERIFY2(hasEvent(events, "link", "lease taken by 'tester'"), eventList(events).c_str());
    QVERIFY2(hasEvent(events, "estop", "e-stop from 'tester': test"), eventList(events).c_str());
    QVERIFY2(hasEvent(events, "rearmed", "re-armed by 'tester'"), eventList(events).c_str());
    QVERIFY2(hasEvent(events, "note", "operator note from the test"), eventList(events).c_str());
    QVERIFY2(hasEvent(events, "link", "lease released by 'tester'"), eventList(events).c_str());
    QVERIFY2(hasEvent(events, "link", "client 1 disconnected"), eventList(events).c_str());
    // Events carry the twin's step and time; the e-stop's stop command is
    // applied at or after the step its event was written at.
    const auto estop = std::find_if(events.begin(), events.end(), [](const LogEvent& e) { return e.kind == "estop"; });
    QVERIFY(estop->step > commands[0].step && estop->step <= commands[1].step);
    QCOMPARE(estop->time, static_cast<double>(estop->step) * sp::test::defaultStep());

    // Samples at 100 Hz, a snapshot at start, every second and at the end.
    const std::vector<int64_t> snapshots = reader->snapshotSteps();
    QVERIFY(snapshots.size() >= 3);
    QCOMPARE(snapshots.front(), int64_t{0});
    QCOMPARE(snapshots[1], sp::test::stepAt(1.0));
    const double end = static_cast<double>(snapshots.back()) * sp::test::defaultStep();
    const std::vector<LogSample> samples = reader->samplesBetween(0, end);
    QVERIFY2(std::abs(static_cast<double>(samples.size()) - end * 100) <= 2, qPrintable(QString::number(samples.size())));
    QVERIFY(!reader->laserBetween(0, end).empty());
    reader.reset();

    // simpartner-sim resim's engine: every hash reproduced, commands included.
    auto report = resimulate(path, {}, error);
    QVERIFY2(report, error.c_str());
    QVERIFY2(!report->divergence, ("diverged at step " + std::to_string(report->divergence->step)).c_str());
    QCOMPARE(report->healthMessage, std::string());
    QCOMPARE(report->endStep, snapshots.back());
    QCOMPARE(report->hashesCompared, static_cast<int>(snapshots.size()));
    QCOMPARE(report->commandsApplied, static_cast<int>(commands.size()));
  }

  // A robot file opened in place of the world's own runs (a heavier rear
  // body here), is logged as the robot, and the log re-simulates with it.
  void robotOpenedInPlaceOfTheWorlds() {
    QTemporaryDir dir;
    std::ifstream in(sourcePath("robots/workpartner.xml"));
    std::stringstream text;
    text << in.rdbuf();
    std::string xml = text.str();
    const std::string from = R"(<link name="rear_body" mass="62")";
    QVERIFY(xml.find(from) != std::string::npos);
    xml.replace(xml.find(from), from.size(), R"(<link name="rear_body" mass="92")");
    const std::string robotFile = dir.filePath("heavy.xml").toStdString();
    std::ofstream(robotFile) << xml;

    const std::string path = dir.filePath("heavy.splog").toStdString();
    StandInOptions o = options(path);
    o.robotFile = robotFile;
    Diagnostics diag;
    auto robot = StandInRobot::create(o, diag);
    QVERIFY2(robot, diag.format().c_str());
    QCOMPARE(robot->world().robots[0].model.file, robotFile);
    QVERIFY(std::abs(robot->world().robots[0].model.totalMass() - 261.2) < 0.01);
    QCOMPARE(robot->start(), std::string());
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    robot->stop();

    std::string error;
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    const auto meta = reader->meta();
    QCOMPARE(meta.at("robot_file"), robotFile);
    QCOMPARE(meta.at("robot_contents"), xml);
    QCOMPARE(meta.at("replaced_robot_file"), sourcePath("robots/workpartner.xml"));
    reader.reset();
    auto report = resimulate(path, {}, error);
    QVERIFY2(report, error.c_str());
    QVERIFY(!report->divergence);
    QVERIFY(report->hashesCompared >= 2);

    // A broken robot file is refused by create(), naming the file and line.
    const std::string broken = dir.filePath("broken.xml").toStdString();
    std::ofstream(broken) << "<robot name=\"x\">\n  <link name=\"a\" mass=\"-1\"/>\n</robot>\n";
    o.robotFile = broken;
    Diagnostics bad;
    QVERIFY(!StandInRobot::create(o, bad));
    QVERIFY2(bad.format().find(broken + ":2:") != std::string::npos, bad.format().c_str());
  }

  // Without a file name the log is a new session-DATE-TIME.splog in the
  // folder (created); a second one started in the same second gets "-2".
  void logDirGetsNewFiles() {
    QTemporaryDir dir;
    const std::string folder = dir.filePath("logs/today").toStdString();
    StandInOptions o = options("");
    o.log = true;
    o.logDir = folder;
    Diagnostics diag;
    auto first = StandInRobot::create(o, diag);
    auto second = StandInRobot::create(o, diag);
    QVERIFY2(first && second, diag.format().c_str());
    QCOMPARE(first->start(), std::string());
    QCOMPARE(second->start(), std::string());
    first->stop();
    second->stop();
    const QRegularExpression name(R"(^session-\d{8}-\d{6}(-2)?\.splog$)");
    for (const std::string& p : {first->logPath(), second->logPath()}) {
      const std::filesystem::path path(p);
      QCOMPARE(path.parent_path().string(), folder);
      QVERIFY2(name.match(QString::fromStdString(path.filename().string())).hasMatch(), p.c_str());
      QVERIFY(std::filesystem::exists(path));
    }
    QVERIFY(first->logPath() != second->logPath());
  }

  // A client of the pick-and-place world receives the pole, its one dynamic
  // object (the static cubes are not sent), in TELEMETRY `objects`, lying
  // where the world file puts it (2.5 0 0.94, rolled 90 degrees).
  void telemetryCarriesDynamicObjects() {
    StandInOptions o = options("");
    o.worldFile = sourcePath("terrains/pick_place.world.xml");
    Diagnostics diag;
    auto robot = StandInRobot::create(o, diag);
    QVERIFY2(robot, diag.format().c_str());
    QCOMPARE(robot->start(), std::string());

    Seen seen;
    std::optional<TelemetryMsg> telemetry;
    RobotClientCallbacks callbacks = seen.callbacks();
    callbacks.telemetry = [&](const TelemetryMsg& t) { seen.add([&] { telemetry = t; }); };
    RobotClientConfig config;
    config.port = robot->port();
    config.token = robot->token();
    config.name = "tester";
    config.role = Role::Monitor;
    RobotClient client(config, callbacks);
    client.start();
    QVERIFY(seen.waitFor([&] { return telemetry.has_value(); }));
    client.stop();
    robot->stop();

    QCOMPARE(telemetry->objects.size(), size_t{1});
    const ObjectPose& pole = telemetry->objects[0];
    QCOMPARE(pole.name, std::string("pole"));
    QVERIFY2(norm(pole.pose.p - Vec3{2.5, 0, 0.94}) < 0.02,
             qPrintable(QStringLiteral("pole at %1 %2 %3").arg(pole.pose.p.x).arg(pole.pose.p.y).arg(pole.pose.p.z)));
    // Rolled 90 degrees about x: q = (cos 45, sin 45, 0, 0), up to sign.
    const Quat& q = pole.pose.q;
    const double alignment = std::abs(q.w * std::sqrt(0.5) + q.x * std::sqrt(0.5));
    QVERIFY2(alignment > 0.999, qPrintable(QStringLiteral("q = %1 %2 %3 %4").arg(q.w).arg(q.x).arg(q.y).arg(q.z)));
  }

  // With logging off no file is written anywhere.
  void noLogWritesNothing() {
    QTemporaryDir dir;
    StandInOptions o = options("");
    o.logDir = dir.filePath("sessions").toStdString();
    Diagnostics diag;
    auto robot = StandInRobot::create(o, diag);
    QVERIFY(robot);
    QCOMPARE(robot->start(), std::string());
    robot->addNote("nowhere to go");
    robot->stop();
    QCOMPARE(robot->logPath(), std::string());
    QVERIFY(!robot->logFailed());
    QVERIFY(!std::filesystem::exists(o.logDir));
  }

  // A robot that is not its twin (--perturb SEED): it tells nothing of its
  // deviations (WELCOME's file hashes are the files'), it reports its IMU
  // bias (roll at rest on flat ground is the drawn bias), its log records
  // the deviations and re-simulates hash for hash with them; the same log
  // re-simulated as if unperturbed diverges (the control).
  void perturbedRobotHidesItsDeviations() {
    QTemporaryDir dir;
    const std::string plainLog = dir.filePath("plain.splog").toStdString();
    const std::string path = dir.filePath("perturbed.splog").toStdString();
    const auto welcomeAndRoll = [&](const std::string& log, std::optional<uint64_t> seed, std::string& worldHash,
                                    std::string& robotHash, double& roll) {
      StandInOptions o = options(log);
      o.perturbSeed = seed;
      if (seed) o.wheelTorque = {1, 1, 0.5, 1};  // and a weak rear-left motor
      Diagnostics diag;
      auto robot = StandInRobot::create(o, diag);
      QVERIFY2(robot, diag.format().c_str());
      QCOMPARE(robot->start(), std::string());
      struct Latest : sp::test::SharedState {
        bool ready = false, lease = false;
        std::optional<TelemetryMsg> telemetry;
      } seen;
      RobotClientConfig config;
      config.port = robot->port();
      config.token = robot->token();
      config.name = "tester";
      RobotClientCallbacks cb;
      cb.connection = [&](ConnectionState s, const std::string&) { seen.add([&] { seen.ready = s == ConnectionState::Ready; }); };
      cb.lease = [&](const LeaseStateMsg& m) { seen.add([&] { seen.lease = m.yours; }); };
      cb.telemetry = [&](const TelemetryMsg& t) { seen.add([&] { seen.telemetry = t; }); };
      RobotClient client(config, cb);
      client.start();
      QVERIFY(seen.waitFor([&] { return seen.ready; }));
      std::this_thread::sleep_for(1500ms);  // settled on the ground
      double settled = 0;
      seen.add([&] { settled = seen.telemetry ? seen.telemetry->roll : 1e9; });
      roll = settled;
      worldHash = client.stats().robotWorldHash;
      robotHash = client.stats().robotRobotHash;
      client.acquireLease();
      QVERIFY(seen.waitFor([&] { return seen.lease; }));
      client.sendCommandText("drive 0.5 10");
      std::this_thread::sleep_for(1500ms);  // past a periodic snapshot, turning
      client.stop();
      robot->stop();
    };
    std::string plainWorld, plainRobot, world, robotHash;
    double plainRoll = 0, roll = 0;
    welcomeAndRoll(plainLog, std::nullopt, plainWorld, plainRobot, plainRoll);
    welcomeAndRoll(path, 11, world, robotHash, roll);
    QVERIFY(!world.empty());
    QCOMPARE(world, plainWorld);
    QCOMPARE(robotHash, plainRobot);
    Diagnostics diag;
    const RobotModel robot = loadWorld(sourcePath("terrains/flat.world.xml"), diag)->robots[0].model;
    const Perturbation p = drawPerturbation(11, robot);
    qInfo("roll at rest: %.5f rad unperturbed, %.5f perturbed (drawn bias %.5f)", plainRoll, roll, p.rollBias);
    QVERIFY(std::abs((roll - plainRoll) - p.rollBias) < 0.002);

    std::string error;
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    const auto meta = reader->meta();
    QCOMPARE(meta.at("perturbation_seed"), std::string("11"));
    QCOMPARE(meta.at("perturbation"), p.report(robot));
    QCOMPARE(meta.at("perturbation_wheel_torque"), std::string("1 1 0.5 1"));
    reader.reset();
    const std::optional<ResimReport> r = resimulate(path, {}, error);
    QVERIFY2(r, error.c_str());
    QVERIFY2(!r->divergence, "the perturbed log does not re-simulate with its deviations");
    QVERIFY(r->hashesCompared >= 2);
    // Controls: the same log as if the robot were its twin, and as if its
    // rear-left motor were as strong as the rest.
    for (const char* pattern : {"perturbation%", "perturbation_wheel_torque"}) {
      const std::string copy = dir.filePath(QString("without-%1.splog").arg(pattern[12] == '%' ? "all" : "torque")).toStdString();
      std::filesystem::copy_file(path, copy);
      sqlite3* db = nullptr;
      QCOMPARE(sqlite3_open(copy.c_str(), &db), SQLITE_OK);
      const std::string sql = std::string("DELETE FROM meta WHERE key LIKE '") + pattern + "'";
      QCOMPARE(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
      sqlite3_close(db);
      const std::optional<ResimReport> control = resimulate(copy, {}, error);
      QVERIFY2(control, error.c_str());
      QVERIFY2(control->divergence, (std::string("re-simulated without meta ") + pattern + ", the log still matched").c_str());
    }
  }

  // A robot that changes while it runs (issue 61): at the time asked its
  // log notes the change and what it was; the meta says it for a replay.
  // Before it (the control) no note. A change that cannot be is refused
  // at create(), naming the field.
  void suddenChangeIsLogged() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("changed.splog").toStdString();
    StandInOptions o = options(path);
    o.change = SuddenChange{0.3, 0.7, 0.1};  // 0.9 s before the stop: time to spare on a loaded machine
    Diagnostics diag;
    auto robot = StandInRobot::create(o, diag);
    QVERIFY2(robot, diag.format().c_str());
    QCOMPARE(robot->start(), std::string());
    std::this_thread::sleep_for(1200ms);
    robot->stop();
    std::string error;
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    QCOMPARE(reader->meta().at("perturbation_change"), std::string("friction x0.7, delay +0.1 s at 0.3 s"));
    std::vector<LogEvent> notes;
    for (const LogEvent& e : reader->events())
      if (e.kind == "note" && e.text.rfind("the stand-in changed", 0) == 0) notes.push_back(e);
    QCOMPARE(notes.size(), size_t{1});
    QVERIFY2(notes[0].time >= 0.3 - 1e-9 && notes[0].time < 0.3 + 0.01, qPrintable(QString::number(notes[0].time)));
    QCOMPARE(notes[0].text, std::string("the stand-in changed: friction x0.7, delay +0.1 s at 0.3 s"));

    // The control: asked for later than the run lasted, nothing changed.
    const std::string later = dir.filePath("later.splog").toStdString();
    StandInOptions l = options(later);
    l.change = SuddenChange{60, 0.7, 0.1};
    auto unchanged = StandInRobot::create(l, diag);
    QVERIFY2(unchanged, diag.format().c_str());
    QCOMPARE(unchanged->start(), std::string());
    std::this_thread::sleep_for(300ms);
    unchanged->stop();
    reader = SessionLogReader::open(later, error);
    QVERIFY2(reader, error.c_str());
    for (const LogEvent& e : reader->events()) QVERIFY2(e.text.find("changed") == std::string::npos, e.text.c_str());

    for (const auto& [bad, expected] : {std::pair{SuddenChange{1, 0, 0}, "change: error: friction factor 0: must be > 0"},
                                        std::pair{SuddenChange{1, 1, -0.1}, "change: error: delay -0.1 s: must be >= 0"},
                                        std::pair{SuddenChange{NAN, 1, 0}, "change: error: at nan s: must be >= 0"}}) {
      StandInOptions b = options("");
      b.change = bad;
      Diagnostics refused;
      QVERIFY(!StandInRobot::create(b, refused));
      QVERIFY2(refused.format().find(expected) != std::string::npos, refused.format().c_str());
    }
  }

  // start() refuses a log file that exists, and then runs nothing; create()
  // names what is wrong with the options.
  void refusals() {
    QTemporaryDir dir;
    const std::string path = dir.filePath("taken.splog").toStdString();
    std::ofstream(path) << "not mine";
    Diagnostics diag;
    auto robot = StandInRobot::create(options(path), diag);
    QVERIFY(robot);
    QCOMPARE(robot->start(), path + ": already exists");
    QCOMPARE(robot->port(), uint16_t{0});
    robot->stop();

    StandInOptions open = options("");
    open.bind = "0.0.0.0";
    open.token.clear();
    QVERIFY(!StandInRobot::create(open, diag));
    QVERIFY2(diag.format().find("refusing to listen on 0.0.0.0 without a token") != std::string::npos,
             diag.format().c_str());

    Diagnostics missing;
    StandInOptions none = options("");
    none.worldFile = dir.filePath("nowhere.world.xml").toStdString();
    QVERIFY(!StandInRobot::create(none, missing));
    QVERIFY(missing.hasErrors());
  }
};

QTEST_GUILESS_MAIN(TestStandIn)
#include "tst_stand_in.moc"
