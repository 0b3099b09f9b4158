// Tests of sp::ConsoleSession (app/console/console_session.h): the console's session
// without its window. A real stand-in robot on loopback, real session logs.

#include <QFileInfo>
#include <QTest>

#include <QTemporaryDir>

#include <algorithm>
#include <condition_variable>
#include <memory>
#include <mutex>

#include "app/console/console_session.h"
#include "app/ghost/ghost.h"
#include "app/console/console_state.h"
#include "app/log/session_log.h"
#include "app/log/session_recorder.h"
#include "app/robot/stand_in.h"
#include "net/robot_client.h"
#include "sim/command_file.h"

using namespace sp;

namespace {

// A bad world file: the loader's error must come back with its line.
const char* kBrokenWorld = R"(<?xml version="1.0"?>
<world name="broken">
  <terrain type="plane" height="oops"/>
</world>
)";

net::TelemetryMsg telemetryAt(double time, std::vector<std::string> names, std::vector<double> positions) {
  net::TelemetryMsg t;
  t.time = time;
  t.pose = Pose{{1, 2, 0.8}, {}};
  t.jointNames = std::move(names);
  t.jointPositions = positions;
  t.jointVelocities.assign(t.jointPositions.size(), 0.5);
  t.wheelNormal = {500, 510, 450, 460};
  return t;
}

}  // namespace

class TestConsoleSession : public QObject {
  Q_OBJECT

 private:
  QTemporaryDir dir_;

  ConsoleSessionOptions options(const std::string& sub) const {
    ConsoleSessionOptions o;
    o.logDir = dir_.filePath(QString::fromStdString(sub)).toStdString();
    o.rtf = 1;
    return o;
  }
  // A console for a remote robot that is not there (nothing listens on port
  // 9), without a log: its telemetry is fed by hand.
  ConsoleSessionOptions unlogged(const std::string& sub) const {
    ConsoleSessionOptions o = options(sub);
    o.connectTo = "127.0.0.1:9";
    o.token = "00112233445566778899aabbccddeeff";
    o.log = false;
    return o;
  }
  std::string write(const std::string& name, const char* text) const {
    const std::string path = dir_.filePath(QString::fromStdString(name)).toStdString();
    QFile f(QString::fromStdString(path));
    if (f.open(QIODevice::WriteOnly)) f.write(text);
    return path;
  }

 private slots:
  // Started without --connect, the session runs the stand-in on loopback
  // (a free port, a generated 128-bit token) and logs into the log folder.
  void standInStarts() {
    ConsoleSession session(options("standin"));
    QCOMPARE(QString::fromStdString(session.start()), QString());
    QVERIFY(!session.remote());
    QVERIFY(session.standIn());
    QCOMPARE(QString::fromStdString(session.endpoint().host), QString("127.0.0.1"));
    QVERIFY(session.endpoint().port > 0);
    QCOMPARE(session.endpoint().port, session.standIn()->port());
    QCOMPARE(session.endpoint().token.size(), size_t{32});
    QVERIFY(QString::fromStdString(session.endpoint().label).contains("stand-in, flat.world.xml"));
    QVERIFY(session.robot());
    QCOMPARE(QString::fromStdString(session.robot()->name), QString("workpartner"));
    QVERIFY(QString::fromStdString(session.logPath()).startsWith(dir_.filePath("standin")));
    QVERIFY(QFile::exists(QString::fromStdString(session.logPath())));
    QCOMPARE(QString::fromStdString(session.logError()), QString());
  }

