// Driving over emulated links (docs/protocol.md, "Settings per link"): the
// stand-in robot on loopback with delay and jitter in both directions, a
// RobotClient taking control and driving. With the table's settings the
// robot is driven over each link: no failsafe, the drive command accepted,
// the robot moves, no telemetry lost or dropped. Then the link fades on
// purpose: a fade the deadman must ride out, and the control, one it cannot.

#include <QTest>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

#include "app/robot/stand_in.h"
#include "net/robot_client.h"
#include "tests/app/shared_state.h"

using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

// What the client's callbacks report (on its thread), for the test's thread.
struct Seen : sp::test::SharedState {
  bool ready = false, lease = false;
  std::optional<ReplyMsg> reply;
  int failsafes = 0;
  std::optional<TelemetryMsg> telemetry;

  RobotClientCallbacks callbacks() {
    RobotClientCallbacks cb;
    cb.connection = [this](ConnectionState s, const std::string&) { add([&] { ready = s == ConnectionState::Ready; }); };
    cb.lease = [this](const LeaseStateMsg& m) { add([&] { lease = m.yours; }); };
    cb.reply = [this](const ReplyMsg& m) { add([&] { reply = m; }); };
    cb.event = [this](const EventMsg& m) { add([&] { failsafes += m.kind == EventKind::Failsafe; }); };
    cb.telemetry = [this](const TelemetryMsg& t) { add([&] { telemetry = t; }); };
    return cb;
  }
};

}  // namespace

class TestLinkDelay : public QObject {
  Q_OBJECT

 private slots:
  void drivesOverEmulatedLinks_data() {
    QTest::addColumn<double>("delay");    // one way [s], both directions
    QTest::addColumn<double>("jitter");   // +- [s], each direction
    QTest::addColumn<double>("deadman");  // the robot's [s]
    QTest::addColumn<double>("fade");     // [s] the link fades while driving; 0 = never
    QTest::addColumn<bool>("failsafe");   // expected
    QTest::newRow("LAN") << 0.0 << 0.0 << 0.2 << 0.0 << false;
    QTest::newRow("radio 300 ms +- 50 round trip") << 0.15 << 0.05 << 0.3 << 0.0 << false;
    QTest::newRow("planetary 2 s +- 0.1 round trip") << 1.0 << 0.1 << 0.5 << 0.0 << false;
    // The bounds, from the protocol: keep-alives leave every
    // min(link.keepalive 50 ms, deadman / 4); a fade of F holds every frame
    // sent in it until its end, so the robot's longest silence is at most
    // F + 50 ms + 2 x jitter (the frame before the fade late by the
    // jitter, the one after early by it), and at least F - 2 x jitter.
    // Ridden out: 0.1 + 0.05 + 0.2 = 0.35 s < 0.5 s (150 ms to spare).
    QTest::newRow("planetary, a 100 ms fade ridden out") << 1.0 << 0.1 << 0.5 << 0.1 << false;
    // Control, tripping by construction: 0.9 - 0.2 = 0.7 s > 0.5 s.
    QTest::newRow("planetary, a 900 ms fade trips the deadman (control)") << 1.0 << 0.1 << 0.5 << 0.9 << true;
  }

  void drivesOverEmulatedLinks() {
    QFETCH(double, delay);
    QFETCH(double, jitter);
    QFETCH(double, deadman);
    QFETCH(double, fade);
    QFETCH(bool, failsafe);
    StandInOptions o;
    o.worldFile = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    o.port = 0;
    o.token = kToken;
    o.log = false;
    o.emulation.delay = delay;
    o.emulation.jitter = jitter;
    o.overrides = {"link.deadman=" + std::to_string(deadman)};
    Diagnostics diag;
    auto robot = StandInRobot::create(o, diag);
    QVERIFY2(robot, diag.format().c_str());
    QCOMPARE(robot->start(), std::string());

    Seen seen;
    RobotClientConfig config;
    config.port = robot->port();
    config.token = kToken;
    config.name = "far";
    const auto roundTrip = std::chrono::milliseconds(static_cast<int>(2000 * (delay + jitter)) + 200);
    {
      RobotClient client(config, seen.callbacks());
      client.start();
      QVERIFY(seen.waitFor([&] { return seen.ready; }, 10s));
      QCOMPARE(client.stats().robotDeadman, deadman);
      client.acquireLease();
      QVERIFY(seen.waitFor([&] { return seen.lease; }, 10s));
      std::this_thread::sleep_for(2 * roundTrip + 500ms);
      QCOMPARE(seen.read([&] { return seen.failsafes; }), 0);
      QVERIFY(seen.waitFor([&] { return seen.telemetry.has_value(); }, 5s));
      const double x0 = seen.read([&] { return seen.telemetry->pose.p.x; });
      const uint64_t seq = client.sendCommandText("drive 0.5 0");
      QVERIFY(seen.waitFor([&] { return seen.reply && seen.reply->seq == seq; }, 10s));
      QCOMPARE(seen.read([&] { return seen.reply->status; }), ReplyStatus::Ok);
      // The robot moves (as its delayed telemetry shows): 0.5 m/s for a while.
      QVERIFY(seen.waitFor([&] { return seen.telemetry->pose.p.x - x0 > 0.5; }, 10s));
      QCOMPARE(seen.read([&] { return seen.failsafes; }), 0);
      if (fade > 0) {
        robot->fadeLink(fade);
        // The fade, then a round trip for the failsafe's EVENT to come back.
        const auto after = std::chrono::milliseconds(static_cast<int>(1000 * fade)) + roundTrip + 500ms;
        if (failsafe) {
          QVERIFY(seen.waitFor([&] { return seen.failsafes > 0; }, after));
        } else {
          std::this_thread::sleep_for(after);
          QCOMPARE(seen.read([&] { return seen.failsafes; }), 0);
        }
      }
      const RobotClientStats stats = client.stats();
      QCOMPARE(stats.telemetryLost, uint64_t{0});
      QCOMPARE(stats.robotDropped, uint64_t{0});
      client.stop();
    }
    robot->stop();
    QCOMPARE(robot->stats().telemetryDropped, uint64_t{0});
    QCOMPARE(robot->stats().emulatedLost, uint64_t{0});
  }
};

QTEST_GUILESS_MAIN(TestLinkDelay)
#include "tst_link_delay.moc"
