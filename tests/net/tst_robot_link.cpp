// The robot side of the link without sockets, on a fake clock: tokens,
// lease, command checks, deadman, latched failsafe, e-stop, re-arm.

#include <QtTest>

#include <random>

#include "net/robot_link.h"
#include "sim/command_file.h"

using namespace sp;
using namespace sp::net;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

// A check standing in for the twin's: knee targets within [-40, 80] deg.
CommandCheck check(const Command& c) {
  if (const auto* t = std::get_if<JointTargetCmd>(&c)) {
    if (t->joint != "knee_fl") return {CommandCheck::Kind::Invalid, "unknown joint '" + t->joint + "'"};
    if (t->position < degToRad(-40) || t->position > degToRad(80))
      return {CommandCheck::Kind::OutOfLimits, "target is outside joint 'knee_fl' limits"};
  }
  return {};
}

struct Fixture {
  RobotLink link{RobotLinkConfig{"workpartner", kToken, 0.2, 50}, nullptr, check};
  double now = 1.0;

  void hello(ClientId id, Role role, const std::string& token = kToken) {
    link.connected(id, now);
    link.received(id, HelloMsg{"client" + std::to_string(id), token, role}, now);
  }
  template <typename T>
  std::vector<T> sentTo(ClientId id) {
    std::vector<T> out;
    for (const auto& o : link.takeOutgoing())
      if (o.client == id)
        if (const auto* m = std::get_if<T>(&o.message)) out.push_back(*m);
    return out;
  }
  ReplyMsg command(ClientId id, uint64_t seq, const std::string& text, uint64_t expires = 1000) {
    link.received(id, CommandMsg{seq, expires, text}, now);
    auto replies = sentTo<ReplyMsg>(id);
    return replies.empty() ? ReplyMsg{} : replies.back();
  }
};

}  // namespace

class TestRobotLink : public QObject {
  Q_OBJECT

 private slots:
  // Tokens compare equal only when equal, whatever their lengths.
  void constantTimeCompare() {
    QVERIFY(equalConstantTime(kToken, kToken));
    QVERIFY(!equalConstantTime(kToken, kToken.substr(0, 31)));
    QVERIFY(!equalConstantTime(kToken, kToken + "0"));
    QVERIFY(!equalConstantTime(kToken, "10112233445566778899aabbccddeeff"));
  }

  // A wrong token gets an error and the connection closes; nothing else.
  void wrongTokenCloses() {
    Fixture f;
    f.hello(1, Role::Control, "ffffffffffffffffffffffffffffffff");
    const auto out = f.link.takeOutgoing();
    QCOMPARE(out.size(), size_t{1});
    QCOMPARE(std::get<ErrorMsg>(out[0].message).reason, std::string("authentication failed"));
    QCOMPARE(f.link.takeClosing(), std::vector<ClientId>{1});
    QVERIFY(!f.link.authenticated(1));
  }

  // Before HELLO nothing is served: a command closes the connection.
  void helloFirst() {
    Fixture f;
    f.link.connected(1, f.now);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    QCOMPARE(f.sentTo<ErrorMsg>(1).at(0).reason, std::string("HELLO first"));
    QCOMPARE(f.link.takeClosing(), std::vector<ClientId>{1});
  }

  // One controlling client at a time: the second is told who holds the
  // lease, a monitor cannot take it, and commands from others are refused.
  void leaseIsExclusive() {
    Fixture f;
    f.hello(1, Role::Control);
    f.hello(2, Role::Control);
    f.hello(3, Role::Monitor);
    f.link.takeOutgoing();
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    f.link.received(2, LeaseAcquireMsg{}, f.now);
    f.link.received(3, LeaseAcquireMsg{}, f.now);
    QCOMPARE(f.link.holder(), ClientId{1});
    const auto out = f.link.takeOutgoing();
    int refusedToTwo = 0;
    for (const auto& o : out)
      if (const auto* s = std::get_if<LeaseStateMsg>(&o.message); s && o.client == 2 && !s->yours) ++refusedToTwo;
    QVERIFY(refusedToTwo >= 1);
    QCOMPARE(f.command(2, 1, "stop").status, ReplyStatus::NotOwner);
    QCOMPARE(f.command(1, 1, "stop").status, ReplyStatus::Ok);
  }

  void commandChecks_data() {
    QTest::addColumn<QString>("text");
    QTest::addColumn<int>("status");
    QTest::newRow("ok") << "target knee_fl 30" << int(ReplyStatus::Ok);
    QTest::newRow("beyond the limit: refused, not clipped") << "target knee_fl 120" << int(ReplyStatus::OutOfLimits);
    QTest::newRow("unknown joint") << "target kne_fl 10" << int(ReplyStatus::Invalid);
    QTest::newRow("typo") << "drvie 1 0" << int(ReplyStatus::Invalid);
  }
  // Each command gets exactly one reply with its status.
  void commandChecks() {
    QFETCH(QString, text);
    QFETCH(int, status);
    Fixture f;
    f.hello(1, Role::Control);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    f.link.takeOutgoing();
    f.link.received(1, CommandMsg{7, 1000, text.toStdString()}, f.now);
    const auto replies = f.sentTo<ReplyMsg>(1);
    QCOMPARE(replies.size(), size_t{1});
    QCOMPARE(int(replies[0].status), status);
    QCOMPARE(replies[0].seq, uint64_t{7});
    QCOMPARE(f.link.takeCommands().size(), size_t(status == int(ReplyStatus::Ok) ? 1 : 0));
  }

