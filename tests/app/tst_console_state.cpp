// Tests of sp::ConsoleState (app/console/console_state.h): what the console
// shows and allows, computed from link events and frames without a window.

#include <QTest>

#include "app/console/console_state.h"

using namespace sp;
using net::ConnectionState;

namespace {

RobotFrame frameWith(bool failsafe, bool estop, std::string health = {}) {
  RobotFrame f;
  f.failsafe = failsafe;
  f.estop = estop;
  f.health = std::move(health);
  return f;
}

// Connected, holding the lease, one healthy frame at wall time 0.
ConsoleState driving() {
  ConsoleState s;
  s.connection(ConnectionState::Ready, {});
  s.lease(true);
  s.frame(frameWith(false, false), 0, std::nullopt);
  return s;
}

bool anyLineHas(const std::vector<std::string>& lines, const std::string& part) {
  for (const std::string& l : lines)
    if (l.find(part) != std::string::npos) return true;
  return false;
}

}  // namespace

class TestConsoleState : public QObject {
  Q_OBJECT

 private slots:
  // Controls act only when connected, holding the lease, unlatched and
  // showing the live robot; each refusal names its reason.
  void controlsRefusal_data() {
    QTest::addColumn<int>("connection");
    QTest::addColumn<bool>("lease");
    QTest::addColumn<bool>("estop");
    QTest::addColumn<bool>("replay");
    QTest::addColumn<QString>("why");
    const int ready = static_cast<int>(ConnectionState::Ready);
    QTest::newRow("driving") << ready << true << false << false << QString();
    QTest::newRow("waiting") << static_cast<int>(ConnectionState::Waiting) << true << false << false
                             << "Not connected to the robot";
    QTest::newRow("no lease") << ready << false << false << false << "Take control first (Robot ▸ Take control)";
    QTest::newRow("latched") << ready << true << true << false << "The robot is stopped and latched: re-arm first";
    QTest::newRow("replay") << ready << true << false << true
                            << "A replay is shown: close it (File ▸ Close replay) to drive the live robot";
  }
  void controlsRefusal() {
    QFETCH(int, connection);
    QFETCH(bool, lease);
    QFETCH(bool, estop);
    QFETCH(bool, replay);
    QFETCH(QString, why);
    ConsoleState s;
    s.connection(static_cast<ConnectionState>(connection), "down");
    s.lease(lease);
    s.frame(frameWith(false, estop), 0, std::nullopt);
    if (replay) s.replay("a.splog");
    QCOMPARE(QString::fromStdString(s.controlsRefusal()), why);
  }

  // Losing the link loses the lease, and says so once (the controls go
  // back to the robot's state then).
  void linkLossLosesTheLease() {
    ConsoleState s = driving();
    QVERIFY(s.leaseHeld());
    QVERIFY(s.connection(ConnectionState::Waiting, "timeout"));
    QVERIFY(!s.leaseHeld());
    QVERIFY(!s.connection(ConnectionState::Connecting, {}));  // nothing more to lose
    QVERIFY(!anyLineHas(s.bannerLines(), "Robot link down"));  // connecting: no banner line
    s.connection(ConnectionState::Waiting, "timeout");
    QVERIFY(anyLineHas(s.bannerLines(), "Robot link down (timeout)"));
    QVERIFY(!s.canRearm());
    QVERIFY(!s.canReconnect());
    QVERIFY(s.canDisconnect());
  }

  // A latch coming on is reported once, with the failsafe's reason in the
  // banner; re-arm is offered while connected.
  void latches() {
    ConsoleState s = driving();
    s.failsafeReason("deadman: no command for 0.2 s");
    const FrameChanges on = s.frame(frameWith(true, false), 0.1, std::nullopt);
    QVERIFY(on.latchedNow);
    QVERIFY(on.banner);
    const FrameChanges again = s.frame(frameWith(true, false), 0.12, std::nullopt);
    QVERIFY(!again.latchedNow && !again.banner);
    QVERIFY(anyLineHas(s.bannerLines(), "FAILSAFE latched: deadman: no command for 0.2 s; the robot stopped."));
    QVERIFY(s.canRearm());
    const FrameChanges off = s.frame(frameWith(false, false), 0.2, std::nullopt);
    QVERIFY(!off.latchedNow && off.latches);
    QVERIFY(s.bannerLines().empty());
  }

