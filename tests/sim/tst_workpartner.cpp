// The shipped WorkPartner model on the shipped worlds: mass and balance,
// standing still, rolling at v = omega r, steering by the articulation hinge.

#include <QTest>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "sim/model_loader.h"
#include "sim/world.h"

using namespace sp;

namespace {

std::unique_ptr<World> load(const char* worldFile) {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(std::string(SP_SOURCE_DIR) + "/" + worldFile, diag);
  if (!diag.empty()) qWarning("%s", diag.format().c_str());
  if (!model || !diag.empty()) return nullptr;
  return World::create(*model, SimParams{}, diag);
}

void stepFor(World& world, double seconds) {
  const auto n = static_cast<int64_t>(seconds / world.params().step + 0.5);
  for (int64_t i = 0; i < n; ++i) world.step();
}

double planar(Vec3 a, Vec3 b) { return std::hypot(a.x - b.x, a.y - b.y); }

}  // namespace

class TestWorkPartner : public QObject {
  Q_OBJECT

 private slots:
  // Issue 30: the shipped WorkPartner's compliant tyres (150 kN/m and
  // 1800 N s/m each, one contact patch per wheel) carry each wheel's static
  // share within +-5 % on flat ground at a steady 0.25 m/s: the compliance
  // makes the four-wheel load determinate. The control, the same robot on
  // rigid tyres, swings the loads between the diagonals (about 50 % off).
  void wheelLoadsSteadyAtConstantSpeed() {
    Diagnostics diag;
    std::optional<WorldModel> model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    QVERIFY2(model, diag.format().c_str());
    const auto worst = [](const WorldModel& m) {
      Diagnostics d;
      auto world = World::create(m, SimParams{}, d);
      const RobotModel& robot = world->robotModel(0);
      std::vector<int> sensors;
      for (size_t i = 0; i < robot.sensors.size(); ++i)
        if (robot.sensors[i].type == SensorType::WheelForce) sensors.push_back(static_cast<int>(i));
      const auto normal = [&](int k) { return std::get<WheelForceReading>(world->sensorSample(0, sensors[k]).value).normal; };
      std::vector<double> standing(sensors.size(), 0);
      stepFor(*world, 2);
      for (int i = 0; i < 100; ++i) {  // the static share: a second standing
        stepFor(*world, 0.01);
        for (size_t k = 0; k < sensors.size(); ++k) standing[k] += normal(static_cast<int>(k)) / 100;
      }
      world->submit(DriveCmd{0.25, 0});
      stepFor(*world, 3);
      double off = 0;
      for (int i = 0; i < 500; ++i) {
        stepFor(*world, 0.01);
        for (size_t k = 0; k < sensors.size(); ++k) off = std::max(off, std::abs(normal(static_cast<int>(k)) / standing[k] - 1));
      }
      return std::make_pair(off, sensors.size());
    };
    QVERIFY(model->robots[0].model.drive->tyreStiffness > 0);
    const auto [compliant, wheels] = worst(*model);
    model->robots[0].model.drive->tyreStiffness = model->robots[0].model.drive->tyreDamping = 0;
    const double rigid = worst(*model).first;
    QCOMPARE(wheels, size_t{4});
    qInfo("largest wheel load off its static share over 5 s at 0.25 m/s: %.1f %% (rigid tyres: %.1f %%)",
          compliant * 100, rigid * 100);
    QVERIFY2(compliant <= 0.05, qPrintable(QString::number(compliant)));
    QVERIFY2(rigid > 0.2, qPrintable(QString::number(rigid)));  // the control
  }

  // About 230 kg, and the front axle carries more than the rear (55/45 by
  // design: the torso and arms sit on the front half).
  void massAndBalance() {
    auto world = load("terrains/flat.world.xml");
    QVERIFY(world);
    const RobotModel& robot = world->robotModel(0);
    QVERIFY(std::abs(robot.totalMass() - 230) < 5);
    const double xCom = world->robotCentreOfMass(0).x;
    const double front = (xCom + 0.55) / 1.1;
    QVERIFY2(front > 0.53 && front < 0.58, qPrintable(QString::number(front)));
  }

  void standsStill_data() {
    QTest::addColumn<QString>("world");
    QTest::newRow("flat") << "terrains/flat.world.xml";
    QTest::newRow("bumpy") << "terrains/bumpy.world.xml";
  }
  // Left alone for 10 s after 2 s of settling onto the ground, the robot drifts
  // less than 1 cm and stays level.
  void standsStill() {
    QFETCH(QString, world);
    auto w = load(qPrintable(world));
    QVERIFY(w);
    stepFor(*w, 2.0);  // settle onto the ground from the start pose
    const Vec3 p0 = w->linkPose(0, 0).p;
    stepFor(*w, 10.0);
    const Pose p1 = w->linkPose(0, 0);
    const double drift = norm(p1.p - p0);
    QVERIFY2(drift < 0.01, qPrintable(QString("drift %1 m").arg(drift)));
    const Vec3 rpy = rpyFromQuat(p1.q);
    QVERIFY(std::abs(rpy.x) < degToRad(5) && std::abs(rpy.y) < degToRad(5));
  }