  // Duplicate and out-of-order sequence numbers are never executed.
  void duplicatesAndOrder() {
    Fixture f;
    f.hello(1, Role::Control);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    QCOMPARE(f.command(1, 5, "stop").status, ReplyStatus::Ok);
    QCOMPARE(f.command(1, 5, "stop").status, ReplyStatus::Duplicate);
    QCOMPARE(f.command(1, 4, "stop").status, ReplyStatus::Duplicate);
    QCOMPARE(f.command(1, 6, "stop").status, ReplyStatus::Ok);
    QCOMPARE(f.link.takeCommands().size(), size_t{2});
  }

  // A command whose expiry is shorter than the link's one-way delay (half
  // the measured round trip) is refused as expired.
  void expiredCommands() {
    Fixture f;
    f.hello(1, Role::Control);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    f.link.sendHeartbeats(f.now);
    const HeartbeatMsg ping = f.sentTo<HeartbeatMsg>(1).at(0);
    f.now += 0.8;  // 800 ms round trip
    f.link.received(1, ping, f.now);
    QVERIFY(std::abs(f.link.rttMs(1) - 800) < 1e-6);
    QCOMPARE(f.command(1, 1, "stop", 300).status, ReplyStatus::Expired);
    QCOMPARE(f.command(1, 2, "stop", 500).status, ReplyStatus::Ok);
  }

  // Deadman: after random cut times in the holder's keep-alives, the stop
  // comes 200 ms after the last packet, never later than 300 ms (ticks
  // every 1 ms, as the server does). Reports the worst case.
  void deadmanTiming() {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> cutAfter(0.05, 3.0), phase(0, 0.05);
    double worst = 0;
    for (int trial = 0; trial < 500; ++trial) {
      Fixture f;
      f.hello(1, Role::Control);
      f.link.received(1, LeaseAcquireMsg{}, f.now);
      const double cut = f.now + cutAfter(rng);
      double nextKeepalive = f.now + phase(rng), last = f.now;
      while (!f.link.failsafeLatched() && f.now < cut + 1.0) {
        f.now += 0.001;
        if (f.now < cut && f.now >= nextKeepalive) {
          f.link.received(1, LeaseKeepaliveMsg{}, f.now);
          last = f.now;
          nextKeepalive += 0.05;
        }
        f.link.tick(f.now);
      }
      QVERIFY(f.link.failsafeLatched());
      const double delay = f.link.lastFailsafeTime() - last;
      QVERIFY2(delay >= 0.2 && delay < 0.3, qPrintable(QString::number(delay)));
      const auto commands = f.link.takeCommands();
      QVERIFY(!commands.empty() && std::holds_alternative<StopCmd>(commands.back()));
      worst = std::max(worst, delay);
    }
    qInfo("deadman: worst stop %.1f ms after the last packet over 500 random cuts", worst * 1000);
  }

  // The failsafe latches: a reconnected operator's commands are refused
  // until it re-arms.
  void failsafeLatches() {
    Fixture f;
    f.hello(1, Role::Control);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    f.link.disconnected(1, f.now);
    f.now += 0.25;
    f.link.tick(f.now);
    QVERIFY(f.link.failsafeLatched());
    f.hello(2, Role::Control);
    f.link.received(2, LeaseAcquireMsg{}, f.now);
    QCOMPARE(f.command(2, 1, "drive 0.5 0").status, ReplyStatus::Failed);
    f.link.received(2, RearmMsg{}, f.now);
    QVERIFY(!f.link.failsafeLatched());
    QCOMPARE(f.command(2, 2, "drive 0.5 0").status, ReplyStatus::Ok);
  }

  // A client taking the lease right after the holder's connection dropped
  // does not inherit its motion: the failsafe fires at once and latches.
  void newHolderDoesNotInheritMotion() {
    Fixture f;
    f.hello(1, Role::Control);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    QCOMPARE(f.command(1, 1, "drive 0.5 0").status, ReplyStatus::Ok);
    f.link.takeCommands();
    f.link.disconnected(1, f.now);
    f.now += 0.05;  // well inside the 200 ms deadman
    f.hello(2, Role::Control);
    f.link.received(2, LeaseAcquireMsg{}, f.now);
    QVERIFY(f.link.failsafeLatched());
    QVERIFY(std::holds_alternative<StopCmd>(f.link.takeCommands().at(0)));
    QCOMPARE(f.link.holder(), ClientId{2});
    QCOMPARE(f.command(2, 1, "drive 0.5 0").status, ReplyStatus::Failed);
  }

  // E-stop from any authenticated client, even a monitor, stops at once and
  // latches; every client hears of it.
  void estopFromMonitor() {
    Fixture f;
    f.hello(1, Role::Control);
    f.hello(2, Role::Monitor);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    f.link.takeOutgoing();
    f.link.received(2, EstopMsg{"hand on the button"}, f.now);
    QVERIFY(f.link.estopLatched());
    QVERIFY(std::holds_alternative<StopCmd>(f.link.takeCommands().at(0)));
    int events = 0;
    for (const auto& o : f.link.takeOutgoing())
      if (const auto* e = std::get_if<EventMsg>(&o.message); e && e->kind == EventKind::Estop) ++events;
    QCOMPARE(events, 2);
    QCOMPARE(f.command(1, 1, "stop").status, ReplyStatus::Failed);
    f.link.received(2, RearmMsg{}, f.now);  // a monitor cannot re-arm
    QVERIFY(f.link.estopLatched());
  }
};

QTEST_GUILESS_MAIN(TestRobotLink)
#include "tst_robot_link.moc"
