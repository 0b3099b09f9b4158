// The robot side of the link without sockets, on a fake clock: tokens,
// lease, command checks, deadman, latched failsafe, e-stop, re-arm.

#include <QTest>

#include <deque>

#include <random>

#include "net/auth.h"
#include "net/link_emulator.h"
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

// Connects `id` and returns the nonce of the CHALLENGE the link sent it
// (taking every message queued so far).
std::string connectClient(RobotLink& link, ClientId id, double now) {
  link.connected(id, now);
  std::string nonce;
  for (const auto& o : link.takeOutgoing())
    if (const auto* c = std::get_if<ChallengeMsg>(&o.message); c && o.client == id) nonce = c->nonce;
  return nonce;
}

// Connects and sends a HELLO proving `token` over the challenge.
void authenticate(RobotLink& link, ClientId id, const std::string& name, Role role, double now,
                  const std::string& token = kToken) {
  const std::string nonce = connectClient(link, id, now);
  link.received(id, HelloMsg{name, {}, role, helloProof(token, nonce, name, role)}, now);
}

struct Fixture {
  RobotLink link{RobotLinkConfig{"workpartner", kToken, 0.2, 10, 50}, nullptr, check};
  double now = 1.0;

  void hello(ClientId id, Role role, const std::string& token = kToken) {
    authenticate(link, id, "client" + std::to_string(id), role, now, token);
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

  // Expiry is judged against the link's usual delay: with the client's
  // clock 5000 s off and a constant 1 s one-way delay nothing expires; a
  // command 300 ms later than the fastest so far expires with a 200 ms
  // expiry and not with a 500 ms one. Without `sent_ms` nothing is judged.
  void expiredCommands() {
    Fixture f;
    f.hello(1, Role::Control);
    f.link.received(1, LeaseAcquireMsg{}, f.now);
    auto sent = [&](double delay, uint64_t seq, uint64_t expires) {
      const auto ms = static_cast<uint64_t>((f.now - delay + 5000) * 1000);
      f.link.received(1, CommandMsg{seq, expires, "stop", ms}, f.now);
      auto replies = f.sentTo<ReplyMsg>(1);
      return replies.empty() ? ReplyMsg{} : replies.back();
    };
    for (uint64_t seq = 1; seq <= 20; ++seq) {
      QCOMPARE(sent(1.0, seq, 100).status, ReplyStatus::Ok);
      f.now += 0.05;
    }
    QCOMPARE(sent(1.3, 21, 500).status, ReplyStatus::Ok);
    const ReplyMsg late = sent(1.3, 22, 200);
    QCOMPARE(late.status, ReplyStatus::Expired);
    QCOMPARE(QString::fromStdString(late.reason), QString("arrived 300 ms later than the link's usual delay, expiry 200 ms"));
    QCOMPARE(f.command(1, 23, "stop", 1).status, ReplyStatus::Ok);  // no sent_ms: not judged
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

  // The deadman judges gaps between arrivals, from the holder's first
  // keep-alive on: over an emulated link (keep-alives every 50 ms through a
  // LinkEmulator, in order as TCP delivers) a constant 1 s delay never trips
  // the LAN deadman of 200 ms, and 2 s +- 0.1 s round trips (1 s +- 0.1 s
  // each way) stay within a 0.5 s deadman for 60 s. Control: the same jitter
  // trips the 200 ms deadman.
  void deadmanUnderDelay_data() {
    QTest::addColumn<double>("jitter");
    QTest::addColumn<double>("deadman");
    QTest::addColumn<bool>("trips");
    QTest::newRow("constant 1 s, deadman 0.2") << 0.0 << 0.2 << false;
    QTest::newRow("1 s +- 0.1, deadman 0.5") << 0.1 << 0.5 << false;
    QTest::newRow("1 s +- 0.1, deadman 0.2 (control)") << 0.1 << 0.2 << true;
  }
  void deadmanUnderDelay() {
    QFETCH(double, jitter);
    QFETCH(double, deadman);
    QFETCH(bool, trips);
    RobotLink link{RobotLinkConfig{"workpartner", kToken, deadman, 10, 50}, nullptr, check};
    LinkEmulator toRobot({1.0, jitter, 0, 0, true, 7}), toClient({1.0, jitter, 0, 0, true, 8});
    double now = 1.0;
    authenticate(link, 1, "far", Role::Control, now);
    link.received(1, LeaseAcquireMsg{}, now);  // arrives now; the grant reaches the client later
    const double grantSeen = *toClient.schedule(64, now);
    std::deque<double> arrivals;
    for (double sent = grantSeen; sent < now + 60; sent += 0.05) arrivals.push_back(*toRobot.schedule(32, sent));
    for (; now < 61 && !link.failsafeLatched(); now += 0.001) {
      while (!arrivals.empty() && arrivals.front() <= now) {
        link.received(1, LeaseKeepaliveMsg{}, arrivals.front());
        arrivals.pop_front();
      }
      link.tick(now);
    }
    QCOMPARE(link.failsafeLatched(), trips);
    QCOMPARE(link.holder(), ClientId{1});
  }

  // A holder that never confirms its lease loses it after leaseConfirm; the
  // robot stood still, so nothing latches.
  void unconfirmedLeaseTakenBack() {
    RobotLink link{RobotLinkConfig{"workpartner", kToken, 0.2, 3, 50}, nullptr, check};
    authenticate(link, 1, "silent", Role::Control, 1.0);
    link.received(1, LeaseAcquireMsg{}, 1.0);
    link.tick(3.9);
    QCOMPARE(link.holder(), ClientId{1});
    link.tick(4.1);
    QCOMPARE(link.holder(), ClientId{0});
    QVERIFY(!link.failsafeLatched());
    QVERIFY(std::holds_alternative<StopCmd>(link.takeCommands().at(0)));
  }

  // A message whose content was refused gets ERROR with the reason (not
  // "ERROR is not sent to the robot"); before HELLO it also closes, with the
  // reason rather than "HELLO first". A client's own ERROR is not answered.
  void refusedMessagesSayWhy() {
    Fixture f;
    connectClient(f.link, 1, f.now);
    f.link.refused(1, "HELLO: key 'token': expected at least 32 hex digits (128 bits), got 31", f.now);
    auto out = f.link.takeOutgoing();
    QCOMPARE(out.size(), size_t{1});
    QCOMPARE(std::get<ErrorMsg>(out[0].message).reason,
             std::string("refused: HELLO: key 'token': expected at least 32 hex digits (128 bits), got 31"));
    QCOMPARE(f.link.takeClosing(), std::vector<ClientId>{1});
    f.hello(2, Role::Control);
    f.link.takeOutgoing();
    f.link.refused(2, "COMMAND: missing key 'expires_ms'", f.now);
    out = f.link.takeOutgoing();
    QCOMPARE(out.size(), size_t{1});
    QCOMPARE(std::get<ErrorMsg>(out[0].message).reason, std::string("refused: COMMAND: missing key 'expires_ms'"));
    QVERIFY(f.link.takeClosing().empty());
    f.link.received(2, ErrorMsg{"something odd"}, f.now);
    QVERIFY(f.link.takeOutgoing().empty());
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