  // Wheels at omega on high friction: the robot moves at v = omega r, within 2 %.
  void rollsAtOmegaR() {
    auto world = load("terrains/flat.world.xml");
    QVERIFY(world);
    const double omega = 5.0, r = world->robotModel(0).drive->wheelRadius;
    QCOMPARE(world->submit(WheelsCmd{{omega, omega, omega, omega}}), std::string());
    stepFor(*world, 2.0);
    const Vec3 p0 = world->linkPose(0, 0).p;
    const double t0 = world->time();
    stepFor(*world, 3.0);
    const Vec3 p1 = world->linkPose(0, 0).p;
    const double v = planar(p1, p0) / (world->time() - t0);
    QVERIFY2(std::abs(v - omega * r) / (omega * r) < 0.02, qPrintable(QString::number(v)));
    QVERIFY(p1.x > p0.x);
    QVERIFY(std::abs(p1.y) < 0.02);
  }

  void steersWithArticulation_data() {
    QTest::addColumn<double>("articulation");
    QTest::newRow("left 15 deg") << 15.0;
    QTest::newRow("right 25 deg") << -25.0;
  }
  // With the hinge held at gamma, the hinge point runs on the circle of
  // articulated-steering kinematics, R_H = sqrt(L_r^2 + R_r^2) with
  // R_r = (L_f + L_r cos gamma) / sin gamma (workpartner-facts.md §3), and
  // turns to the side the front body points.
  void steersWithArticulation() {
    QFETCH(double, articulation);
    auto world = load("terrains/flat.world.xml");
    QVERIFY(world);
    const RobotModel& robot = world->robotModel(0);
    const int hinge = robot.findJoint("articulation");
    QCOMPARE(world->submit(DriveCmd{0.5, degToRad(articulation)}), std::string());
    stepFor(*world, 4.0);
    QVERIFY(std::abs(radToDeg(world->jointPosition(0, hinge)) - articulation) < 0.5);
    // Sample the hinge point (0.45 m ahead of the rear body's frame) on a
    // quarter circle and fit its radius from three points.
    auto hingePoint = [&] { return transformPoint(world->linkPose(0, 0), {0.45, 0, 0}); };
    const double yaw0 = rpyFromQuat(world->linkPose(0, 0).q).z;
    const Vec3 a = hingePoint();
    stepFor(*world, 3.0);
    const Vec3 b = hingePoint();
    stepFor(*world, 3.0);
    const Vec3 c = hingePoint();
    const double yaw1 = rpyFromQuat(world->linkPose(0, 0).q).z;
    const double ab = planar(a, b), bc = planar(b, c), ca = planar(c, a);
    const double area2 = std::abs((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
    const double radius = ab * bc * ca / (2 * area2);
    const DriveGeometry g = *world->driveGeometry(0);
    const double s = std::sin(g.articulation), co = std::cos(g.articulation);
    const double rRear = (g.frontLength + g.rearLength * co) / s;
    const double expected = std::abs(std::hypot(g.rearLength, rRear));
    QVERIFY2(std::abs(radius - expected) / expected < 0.02,
             qPrintable(QString("radius %1, kinematics %2").arg(radius).arg(expected)));
    QVERIFY((wrapAngle(yaw1 - yaw0) > 0) == (articulation > 0));
  }

  // Driving by turn rate: the hinge angle is solved from the kinematics
  // each step, and the robot turns at the commanded yaw rate.
  void turnsAtCommandedYawRate() {
    auto world = load("terrains/flat.world.xml");
    QVERIFY(world);
    const double yawRate = degToRad(-8);
    QCOMPARE(world->submit(TurnCmd{0.6, yawRate}), std::string());
    stepFor(*world, 4.0);
    const double yaw0 = rpyFromQuat(world->linkPose(0, 0).q).z;
    stepFor(*world, 4.0);
    const double measured = wrapAngle(rpyFromQuat(world->linkPose(0, 0).q).z - yaw0) / 4.0;
    QVERIFY2(std::abs(measured - yawRate) / std::abs(yawRate) < 0.02,
             qPrintable(QString("%1 deg/s").arg(radToDeg(measured))));
  }
};

QTEST_GUILESS_MAIN(TestWorkPartner)
#include "tst_workpartner.moc"
