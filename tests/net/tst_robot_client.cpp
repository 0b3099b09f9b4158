// The console's client of the robot link (net/robot_client.h) on real
// sockets over loopback: against the stand-in robot (simpartner-robot, one
// fresh process per test) for the lease, commands, round trips and the
// safety chain; against a scripted fake robot for what the real one cannot
// be made to do on cue (gaps in telemetry, its own heartbeats).

#include <QProcess>
#include <QRegularExpression>
#include <QTest>

#include <asio.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "net/frame.h"
#include "net/message.h"
#include "net/auth.h"
#include "net/robot_client.h"

using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;

namespace {

using Clock = std::chrono::steady_clock;
const std::string kToken = "00112233445566778899aabbccddeeff";

double msBetween(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

QString robotExecutable() {
  const QByteArray fromEnv = qgetenv("SP_ROBOT");
  if (!fromEnv.isEmpty()) return QString::fromLocal8Bit(fromEnv);
#ifdef SP_ROBOT_EXE
  return QStringLiteral(SP_ROBOT_EXE);
#else
  return QStringLiteral(SP_BINARY_DIR "/app/simpartner-robot");
#endif
}

// The stand-in robot as a child process on a free port of 127.0.0.1.
class RobotProcess {
 public:
  // Starts it (--port 0: the robot picks a free port and prints it; no
  // session log) and waits for `listening on 127.0.0.1:PORT`; "" on
  // success, else why not.
  QString start(const QStringList& extra = {}) {
    process_.setProgram(robotExecutable());
    process_.setArguments(QStringList{"--world", SP_SOURCE_DIR "/terrains/flat.world.xml", "--port", "0", "--token",
                                      QString::fromStdString(kToken), "--no-log"} +
                          extra);
    process_.setWorkingDirectory(SP_SOURCE_DIR);
    process_.start();
    if (!process_.waitForStarted(10000)) return "cannot start " + robotExecutable() + ": " + process_.errorString();
    const QRegularExpression ready(R"(^listening on 127\.0\.0\.1:(\d+)\s*$)");
    QElapsedTimer timer;
    timer.start();
    while (timer.elapsed() < 30000) {
      while (process_.canReadLine()) {
        const QString line = QString::fromUtf8(process_.readLine());
        if (const auto m = ready.match(line); m.hasMatch()) {
          port_ = m.captured(1).toUShort();
          return {};
        }
      }
      if (process_.state() == QProcess::NotRunning)
        return "the robot exited: " + QString::fromUtf8(process_.readAllStandardError());
      process_.waitForReadyRead(100);
    }
    return "no `listening on` line within 30 s";
  }
  ~RobotProcess() {
    if (process_.state() == QProcess::NotRunning) return;
    process_.terminate();
    if (!process_.waitForFinished(5000)) {
      process_.kill();
      process_.waitForFinished(5000);
    }
  }
  uint16_t port() const { return port_; }

 private:
  QProcess process_;
  uint16_t port_ = 0;
};

// Collects what a client's callbacks report (on the client's thread) for
// the test's thread to wait on.
class Recorder {
 public:
  struct Timed {
    EventMsg event;
    Clock::time_point at;
  };
  RobotClientCallbacks callbacks() {
    RobotClientCallbacks cb;
    cb.telemetry = [this](const TelemetryMsg& m) { add([&] { telemetry.push_back(m); }); };
    cb.reply = [this](const ReplyMsg& m) { add([&] { replies.push_back(m); }); };
    cb.event = [this](const EventMsg& m) { add([&] { events.push_back({m, Clock::now()}); }); };
    cb.lease = [this](const LeaseStateMsg& m) { add([&] { leases.push_back(m); }); };
    cb.connection = [this](ConnectionState s, const std::string& detail) {
      add([&] { states.push_back({s, detail, Clock::now()}); });
    };
    cb.error = [this](const ErrorMsg& m) { add([&] { errors.push_back(m); }); };
    cb.rtt = [this](double ms) { add([&] { rtts.push_back(ms); }); };
    return cb;
  }
  // Waits until `pred` (called under the lock) holds; false on timeout.
  template <typename P>
  bool waitFor(P pred, std::chrono::milliseconds timeout = 5000ms) {
    std::unique_lock lock(mutex_);
    return cv_.wait_for(lock, timeout, [&] { return pred(); });
  }
  template <typename F>
  auto read(F f) {
    std::lock_guard lock(mutex_);
    return f();
  }

  // Under the lock.
  std::vector<TelemetryMsg> telemetry;
  std::vector<ReplyMsg> replies;
  std::vector<Timed> events;
  std::vector<LeaseStateMsg> leases;
  struct State {
    ConnectionState state;
    std::string detail;
    Clock::time_point at;
  };
  std::vector<State> states;
  std::vector<ErrorMsg> errors;
  std::vector<double> rtts;

  bool ready() const { return !states.empty() && states.back().state == ConnectionState::Ready; }
  bool leaseYours() const { return !leases.empty() && leases.back().yours; }
  const ReplyMsg* reply(uint64_t seq) const {
    for (const auto& r : replies)
      if (r.seq == seq) return &r;
    return nullptr;
  }
  const Timed* event(EventKind kind) const {
    for (const auto& e : events)
      if (e.event.kind == kind) return &e;
    return nullptr;
  }

 private:
  template <typename F>
  void add(F f) {
    {
      std::lock_guard lock(mutex_);
      f();
    }
    cv_.notify_all();
  }
  std::mutex mutex_;
  std::condition_variable cv_;
};

RobotClientConfig clientConfig(uint16_t port, const std::string& name, Role role = Role::Control) {
  RobotClientConfig c;
  c.port = port;
  c.name = name;
  c.token = kToken;
  c.role = role;
  return c;
}

// A client with its recorder, started.
struct Client {
  Recorder rec;
  RobotClient client;
  explicit Client(RobotClientConfig config) : client(std::move(config), rec.callbacks()) { client.start(); }
  bool waitReady(std::chrono::milliseconds timeout = 5000ms) {
    return rec.waitFor([&] { return rec.ready(); }, timeout);
  }
  bool waitLease(std::chrono::milliseconds timeout = 5000ms) {
    return rec.waitFor([&] { return rec.leaseYours(); }, timeout);
  }
  // Sends `text` and waits for its reply; nullopt if none within the timeout.
  std::optional<ReplyMsg> command(const std::string& text, std::chrono::milliseconds timeout = 5000ms) {
    const uint64_t seq = client.sendCommandText(text);
    if (!rec.waitFor([&] { return rec.reply(seq) != nullptr; }, timeout)) return std::nullopt;
    return rec.read([&] { return *rec.reply(seq); });
  }
};

// A scripted robot on loopback for one client: accepts, reads frames,
// writes what the test says. Blocking Asio on the test's thread.
class FakeRobot {
 public:
  FakeRobot() : acceptor_(io_, asio::ip::tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)) {}
  uint16_t port() const { return acceptor_.local_endpoint().port(); }
  void accept() { acceptor_.accept(socket_); }
  void send(const Message& m) {
    std::string error;
    const auto frame = encodeMessage(m, error);
    QVERIFY2(frame, error.c_str());
    asio::write(socket_, asio::buffer(*frame));
  }
  // The next message from the client (blocking, 5 s at most).
  std::optional<Message> next() {
    const auto deadline = Clock::now() + 5s;
    while (Clock::now() < deadline) {
      if (auto frame = decoder_.next()) {
        std::string error;
        return decodeMessage(*frame, error);
      }
      if (decoder_.failed()) return std::nullopt;
      if (socket_.available() == 0) {
        std::this_thread::sleep_for(1ms);
        continue;
      }
      std::array<char, 4096> buffer;
      const size_t n = socket_.read_some(asio::buffer(buffer));
      decoder_.feed(buffer.data(), n);
    }
    return std::nullopt;
  }
  // The next message of type T, skipping others (keep-alives, heartbeats).
  template <typename T>
  std::optional<T> nextOf() {
    for (int i = 0; i < 1000; ++i) {
      auto m = next();
      if (!m) return std::nullopt;
      if (const T* t = std::get_if<T>(&*m)) return *t;
    }
    return std::nullopt;
  }

 private:
  asio::io_context io_;
  asio::ip::tcp::acceptor acceptor_;
  asio::ip::tcp::socket socket_{io_};
  FrameDecoder decoder_;
};

TelemetryMsg telemetryFrame(uint64_t seq) {
  TelemetryMsg t;
  t.seq = seq;
  t.time = 0.02 * static_cast<double>(seq);
  t.pose.q = Quat{1, 0, 0, 0};
  t.jointNames = {"hinge"};
  t.jointPositions = {0};
  t.jointVelocities = {0};
  return t;
}

}  // namespace

