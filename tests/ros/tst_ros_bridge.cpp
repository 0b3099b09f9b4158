// The ROS bridge end to end with real ROS (docs/ros.md): a roscore of its own
// on a free port, the twin as a ROS robot (simpartner-ros-twin), the bridge
// (simpartner-ros-bridge), a link client on loopback, and this test as a ROS
// node listening to /cmd_vel. The client takes the lease and drives: the
// robot moves (its odometry comes back as telemetry). It goes silent: the
// deadman's zero Twist reaches ROS within deadman + 100 ms. The twin freezes
// (SIGSTOP): stale odometry fires the failsafe with its reason. A session
// log exported as a bag: rosbag info lists every topic with the log's
// counts. Bad input: a joint map naming a joint the robot lacks, a topic
// that is no ROS name, a bag that cannot be written: clear errors, nothing
// half-written. Measured: the command-to-cmd_vel latency through the bridge.

#include <QProcess>
#include <QTcpServer>
#include <QTest>

#include <signal.h>

#include <algorithm>
#include <mutex>

#include "app/log/session_log.h"
#include "net/robot_client.h"
#include "ros/ros1.h"
#include "tests/app/shared_state.h"
#include "tests/net/raw_client.h"

using namespace sp;
using namespace sp::test;

namespace {

const QString kApp = QStringLiteral(SP_BINARY_DIR "/app/");

double steadyNow() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

/// The first line of `process`'s stdout that starts with `prefix`, within `timeout`.
QString lineStarting(QProcess& process, const QString& prefix, int timeoutMs = 15000, QString* seen = nullptr) {
  QElapsedTimer t;
  t.start();
  QString all;
  while (t.elapsed() < timeoutMs) {
    if (!process.canReadLine() && !process.waitForReadyRead(100)) {
      if (process.state() == QProcess::NotRunning) break;
      continue;
    }
    while (process.canReadLine()) {
      const QString line = QString::fromUtf8(process.readLine()).trimmed();
      all += line + "\n";
      if (line.startsWith(prefix)) return line;
    }
  }
  if (seen) *seen = all + QString::fromUtf8(process.readAllStandardError());
  return {};
}

}  // namespace

class TestRosBridge : public QObject {
  Q_OBJECT

  QTemporaryDir dir_;
  QProcess roscore_, twin_, bridge_;
  std::unique_ptr<ros1::Node> node_;
  uint16_t port_ = 0;
  std::mutex mutex_;
  struct Seen {
    double linear, at;
  };
  std::vector<Seen> twists_;

  static void stop(QProcess& p, int signal = SIGTERM) {
    if (p.state() == QProcess::NotRunning) return;
    ::kill(static_cast<pid_t>(p.processId()), signal);
    if (!p.waitForFinished(10000)) p.kill();
    p.waitForFinished(2000);
  }

  std::vector<Seen> twists() {
    std::lock_guard lock(mutex_);
    return twists_;
  }

 private slots:
  void initTestCase() {
    QVERIFY(dir_.isValid());
    QTcpServer probe;  // a free port for the master
    QVERIFY(probe.listen(QHostAddress::LocalHost, 0));
    const quint16 masterPort = probe.serverPort();
    probe.close();
    qputenv("ROS_MASTER_URI", QStringLiteral("http://127.0.0.1:%1").arg(masterPort).toUtf8());
    qputenv("ROS_HOME", dir_.filePath("ros").toUtf8());  // its logs, not the user's ~/.ros
    qputenv("ROS_IP", "127.0.0.1");
    roscore_.setProcessChannelMode(QProcess::MergedChannels);
    roscore_.start(QStringLiteral("roscore"), {QStringLiteral("-p"), QString::number(masterPort)});
    QVERIFY2(roscore_.waitForStarted(), "roscore (Debian: ros-core; scripts/install-deps.sh)");
    std::string error;
    node_ = ros1::Node::create("tst_ros_bridge", 30, error);
    QVERIFY2(node_, error.c_str());
    node_->onTwist("/cmd_vel", [this](const ros1::Twist& t) {
      std::lock_guard lock(mutex_);
      twists_.push_back({t.linear, steadyNow()});
    });

    twin_.start(kApp + "simpartner-ros-twin", {});
    QVERIFY2(!lineStarting(twin_, "running").isEmpty(), twin_.readAllStandardError().constData());
    bridge_.start(kApp + "simpartner-ros-bridge", {"--port", "0", "--token", QString::fromStdString(kToken)});
    QString seen;
    const QString listening = lineStarting(bridge_, "listening on", 15000, &seen);
    QVERIFY2(!listening.isEmpty(), qPrintable(seen));
    port_ = static_cast<uint16_t>(listening.section(':', -1).toUInt());
    QVERIFY(port_ > 0);
  }

