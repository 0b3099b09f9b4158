// SIGTERM and SIGINT stop the robot before `simpartner-robot` ends (issue
// 36): a controller drives at 0.5 m/s; after the signal the controller
// hears why (EVENT estop, then the connection closes), the process exits 0,
// and its session log ends with the stop: the last command is `stop`, the
// robot is at rest in the last samples, and the shutdown is logged. Before
// this, the process ended in 0.02 s with the last samples at 0.5 m/s and
// the last command `drive 0.5 0` (the control that these criteria fail).

#include <QTemporaryDir>
#include <QTest>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "app/log/session_log.h"
#include "net/robot_client.h"
#include "tests/app/robot_process.h"
#include "tests/app/shared_state.h"


using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

struct Seen : sp::test::SharedState {
  bool ready = false, lease = false, ok = false, lost = false;
  std::string estop;  // the EVENT estop's text
};

}  // namespace

class TestRobotShutdown : public QObject {
  Q_OBJECT

 private slots:
  void signalStopsTheRobot_data() {
    QTest::addColumn<int>("signal");
    QTest::newRow("SIGTERM") << SIGTERM;
    QTest::newRow("SIGINT") << SIGINT;
  }
  void signalStopsTheRobot() {
    QFETCH(int, signal);
    QTemporaryDir dir;
    const std::string log = dir.filePath(QStringLiteral("robot.splog")).toStdString();
    int out[2];
    QVERIFY(pipe(out) == 0);
    const std::string world = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    const pid_t pid = test::spawnRobot({"--world", world, "--port", "0", "--token", kToken, "--log", log}, out[1]);
    QVERIFY(pid != 0);
    test::ChildReaper reaper(pid);  // a failure below must not leave it running
    close(out[1]);
    std::string text;
    const uint16_t port = test::listeningPort(out[0], text);
    QVERIFY2(port != 0, text.c_str());

    Seen seen;
    RobotClientConfig config;
    config.port = port;
    config.token = kToken;
    config.name = "operator";
    RobotClientCallbacks callbacks;
    callbacks.connection = [&](ConnectionState s, const std::string&) {
      seen.add([&] {
        if (seen.ready && s != ConnectionState::Ready) seen.lost = true;
        seen.ready = s == ConnectionState::Ready;
      });
    };
    callbacks.lease = [&](const LeaseStateMsg& m) { seen.add([&] { seen.lease = m.yours; }); };
    callbacks.reply = [&](const ReplyMsg& m) { seen.add([&] { seen.ok = m.status == ReplyStatus::Ok; }); };
    callbacks.event = [&](const EventMsg& m) {
      if (m.kind == EventKind::Estop) seen.add([&] { seen.estop = m.text; });
    };
    RobotClient client(config, callbacks);
    client.start();
    QVERIFY(seen.waitFor([&] { return seen.ready; }, 5000ms));
    client.acquireLease();
    QVERIFY(seen.waitFor([&] { return seen.lease; }, 5000ms));
    client.sendCommandText("drive 0.5 0");
    QVERIFY(seen.waitFor([&] { return seen.ok; }, 5000ms));
    std::this_thread::sleep_for(2000ms);  // up to speed

    const Clock::time_point sent = Clock::now();
    kill(pid, signal);
    int status = 0;
    pid_t done = 0;
    for (auto until = Clock::now() + 8s; (done = waitpid(pid, &status, WNOHANG)) == 0 && Clock::now() < until;)
      std::this_thread::sleep_for(20ms);
    if (done == 0) kill(pid, SIGKILL), waitpid(pid, &status, 0);
    reaper.release();
    const double took = std::chrono::duration<double>(Clock::now() - sent).count();
    QVERIFY2(done == pid, "simpartner-robot did not end within 8 s of the signal");
    QVERIFY(WIFEXITED(status));
    QCOMPARE(WEXITSTATUS(status), 0);
    QVERIFY(seen.waitFor([&] { return seen.lost; }, 2000ms));
    std::string estop;
    seen.add([&] { estop = seen.estop; });
    QVERIFY2(estop.find("robot shutting down") != std::string::npos, estop.c_str());
    client.stop();
    close(out[0]);

    std::string error;
    const auto reader = SessionLogReader::open(log, error);
    QVERIFY2(reader, error.c_str());
    const std::vector<LogCommand> commands = reader->commands();
    QVERIFY(!commands.empty());
    QCOMPARE(QString::fromStdString(commands.back().text), QStringLiteral("stop"));
    bool logged = false;
    for (const LogEvent& e : reader->events()) logged |= e.kind == "shutdown";
    QVERIFY(logged);
    const auto range = reader->sampleTimeRange();
    QVERIFY(range);
    const std::vector<LogSample> last = reader->samplesBetween(range->second - 0.05, range->second);
    QVERIFY(last.size() >= 2);
    const LogSample& a = last.front();
    const LogSample& b = last.back();
    const double speed = std::hypot(b.base[0] - a.base[0], b.base[1] - a.base[1]) / (b.time - a.time);
    const std::vector<LogSample> driving = reader->samplesBetween(commands.back().time - 0.2, commands.back().time - 0.1);
    QVERIFY(driving.size() >= 2);
    const double before = std::hypot(driving.back().base[0] - driving.front().base[0],
                                     driving.back().base[1] - driving.front().base[1]) /
                          (driving.back().time - driving.front().time);
    qInfo("%s: the process ended %.2f s after it; %.3f m/s before the stop, %.4f m/s in the last 50 ms of the log",
          signal == SIGTERM ? "SIGTERM" : "SIGINT", took, before, speed);
    QVERIFY2(before > 0.2, qPrintable(QString::number(before)));  // it was driving (else this proves nothing)
    QVERIFY2(speed < 0.01, qPrintable(QString::number(speed)));
    // Nothing left beside a log its writer closed, even after reading it.
    QVERIFY(!QFileInfo::exists(QString::fromStdString(log + "-wal")));
    QVERIFY(!QFileInfo::exists(QString::fromStdString(log + "-shm")));
  }
};

QTEST_GUILESS_MAIN(TestRobotShutdown)
#include "tst_robot_shutdown.moc"