  // An e-stop sent is in flight until a frame shows the latch (issue 31):
  // the banner says so at once, counting down (issue 59: it said "lands in
  // ~1.0 s" 1.5 s after the press), then that it should have landed; the
  // controls wait. A re-arm sent is pending until a frame shows the latch
  // off. A dropped link ends both (they may never land; the banner says
  // the link is down).
  void inFlight() {
    ConsoleState s = driving();
    s.estopSent(1.04, 10.0);
    QVERIFY(s.estopInFlight());
    QVERIFY(anyLineHas(s.bannerLines(), "E-STOP in flight: lands in ~1.0 s"));
    QCOMPARE(s.controlsRefusal(), std::string("E-STOP in flight: lands in ~1.0 s"));
    QVERIFY(!s.frame(frameWith(false, false), 10.5, std::nullopt).latchedNow);  // not landed yet
    QVERIFY(s.estopInFlight());
    QVERIFY(anyLineHas(s.bannerLines(), "E-STOP in flight: lands in ~0.5 s"));
    const uint64_t before = s.revision();
    s.tick(10.8);
    QVERIFY(s.revision() != before);  // the countdown redraws
    QVERIFY(anyLineHas(s.bannerLines(), "E-STOP in flight: lands in ~0.2 s"));
    s.tick(11.5);
    QVERIFY2(anyLineHas(s.bannerLines(), "E-STOP should have landed (sent 1.5 s ago); waiting for the robot's report"),
             s.bannerLines().front().c_str());
    QVERIFY(!anyLineHas(s.bannerLines(), "lands in"));  // the old text's claim, 1.5 s after the press
    QVERIFY(s.frame(frameWith(false, true), 12.1, std::nullopt).latchedNow);
    QVERIFY(!s.estopInFlight());
    QVERIFY(!anyLineHas(s.bannerLines(), "in flight"));
    QVERIFY(anyLineHas(s.bannerLines(), "E-STOP latched: the robot is stopped"));
    s.rearmSent(1.0, 12.2);
    QVERIFY(anyLineHas(s.bannerLines(), "E-STOP latched: the robot is stopped. Re-arm in flight: lands in ~1.0 s."));
    QCOMPARE(s.controlsRefusal(), std::string("Re-arm in flight: lands in ~1.0 s"));
    s.frame(frameWith(false, false), 14.2, std::nullopt);
    QVERIFY(!s.rearmInFlight());
    QVERIFY(s.bannerLines().empty());
    QCOMPARE(s.controlsRefusal(), std::string());
    s.rearmSent(1.0, 14.3);  // nothing latched: nothing pending
    QVERIFY(!s.rearmInFlight());
    s.estopSent(-1, 14.4);  // before a round trip was measured: not "~0.0 s"
    QVERIFY(anyLineHas(s.bannerLines(), "E-STOP in flight: the round trip is not measured yet"));
    s.connection(ConnectionState::Waiting, "timeout");
    QVERIFY(!s.estopInFlight());
  }

  // Stale: connected, a frame seen, none for longer than staleAfter. The
  // next frame ends it; a replay shown hides the stale line (issue 27: a
  // replay showed "no data 4.8 s" while telemetry arrived at 50 Hz).
  void staleness() {
    ConsoleState s = driving();
    QVERIFY(!s.tick(0.4));
    QVERIFY(s.tick(0.6));
    QVERIFY(s.stale());
    QCOMPARE(s.staleText(0.6), std::string("no data 0.6 s: the robot drawn is where it was 0.6 s ago"));
    QCOMPARE(s.health().text, std::string("no data"));
    QVERIFY(s.frame(frameWith(false, false), 0.7, std::nullopt).staleEnded);
    QVERIFY(!s.stale());
    // Frames keep arriving while a replay is shown: never stale.
    s.replay("b.splog");
    for (double t = 0.72; t < 5; t += 0.02) {
      s.frame(frameWith(false, false), t, std::nullopt);
      s.tick(t + 0.01);
    }
    QVERIFY(!s.stale());
    QCOMPARE(s.health().text, std::string("replay"));
    // Not connected: not stale, however old the data, but the robot drawn
    // is said to be as old as it is (issue 59: drawn in full colour, as if
    // live, after a disconnect).
    ConsoleState d = driving();
    QCOMPARE(d.staleText(0.1), std::string());  // the control: connected and fresh
    d.connection(ConnectionState::Waiting, {});
    QVERIFY(!d.tick(10));
    QVERIFY(!d.stale());
    QCOMPARE(d.staleText(10), std::string("not connected: the robot drawn is where it was 10.0 s ago"));
  }

