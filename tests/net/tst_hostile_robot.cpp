// The console's client against a robot that lies or breaks (issue 58): a
// fake robot (hostile_robot.h) completes the handshake, or misbehaves in it,
// and then plays one misbehaviour on real loopback sockets. For each the
// client stays up, passes nothing unchecked on, stays within a memory bound,
// stops within a second when asked, and says what is wrong, once per kind;
// a well-behaved robot (the control) says nothing of the kind.

#include <QTest>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "net/link_check.h"
#include "net/robot_client.h"
#include "sim/model_loader.h"
#include "tests/net/hostile_robot.h"

using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;
using sp::test::HostileRobot;
using Clock = std::chrono::steady_clock;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";
constexpr double kInf = std::numeric_limits<double>::infinity();

// [MiB] this process's resident memory now (the fake robot's included).
double residentMiB() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      double kb = 0;
      status >> kb;
      return kb / 1024;
    }
  }
  return 0;
}

// What the client's callbacks reported, for the test's thread.
struct Seen {
  std::mutex mutex;
  std::vector<TelemetryMsg> telemetry;
  std::vector<EventMsg> events;
  std::vector<std::string> notices;  // `error`: the robot's ERRORs and the client's own notices
  std::vector<std::pair<ConnectionState, std::string>> states;
  size_t laser = 0;

  RobotClientCallbacks callbacks() {
    RobotClientCallbacks cb;
    cb.telemetry = [this](const TelemetryMsg& m) { add([&] { telemetry.push_back(m); }); };
    cb.event = [this](const EventMsg& m) { add([&] { events.push_back(m); }); };
    cb.laser = [this](const LaserMsg&) { add([&] { ++laser; }); };
    cb.error = [this](const ErrorMsg& m) { add([&] { notices.push_back(m.reason); }); };
    cb.connection = [this](ConnectionState s, const std::string& d) { add([&] { states.emplace_back(s, d); }); };
    return cb;
  }
  template <typename F>
  void add(F f) {
    std::lock_guard lock(mutex);
    f();
  }
  template <typename F>
  auto read(F f) {
    std::lock_guard lock(mutex);
    return f();
  }
  // Notices containing `text`.
  size_t noticesWith(const std::string& text) {
    return read([&] {
      size_t n = 0;
      for (const std::string& s : notices) n += s.find(text) != std::string::npos;
      return n;
    });
  }
  bool everReady() {
    return read([&] {
      for (const auto& [s, d] : states)
        if (s == ConnectionState::Ready) return true;
      return false;
    });
  }
  // The first Waiting state's detail containing `text`, or "".
  std::string droppedWith(const std::string& text) {
    return read([&] {
      for (const auto& [s, d] : states)
        if (s == ConnectionState::Waiting && d.find(text) != std::string::npos) return d;
      return std::string();
    });
  }
  std::string all() {
    return read([&] {
      std::string out;
      for (const std::string& s : notices) out += "  notice: " + s + "\n";
      for (const auto& [s, d] : states) out += std::string("  state: ") + toString(s) + " " + d + "\n";
      return out;
    });
  }
};

// Polls `pred` for up to `timeout`.
template <typename P>
bool eventually(P pred, std::chrono::milliseconds timeout = 5000ms) {
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(5ms);
  }
  return pred();
}

const RobotModel& robotFile() {
  static const RobotModel robot = [] {
    Diagnostics diag;
    std::optional<WorldModel> w = loadWorld(SP_SOURCE_DIR "/terrains/flat.world.xml", diag);
    if (!w) qFatal("cannot load the flat world: %s", diag.format().c_str());
    return w->robots[0].model;
  }();
  return robot;
}

// A frame the robot file believes: every joint at 0, the base at `x`.
TelemetryMsg goodFrame(uint64_t seq, double time, double x = 0) {
  TelemetryMsg t;
  t.seq = seq;
  t.time = time;
  t.pose.p = {x, 0, 0.6};
  for (const JointSpec& j : robotFile().joints) {
    t.jointNames.push_back(j.name);
    t.jointPositions.push_back(j.limited ? std::clamp(0.0, j.lower, j.upper) : 0.0);
    t.jointVelocities.push_back(0);
  }
  return t;
}

