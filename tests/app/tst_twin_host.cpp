// Tests of sp::TwinHost (app/robot/twin_host.h): the twin on its own physics
// thread behind the robot port, stepping through sp::Runner and publishing
// sp::readRobot's read-out.

#include <QTest>

#include <QTemporaryDir>

#include <chrono>
#include <memory>
#include <thread>

#include "app/log/session_recorder.h"
#include "app/robot/twin_host.h"
#include "sim/model_loader.h"
#include "sim/readout.h"

using namespace sp;

namespace {

std::unique_ptr<World> flatWorld(SimParams params = {}) {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld("terrains/flat.world.xml", diag);
  if (!model) return nullptr;
  return World::create(*model, params, diag);
}

/// Waits (up to 10 s) until `done` holds.
template <typename F>
bool waitFor(F done) {
  for (int i = 0; i < 1000 && !done(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return done();
}

}  // namespace

class TestTwinHost : public QObject {
  Q_OBJECT

 private slots:
  // Before it runs, the published state is the read-out of the world it
  // was given, joints named in the model's order.
  void publishesTheReadout() {
    auto world = flatWorld();
    QVERIFY(world);
    const RobotReadout expected = readRobot(*world);
    const RobotModel robot = world->robotModel(0);
    TwinHost host(std::move(world), 0);
    const net::RobotState s = host.state();
    QCOMPARE(s.time, 0.0);
    QCOMPARE(s.pose, expected.base);
    QCOMPARE(s.jointPositions, expected.jointPositions);
    QCOMPARE(s.jointVelocities, expected.jointRates);
    QCOMPARE(s.jointNames.size(), robot.joints.size());
    for (size_t j = 0; j < robot.joints.size(); ++j) QCOMPARE(s.jointNames[j], robot.joints[j].name);
    QVERIFY(s.health.empty());
  }

  // Checks answer by kind: limits are out_of_limits, the rest invalid.
  void checksByKind() {
    TwinHost host(flatWorld(), 0);
    QVERIFY(host.check(DriveCmd{0.5, 0}).ok());
    QCOMPARE(host.check(DriveCmd{0.5, degToRad(80)}).kind, CommandCheck::Kind::OutOfLimits);
    QCOMPARE(host.check(JointTargetCmd{"nope", 0}).kind, CommandCheck::Kind::Invalid);
    // Terrain edits are the simulator's: the robot's side refuses them.
    QCOMPARE(host.check(TerrainPatchCmd{0, 0, 1, 1, {0.1}}).kind, CommandCheck::Kind::Invalid);
  }

  // Running, commands drive the twin, the state follows, laser scans come
  // with increasing counts; a command applied just before stop() is still
  // stepped and logged.
  void runsCommandsAndLogs() {
    QTemporaryDir dir;
    const std::string logPath = dir.filePath("host.splog").toStdString();
    auto world = flatWorld();
    QVERIFY(world);
    const std::string worldFile = world->model().file, robotFile = world->robotModel(0).file;
    TwinHost host(std::move(world), 2.0);  // paced at twice real time
    std::string error;
    SessionSources sources;
    sources.worldFile = worldFile;
    sources.robotFile = robotFile;
    host.logTo(openSessionLog(logPath, sources, error));
    QVERIFY2(host.log(), error.c_str());
    const double x0 = host.state().pose.p.x;
    host.start();
    host.apply({DriveCmd{0.8, 0}});
    QVERIFY(waitFor([&] { return host.state().time > 1.5; }));
    QVERIFY2(host.state().pose.p.x - x0 > 0.5, qPrintable(QString::number(host.state().pose.p.x - x0)));
    const std::optional<net::LaserScanState> first = host.laserAfter(0);
    QVERIFY(first);
    QVERIFY(waitFor([&] { return host.laserAfter(first->count).has_value(); }));
    QVERIFY(!host.laserAfter(host.laserAfter(first->count)->count));
    host.apply({StopCmd{}});
    host.stop();
    auto reader = SessionLogReader::open(logPath, error);
    QVERIFY2(reader, error.c_str());
    const std::vector<LogCommand> commands = reader->commands();
    QCOMPARE(commands.size(), size_t{2});
    QCOMPARE(QString::fromStdString(commands[1].text), QString("stop"));
    QVERIFY(reader->hashes().size() >= 2);
  }

  // A robot with an actuator delay (sim/perturbation.h) acts on a command
  // that long after it arrives: the logged step of a command handed over
  // at sim time t is at t + 50 ms (one pacing pass of slack); without a
  // delay, at t (the control). A command still delayed at stop() is applied.
  void actuatorDelay_data() {
    QTest::addColumn<double>("delay");
    QTest::newRow("50 ms") << 0.05;
    QTest::newRow("control: none") << 0.0;
  }
  void actuatorDelay() {
    QFETCH(double, delay);
    QTemporaryDir dir;
    const std::string logPath = dir.filePath("delay.splog").toStdString();
    auto world = flatWorld();
    QVERIFY(world);
    SessionSources sources;
    sources.worldFile = world->model().file;
    sources.robotFile = world->robotModel(0).file;
    TwinHost host(std::move(world), 1.0);
    host.setDeviations(delay, 0, 0);
    std::string error;
    host.logTo(openSessionLog(logPath, sources, error));
    QVERIFY2(host.log(), error.c_str());
    host.start();
    QVERIFY(waitFor([&] { return host.state().time > 0.3; }));
    const double handed = host.state().time;  // published at 100 Hz: at most 10 ms old
    host.apply({DriveCmd{0.3, 0}});
    QVERIFY(waitFor([&] { return host.state().time > handed + 0.3; }));
    host.apply({StopCmd{}});
    host.stop();
    auto reader = SessionLogReader::open(logPath, error);
    QVERIFY2(reader, error.c_str());
    const std::vector<LogCommand> commands = reader->commands();
    QCOMPARE(commands.size(), size_t{2});
    const double lag = commands[0].time - handed;
    qInfo("delay %.3f s: the command acted %.1f ms after it was handed over", delay, lag * 1000);
    QVERIFY2(lag >= delay - 0.002 && lag <= delay + 0.025, qPrintable(QString::number(lag)));
    QCOMPARE(QString::fromStdString(commands[1].text), QString("stop"));
  }

  // A diverging twin stops, says why in its state, and logs a health event.
  void divergenceReported() {
    QTemporaryDir dir;
    const std::string logPath = dir.filePath("diverged.splog").toStdString();
    SimParams params;
    params.maxLinearSpeed = 0.05;
    auto world = flatWorld(params);
    QVERIFY(world);
    const std::string worldFile = world->model().file, robotFile = world->robotModel(0).file;
    TwinHost host(std::move(world), 0);
    std::string error;
    SessionSources sources;
    sources.worldFile = worldFile;
    sources.robotFile = robotFile;
    host.logTo(openSessionLog(logPath, sources, error));
    host.start();
    host.apply({DriveCmd{0.5, 0}});
    QVERIFY(waitFor([&] { return !host.state().health.empty(); }));
    QVERIFY2(QString::fromStdString(host.state().health).contains("health.max_linear_speed"),
             host.state().health.c_str());
    host.stop();
    auto reader = SessionLogReader::open(logPath, error);
    QVERIFY2(reader, error.c_str());
    int health = 0;
    for (const LogEvent& e : reader->events()) health += e.kind == "health";
    QCOMPARE(health, 1);
  }
};

QTEST_GUILESS_MAIN(TestTwinHost)
#include "tst_twin_host.moc"