  // The edge warning appears within edgeWarning of a heightfield's edge,
  // updates in 0.1 m steps, and says so when beyond it.
  void edge() {
    ConsoleState s = driving();
    s.terrain(true, 20, 10);
    QVERIFY(!s.frame(frameWith(false, false), 0.1, 3.0).banner);
    QVERIFY(s.frame(frameWith(false, false), 0.2, 1.4).banner);
    QVERIFY(anyLineHas(s.bannerLines(), "Near the terrain's edge: 1.4 m to the edge of the 20.0 × 10.0 m heightfield"));
    QVERIFY(!s.bannerAlarm());  // a warning: amber, not the latch's red (issue 31)
    QVERIFY(!s.frame(frameWith(false, false), 0.3, 1.35).banner);  // under 0.1 m: unchanged
    QVERIFY(s.frame(frameWith(false, false), 0.4, -0.5).banner);
    QVERIFY(anyLineHas(s.bannerLines(), "off the terrain (0.5 m beyond its edge)"));
    QVERIFY(s.bannerAlarm());  // off the terrain: an alarm
    s.clearFrames();
    QVERIFY(s.bannerLines().empty());
  }

  // Both latches on after a reconnect, the failsafe's reason lost with the
  // old connection (issue 59: the banner said "failsafe latched" twice and
  // "re-arm" three times, and no reason): one line says what latched, that
  // the reason did not arrive, and to re-arm, once each.
  void bothLatchesOneLine() {
    ConsoleState s = driving();
    s.failsafeReason("deadman: no keep-alive for 0.2 s");
    s.frame(frameWith(true, false), 0.05, std::nullopt);
    s.frame(frameWith(false, false), 0.1, std::nullopt);  // re-armed: that failsafe's reason goes with it
    s.connection(ConnectionState::Waiting, "timeout");
    s.connection(ConnectionState::Ready, "robot");
    s.frame(frameWith(true, true), 0.3, std::nullopt);
    const std::vector<std::string> lines = s.bannerLines();
    QCOMPARE(lines.size(), size_t{1});
    const std::string& line = lines[0];
    const auto count = [&](const std::string& what) {
      size_t n = 0;
      for (size_t at = line.find(what); at != std::string::npos; at = line.find(what, at + 1)) ++n;
      return n;
    };
    QCOMPARE(line, std::string("E-STOP and FAILSAFE latched: the robot stopped itself (its reason did not reach this "
                               "console: see the robot's log). Re-arm to continue."));
    QCOMPARE(count("latched"), size_t{1});
    QCOMPARE(count("Re-arm"), size_t{1});
    QVERIFY(line.find("deadman") == std::string::npos);  // not the old failsafe's reason
  }

  // A twin that cannot keep real time says so after 3 s below 0.8 x the
  // target, and stops saying so above 0.9 x; a twin on time (the control)
  // says nothing.
  void slowTwinSaysSo() {
    ConsoleState s = driving();
    for (double t = 0; t < 5; t += 0.3) s.realTime(0.98, 1.0, t);
    QVERIFY(!s.slowTwin());
    for (double t = 5; t < 7.9; t += 0.3) s.realTime(0.54, 1.0, t);
    QVERIFY(!s.slowTwin());  // not yet 3 s
    s.realTime(0.54, 1.0, 8.1);
    QVERIFY(s.slowTwin());
    QVERIFY(anyLineHas(s.bannerLines(), "The stand-in's twin runs at 0.55 × real time (asked 1.00)"));
    s.realTime(0.85, 1.0, 8.4);
    QVERIFY(s.slowTwin());  // hysteresis
    s.realTime(0.95, 1.0, 8.7);
    QVERIFY(!s.slowTwin());
  }