  // A broken world or robot file is refused with file:line and leaves the
  // running session as it was; a good one replaces the stand-in.
  void openWorldKeepsSessionOnError() {
    ConsoleSession session(options("open"));
    QCOMPARE(QString::fromStdString(session.start()), QString());
    const RobotEndpoint before = session.endpoint();
    const std::string log = session.logPath();
    const int version = session.worldVersion();
    const std::string bad = write("broken.world.xml", kBrokenWorld);
    const QString error = QString::fromStdString(session.openWorld(bad));
    QVERIFY2(error.startsWith(QString::fromStdString(bad) + ":3: error:"), qPrintable(error));
    QCOMPARE(session.endpoint().port, before.port);
    QCOMPARE(session.logPath(), log);
    QCOMPARE(session.worldVersion(), version);
    const QString robotError = QString::fromStdString(session.openRobot(bad));
    QVERIFY2(robotError.contains(QString::fromStdString(bad)) && robotError.contains("error:"), qPrintable(robotError));
    QCOMPARE(session.endpoint().port, before.port);

    QCOMPARE(QString::fromStdString(session.openWorld("terrains/bumpy.world.xml")), QString());
    QCOMPARE(session.worldVersion(), version + 1);
    QVERIFY(session.endpoint().port != before.port || session.endpoint().token != before.token);
    QVERIFY(session.logPath() != log);
    QCOMPARE(QString::fromStdString(session.world()->file), QString("terrains/bumpy.world.xml"));
  }

  // --connect checks its endpoint before anything is opened.
  void badEndpointsRefused_data() {
    QTest::addColumn<QString>("endpoint");
    QTest::newRow("no port") << "robot.local";
    QTest::newRow("empty port") << "robot.local:";
    QTest::newRow("port 0") << "robot.local:0";
    QTest::newRow("port too big") << "robot.local:70000";
    QTest::newRow("not a number") << "robot.local:47x0";
    QTest::newRow("no host") << ":47800";
  }
  void badEndpointsRefused() {
    QFETCH(QString, endpoint);
    ConsoleSessionOptions o = options("bad");
    o.connectTo = endpoint.toStdString();
    ConsoleSession session(o);
    QCOMPARE(QString::fromStdString(session.start()), "--connect: expected HOST:PORT, got '" + endpoint + "'");
    QCOMPARE(session.endpoint().port, uint16_t{0});
  }

  // Robot > Connect: a bad endpoint or token changes nothing; a good one
  // stops the stand-in (its log complete) and logs what the console sees;
  // back to a stand-in, a new one runs.
  void connectToAndBack() {
    ConsoleSessionOptions o = options("switch");
    ConsoleSession session(o);
    QCOMPARE(QString::fromStdString(session.start()), QString());
    QVERIFY(session.standIn());
    const RobotEndpoint before = session.endpoint();
    const std::string standInLog = session.logPath();
    QCOMPARE(QString::fromStdString(session.connectTo("robot.local:47800", "abc")),
             QString("the token must have at least 32 hex digits (128 bits), got 3 digits"));
    QCOMPARE(QString::fromStdString(session.connectTo("robot.local", "00112233445566778899aabbccddeeff")),
             QString("expected HOST:PORT, got 'robot.local'"));
    QVERIFY(session.standIn());
    QCOMPARE(session.endpoint().port, before.port);
    QCOMPARE(QString::fromStdString(session.connectTo("127.0.0.1:9", "00112233445566778899aabbccddeeff")), QString());
    QVERIFY(session.remote());
    QVERIFY(!session.standIn());
    QCOMPARE(session.endpoint().port, uint16_t{9});
    QVERIFY(session.logPath() != standInLog);
    QVERIFY(QFileInfo::exists(QString::fromStdString(standInLog)));
    QCOMPARE(QString::fromStdString(session.useStandIn()), QString());
    QVERIFY(!session.remote());
    QVERIFY(session.standIn());
    QVERIFY(session.endpoint().port != 9);
  }