class TestRobotClient : public QObject {
  Q_OBJECT

  std::unique_ptr<RobotProcess> robot_;

 private slots:
  void init() {
    const QString fn = QTest::currentTestFunction();
    if (fn.startsWith("fake") || fn == "backoffWithoutRobot" || fn.startsWith("link")) return;  // none, or its own
    robot_ = std::make_unique<RobotProcess>();
    const QString error = robot_->start();
    QVERIFY2(error.isEmpty(), qPrintable(error));
  }
  void cleanup() { robot_.reset(); }

  // The whole path: WELCOME, lease, `drive 0.5 0` answered ok, and the
  // robot's pose moves forward (+x) in the telemetry that follows.
  void leaseDriveAndTelemetry() {
    Client c(clientConfig(robot_->port(), "operator"));
    QVERIFY(c.waitReady());
    c.client.acquireLease();
    QVERIFY(c.waitLease());
    QVERIFY(c.rec.waitFor([&] { return !c.rec.telemetry.empty(); }));
    const double x0 = c.rec.read([&] { return c.rec.telemetry.back().pose.p.x; });
    const auto reply = c.command("drive 0.5 0");
    QVERIFY(reply);
    QCOMPARE(reply->status, ReplyStatus::Ok);
    const bool moved = c.rec.waitFor([&] { return c.rec.telemetry.back().pose.p.x > x0 + 0.2; }, 5000ms);
    const double x1 = c.rec.read([&] { return c.rec.telemetry.back().pose.p.x; });
    QVERIFY2(moved, qPrintable(QString("x from %1 to %2").arg(x0).arg(x1)));
    QCOMPARE(c.command("stop")->status, ReplyStatus::Ok);
    // Keep-alives kept the deadman quiet all along.
    QVERIFY(c.rec.read([&] { return c.rec.event(EventKind::Failsafe) == nullptr; }));
    const RobotClientStats s = c.client.stats();
    QVERIFY(s.connected && s.leaseHeld);
    QCOMPARE(s.robot, std::string("workpartner"));
    QCOMPARE(s.telemetryLost, uint64_t{0});
    QVERIFY(s.telemetryFrames >= 20);
    QCOMPARE(s.repliesReceived, uint64_t{2});
    QCOMPARE(s.reconnects, uint64_t{0});
    c.client.releaseLease();
    QVERIFY(c.rec.waitFor([&] { return !c.rec.leaseYours(); }));
  }