// Telemetry at 50 Hz for `seconds`, each frame passed through `edit`
// (frame index, frame) before it goes.
HostileRobot::Behaviour telemetry(double seconds, std::function<void(int, TelemetryMsg&)> edit = {}) {
  return [seconds, edit](HostileRobot::Peer& peer) {
    const int n = static_cast<int>(seconds * 50);
    for (int i = 0; i < n && !peer.stopped(); ++i) {
      TelemetryMsg t = goodFrame(static_cast<uint64_t>(i + 1), 0.02 * i, 0.01 * i);
      if (edit) edit(i, t);
      if (!peer.send(t) || !peer.drain()) return;
      std::this_thread::sleep_for(20ms);
    }
  };
}

RobotClientConfig config(uint16_t port) {
  RobotClientConfig c;
  c.port = port;
  c.name = "console";
  c.token = kToken;
  c.bounds = telemetryBounds(robotFile());
  c.reconnectMin = c.reconnectMax = 5;  // one connection per test: the misbehaving one
  return c;
}

// [s] how long stop() took.
double timedStop(RobotClient& client) {
  const auto t0 = Clock::now();
  client.stop();
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

class TestHostileRobot : public QObject {
  Q_OBJECT

 private slots:
  // The control: a robot that behaves is believed whole, and the client
  // says nothing of refusals, shedding or renumbering.
  void wellBehavedSaysNothing() {
    HostileRobot robot({}, telemetry(2));
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY(eventually([&] { return robot.finished(); }, 8000ms));
    const RobotClientStats s = client.stats();
    QVERIFY2(s.refused == 0 && s.shed == 0 && s.renumbered == 0, seen.all().c_str());
    QCOMPARE(seen.read([&] { return seen.telemetry.size(); }), size_t{100});
    QCOMPARE(seen.noticesWith("client:"), size_t{0});
    QVERIFY(timedStop(client) < 1.0);
  }

  // Each lie in a frame is refused where it is decoded, said once with
  // what is wrong, counted after that; the frames before it pass.
  void lyingTelemetryRefused_data() {
    QTest::addColumn<int>("lie");
    QTest::addColumn<QString>("said");
    QTest::newRow("pose inf") << 0 << "not finite: pose[0] = inf";
    QTest::newRow("pose nan") << 1 << "not finite: pose[2] = nan";
    QTest::newRow("pose 1e308") << 2 << "out of bounds: pose (1e+308";
    QTest::newRow("1 km a frame") << 3 << "pose jumped: 1000";
    QTest::newRow("time back") << 4 << "time went back";
    QTest::newRow("time +1e9 s") << 5 << "time jumped: +1e+09 s";
    QTest::newRow("joint renamed") << 6 << "joint 'renamed' is not in the robot file";
    QTest::newRow("joint missing") << 7 << "of the robot file is missing";
    QTest::newRow("joint past limit") << 8 << "joint beyond its limits";
    QTest::newRow("rtt 1e303 ms") << 9 << "out of bounds: rtt_ms 1e+303";
    QTest::newRow("quaternion 0") << 10 << "quaternion of norm 0";
  }
  void lyingTelemetryRefused() {
    QFETCH(int, lie);
    QFETCH(QString, said);
    // 25 good frames, then 75 that lie.
    HostileRobot robot({}, telemetry(2, [lie](int i, TelemetryMsg& t) {
      if (i < 25) return;
      switch (lie) {
        case 0: t.pose.p.x = kInf; break;
        case 1: t.pose.p.z = std::nan(""); break;
        case 2: t.pose.p.x = 1e308; break;
        case 3: t.pose.p.x += 1000.0 * (i - 24); break;
        case 4: t.time = 0.3 - 0.003 * (i - 24); break;
        case 5: t.time += 1e9; break;
        case 6: t.jointNames[0] = "renamed"; break;
        case 7:
          t.jointNames.pop_back();
          t.jointPositions.pop_back();
          t.jointVelocities.pop_back();
          break;
        case 8: {
          const auto& joints = robotFile().joints;
          for (size_t k = 0; k < joints.size(); ++k)
            if (joints[k].limited) {
              t.jointPositions[k] = joints[k].upper + 1.0;
              break;
            }
          break;
        }
        case 9: t.rttMs = 1e303; break;
        case 10: t.pose.q = Quat{0, 0, 0, 0}; break;
      }
    }));
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY(eventually([&] { return robot.finished(); }, 8000ms));
    QVERIFY(eventually([&] { return client.stats().telemetryFrames + client.stats().refused >= 100; }));
    const RobotClientStats s = client.stats();
    QCOMPARE(s.telemetryFrames, uint64_t{25});
    QCOMPARE(s.refused, uint64_t{75});
    QCOMPARE(seen.read([&] { return seen.telemetry.size(); }), size_t{25});
    QVERIFY2(seen.noticesWith(said.toStdString()) == 1, seen.all().c_str());
    QCOMPARE(seen.noticesWith("client: refused"), size_t{1});  // one per kind, not one per frame
    QVERIFY(timedStop(client) < 1.0);
  }

  // Nothing before WELCOME is used: telemetry and events from a robot that
  // never welcomes are refused, and the handshake is given up after
  // link.hello_timeout with the reason.
  void nothingBeforeWelcome() {
    HostileRobot::Handshake h;
    h.welcome = false;
    HostileRobot robot(h, [](HostileRobot::Peer& peer) {
      for (int i = 0; i < 200 && !peer.stopped(); ++i) {
        peer.send(goodFrame(static_cast<uint64_t>(i + 1), 0.02 * i));
        peer.send(EventMsg{EventKind::Link, "hello from nowhere"});
        std::this_thread::sleep_for(10ms);
      }
    });
    Seen seen;
    RobotClientConfig c = config(robot.port());
    c.helloTimeout = 1.0;
    RobotClient client(c, seen.callbacks());
    client.start();
    QVERIFY2(eventually([&] { return !seen.droppedWith("no WELCOME within 1000 ms").empty(); }, 4000ms),
             seen.all().c_str());
    QVERIFY(!seen.everReady());
    QCOMPARE(seen.read([&] { return seen.telemetry.size() + seen.events.size(); }), size_t{0});
    QVERIFY(client.stats().refused > 0);
    QVERIFY2(seen.noticesWith("before WELCOME") == 1, seen.all().c_str());
    QVERIFY(timedStop(client) < 1.0);
  }

  // A robot that sends CHALLENGE again and again (each would be answered
  // with a HELLO) is given up at the second.
  void repeatedChallengeGivenUp() {
    HostileRobot robot({}, [](HostileRobot::Peer& peer) {
      for (int i = 0; i < 10000 && !peer.stopped(); ++i)
        if (!peer.send(ChallengeMsg{"0123456789abcdef0123456789abcdef"})) return;
    });
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY2(eventually([&] { return !seen.droppedWith("CHALLENGE again").empty(); }), seen.all().c_str());
    QVERIFY(timedStop(client) < 1.0);
  }

  // A WELCOME no robot could mean is refused and the connection dropped
  // with the field and its bounds; a plausible one (the control) is taken.
  void implausibleWelcomeRefused_data() {
    QTest::addColumn<double>("rate");
    QTest::addColumn<double>("deadman");
    QTest::addColumn<QString>("said");
    QTest::newRow("deadman 1e-9 s") << 50.0 << 1e-9 << "WELCOME deadman 1e-09 s is outside [0.02, 60]";
    QTest::newRow("deadman 1e9 s") << 50.0 << 1e9 << "WELCOME deadman 1e+09 s is outside";
    QTest::newRow("rate 0.01 Hz") << 0.01 << 0.2 << "WELCOME telemetry_rate 0.01 Hz is outside [0.5, 2000]";
    QTest::newRow("rate 1e6") << 1e6 << 0.2 << "WELCOME telemetry_rate 1e+06 Hz";
    QTest::newRow("control") << 50.0 << 0.2 << "";
  }
  void implausibleWelcomeRefused() {
    QFETCH(double, rate);
    QFETCH(double, deadman);
    QFETCH(QString, said);
    HostileRobot::Handshake h;
    h.welcomeMsg.telemetryRate = rate;
    h.welcomeMsg.deadman = deadman;
    HostileRobot robot(h, telemetry(0.5));
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    if (said.isEmpty()) {
      QVERIFY(eventually([&] { return seen.everReady(); }));
    } else {
      QVERIFY2(eventually([&] { return !seen.droppedWith(said.toStdString()).empty(); }), seen.all().c_str());
      QVERIFY(!seen.everReady());
    }
    QVERIFY(timedStop(client) < 1.0);
  }

  // Keep-alives have a floor: a robot announcing the shortest deadman a
  // WELCOME may carry (20 ms) gets one every 5 ms, not one per 5 us.
  void keepalivesHaveAFloor() {
    HostileRobot::Handshake h;
    h.welcomeMsg.deadman = kMinDeadman;
    std::atomic<int> keepalives{0};
    HostileRobot robot(h, [&](HostileRobot::Peer& peer) {
      peer.send(LeaseStateMsg{"console", true});
      const auto end = Clock::now() + 1s;
      while (Clock::now() < end && peer.drain([&](const Message& m) {
        if (std::holds_alternative<LeaseKeepaliveMsg>(m)) ++keepalives;
      }))
        std::this_thread::sleep_for(2ms);
    });
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY(eventually([&] { return robot.finished(); }));
    // 1 s at one per 5 ms: 200; the lease state arrives a little after the start.
    QVERIFY2(keepalives > 100 && keepalives <= 210, std::to_string(keepalives.load()).c_str());
    QVERIFY(timedStop(client) < 1.0);
  }

  // A robot that stops reading while the console has much to send is
  // dropped once the queue holds maxQueuedBytes, with the reason; memory
  // stays bounded, and the client still stops at once.
  void robotThatDoesNotReadDropped() {
    HostileRobot robot({}, [](HostileRobot::Peer& peer) {
      peer.send(LeaseStateMsg{"console", true});
      while (!peer.stopped()) std::this_thread::sleep_for(10ms);  // reads nothing
    });
    Seen seen;
    RobotClientConfig c = config(robot.port());
    c.maxQueuedBytes = 256 * 1024;
    RobotClient client(c, seen.callbacks());
    client.start();
    QVERIFY(eventually([&] { return client.stats().connected; }));
    const double before = residentMiB();
    // 60 KiB a command, 1,000 of them: 60 MB the robot never takes.
    const std::string big = "note " + std::string(60 * 1024, 'x');
    for (int i = 0; i < 1000; ++i) client.sendCommandText(big, 60000);
    QVERIFY2(eventually([&] { return !seen.droppedWith("does not read").empty(); }), seen.all().c_str());
    const double grown = residentMiB() - before;
    QVERIFY2(grown < 30, (std::to_string(grown) + " MiB").c_str());
    QVERIFY(timedStop(client) < 1.0);
  }

  // A robot that does not read and floods bad frames (each once answered
  // with an ERROR), its own heartbeats to echo, or both: the answers are
  // rate-limited and the memory stays bounded over 3 s.
  void floodsDoNotExhaust_data() {
    QTest::addColumn<int>("flood");
    QTest::newRow("bad messages") << 0;
    QTest::newRow("heartbeats to echo") << 1;
    QTest::newRow("unknown types") << 2;
  }
  void floodsDoNotExhaust() {
    QFETCH(int, flood);
    HostileRobot robot({}, [flood](HostileRobot::Peer& peer) {
      uint64_t n = 0;
      while (!peer.stopped()) {
        bool ok = true;
        if (flood == 0) ok = peer.sendRaw(*encodeFrame(static_cast<uint8_t>(MessageType::Telemetry), "seq=not a number\n"));
        if (flood == 1) ok = peer.send(HeartbeatMsg{(uint64_t{1} << 62) + ++n, 1.0});
        if (flood == 2) ok = peer.sendRaw(*encodeFrame(200, "x=1\n"));
        if (!ok) return;
      }
    }, 3);
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY(eventually([&] { return seen.everReady(); }));
    const double before = residentMiB();
    QVERIFY(eventually([&] { return robot.finished(); }, 6000ms));
    const double grown = residentMiB() - before;
    QVERIFY2(grown < 30, (std::to_string(grown) + " MiB").c_str());
    const RobotClientStats s = client.stats();
    QVERIFY2(s.framesSent < 500, std::to_string(s.framesSent).c_str());  // ~3 s of answers at their limits
    QVERIFY(s.framesReceived > 1000);
    QVERIFY(timedStop(client) < 1.0);
  }

  // Telemetry at 200 times the announced rate is shed, the newest kept;
  // 100,000 EVENTs in a burst reach the callbacks at the event rate; each
  // said once.
  void beyondTheRatesShed() {
    HostileRobot robot({}, [](HostileRobot::Peer& peer) {
      for (int i = 0; i < 20000 && !peer.stopped(); ++i)
        if (!peer.send(goodFrame(static_cast<uint64_t>(i + 1), 0.0001 * i))) return;
      for (int i = 0; i < 100000 && !peer.stopped(); ++i)
        if (!peer.send(EventMsg{EventKind::Link, "burst " + std::to_string(i)})) return;
      peer.send(goodFrame(20001, 2.5));
    });
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY(eventually([&] { return robot.finished(); }, 15000ms));
    QVERIFY(eventually([&] { return client.stats().framesReceived >= 120001; }));
    const RobotClientStats s = client.stats();
    const auto [frames, events, newest] = seen.read([&] {
      return std::tuple(seen.telemetry.size(), seen.events.size(), seen.telemetry.empty() ? 0.0 : seen.telemetry.back().time);
    });
    // A second's burst and 76 a second over the few seconds it took.
    QVERIFY2(frames < 1000, std::to_string(frames).c_str());
    QVERIFY2(events < 400, std::to_string(events).c_str());
    QCOMPARE(newest, 2.5);
    QVERIFY(s.shed > 100000);
    QCOMPARE(seen.noticesWith("telemetry beyond the announced rate"), size_t{1});
    QCOMPARE(seen.noticesWith("events beyond 20 a second"), size_t{1});
    QVERIFY(timedStop(client) < 1.0);
  }

  // A sequence-number jump no link could lose (a wrap, a renumbering) is
  // said and not counted as lost; a true gap (the control) is counted.
  void seqRenumberingIsNotLoss() {
    HostileRobot robot({}, telemetry(1, [](int i, TelemetryMsg& t) {
      if (i >= 20) t.seq = (uint64_t{1} << 63) + static_cast<uint64_t>(i);
      if (i == 10) t.seq += 3;  // three frames lost, truly
      if (i > 10 && i < 20) t.seq += 3;
    }));
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY(eventually([&] { return robot.finished(); }, 8000ms));
    QVERIFY(eventually([&] { return client.stats().telemetryFrames == 50; }));
    const RobotClientStats s = client.stats();
    QCOMPARE(s.telemetryLost, uint64_t{3});
    QCOMPARE(s.renumbered, uint64_t{1});
    QCOMPARE(seen.noticesWith("seq renumbered"), size_t{1});
    QVERIFY(timedStop(client) < 1.0);
  }

  // LIMITS that no robot has (NaN, lower above upper) are refused; the
  // client keeps none, so the console keeps the robot file's.
  void absurdLimitsRefused() {
    HostileRobot robot({}, [](HostileRobot::Peer& peer) {
      LimitsMsg l;
      l.joints = {"hip_fl"};
      l.lower = {1};
      l.upper = {-1};
      l.maxVelocity = {1};
      l.maxTorque = {1};
      peer.send(l);
      while (!peer.stopped() && peer.drain()) std::this_thread::sleep_for(10ms);
    }, 2);
    Seen seen;
    RobotClient client(config(robot.port()), seen.callbacks());
    client.start();
    QVERIFY2(eventually([&] { return seen.noticesWith("LIMITS hip_fl: lower 1 is not at most upper -1") == 1; }),
             seen.all().c_str());
    QVERIFY(!client.limits());
    QVERIFY(timedStop(client) < 1.0);
  }

  // Text from the robot is made safe to store: escapes and control
  // characters as \xNN, and bounded.
  void escapeText() {
    QCOMPARE(net::escapeText("ok \x1b[2J\x07 back\\slash\n"), std::string("ok \\x1b[2J\\x07 back\\\\slash\\x0a"));
    QCOMPARE(net::escapeText(std::string(10, 'a'), 4), std::string("aaaa..."));
    QCOMPARE(net::escapeText("plain"), std::string("plain"));
  }
};

QTEST_GUILESS_MAIN(TestHostileRobot)
#include "tst_hostile_robot.moc"