  void cleanupTestCase() {
    stop(bridge_);
    stop(twin_);
    node_.reset();
    stop(roscore_, SIGINT);
  }

  // The console's own client (RobotClient) drives the ROS robot through the
  // bridge: lease, drive accepted, the robot moves, and releasing stops it.
  void theConsolesClientDrives() {
    struct Callbacks : SharedState {
      bool ready = false, lease = false;
      std::optional<ReplyMsg> reply;
      std::optional<TelemetryMsg> telemetry;
    } seen;
    RobotClientCallbacks cb;
    cb.connection = [&seen](ConnectionState s, const std::string&) { seen.add([&] { seen.ready = s == ConnectionState::Ready; }); };
    cb.lease = [&seen](const LeaseStateMsg& m) { seen.add([&] { seen.lease = m.yours; }); };
    cb.reply = [&seen](const ReplyMsg& m) { seen.add([&] { seen.reply = m; }); };
    cb.telemetry = [&seen](const TelemetryMsg& t) { seen.add([&] { seen.telemetry = t; }); };
    RobotClientConfig config;
    config.port = port_;
    config.token = kToken;
    RobotClient client(config, cb);
    client.start();
    QVERIFY(seen.waitFor([&] { return seen.ready && seen.telemetry; }, std::chrono::seconds(10)));
    client.acquireLease();
    QVERIFY(seen.waitFor([&] { return seen.lease; }));
    client.rearm();  // in case odometry came late at the bridge's start
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const double x0 = seen.read([&] { return seen.telemetry->pose.p.x; });
    const uint64_t seq = client.sendCommandText("drive 0.5 0");
    QVERIFY(seen.waitFor([&] { return seen.reply && seen.reply->seq == seq; }));
    QCOMPARE(seen.read([&] { return seen.reply->status; }), ReplyStatus::Ok);
    QVERIFY(seen.waitFor([&] { return seen.telemetry->pose.p.x - x0 > 0.5; }, std::chrono::seconds(5)));
    client.sendCommandText("stop");
    client.releaseLease();
    client.stop();
  }