  // The pose and motion read-outs: position, heading, ground speed and the
  // distance driven, a reset's leap not counted.
  void odometry() {
    ConsoleState s;
    s.connection(ConnectionState::Ready, {});
    QCOMPARE(s.poseText(), std::string());
    RobotFrame f;
    for (int i = 0; i <= 10; ++i) {
      f.time = 0.1 * i;
      f.base.p = {0.05 * i, 0, 0.5};
      s.frame(f, f.time, std::nullopt);
    }
    QCOMPARE(s.poseText(), std::string("x 0.50 m  y 0.00 m  heading 0.0°"));
    QCOMPARE(s.motionText(), std::string("0.50 m/s, 0.5 m driven"));
    f.time = 1.1;
    f.base.p = {20, 0, 0.5};  // a reset puts it elsewhere: not driven
    s.frame(f, f.time, std::nullopt);
    QCOMPARE(s.odometry().distance, 0.5);
    f.base.p = {0.5, -0.0001, 0.5};  // a hair below zero reads 0.00, not -0.00
    f.time = 1.2;
    s.frame(f, f.time, std::nullopt);
    QCOMPARE(s.poseText(), std::string("x 0.50 m  y 0.00 m  heading 0.0°"));
  }

  // An e-stop pressed says what became of it (issue 59: "E-STOP sent" while
  // disconnected, right under the error that said it was not).
  void estopPressedSaysTheTruth() {
    ConsoleState s = driving();
    QCOMPARE(s.estopPressedText(true), std::string("E-STOP sent"));
    s.connection(ConnectionState::Waiting, "timeout");
    QVERIFY(s.estopPressedText(true).starts_with("E-STOP NOT sent: the link is down; it goes out when"));
    s.connection(ConnectionState::Stopped, "disconnected");
    QCOMPARE(s.estopPressedText(false), std::string("E-STOP NOT sent: not connected to the robot"));
    QVERIFY(s.estopPressedText(false).find("E-STOP sent") == std::string::npos);
  }

  // While a replay is shown the banner says which robot its alarms are
  // about; closing the replay brings the live robot's banner back.
  void replayBanner() {
    ConsoleState s = driving();
    s.frame(frameWith(false, true), 0.1, std::nullopt);
    const uint64_t before = s.revision();
    s.replay("session-1.splog");
    QVERIFY(s.revision() > before);
    const std::vector<std::string> lines = s.bannerLines();
    QCOMPARE(lines.size(), size_t(2));
    QVERIFY(anyLineHas(lines, "Replay of session-1.splog"));
    QVERIFY(anyLineHas(lines, "Live robot: E-STOP latched"));
    s.replay({});
    QCOMPARE(s.bannerLines(), std::vector<std::string>{"E-STOP latched: the robot is stopped. Re-arm to continue."});
  }

  // Health names what is shown: diverged beats stale, not connected, and
  // healthy only once telemetry came.
  void health() {
    ConsoleState s;
    QCOMPARE(s.health().text, std::string("not connected"));
    s.connection(ConnectionState::Ready, {});
    QCOMPARE(s.health().text, std::string("no telemetry"));
    s.frame(frameWith(false, false), 0, std::nullopt);
    QCOMPARE(s.health().text, std::string("healthy"));
    QVERIFY(s.health().level == HealthLevel::Good);
    s.frame(frameWith(false, false, "body 3 position is NaN"), 0.1, std::nullopt);
    QCOMPARE(s.health().text, std::string("diverged"));
    QCOMPARE(s.health().detail, std::string("body 3 position is NaN"));
    QVERIFY(s.health().level == HealthLevel::Alarm);
  }
};

QTEST_GUILESS_MAIN(TestConsoleState)
#include "tst_console_state.moc"
