// The safety chain never waits on logging: `simpartner-robot` with a stderr
// pipe that nobody reads (filled by 1500 connections' lines) still streams
// telemetry, and its deadman still stops the robot 200 ms after a lost
// controller (bound asserted: 500 ms of wall time on a busy machine; it took
// 4.2 s when the link thread wrote its lines itself). SIGTERM then stops it
// cleanly, without waiting for the reader that never comes.

#include <QTest>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "net/robot_client.h"
#include "tests/app/robot_process.h"
#include "tests/app/shared_state.h"


using namespace sp::net;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

struct Seen : sp::test::SharedState {
  bool ready = false, lease = false, ok = false;
  Clock::time_point failsafeAt{};
};

}  // namespace

class TestRobotStderr : public QObject {
  Q_OBJECT

 private slots:
  void deadmanWithBlockedStderr() {
    int out[2], err[2];
    QVERIFY(pipe(out) == 0 && pipe(err) == 0);
    const std::string world = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    const pid_t pid = sp::test::spawnRobot({"--world", world, "--port", "0", "--token", kToken, "--no-log"}, out[1], err[1]);
    QVERIFY(pid != 0);
    sp::test::ChildReaper reaper(pid);  // a failure below must not leave it running
    close(out[1]);
    close(err[1]);  // err[0] stays open and unread: writes to it block once it is full

    // The port, from stdout's "listening on 127.0.0.1:PORT".
    std::string text;
    const uint16_t port = sp::test::listeningPort(out[0], text);
    QVERIFY2(port != 0, text.c_str());

    // Fill stderr's pipe: every connection writes two lines.
    for (int i = 0; i < 1500; ++i) {
      const int s = socket(AF_INET, SOCK_STREAM, 0);
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_port = htons(port);
      a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      QVERIFY(::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
      close(s);
    }
    std::this_thread::sleep_for(500ms);
    int pending = 0;
    QVERIFY(ioctl(err[0], FIONREAD, &pending) == 0);
    QVERIFY2(pending >= 60000, qPrintable(QString::number(pending)));  // full (64 KiB): writes block

    Seen control, monitor;
    RobotClientConfig cc;
    cc.port = port;
    cc.token = kToken;
    cc.name = "operator";
    RobotClientCallbacks ccb;
    ccb.connection = [&](ConnectionState s, const std::string&) { control.add([&] { control.ready = s == ConnectionState::Ready; }); };
    ccb.lease = [&](const LeaseStateMsg& m) { control.add([&] { control.lease = m.yours; }); };
    ccb.reply = [&](const ReplyMsg& m) { control.add([&] { control.ok = m.status == ReplyStatus::Ok; }); };
    RobotClientConfig mc = cc;
    mc.name = "watcher";
    mc.role = Role::Monitor;
    RobotClientCallbacks mcb;
    mcb.connection = [&](ConnectionState s, const std::string&) { monitor.add([&] { monitor.ready = s == ConnectionState::Ready; }); };
    mcb.event = [&](const EventMsg& m) {
      if (m.kind == EventKind::Failsafe) monitor.add([&] { monitor.failsafeAt = Clock::now(); });
    };
    RobotClient operatorClient(cc, ccb), watcher(mc, mcb);
    operatorClient.start();
    watcher.start();
    QVERIFY(control.waitFor([&] { return control.ready; }, 5000ms));
    QVERIFY(monitor.waitFor([&] { return monitor.ready; }, 5000ms));
    operatorClient.acquireLease();
    QVERIFY(control.waitFor([&] { return control.lease; }, 5000ms));
    operatorClient.sendCommandText("drive 0.3 0");
    QVERIFY(control.waitFor([&] { return control.ok; }, 5000ms));
    std::this_thread::sleep_for(1500ms);
    QVERIFY2(watcher.stats().telemetryRateHz > 40, qPrintable(QString::number(watcher.stats().telemetryRateHz)));

    const Clock::time_point cut = Clock::now();
    operatorClient.dropConnection();
    QVERIFY(monitor.waitFor([&] { return monitor.failsafeAt != Clock::time_point{}; }, 5000ms));
    const double ms = std::chrono::duration<double, std::milli>(monitor.failsafeAt - cut).count();
    qInfo("failsafe seen by a monitor %.0f ms after the controller's link was cut, stderr blocked", ms);
    QVERIFY2(ms >= 150 && ms < 500, qPrintable(QString::number(ms)));
    operatorClient.stop();
    watcher.stop();

    // SIGTERM: a clean stop, not a hang on the blocked pipe.
    kill(pid, SIGTERM);
    int status = 0;
    pid_t done = 0;
    for (auto until = Clock::now() + 5s; (done = waitpid(pid, &status, WNOHANG)) == 0 && Clock::now() < until;)
      std::this_thread::sleep_for(20ms);
    if (done == 0) kill(pid, SIGKILL), waitpid(pid, &status, 0);
    reaper.release();
    QVERIFY2(done == pid, "simpartner-robot did not stop within 5 s of SIGTERM");
    QVERIFY(WIFEXITED(status));
    QCOMPARE(WEXITSTATUS(status), 0);
    close(out[0]);
    close(err[0]);
  }
};

QTEST_GUILESS_MAIN(TestRobotStderr)
#include "tst_robot_stderr.moc"