  // Lease, drive 0.5 m/s: the robot moves (the twin's odometry through the
  // bridge), /cmd_vel carries the drive; the command-to-cmd_vel latency.
  // Then silence: the deadman's zero Twist within deadman + 100 ms.
  void drivesAndTheDeadmanStopsIt() {
    RawClient client(port_);
    client.hello(Role::Control, "operator");
    client.send(LeaseAcquireMsg{});
    client.send(RearmMsg{});  // the bridge may have started before odometry flowed
    std::optional<TelemetryMsg> first;
    double lastSent = 0;  // [s, steady] the deadman counts from the last packet's arrival
    const auto keepAlive = [&client, &lastSent](double seconds_) {
      const auto t0 = Clock::now();
      std::optional<TelemetryMsg> last;
      while (seconds(t0) < seconds_) {
        lastSent = steadyNow();
        client.send(LeaseKeepaliveMsg{});
        if (auto t = client.waitFor<TelemetryMsg>(0.04)) last = t;
      }
      return last;
    };
    first = keepAlive(0.5);
    QVERIFY(first);
    // The latency: each command until its speed shows on /cmd_vel.
    std::vector<double> latencies;
    for (int i = 1; i <= 20; ++i) {
      const double speed = 0.02 * i;
      const double sent = steadyNow();
      client.send(CommandMsg{static_cast<uint64_t>(i), 1000, "drive " + std::to_string(speed) + " 0"});
      const auto t0 = Clock::now();
      double arrived = 0;
      while (seconds(t0) < 1.0 && arrived == 0) {
        client.send(LeaseKeepaliveMsg{});
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        for (const Seen& s : twists())
          if (s.at >= sent && std::abs(s.linear - speed) < 1e-9) {
            arrived = s.at;
            break;
          }
      }
      QVERIFY2(arrived > 0, qPrintable(QString("drive %1 never reached /cmd_vel").arg(speed)));
      latencies.push_back(arrived - sent);
    }
    std::sort(latencies.begin(), latencies.end());
    qInfo("link command -> /cmd_vel: median %.2f ms, max %.2f ms over %zu commands", latencies[latencies.size() / 2] * 1000,
          latencies.back() * 1000, latencies.size());
    client.send(CommandMsg{100, 1000, "drive 0.5 0"});
    const std::optional<TelemetryMsg> moved = keepAlive(2.5);
    QVERIFY(moved);
    const double distance = moved->pose.p.x - first->pose.p.x;
    QVERIFY2(distance > 0.5, qPrintable(QString("moved %1 m").arg(distance)));

    // Silent from here, the connection open.
    const double silentFrom = lastSent;
    std::optional<EventMsg> event;
    while (!event || event->kind != EventKind::Failsafe) QVERIFY((event = client.waitFor<EventMsg>(2.0)));
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const std::vector<Seen> after = twists();
    double firstZero = 0;
    for (const Seen& s : after)
      if (s.at > silentFrom && s.linear == 0) {
        firstZero = s.at;
        break;
      }
    QVERIFY(firstZero > 0);
    const double delay = firstZero - silentFrom;
    qInfo("zero Twist on /cmd_vel %.0f ms after the controller went silent (deadman 200 ms)", delay * 1000);
    QVERIFY2(delay >= 0.2 && delay < 0.3, qPrintable(QString::number(delay)));
    // Until then the drive went on being published (the bridge's 20 Hz).
    QVERIFY(std::any_of(after.begin(), after.end(), [&](const Seen& s) { return s.at > silentFrom && s.at < firstZero && s.linear == 0.5; }));
  }

  // The twin frozen: odometry stops, and the failsafe says why.
  void staleOdometryIsAFailsafe() {
    RawClient client(port_);
    client.hello(Role::Control, "operator2");
    client.send(LeaseAcquireMsg{});
    client.send(RearmMsg{});
    const auto nextFailsafe = [&client](double timeout) { return client.failsafeWhileKeepingAlive(timeout, 0.04); };
    // Taking the lease tells the latch left by the last test; then, the
    // control: odometry flows, nothing fires.
    nextFailsafe(0.3);
    client.send(RearmMsg{});
    if (const auto early = nextFailsafe(1.0)) QFAIL(early->text.c_str());
    ::kill(static_cast<pid_t>(twin_.processId()), SIGSTOP);
    const std::optional<EventMsg> event = nextFailsafe(3.0);
    ::kill(static_cast<pid_t>(twin_.processId()), SIGCONT);
    QVERIFY(event);
    QVERIFY2(event->text.rfind("stale ROS input: no odometry on /odom for 0.5", 0) == 0, event->text.c_str());
  }

