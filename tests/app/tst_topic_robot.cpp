// The ROS bridge's core without ROS (app/bridge/topic_robot.h): its
// parameters file and what it refuses; drive and turn as a velocity whose
// yaw rate is the articulated-steering kinematics'; odometry turned into
// telemetry; and, behind the real link server on loopback, the safety chain:
// a silent controller's deadman publishes a zero velocity within deadman +
// 100 ms, and odometry gone stale fires the failsafe with its reason.

#include <QTest>

#include <atomic>
#include <mutex>

#include "app/bridge/topic_robot.h"
#include "sim/model_loader.h"
#include "tests/net/raw_client.h"

using namespace sp;
using namespace sp::test;

namespace {

RobotModel workPartner() {
  Diagnostics diag;
  std::optional<RobotModel> robot = loadRobot(SP_SOURCE_DIR "/robots/workpartner.xml", diag);
  if (!robot) qFatal("%s", diag.format().c_str());
  return *robot;
}

/// What the bridge published, with when [s, steady clock].
struct Recorder : TopicOutput {
  struct Velocity {
    double linear, angular, at;
  };
  std::mutex mutex;
  std::vector<Velocity> velocities;
  std::vector<std::pair<std::vector<std::string>, std::vector<double>>> targets;
  void velocity(double linear, double angular) override {
    std::lock_guard lock(mutex);
    velocities.push_back({linear, angular, std::chrono::duration<double>(Clock::now().time_since_epoch()).count()});
  }
  void jointTargets(const std::vector<std::string>& names, const std::vector<double>& positions) override {
    std::lock_guard lock(mutex);
    targets.emplace_back(names, positions);
  }
};

double steadyNow() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

}  // namespace

class TestTopicRobot : public QObject {
  Q_OBJECT

 private slots:
  void parametersFile() {
    const RobotModel robot = workPartner();
    Diagnostics diag;
    std::optional<BridgeConfig> c = parseBridgeConfig("ros.odom = /robot/odom\nros.joint.hip_fl = fl_hip  # theirs\n"
                                                      "ros.stale_after = 0.3\n",
                                                      "b.params", robot, diag);
    QVERIFY2(c, diag.format().c_str());
    QCOMPARE(c->odom, std::string("/robot/odom"));
    QCOMPARE(c->cmdVel, std::string("/cmd_vel"));  // the default kept
    QCOMPARE(c->jointNames.at("hip_fl"), std::string("fl_hip"));
    QCOMPARE(c->staleAfter, 0.3);
    // Each error names its line; nothing half-applied: no config at all.
    const std::pair<const char*, const char*> bad[] = {
        {"ros.odom = /odom\nros.scann = /scan\n", "b.params:2: error: unknown key 'ros.scann'"},
        {"ros.cmd_vel = cmd vel\n", "b.params:1: error: ros.cmd_vel: 'cmd vel' is not a ROS topic name"},
        {"ros.joint.hip_xx = a\n", "b.params:1: error: ros.joint.hip_xx: the robot 'workpartner' has no joint 'hip_xx'"},
        {"ros.joint.hip_fl = a\nros.joint.hip_fr = a\n", "b.params:2: error: ros.joint.hip_fr: 'a' is mapped already (line 1)"},
        {"ros.joint.hip_fl = knee_fl\n", "b.params:1: error: 'knee_fl' is the name of the robot's own joint 'knee_fl' too"},
        {"ros.stale_after = 0\n", "b.params:1: error: ros.stale_after: expected a number in [0.05, 10], got '0'"},
    };
    for (const auto& [text, message] : bad) {
      Diagnostics d;
      QVERIFY2(!parseBridgeConfig(text, "b.params", robot, d), text);
      QVERIFY2(d.format().find(message) != std::string::npos, d.format().c_str());
    }
    Diagnostics d;
    QVERIFY(!loadBridgeConfig("/nonexistent/b.params", robot, d));
    QVERIFY(d.format().find("/nonexistent/b.params: error: cannot open") != std::string::npos);
  }