  // The robot announces the files it runs (WELCOME, over real TCP); the
  // console's own files match the stand-in's, and a robot on another world
  // is told apart, naming the file. Not announced: nothing to say.
  void robotFilesChecked() {
    ConsoleSession session(options("files"));
    QCOMPARE(QString::fromStdString(session.start()), QString());
    std::mutex mutex;
    std::condition_variable ready;
    bool welcomed = false;
    net::RobotClientConfig config;
    config.host = session.endpoint().host;
    config.port = session.endpoint().port;
    config.token = session.endpoint().token;
    config.name = "files test";
    net::RobotClientCallbacks callbacks;
    callbacks.connection = [&](net::ConnectionState state, const std::string&) {
      std::lock_guard lock(mutex);
      welcomed = welcomed || state == net::ConnectionState::Ready;
      ready.notify_all();
    };
    net::RobotClient client(config, callbacks);
    client.start();
    {
      std::unique_lock lock(mutex);
      QVERIFY(ready.wait_for(lock, std::chrono::seconds(10), [&] { return welcomed; }));
    }
    const net::RobotClientStats stats = client.stats();
    client.stop();
    QCOMPARE(stats.robotWorldHash, fileHash(session.world()->file));
    QCOMPARE(stats.robotWorldHash.size(), size_t{16});
    QCOMPARE(stats.robotRobotHash.size(), size_t{16});
    QCOMPARE(QString::fromStdString(session.filesMismatch(stats.robotWorldHash, stats.robotRobotHash)), QString());
    QCOMPARE(QString::fromStdString(session.filesMismatch("", "")), QString());
    const std::string track = fileHash(std::string(SP_SOURCE_DIR) + "/terrains/test_track.world.xml");
    const QString differs = QString::fromStdString(session.filesMismatch(track, stats.robotRobotHash));
    QVERIFY2(differs.contains("its world file differs from " + QString::fromStdString(session.world()->file)),
             qPrintable(differs));
    QVERIFY(!differs.contains("robot file"));
  }

  // Reset restarts the stand-in with the robot at its start; both logs say
  // so. A remote robot cannot be reset from here.
  void resetRestartsTheStandIn() {
    ConsoleSession session(options("reset"));
    QCOMPARE(QString::fromStdString(session.start()), QString());
    const std::string oldLog = session.logPath();
    const uint16_t oldPort = session.endpoint().port;
    QCOMPARE(QString::fromStdString(session.resetRobot()), QString());
    QVERIFY(session.endpoint().port != oldPort);
    QVERIFY(session.logPath() != oldLog);
    // The old log is complete (its stand-in stopped) and says why it ends.
    std::string error;
    auto reader = SessionLogReader::open(oldLog, error);
    QVERIFY2(reader, error.c_str());
    const auto events = reader->events();
    QVERIFY(std::any_of(events.begin(), events.end(), [](const LogEvent& e) { return e.text.find("reset:") == 0; }));
    ConsoleSessionOptions o = options("reset-remote");
    o.connectTo = "127.0.0.1:9";
    o.token = "00112233445566778899aabbccddeeff";
    ConsoleSession remote(o);
    QCOMPARE(QString::fromStdString(remote.start()), QString());
    QVERIFY(!remote.resetRobot().empty());
  }

  // Every shipped heightfield world starts its robot with room: no edge
  // warning from the first frame (issue 31: the test track's start sat
  // 0.1 m from its edge, and the console warned in red at once).
  void shippedWorldsStartWithRoom() {
    for (const char* file : {"bumpy", "test_track"}) {
      ConsoleSessionOptions o = options(file);
      o.world = std::string(SP_SOURCE_DIR "/terrains/") + file + ".world.xml";
      o.connectTo = "127.0.0.1:9";
      o.token = "00112233445566778899aabbccddeeff";
      o.log = false;
      ConsoleSession session(o);
      QCOMPARE(QString::fromStdString(session.start()), QString());
      const RobotInstance& robot = session.world()->robots[0];
      Pose base = robot.pose;
      base.p = robot.pose.p + rotate(robot.pose.q, robot.model.links[0].pose.p);
      const double room = session.edgeDistance(base).value_or(-1);
      qInfo("%s: the robot starts %.2f m from the terrain's edge", file, room);
      QVERIFY2(room > ConsoleState::Config{}.edgeWarning, file);
    }
  }