  // A session log as a bag: rosbag info lists each topic with the log's count.
  void sessionLogAsABag() {
    const QString log = dir_.filePath("s.splog"), bag = dir_.filePath("s.bag");
    QProcess sim;
    sim.start(kApp + "simpartner-sim", {"run", "--world", SP_SOURCE_DIR "/terrains/laser_wall.world.xml", "--commands",
                                        SP_SOURCE_DIR "/terrains/demo.seq", "--duration", "3", "--rtf", "max", "--quiet",
                                        "--log", log});
    QVERIFY(sim.waitForFinished(60000));
    QCOMPARE(sim.exitCode(), 0);
    sim.start(kApp + "simpartner-sim", {"export", log, "--bag", bag});
    QVERIFY(sim.waitForFinished(60000));
    QVERIFY2(sim.exitCode() == 0, sim.readAllStandardError().constData());
    std::string error;
    const auto reader = SessionLogReader::open(log.toStdString(), error);
    QVERIFY2(reader, error.c_str());
    const size_t samples = reader->samplesBetween(-1e300, 1e300).size();
    const size_t scans = reader->laserBetween(-1e300, 1e300).size();
    const size_t commands = reader->commands().size();
    QVERIFY(samples > 100 && scans > 10 && commands > 0);
    QProcess info;
    info.start(QStringLiteral("rosbag"), {"info", "--yaml", "--key=topics", bag});
    QVERIFY(info.waitForFinished(60000));
    const QString yaml = QString::fromUtf8(info.readAllStandardOutput());
    QVERIFY2(info.exitCode() == 0, qPrintable(yaml + info.readAllStandardError()));
    const auto count = [&yaml](const QString& topic) {
      // "- topic: /odom\n    type: ...\n    messages: 301"
      const QRegularExpression re("topic: " + QRegularExpression::escape(topic) + "\\s+type: \\S+\\s+messages:\\s+(\\d+)");
      const auto m = re.match(yaml);
      return m.hasMatch() ? m.captured(1).toULongLong() : 0;
    };
    QCOMPARE(count("/odom"), samples);
    QCOMPARE(count("/joint_states"), samples);
    QCOMPARE(count("/tf"), samples);
    QCOMPARE(count("/scan"), scans);
    QCOMPARE(count("/simpartner/commands"), commands);
    // Bad input: a bag that cannot be written is an error and leaves nothing.
    sim.start(kApp + "simpartner-sim", {"export", log, "--bag", dir_.filePath("none/x.bag")});
    QVERIFY(sim.waitForFinished(60000));
    QCOMPARE(sim.exitCode(), 1);
    QVERIFY(sim.readAllStandardError().contains("none/x.bag: error: cannot write the bag"));
    QVERIFY(!QFileInfo::exists(dir_.filePath("none")));
  }

  // A bridge file naming a joint the robot lacks, or a topic that is no ROS
  // name: the bridge says where and does not start.
  void badBridgeFiles_data() {
    QTest::addColumn<QByteArray>("text");
    QTest::addColumn<QString>("message");
    QTest::newRow("joint") << QByteArray("ros.odom = /odom\nros.joint.hip_xx = front_hip\n")
                           << "b.params:2: error: ros.joint.hip_xx: the robot 'workpartner' has no joint 'hip_xx'";
    QTest::newRow("topic") << QByteArray("ros.scan = laser scan\n") << "b.params:1: error: ros.scan: 'laser scan' is not a ROS topic name";
  }
  void badBridgeFiles() {
    QFETCH(QByteArray, text);
    QFETCH(QString, message);
    QFile file(dir_.filePath("b.params"));
    QVERIFY(file.open(QIODevice::WriteOnly));
    file.write(text);
    file.close();
    QProcess bridge;
    bridge.start(kApp + "simpartner-ros-bridge", {"--port", "0", "--bridge", file.fileName()});
    QVERIFY(bridge.waitForFinished(20000));
    QCOMPARE(bridge.exitCode(), 1);
    const QString err = QString::fromUtf8(bridge.readAllStandardError());
    QVERIFY2(err.contains(message), qPrintable(err));
  }
};

QTEST_GUILESS_MAIN(TestRosBridge)
#include "tst_ros_bridge.moc"
