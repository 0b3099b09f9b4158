// Holding joints rigid (sim/rigid.h): the welded robot has the full robot's
// mass, centre of mass and link poses in the held pose, and drives like it;
// what cannot be held is refused, naming the joint.

#include <QtTest>

#include <cmath>

#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/rigid.h"
#include "sim/world.h"

using namespace sp;

namespace {

WorldModel flat() {
  Diagnostics diag;
  auto model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
  if (!model) qFatal("%s", diag.format().c_str());
  return *model;
}

double distance(Vec3 a, Vec3 b) { return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)); }

}  // namespace

class TestRigid : public QObject {
  Q_OBJECT

 private slots:
  // The upper body (the waist and all below it: torso, head, arms,
  // fingers) held with the elbows bent: 14 bodies fewer, the same mass and
  // centre of mass, every link where the full robot's kinematics puts it.
  void upperBodyHeldKeepsMassAndPoses() {
    const WorldModel world = flat();
    const RobotModel& robot = world.robots[0].model;
    std::vector<double> q(robot.joints.size(), 0.0);
    q[static_cast<size_t>(robot.findJoint("elbow_l"))] = degToRad(40);
    q[static_cast<size_t>(robot.findJoint("shoulder_pitch_r"))] = degToRad(-30);
    const std::vector<int> held = subtreeJoints(robot, "waist_yaw");
    QCOMPARE(held.size(), size_t{14});
    std::string error;
    const auto rigid = holdRigid(robot, q, held, error);
    QVERIFY2(rigid, error.c_str());
    QCOMPARE(rigid->model.links.size(), robot.links.size() - 14);
    QCOMPARE(rigid->model.joints.size(), robot.joints.size() - 14);
    QCOMPARE(rigid->model.totalMass(), robot.totalMass());
    QVERIFY(rigid->model.drive);
    QCOMPARE(rigid->model.joints[static_cast<size_t>(rigid->model.drive->articulation)].name, std::string("articulation"));

    // Poses: the rigid robot's links where the full robot's are, and the
    // gathered geoms with them (checked through the rebuilt full joints).
    const Pose base = robot.links[0].pose;
    const std::vector<Pose> full = linkPoses(robot, base, q);
    const std::vector<Pose> welded = linkPoses(rigid->model, base, rigidJoints(*rigid, q));
    for (size_t l = 0; l < rigid->model.links.size(); ++l)
      QVERIFY(distance(welded[l].p, full[static_cast<size_t>(rigid->linkOf[l])].p) < 1e-12);
    QCOMPARE(fullJoints(*rigid, rigidJoints(*rigid, q)), q);

    // Centre of mass of the two worlds, the full one put in the held pose.
    WorldModel rigidWorld = world;
    rigidWorld.robots[0].model = rigid->model;
    Diagnostics diag;
    auto a = World::create(world, SimParams{}, diag);
    auto b = World::create(rigidWorld, SimParams{}, diag);
    QVERIFY2(a && b, diag.format().c_str());
    const Pose start = world.robots[0].pose * base;
    QCOMPARE(a->setRobotMotion(0, linkMotions(robot, start, {}, {}, q, std::vector<double>(q.size(), 0.0))), std::string());
    const Vec3 ca = a->robotCentreOfMass(0), cb = b->robotCentreOfMass(0);
    qInfo("centre of mass full %.6f %.6f %.6f, rigid %.6f %.6f %.6f", ca.x, ca.y, ca.z, cb.x, cb.y, cb.z);
    QVERIFY(distance(ca, cb) < 1e-9);
    // Control: the same merge with the gathered mass spread over the geoms
    // by volume (a naive merge) moves the centre of mass, and this sees it.
    for (LinkSpec& link : rigidWorld.robots[0].model.links)
      for (GeomSpec& g : link.geoms) g.mass = -1;
    auto naive = World::create(rigidWorld, SimParams{}, diag);
    QVERIFY2(naive, diag.format().c_str());
    const Vec3 cn = naive->robotCentreOfMass(0);
    qInfo("naive merge: centre of mass %.1f mm off", distance(ca, cn) * 1000);
    QVERIFY(distance(ca, cn) > 1e-3);
  }

  // Driving and turning 5 s from rest, the held robot's base stays within
  // 3 cm and 1 degree of the full robot's.
  void heldRobotDrivesLikeTheFull() {
    const WorldModel world = flat();
    const RobotModel& robot = world.robots[0].model;
    const std::vector<double> q(robot.joints.size(), 0.0);
    std::string error;
    const auto rigid = holdRigid(robot, q, subtreeJoints(robot, "waist_yaw"), error);
    QVERIFY2(rigid, error.c_str());
    WorldModel rigidWorld = world;
    rigidWorld.robots[0].model = rigid->model;
    Diagnostics diag;
    auto a = World::create(world, SimParams{}, diag);
    auto b = World::create(rigidWorld, SimParams{}, diag);
    QVERIFY2(a && b, diag.format().c_str());
    for (World* w : {a.get(), b.get()}) {
      QCOMPARE(w->submit(DriveCmd{0.5, degToRad(12)}), std::string());
      for (int i = 0; i < 5000; ++i) QVERIFY(w->step());
    }
    const Pose pa = a->linkPose(0, 0), pb = b->linkPose(0, 0);
    const double off = std::hypot(pa.p.x - pb.p.x, pa.p.y - pb.p.y);
    const double yaw = radToDeg(std::abs(std::remainder(heading(pa.q) - heading(pb.q), 2 * kPi)));
    qInfo("after 5 s: %.1f mm, %.3f deg apart; full robot moved %.2f m", off * 1000, yaw, std::hypot(pa.p.x, pa.p.y));
    QVERIFY(off < 0.03);
    QVERIFY(yaw < 1);
  }

  void refusals() {
    const WorldModel world = flat();
    const RobotModel& robot = world.robots[0].model;
    const std::vector<double> q(robot.joints.size(), 0.0);
    std::string error;
    QVERIFY(!holdRigid(robot, q, {robot.findJoint("elbow_l")}, error));
    QCOMPARE(error, std::string("joint 'finger_l1' moves below held joint 'elbow_l': hold its whole subtree"));
    QVERIFY(!holdRigid(robot, q, subtreeJoints(robot, "knee_fl"), error));
    QCOMPARE(error, std::string("joint 'wheel_fl' drives the robot and cannot be held"));
    QVERIFY(!holdRigid(robot, std::vector<double>(3, 0.0), {}, error));
    QCOMPARE(error, std::string("expected 27 joint positions, got 3"));
    QVERIFY(!holdRigid(robot, q, {99}, error));
    QCOMPARE(error, std::string("no joint 99"));
    QVERIFY(subtreeJoints(robot, "nope").empty());
  }
};

QTEST_GUILESS_MAIN(TestRigid)
#include "tst_rigid.moc"