  // A drive's velocity: the yaw rate that articulationForTurn turns back
  // into the drive's hinge angle (the kinematics both ways), a turn as it
  // is, stop as zero; joint targets under the robot's own names; the rest
  // refused, naming what the robot's ROS interface takes.
  void commandsAsTopics() {
    Recorder out;
    BridgeConfig config;
    config.jointNames["hip_fl"] = "fl_hip";
    TopicRobot robot(workPartner(), config, out, steadyNow);
    for (double deg : {-20.0, -5.0, 10.0, 25.0}) {
      const double gamma = degToRad(deg);
      for (double speed : {0.5, -0.3}) {
        const double yaw = robot.yawRateOf(speed, gamma);
        QVERIFY((yaw > 0) == ((gamma > 0) == (speed > 0)));  // left for a left hinge going forward
        DriveGeometry g;
        g.frontLength = g.rearLength = 0.55;  // the robot file's hinge-to-axle, in the stance
        g.frontTrack = g.rearTrack = 0.84;
        QVERIFY2(std::abs(articulationForTurn(g, speed, yaw, kPi) - gamma) < 1e-6, qPrintable(QString::number(deg)));
      }
    }
    QCOMPARE(robot.yawRateOf(0.5, 0), 0.0);
    robot.apply({DriveCmd{0.5, degToRad(10)}, TurnCmd{0.4, 0.2}, StopCmd{}, JointTargetCmd{"hip_fl", 0.1}});
    QCOMPARE(out.velocities.size(), size_t{3});
    QCOMPARE(out.velocities[0].linear, 0.5);
    QCOMPARE(out.velocities[0].angular, robot.yawRateOf(0.5, degToRad(10)));
    QCOMPARE(out.velocities[1].angular, 0.2);
    QCOMPARE(out.velocities[2].linear, 0.0);
    QCOMPARE(out.velocities[2].angular, 0.0);
    QCOMPARE(out.targets.at(0).first, std::vector<std::string>{"fl_hip"});
    QVERIFY(robot.check(DriveCmd{0.5, degToRad(10)}).ok());
    QCOMPARE(robot.check(DriveCmd{0.5, degToRad(40)}).kind, CommandCheck::Kind::OutOfLimits);
    QCOMPARE(robot.check(JointTargetCmd{"wheel_fl", 1}).message, std::string("'wheel_fl' is driven through /cmd_vel (drive, turn)"));
    QCOMPARE(robot.check(GaitCmd{Gait::Rolking}).message,
             std::string("the ROS bridge sends drive, turn, stop (/cmd_vel) and joint targets (/joint_trajectory) only, "
                         "not 'gait'"));
    QCOMPARE(robot.check(JointTargetCmd{"hip_fl", degToRad(80)}).kind, CommandCheck::Kind::OutOfLimits);
  }

  // Telemetry from topics: the odometry's body-frame twist in the world's
  // frame, joints by the map, roll and pitch from the IMU, scans with
  // "nothing" as the maximum range; odometry older than stale_after is a
  // fault that says so.
  void telemetryFromTopics() {
    Recorder out;
    BridgeConfig config;
    config.jointNames["hip_fl"] = "fl_hip";
    double now = 100;
    TopicRobot robot(workPartner(), config, out, [&now] { return now; });
    QVERIFY(robot.fault().empty());
    now = 100.6;
    QCOMPARE(robot.fault(), std::string("stale ROS input: no odometry on /odom since the start, 0.60 s (ros.stale_after 0.5 s)"));
    const Quat yaw90 = quatFromAxisAngle({0, 0, 1}, kPi / 2);
    robot.odometry({5, {{1, 2, 0.8}, yaw90}, {0.5, 0, 0}, {0, 0, 0.1}});
    QVERIFY(robot.fault().empty());
    robot.jointStates({5, {"fl_hip", "knee_fl", "gripper"}, {0.2, 0.3, 9}, {0.01, 0.02, 9}});
    robot.imu({5, quatFromRpy({0.1, -0.05, 0})});
    robot.scan({5, -1, 0.5, 10, {1.0, std::numeric_limits<double>::infinity(), 20.0}});
    const net::RobotState s = robot.state();
    QVERIFY(norm(s.baseLinearVelocity - Vec3{0, 0.5, 0}) < 1e-12);  // forward in the body is +y in the world
    QCOMPARE(s.jointPositions[static_cast<size_t>(workPartner().findJoint("hip_fl"))], 0.2);
    QCOMPARE(s.jointPositions[static_cast<size_t>(workPartner().findJoint("knee_fl"))], 0.3);
    QVERIFY(std::abs(s.roll - 0.1) < 1e-9);
    QVERIFY(std::abs(s.pitch + 0.05) < 1e-9);
    const std::optional<net::LaserScanState> scan = robot.laserAfter(0);
    QVERIFY(scan);
    QCOMPARE(scan->ranges, (std::vector<double>{1.0, 10.0, 10.0}));
    QVERIFY(!robot.laserAfter(scan->count));
    now = 101.2;
    QCOMPARE(robot.fault(), std::string("stale ROS input: no odometry on /odom for 0.60 s (ros.stale_after 0.5 s)"));
  }