  // Holding the lease without commands: the automatic keep-alives (every
  // 50 ms) keep the 200 ms deadman from firing; the telemetry rate is measured.
  void keepalivesHoldTheDeadman() {
    Client c(clientConfig(robot_->port(), "operator"));
    QVERIFY(c.waitReady());
    c.client.acquireLease();
    QVERIFY(c.waitLease());
    std::this_thread::sleep_for(1500ms);
    QVERIFY(c.rec.read([&] { return c.rec.event(EventKind::Failsafe) == nullptr; }));
    QCOMPARE(c.command("drive 0.2 0")->status, ReplyStatus::Ok);
    const RobotClientStats s = c.client.stats();
    QVERIFY2(std::abs(s.telemetryRateHz - s.telemetryRateAnnounced) < 0.2 * s.telemetryRateAnnounced,
             qPrintable(QString("measured %1 Hz, announced %2").arg(s.telemetryRateHz).arg(s.telemetryRateAnnounced)));
  }

  // Issue 30: over a planetary link (the robot emulating 1 s +- 0.1 each
  // way) with the LAN's 200 ms deadman, the client says at connect time,
  // before any failsafe, that the deadman will fire and which setting
  // carries the link; with the table's 0.5 s it says nothing (the control).
  void linkTooJitteryForTheDeadman() {
    for (const char* deadman : {"0.2", "0.5"}) {
      RobotProcess robot;
      const QString error = robot.start({"--delay", "1", "--jitter", "0.1", "--set", QString("link.deadman=") + deadman});
      QVERIFY2(error.isEmpty(), qPrintable(error));
      Client c(clientConfig(robot.port(), "far", Role::Monitor));
      QVERIFY(c.waitReady(8000ms));
      std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(kLinkCheckSeconds * 1000) + 500));
      const RobotClientStats s = c.client.stats();
      qInfo("deadman %s s: delay spread %.0f ms; %s", deadman, s.delaySpreadMs, s.linkWarning.c_str());
      QVERIFY2(s.delaySpreadMs > 100 && s.delaySpreadMs < 300, qPrintable(QString::number(s.delaySpreadMs)));
      const bool warned = c.rec.read([&] {
        return std::any_of(c.rec.errors.begin(), c.rec.errors.end(),
                           [](const ErrorMsg& e) { return e.reason.rfind("client: this link's delay varies", 0) == 0; });
      });
      if (std::string(deadman) == "0.2") {
        QVERIFY(warned);
        QVERIFY2(s.linkWarning.find("Set link.deadman=0.") != std::string::npos, s.linkWarning.c_str());
      } else {
        QVERIFY(!warned);
        QVERIFY(s.linkWarning.empty());
      }
    }
  }

  // Issue 59: on loopback, a stand-in twin at 0.83 of real time (a loaded
  // machine) was taken for a link whose delay varies by 336 ms. The spread
  // is about the trend: a robot clock running slow adds nothing, the link's
  // jitter all of its peak-to-peak. Control: the raw peak-to-peak of the
  // slow clock (what was judged before) is 0.4 s.
  void delaySpreadIgnoresATrend() {
    std::vector<std::pair<double, double>> slow, jittery, both;
    double rawLo = INFINITY, rawHi = -INFINITY;
    for (int i = 0; i <= 100; ++i) {
      const double wall = 5000 + 0.02 * i;  // arrivals at 50 Hz, seconds since boot
      const double jitter = (i % 2 ? 0.05 : -0.05) * (i % 7 == 3 ? 1 : 0.5);  // +-50 ms at most
      slow.emplace_back(wall, 0.8 * 0.02 * i);
      jittery.emplace_back(wall, 0.02 * i - jitter);
      both.emplace_back(wall, 0.8 * 0.02 * i - jitter);
      rawLo = std::min(rawLo, wall - 0.8 * 0.02 * i);
      rawHi = std::max(rawHi, wall - 0.8 * 0.02 * i);
    }
    QVERIFY2(rawHi - rawLo > 0.39, qPrintable(QString::number(rawHi - rawLo)));
    QVERIFY2(delaySpread(slow) < 1e-6, qPrintable(QString::number(delaySpread(slow))));
    QVERIFY2(std::abs(delaySpread(jittery) - 0.1) < 0.005, qPrintable(QString::number(delaySpread(jittery))));
    QVERIFY2(std::abs(delaySpread(both) - 0.1) < 0.005, qPrintable(QString::number(delaySpread(both))));
    QCOMPARE(delaySpread({{1, 0}, {2, 1}}), 0.0);
  }

  // The advice's arithmetic: keep-alives every 50 ms on a delay seen to
  // vary by 140 ms need 50 + 1.5 x 140 = 260 ms; at 1.5 times that,
  // rounded up to 50 ms: 0.40 s.
  void linkAdviceNamesTheSetting() {
    QVERIFY(linkAdvice(0.2, 0.05, 0.09).empty());  // 185 ms < 200: fits
    QVERIFY(linkAdvice(0, 0.05, 5).empty());       // no deadman announced
    const std::string a = linkAdvice(0.2, 0.05, 0.14);
    QVERIFY2(a.find("Set link.deadman=0.40 on the robot") != std::string::npos, a.c_str());
    QVERIFY2(a.find("may arrive 260 ms apart") != std::string::npos, a.c_str());
  }

  // Round trips are measured from our heartbeats' echoes, and the robot
  // measures its own from the echoes we send back.
  void roundTripMeasured() {
    Client c(clientConfig(robot_->port(), "operator", Role::Monitor));
    QVERIFY(c.waitReady());
    QVERIFY(c.rec.waitFor([&] { return c.rec.rtts.size() >= 3; }));
    const RobotClientStats s = c.client.stats();
    QVERIFY(s.rttMs > 0 && s.rttMs < 100);
    QVERIFY(s.rttMeanMs > 0 && s.rttMaxMs >= s.rttMs);
    // The robot's heartbeats come every 0.5 s; its figure arrives in TELEMETRY.
    QVERIFY(c.rec.waitFor([&] { return !c.rec.telemetry.empty() && c.rec.telemetry.back().rttMs > 0; }, 3000ms));
  }

  // Round trip on loopback over 1000 heartbeats (one every 2 ms): median
  // and maximum reported, the median asserted under 5 ms.
  void roundTripFigures() {
    RobotClientConfig config = clientConfig(robot_->port(), "bench", Role::Monitor);
    config.heartbeatInterval = 0.002;
    Client c(config);
    QVERIFY(c.waitReady());
    QVERIFY(c.rec.waitFor([&] { return c.rec.rtts.size() >= 1000; }, 20000ms));
    std::vector<double> rtts = c.rec.read([&] { return c.rec.rtts; });
    rtts.resize(1000);
    std::sort(rtts.begin(), rtts.end());
    const double median = (rtts[499] + rtts[500]) / 2, p99 = rtts[989], max = rtts.back();
    qInfo("loopback RTT over 1000 heartbeats: median %.3f ms, 99th percentile %.3f ms, max %.3f ms", median, p99,
          max);
    QVERIFY(median > 0 && median < 5);
  }

  // Client-side link emulation: 100 ms on every frame we send shows in the
  // round trip.
  void emulatedDelayShowsInRoundTrip() {
    RobotClientConfig config = clientConfig(robot_->port(), "far", Role::Monitor);
    config.emulation.delay = 0.1;
    config.emulation.jitter = 0.01;
    Client c(config);
    QVERIFY(c.waitReady());
    QVERIFY(c.rec.waitFor([&] { return c.rec.rtts.size() >= 5; }));
    const auto rtts = c.rec.read([&] { return c.rec.rtts; });
    for (double r : rtts) QVERIFY2(r >= 90 && r < 200, qPrintable(QString::number(r)));
    // Switched off at run time: back to loopback figures.
    c.client.setEmulation({});
    QVERIFY(c.rec.waitFor([&] { return c.rec.rtts.size() >= rtts.size() + 3 && c.rec.rtts.back() < 20; }));
  }

  // One controlling client at a time: a second one is told who holds the
  // lease, and its commands are refused (not_owner).
  void secondClientCannotTakeLease() {
    Client a(clientConfig(robot_->port(), "alice"));
    Client b(clientConfig(robot_->port(), "bob"));
    QVERIFY(a.waitReady() && b.waitReady());
    a.client.acquireLease();
    QVERIFY(a.waitLease());
    b.client.acquireLease();
    QVERIFY(b.rec.waitFor([&] {
      return std::any_of(b.rec.leases.begin(), b.rec.leases.end(),
                         [](const LeaseStateMsg& l) { return l.holder == "alice" && !l.yours; });
    }));
    const auto reply = b.command("drive 0.5 0");
    QVERIFY(reply);
    QCOMPARE(reply->status, ReplyStatus::NotOwner);
    QVERIFY(!b.client.stats().leaseHeld);
    QVERIFY(a.client.stats().leaseHeld);
    QCOMPARE(a.command("stop")->status, ReplyStatus::Ok);
  }

  // A wrong token: the robot's ERROR, the connection closed, state Refused,
  // and no reconnect attempts (a wrong secret does not get better by retrying).
  void wrongTokenRefused() {
    RobotClientConfig config = clientConfig(robot_->port(), "intruder");
    config.token = "ffffffffffffffffffffffffffffffff";
    Client c(config);
    QVERIFY(c.rec.waitFor(
        [&] { return !c.rec.states.empty() && c.rec.states.back().state == ConnectionState::Refused; }));
    QCOMPARE(c.rec.read([&] { return c.rec.errors.at(0).reason; }), std::string("authentication failed"));
    QCOMPARE(c.rec.read([&] { return c.rec.states.back().detail; }), std::string("authentication failed"));
    std::this_thread::sleep_for(700ms);  // longer than the first backoffs
    QCOMPARE(c.rec.read([&] { return c.rec.states.back().state; }), ConnectionState::Refused);
    QVERIFY(c.rec.read([&] { return c.rec.telemetry.empty(); }));
    const RobotClientStats s = c.client.stats();
    QCOMPARE(s.reconnects, uint64_t{0});
    QVERIFY(!s.connected);
    QCOMPARE(s.lastError, std::string("authentication failed"));
  }

  // stop() while holding the lease is a lost operator: a monitor sees the
  // failsafe EVENT within 300 ms. The failsafe latches: after start() again
  // and the lease, commands fail until re-armed, then succeed.
  void stopWhileHoldingLeaseLatchesFailsafe() {
    Client monitor(clientConfig(robot_->port(), "monitor", Role::Monitor));
    Client op(clientConfig(robot_->port(), "operator"));
    QVERIFY(monitor.waitReady() && op.waitReady());
    op.client.acquireLease();
    QVERIFY(op.waitLease());
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Ok);
    std::this_thread::sleep_for(300ms);
    const auto cut = Clock::now();
    op.client.stop();
    QVERIFY(monitor.rec.waitFor([&] { return monitor.rec.event(EventKind::Failsafe) != nullptr; }, 1000ms));
    const double ms = msBetween(cut, monitor.rec.read([&] { return monitor.rec.event(EventKind::Failsafe)->at; }));
    qInfo("failsafe EVENT at the monitor %.1f ms after stop()", ms);
    QVERIFY2(ms < 300, qPrintable(QString::number(ms)));
    QCOMPARE(op.client.stats().state, ConnectionState::Stopped);

    // Back again: the lease is free, but the robot stays stopped until re-armed.
    op.client.start();
    QVERIFY(op.rec.waitFor([&] { return op.rec.ready() && op.rec.event(EventKind::Failsafe) != nullptr; }));
    op.client.acquireLease();
    QVERIFY(op.waitLease());
    const auto refused = op.command("drive 0.3 0");
    QVERIFY(refused);
    QCOMPARE(refused->status, ReplyStatus::Failed);
    QVERIFY2(refused->reason.find("failsafe") != std::string::npos, refused->reason.c_str());
    op.client.rearm();
    QVERIFY(monitor.rec.waitFor([&] { return monitor.rec.event(EventKind::Rearmed) != nullptr; }));
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Ok);
  }

  // A dropped connection: the client reconnects by itself (after 0.2 s) and
  // says HELLO again; the failsafe that fired meanwhile stays latched, and
  // the lease is not taken again until asked for (the default).
  void dropReconnectsAndStaysLatched() {
    Client monitor(clientConfig(robot_->port(), "monitor", Role::Monitor));
    Client op(clientConfig(robot_->port(), "operator"));
    QVERIFY(monitor.waitReady() && op.waitReady());
    op.client.acquireLease();
    QVERIFY(op.waitLease());
    std::this_thread::sleep_for(200ms);
    const auto cut = Clock::now();
    op.client.dropConnection();
    QVERIFY(monitor.rec.waitFor([&] { return monitor.rec.event(EventKind::Failsafe) != nullptr; }, 1000ms));
    const double ms = msBetween(cut, monitor.rec.read([&] { return monitor.rec.event(EventKind::Failsafe)->at; }));
    QVERIFY2(ms < 300, qPrintable(QString::number(ms)));

    QVERIFY(op.rec.waitFor([&] { return op.rec.ready() && op.rec.states.size() >= 7; }));
    const auto states = op.rec.read([&] { return op.rec.states; });
    const std::vector<ConnectionState> expected{ConnectionState::Connecting, ConnectionState::Authenticating,
                                                ConnectionState::Ready,      ConnectionState::Waiting,
                                                ConnectionState::Connecting, ConnectionState::Authenticating,
                                                ConnectionState::Ready};
    QCOMPARE(states.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) QCOMPARE(states[i].state, expected[i]);
    // The backoff: 0.2 s from the drop to the next attempt.
    const double backoff = std::chrono::duration<double>(states[4].at - states[3].at).count();
    QVERIFY2(backoff >= 0.19 && backoff < 0.4, qPrintable(QString::number(backoff)));
    QCOMPARE(op.client.stats().reconnects, uint64_t{1});
    // The lease went with the connection: reported locally, not taken again.
    QVERIFY(op.rec.read(
        [&] { return !op.rec.leases.empty() && op.rec.leases.back().holder.empty() && !op.rec.leaseYours(); }));
    QVERIFY(!op.client.stats().leaseHeld);
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::NotOwner);

    op.client.acquireLease();
    QVERIFY(op.waitLease());
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Failed);
    QCOMPARE(op.command("wheels 1 1 1 1")->status, ReplyStatus::Failed);
    op.client.rearm();
    QVERIFY(op.rec.waitFor([&] { return op.rec.event(EventKind::Rearmed) != nullptr; }));
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Ok);
  }

  // With reacquireLease the lease is asked for again after a reconnect (here
  // after 0.5 s, once the deadman has fired): still latched until re-armed.
  void reacquireLeaseAfterReconnect() {
    Client monitor(clientConfig(robot_->port(), "monitor", Role::Monitor));
    RobotClientConfig config = clientConfig(robot_->port(), "operator");
    config.reacquireLease = true;
    config.reconnectMin = 0.5;
    Client op(config);
    QVERIFY(monitor.waitReady() && op.waitReady());
    op.client.acquireLease();
    QVERIFY(op.waitLease());
    op.client.dropConnection();
    QVERIFY(monitor.rec.waitFor([&] { return monitor.rec.event(EventKind::Failsafe) != nullptr; }, 1000ms));
    QVERIFY(op.rec.waitFor([&] { return op.rec.ready() && op.rec.states.size() >= 7 && op.rec.leaseYours(); }));
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Failed);
    op.client.rearm();
    QVERIFY(op.rec.waitFor([&] { return op.rec.event(EventKind::Rearmed) != nullptr; }));
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Ok);
  }

  // E-stop from a monitor latches; commands fail until the holder re-arms.
  void estopLatches() {
    Client monitor(clientConfig(robot_->port(), "monitor", Role::Monitor));
    Client op(clientConfig(robot_->port(), "operator"));
    QVERIFY(monitor.waitReady() && op.waitReady());
    op.client.acquireLease();
    QVERIFY(op.waitLease());
    monitor.client.estop("test");
    QVERIFY(op.rec.waitFor([&] { return op.rec.event(EventKind::Estop) != nullptr; }));
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Failed);
    op.client.rearm();
    QVERIFY(op.rec.waitFor([&] { return op.rec.event(EventKind::Rearmed) != nullptr; }));
    QCOMPARE(op.command("drive 0.3 0")->status, ReplyStatus::Ok);
  }

  // Commands while not connected are answered at once, locally.
  void commandWithoutConnection() {
    RobotClientConfig config = clientConfig(robot_->port(), "late");
    Client c(config);
    c.client.stop();
    const uint64_t seq = c.client.sendCommandText("stop");
    c.client.start();  // the queued command runs before the first connect
    QVERIFY(c.rec.waitFor([&] { return c.rec.reply(seq) != nullptr; }));
    const ReplyMsg r = c.rec.read([&] { return *c.rec.reply(seq); });
    QCOMPARE(r.status, ReplyStatus::Failed);
    QCOMPARE(r.reason, std::string("client: not connected, not sent"));
    // A text that cannot be sent at all is invalid, locally.
    QVERIFY(c.waitReady());
    const auto bad = c.command("stop\nstop");
    QVERIFY(bad);
    QCOMPARE(bad->status, ReplyStatus::Invalid);
  }

  // Nothing listening: attempts at 0.2, 0.4, 0.8, 1.6 s intervals (doubling
  // up to 2 s). A gap is never shorter than its step, and shorter than
  // 1.9 steps, so a skipped doubling shows; the slack absorbs a stalled VM
  // (a gap of 0.69 s for the 0.4 s step was seen once).
  void backoffWithoutRobot() {
    uint16_t port = 0;
    {
      // A port that was free a moment ago and has nobody listening now.
      asio::io_context io;
      asio::ip::tcp::acceptor a(io, asio::ip::tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
      port = a.local_endpoint().port();
    }
    RobotClientConfig config = clientConfig(port, "lonely");
    Client c(config);
    QVERIFY(c.rec.waitFor(
        [&] {
          return std::count_if(c.rec.states.begin(), c.rec.states.end(),
                               [](const auto& s) { return s.state == ConnectionState::Connecting; }) >= 5;
        },
        6000ms));
    c.client.stop();
    std::vector<Clock::time_point> attempts;
    for (const auto& s : c.rec.read([&] { return c.rec.states; }))
      if (s.state == ConnectionState::Connecting) attempts.push_back(s.at);
    const double expected[] = {0.2, 0.4, 0.8, 1.6};
    for (size_t i = 0; i < 4; ++i) {
      const double gap = std::chrono::duration<double>(attempts[i + 1] - attempts[i]).count();
      QVERIFY2(gap >= expected[i] - 0.01 && gap < 1.9 * expected[i],
               qPrintable(QString("attempt %1: %2 s").arg(i + 1).arg(gap)));
    }
    QCOMPARE(c.client.stats().reconnects, uint64_t{0});
  }

  // Against a scripted robot: gaps in TELEMETRY seq count as lost frames,
  // the robot's heartbeats (seq >= 2^62) come back byte for byte, and the
  // client's own start below 2^62.
  void fakeRobotLostFramesAndHeartbeats() {
    FakeRobot fake;
    Client c(clientConfig(fake.port(), "operator"));
    fake.accept();
    // The client answers the challenge with a proof, never the token.
    const std::string nonce = "0123456789abcdef0123456789abcdef";
    fake.send(ChallengeMsg{nonce});
    const auto hello = fake.nextOf<HelloMsg>();
    QVERIFY(hello);
    QCOMPARE(hello->name, std::string("operator"));
    QVERIFY(hello->token.empty());
    QCOMPARE(hello->proof, helloProof(kToken, nonce, "operator", Role::Control));
    QCOMPARE(hello->role, Role::Control);
    fake.send(WelcomeMsg{"fake", 1, 50, 0, "", "", ""});
    QVERIFY(c.waitReady());
    for (uint64_t seq : {1, 2, 5, 6, 10, 11}) fake.send(telemetryFrame(seq));
    QVERIFY(c.rec.waitFor([&] { return c.rec.telemetry.size() == 6; }));
    QCOMPARE(c.client.stats().telemetryLost, uint64_t{2 + 3});
    QCOMPARE(c.client.stats().telemetryFrames, uint64_t{6});

    const HeartbeatMsg ping{(uint64_t{1} << 62) + 7, 123.456789};
    fake.send(ping);
    const auto echo = fake.nextOf<HeartbeatMsg>();
    // The client's own first heartbeat may come first (sent on WELCOME).
    QVERIFY(echo);
    if (echo->seq < (uint64_t{1} << 62)) {
      QCOMPARE(echo->seq, uint64_t{1});
      QCOMPARE(fake.nextOf<HeartbeatMsg>(), std::optional<HeartbeatMsg>(ping));
    } else {
      QCOMPARE(*echo, ping);
    }
  }

  // Against a scripted robot: a command the robot never answers is answered
  // locally once its expiry and the grace have passed; a late REPLY is dropped.
  void fakeRobotReplyTimeout() {
    FakeRobot fake;
    RobotClientConfig config = clientConfig(fake.port(), "operator");
    config.replyGrace = 0.3;
    Client c(config);
    fake.accept();
    fake.send(ChallengeMsg{"0123456789abcdef0123456789abcdef"});
    QVERIFY(fake.nextOf<HelloMsg>());
    fake.send(WelcomeMsg{"fake", 1, 50, 0, "", "", ""});
    QVERIFY(c.waitReady());
    const uint64_t seq = c.client.sendCommandText("stop", 100);
    const auto sent = fake.nextOf<CommandMsg>();
    QVERIFY(sent);
    QCOMPARE(sent->seq, seq);
    QCOMPARE(sent->expiresMs, uint64_t{100});
    QCOMPARE(sent->command, std::string("stop"));
    QVERIFY(c.rec.waitFor([&] { return c.rec.reply(seq) != nullptr; }, 2000ms));
    const ReplyMsg local = c.rec.read([&] { return *c.rec.reply(seq); });
    QCOMPARE(local.status, ReplyStatus::Failed);
    QVERIFY2(local.reason.starts_with("client: no reply within"), local.reason.c_str());
    fake.send(ReplyMsg{seq, ReplyStatus::Ok, ""});
    std::this_thread::sleep_for(100ms);
    QCOMPARE(c.rec.read([&] { return c.rec.replies.size(); }), size_t{1});
  }
};

QTEST_GUILESS_MAIN(TestRobotClient)
#include "tst_robot_client.moc"