  // The distance to a heightfield's edge, in the terrain's own frame; none
  // on a plane.
  void edgeDistanceOnHeightfields() {
    ConsoleSessionOptions o = options("edge");
    o.world = SP_SOURCE_DIR "/terrains/bumpy.world.xml";
    o.connectTo = "127.0.0.1:9";
    o.token = "00112233445566778899aabbccddeeff";
    o.log = false;
    ConsoleSession session(o);
    QCOMPARE(QString::fromStdString(session.start()), QString());
    const TerrainSpec& t = session.world()->terrain;
    QCOMPARE(int(t.kind), int(TerrainSpec::Kind::Heightfield));
    Pose at;
    at.p = {t.pose.p.x, t.pose.p.y, 0};
    QVERIFY(std::abs(*session.edgeDistance(at) - std::min(t.grid.width, t.grid.depth) / 2) < 1e-9);
    at.p.x = t.pose.p.x + t.grid.width / 2 - 0.5;
    at.p.y = t.pose.p.y;
    QVERIFY(std::abs(*session.edgeDistance(at) - std::min(0.5, t.grid.depth / 2)) < 1e-9);
    at.p.x = t.pose.p.x + t.grid.width / 2 + 2;
    QVERIFY(*session.edgeDistance(at) < 0);
    ConsoleSessionOptions flat = options("edge-flat");
    flat.connectTo = o.connectTo;
    flat.token = o.token;
    flat.log = false;
    flat.world = SP_SOURCE_DIR "/terrains/flat.world.xml";
    ConsoleSession plane(flat);
    QCOMPARE(QString::fromStdString(plane.start()), QString());
    QVERIFY(!plane.edgeDistance(at));
  }

  // Telemetry becomes a frame in the model's joint order, whatever order
  // the robot names its joints in; unknown names are ignored, joints not
  // reported read 0; latches and wheel forces pass through.
  void telemetryToModelOrder() {
    ConsoleSessionOptions o = options("remote");
    o.connectTo = "127.0.0.1:9";
    o.token = "00112233445566778899aabbccddeeff";
    o.log = false;
    ConsoleSession session(o);
    QCOMPARE(QString::fromStdString(session.start()), QString());
    const RobotModel& robot = *session.robot();
    const int knee = robot.findJoint("knee_fl"), waist = robot.findJoint("waist_yaw");
    QVERIFY(knee >= 0 && waist >= 0);
    net::TelemetryMsg t = telemetryAt(1.0, {"waist_yaw", "no_such_joint", "knee_fl"}, {0.3, 9.0, -0.2});
    t.estop = true;
    const RobotFrame f = session.telemetry(t, 100.0);
    QCOMPARE(f.jointPositions.size(), robot.joints.size());
    QCOMPARE(f.jointPositions[static_cast<size_t>(waist)], 0.3);
    QCOMPARE(f.jointPositions[static_cast<size_t>(knee)], -0.2);
    QCOMPARE(f.jointRates[static_cast<size_t>(knee)], 0.5);
    double others = 0;
    for (size_t j = 0; j < f.jointPositions.size(); ++j)
      if (static_cast<int>(j) != knee && static_cast<int>(j) != waist) others += std::abs(f.jointPositions[j]);
    QCOMPARE(others, 0.0);
    QVERIFY(f.estop && !f.failsafe);
    QCOMPARE(f.wheelNormal[2], 450.0);
    QCOMPARE(f.base.p.y, 2.0);
  }

  // The real-time factor is robot time over wall time across the last
  // second; a robot time that goes back (a new session) starts it over.
  void realTimeFactor() {
    ConsoleSession session(unlogged("rtf"));
    QCOMPARE(QString::fromStdString(session.start()), QString());
    QCOMPARE(session.realTimeFactor(), 0.0);
    for (int i = 0; i <= 100; ++i) session.telemetry(telemetryAt(2.0 * 0.02 * i, {}, {}), 50.0 + 0.02 * i);
    QVERIFY2(std::abs(session.realTimeFactor() - 2.0) < 1e-9, qPrintable(QString::number(session.realTimeFactor())));
    for (int i = 0; i <= 100; ++i) session.telemetry(telemetryAt(0.5 * 0.02 * i, {}, {}), 60.0 + 0.02 * i);
    QVERIFY2(std::abs(session.realTimeFactor() - 0.5) < 1e-9, qPrintable(QString::number(session.realTimeFactor())));
  }