  // Behind the real server on loopback: a controller that goes silent
  // trips the deadman, which publishes a zero velocity within deadman +
  // 100 ms of its last packet; odometry that stops fires the failsafe with
  // the reason, again after a re-arm while it stays stale, and not once it
  // flows again.
  void safetyChainOverTheLink() {
    Recorder out;
    TopicRobot robot(workPartner(), BridgeConfig{}, out, steadyNow);
    std::atomic<bool> odometryFlows{true}, stop{false};
    std::thread odometry([&] {
      while (!stop) {
        if (odometryFlows) robot.odometry({0, {}, {}, {}});
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
    asio::io_context io;
    RobotServerConfig config;
    config.port = 0;
    config.link.token = kToken;
    config.link.deadman = 0.3;
    RobotServer server(io, config, robot);
    QCOMPARE(server.start(), std::string());
    std::thread ioThread([&] { io.run(); });

    RawClient holder(server.port());
    holder.hello(Role::Control, "operator");
    holder.send(LeaseAcquireMsg{});
    holder.send(CommandMsg{1, 1000, "drive 0.4 0"});
    const auto reply = holder.waitFor<ReplyMsg>(2.0);
    QVERIFY(reply);
    QCOMPARE(reply->status, ReplyStatus::Ok);
    Clock::time_point lastPacket;
    for (int i = 0; i < 10; ++i) {
      lastPacket = Clock::now();
      holder.send(LeaseKeepaliveMsg{});
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
    }
    const double silentFrom = std::chrono::duration<double>(lastPacket.time_since_epoch()).count();
    std::optional<EventMsg> event;
    while (!event || event->kind != EventKind::Failsafe) QVERIFY((event = holder.waitFor<EventMsg>(2.0)));
    {
      std::lock_guard lock(out.mutex);
      QVERIFY(out.velocities.size() >= 2);
      QCOMPARE(out.velocities.front().linear, 0.4);
      const Recorder::Velocity zero = out.velocities.back();
      QCOMPARE(zero.linear, 0.0);
      const double after = zero.at - silentFrom;
      qInfo("zero velocity %.0f ms after the controller's last packet (deadman 300 ms)", after * 1000);
      QVERIFY2(after >= 0.3 && after < 0.4, qPrintable(QString::number(after)));
    }

    // Stale odometry: the failsafe with its reason. The controller keeps
    // its lease alive meanwhile, so the deadman stays quiet.
    const auto nextFailsafe = [&holder](double timeout) { return holder.failsafeWhileKeepingAlive(timeout, 0.05); };
    holder.send(RearmMsg{});
    QVERIFY(!nextFailsafe(0.3));  // odometry flows: nothing
    odometryFlows = false;
    event = nextFailsafe(2.0);
    QVERIFY(event);
    QVERIFY2(event->text.rfind("stale ROS input: no odometry on /odom for 0.5", 0) == 0, event->text.c_str());
    // Re-armed while still stale: it fires again.
    holder.send(RearmMsg{});
    QVERIFY(nextFailsafe(2.0));
    // The control: odometry back, a re-arm holds.
    odometryFlows = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    holder.send(RearmMsg{});
    QVERIFY(!nextFailsafe(1.0));
    stop = true;
    odometry.join();
    asio::post(io, [&] {
      server.stop();
      io.stop();
    });
    ioThread.join();
  }
};

QTEST_GUILESS_MAIN(TestTopicRobot)
#include "tst_topic_robot.moc"
