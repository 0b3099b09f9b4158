// Forward kinematics (sim/kinematics.h) against the physics world: after the
// WorkPartner has moved many joints, the links drawn from its base pose and
// joint positions are where ODE has them.

#include <QTest>

#include <cmath>

#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/world.h"

using namespace sp;

namespace {

/// The angle [rad] of the rotation between two unit quaternions.
double angleBetween(const Quat& a, const Quat& b) {
  const Quat d = conjugate(a) * b;
  return 2 * std::atan2(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z), std::abs(d.w));
}

/// A base and one child at `child` (zero pose), joined at `anchor` about `axis`.
RobotModel twoLinks(Vec3 child, Vec3 anchor, Vec3 axis) {
  RobotModel robot;
  robot.links.resize(2);
  robot.links[1].pose.p = child;
  JointSpec joint;
  joint.parent = 0;
  joint.child = 1;
  joint.anchor = anchor;
  joint.axis = axis;
  robot.joints.push_back(joint);
  return robot;
}

}  // namespace

class TestKinematics : public QObject {
  Q_OBJECT

 private slots:
  // A hinge about z through (1, 0, 0) turned by 90 degrees carries a child
  // at (2, 0, 0) to (1, 1, 0); a slider along x by 0.3 m moves it to 2.3.
  void hingeAndSliderByHand() {
    RobotModel robot = twoLinks({2, 0, 0}, {1, 0, 0}, {0, 0, 1});
    const Pose base{{10, 0, 0}, Quat{}};

    std::vector<double> q{kPi / 2};
    std::vector<Pose> poses = linkPoses(robot, base, q);
    QCOMPARE(poses.size(), size_t{2});
    QVERIFY(std::abs(poses[1].p.x - 11) < 1e-12);
    QVERIFY(std::abs(poses[1].p.y - 1) < 1e-12);
    QVERIFY(std::abs(angleBetween(poses[1].q, quatFromAxisAngle({0, 0, 1}, kPi / 2))) < 1e-12);

    robot.joints[0].type = JointType::Slider;
    robot.joints[0].axis = {1, 0, 0};
    q = {0.3};
    poses = linkPoses(robot, base, q);
    QVERIFY(std::abs(poses[1].p.x - 12.3) < 1e-12);
    QVERIFY(std::abs(poses[1].p.y) < 1e-12);
  }

  // A wheel of radius 0.2 about y, its link frame 0.1 m beside its hub (the
  // anchor), turned 90 degrees about z (the axle now along -x), spinning at
  // 3 rad/s and its hub moving at 0.6 m/s along y: rolling without slip,
  // spin x radius = |across|; the link origin's own velocity differs from the
  // hub's by spin x offset (which must be accounted for). Control: the same
  // hub speed with the wheel locked (a slide) gives spin 0.
  void wheelRollingByHand() {
    const RobotModel robot = twoLinks({0, 0.1, 0}, {0, 0, 0}, {0, 1, 0});  // link frame beside the hub
    const JointSpec& joint = robot.joints[0];
    const Quat turn = quatFromAxisAngle({0, 0, 1}, kPi / 2);
    LinkMotion wheel;
    wheel.pose = {rotate(turn, Vec3{0, 0.1, 0}), turn};  // hub at the world origin
    const Vec3 axle = rotate(turn, Vec3{0, 1, 0});       // (-1, 0, 0)
    wheel.angular = 3.0 * axle;
    const Vec3 hubVelocity{0, 0.6, 0};
    // The link origin's velocity: the hub's plus angular x (origin - hub).
    wheel.linear = hubVelocity + cross(wheel.angular, wheel.pose.p - Vec3{0, 0, 0});
    const WheelRolling r = wheelRolling(robot, joint, wheel);
    QVERIFY(std::abs(r.spin - 3.0) < 1e-12);
    QVERIFY(norm(r.axle - axle) < 1e-12);
    QVERIFY2(norm(r.across - hubVelocity) < 1e-12, qPrintable(QString::number(norm(r.across - hubVelocity))));
    QVERIFY(std::abs(std::abs(r.spin) * 0.2 - norm(r.across)) < 1e-12);  // rolls without slip
    wheel.angular = {};
    wheel.linear = hubVelocity;
    const WheelRolling locked = wheelRolling(robot, joint, wheel);
    QVERIFY(std::abs(locked.spin) < 1e-12 && norm(locked.across) > 0.5);  // control: slides
  }

  // Every joint of the WorkPartner driven somewhere, the robot driving and
  // steering: FK from the base pose and joint positions puts each link within
  // 3 mm and 0.01 rad of ODE's body (joint error of the soft constraints).
  void workPartnerMatchesTheWorld() {
    Diagnostics diag;
    auto model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    QVERIFY2(model, diag.format().c_str());
    auto world = World::create(*model, SimParams{}, diag);
    QVERIFY2(world, diag.format().c_str());
    const RobotModel& robot = world->model().robots[0].model;

    const std::vector<std::pair<const char*, double>> targets{
        {"waist_yaw", 0.4}, {"waist_pitch", 0.2}, {"head_pan", -0.5}, {"head_tilt", 0.3},
        {"shoulder_pitch_l", 0.6}, {"shoulder_roll_l", 0.3}, {"elbow_l", 0.8}, {"finger_l1", 0.02},
        {"shoulder_pitch_r", -0.4}, {"elbow_r", 0.5}, {"knee_fl", 0.1}};
    for (const auto& [name, value] : targets) {
      QVERIFY2(robot.findJoint(name) >= 0, name);
      QCOMPARE(world->submit(JointTargetCmd{name, value}), std::string());
    }
    QCOMPARE(world->submit(DriveCmd{0.4, degToRad(15)}), std::string());
    for (int i = 0; i < 2000; ++i) world->step();

    std::vector<double> q;
    for (size_t j = 0; j < robot.joints.size(); ++j) q.push_back(world->jointPosition(0, static_cast<int>(j)));
    // The arm joints really moved, so the comparison means something.
    QVERIFY(std::abs(q[static_cast<size_t>(robot.findJoint("elbow_l"))] - 0.8) < 0.05);
    QVERIFY(std::abs(q[static_cast<size_t>(robot.findJoint("articulation"))]) > degToRad(10));

    const std::vector<Pose> poses = linkPoses(robot, world->linkPose(0, 0), q);
    QCOMPARE(poses.size(), robot.links.size());
    double worstDistance = 0, worstAngle = 0;
    for (size_t i = 0; i < poses.size(); ++i) {
      const Pose ode = world->linkPose(0, static_cast<int>(i));
      const double d = norm(poses[i].p - ode.p), a = angleBetween(poses[i].q, ode.q);
      if (d > 3e-3 || a > 0.01) qWarning("link %s: %.4f m, %.4f rad off", robot.links[i].name.c_str(), d, a);
      worstDistance = std::max(worstDistance, d);
      worstAngle = std::max(worstAngle, a);
    }
    qInfo("worst link: %.2f mm, %.4f rad", worstDistance * 1e3, worstAngle);
    QVERIFY(worstDistance < 3e-3);
    QVERIFY(worstAngle < 0.01);
  }
};

QTEST_GUILESS_MAIN(TestKinematics)
#include "tst_kinematics.moc"