  // A frame whose twin diverged halts the ghost (issue 31): it says why and
  // predicts nothing more (its view stays as it was), until a healthy frame.
  void divergedRobotHaltsTheGhost() {
    ConsoleSession session(unlogged("halt"));
    QCOMPARE(QString::fromStdString(session.start()), QString());
    const Ghost* ghost = session.ghost();
    QVERIFY(ghost);
    net::TelemetryMsg t = telemetryAt(1.0, {}, {});
    t.health = "angular speed 512 rad/s exceeds 200";
    session.telemetry(t, 20.0);
    const std::string why = "the robot's twin diverged: angular speed 512 rad/s exceeds 200";
    QCOMPARE(ghost->view().problem, why);
    const uint64_t version = ghost->view().version;
    QTest::qWait(300);  // its threads publish nothing meanwhile
    QCOMPARE(ghost->view().version, version);
    QCOMPARE(ghost->view().problem, why);
    session.telemetry(telemetryAt(1.1, {}, {}), 20.1);  // healthy again: it anchors
    QTRY_VERIFY_WITH_TIMEOUT(ghost->view().problem != why, 3000);
  }

  // Only the lease holder commands.
  void commandsNeedTheLease() {
    ConsoleSession session(options("lease"));
    QCOMPARE(QString::fromStdString(session.commandRefusal(false)),
             QString("Not sent: take control first (Robot ▸ Take control)"));
    QCOMPARE(QString::fromStdString(session.commandRefusal(true)), QString());
  }

  // With a remote robot the console logs what it saw and did: telemetry
  // samples, laser, the operator's commands, notes and link events.
  void remoteSessionLogged() {
    ConsoleSessionOptions o = options("remote-log");
    o.connectTo = "127.0.0.1:9";
    o.token = "00112233445566778899aabbccddeeff";
    std::string path;
    {
      ConsoleSession session(o);
      QCOMPARE(QString::fromStdString(session.start()), QString());
      path = session.logPath();
      QVERIFY(!path.empty());
      for (int i = 0; i < 5; ++i) session.telemetry(telemetryAt(0.1 * i, {"knee_fl"}, {0.1 * i}), 10.0 + 0.1 * i);
      session.laser(net::LaserMsg{1, 0.4, -1.0, 0.5, {1.0, 2.0, 3.0, 4.0, 5.0}});
      session.commandSent(DriveCmd{0.5, degToRad(10)});
      session.note("checked the left arm");
      session.event("link", "link connected");
    }
    std::string error;
    auto reader = SessionLogReader::open(path, error);
    QVERIFY2(reader, error.c_str());
    QCOMPARE(QString::fromStdString(reader->meta().at("log_source")), QString("telemetry"));
    QCOMPARE(QString::fromStdString(reader->meta().at("robot_endpoint")), QString("127.0.0.1:9"));
    QCOMPARE(reader->samplesBetween(0, 1).size(), size_t{5});
    QCOMPARE(reader->laserBetween(0, 1).size(), size_t{1});
    const std::vector<LogCommand> commands = reader->commands();
    QCOMPARE(commands.size(), size_t{1});
    QCOMPARE(QString::fromStdString(commands[0].text), QString("drive 0.5 10"));
    QCOMPARE(QString::fromStdString(commands[0].source), QString("operator"));
    QStringList events;
    for (const LogEvent& e : reader->events()) events << QString::fromStdString(e.kind + ": " + e.text);
    QVERIFY2(events.contains("note: checked the left arm"), qPrintable(events.join('\n')));
    QVERIFY2(events.contains("link: link connected"), qPrintable(events.join('\n')));
  }
};

QTEST_GUILESS_MAIN(TestConsoleSession)
#include "tst_console_session.moc"
