// Sensors against analytic values: laser ranges to a wall, to flat ground
// from a tilted scanner and to a slope; encoders, poses, joint and wheel
// forces, the IMU at rest; rates and seeded noise.

#include <QTest>

#include <cmath>

#include "tests/default_step.h"
#include "tests/sim/world_fixture.h"

using namespace sp;
using sp::test::stepFor;
using sp::test::WorldFixture;

namespace {

// A post fixed to the world with a scanner `height` m up, pitched down by
// `pitch` deg, and an encoder and pose sensor on a free hinge.
std::string scannerRobot(double height, double pitch, const char* extra = "", bool excludeSelf = true) {
  return QString(R"(<robot name="scanner">
  <link name="post" mass="10" xyz="0 0 %1"><geom type="box" size="0.1 0.1 0.1"/></link>
  <link name="flag" mass="1" xyz="0.3 0 %1"><geom type="box" size="0.1 0.02 0.1"/></link>
  <joint name="fix" type="fixed" parent="world" child="post"/>
  <joint name="flag" type="hinge" parent="post" child="flag" xyz="0.3 0 %1" axis="0 0 1"/>
  <sensor name="laser" type="laser" link="post" rpy="0 %2 0" rate="20" fov="180" beams="181"
          min_range="0.05" max_range="10" exclude_self="%3"/>
  <sensor name="enc" type="encoder" joint="flag"/>
  <sensor name="where" type="pose" link="flag" rate="100"/>
  %4
</robot>)")
      .arg(height)
      .arg(pitch)
      .arg(excludeSelf ? "true" : "false")
      .arg(extra)
      .toStdString();
}

const LaserReading& scanOf(const World& w) {
  const int laser = w.robotModel(0).findSensor("laser");
  return std::get<LaserReading>(w.sensorSample(0, laser).value);
}

}  // namespace

class TestSensors : public QObject {
  Q_OBJECT

 private slots:
  // A wall whose face is 6 m ahead: beam a reads 6 / cos a while that is
  // within range, and no return beyond; the centre beam reads exactly 6.
  void laserWallAtSixMetres() {
    WorldFixture f;
    auto world = f.build(R"(<world name="w"><gravity xyz="0 0 0"/><terrain type="plane" xyz="0 0 -100"/>
      <object name="wall"><geom type="box" size="0.2 40 5" xyz="6.1 0 1"/></object>
      <robot name="s" file="robot.xml"/></world>)",
                         scannerRobot(1.0, 0));
    QVERIFY(world);
    stepFor(*world, 0.05);
    const LaserReading& scan = scanOf(*world);
    QCOMPARE(scan.ranges.size(), size_t{181});
    QVERIFY(std::abs(scan.ranges[90] - 6.0) < 1e-9);
    int hits = 0;
    for (size_t b = 0; b < scan.ranges.size(); ++b) {
      const double a = scan.angleMin + static_cast<double>(b) * scan.angleStep;
      const double expected = 6.0 / std::cos(a);
      if (std::cos(a) > 0 && expected <= 10) {
        QVERIFY2(std::abs(scan.ranges[b] - expected) < 1e-9, qPrintable(QString("beam %1").arg(b)));
        ++hits;
      } else {
        QVERIFY2(std::isinf(scan.ranges[b]), qPrintable(QString("beam %1: %2").arg(b).arg(scan.ranges[b])));
      }
    }
    QCOMPARE(hits, 107);  // |a| < acos(0.6) = 53.13 deg: beams -53..53
  }

  void laserTiltedOverFlatGround_data() {
    QTest::addColumn<bool>("heightfield");
    QTest::newRow("plane") << false;
    QTest::newRow("flat heightfield") << true;
  }
  // A scanner 1 m up pitched down 20 deg sees flat ground at
  // h / (sin(pitch) cos(a)) along beam a.
  void laserTiltedOverFlatGround() {
    QFETCH(bool, heightfield);
    WorldFixture f;
    f.write("flat.csv", "0.2,0.2,0.2\n0.2,0.2,0.2\n0.2,0.2,0.2\n");
    const std::string terrain = heightfield ? R"(<terrain type="heightfield" file="flat.csv" width="40" depth="40"/>)"
                                            : R"(<terrain type="plane" xyz="0 0 0.2"/>)";
    auto world = f.build(R"(<world name="w"><gravity xyz="0 0 0"/>)" + terrain +
                             R"(<robot name="s" file="robot.xml"/></world>)",
                         scannerRobot(1.2, 20));
    QVERIFY(world);
    stepFor(*world, 0.05);
    const LaserReading& scan = scanOf(*world);
    const double s = std::sin(degToRad(20));
    for (size_t b = 0; b < scan.ranges.size(); ++b) {
      const double a = scan.angleMin + static_cast<double>(b) * scan.angleStep;
      const double expected = 1.0 / (s * std::cos(a));
      if (std::cos(a) > 1e-9 && expected <= 10)
        QVERIFY2(std::abs(scan.ranges[b] - expected) < 1e-9,
                 qPrintable(QString("beam %1: %2 vs %3").arg(b).arg(scan.ranges[b]).arg(expected)));
      else
        QVERIFY(std::isinf(scan.ranges[b]));
    }
  }

  // A level scanner facing up a slope z = 0.1 (x + 10) hits it where the
  // beam's height meets the plane: t = (h - 0.1 (x0 + 10)) / (0.1 cos a).
  void laserSeesSlope() {
    WorldFixture f;
    // 3 x 3 samples over 20 m x 20 m, heights 0, 1, 2 m from west to east
    // (every row alike): the plane z = 0.1 (x + 10).
    f.write("slope.csv", "0,1,2\n0,1,2\n0,1,2\n");
    auto world = f.build(R"(<world name="w"><gravity xyz="0 0 0"/>
      <terrain type="heightfield" file="slope.csv" width="20" depth="20"/>
      <robot name="s" file="robot.xml"/></world>)",
                         scannerRobot(1.5, 0));
    QVERIFY(world);
    stepFor(*world, 0.05);
    const LaserReading& scan = scanOf(*world);
    for (size_t b = 0; b < scan.ranges.size(); ++b) {
      const double a = scan.angleMin + static_cast<double>(b) * scan.angleStep;
      const double t = (1.5 - 0.1 * 10) / (0.1 * std::cos(a));
      const double y = t * std::sin(a);
      if (std::cos(a) > 1e-9 && t <= 10 && std::abs(y) <= 10)
        QVERIFY2(std::abs(scan.ranges[b] - t) < 1e-9, qPrintable(QString("beam %1").arg(b)));
    }
    QVERIFY(std::abs(scan.ranges[90] - 5.0) < 1e-9);
  }

  // Beams pass through the scanner's own robot unless told not to.
  void laserSelfExclusion() {
    for (const bool exclude : {true, false}) {
      WorldFixture f;
      auto world = f.build(R"(<world name="w"><gravity xyz="0 0 0"/><terrain type="plane" xyz="0 0 -100"/>
        <robot name="s" file="robot.xml"/></world>)",
                           scannerRobot(1.0, 0, "", exclude));
      QVERIFY(world);
      stepFor(*world, 0.05);
      // The flag's near face is 0.25 m ahead of the scanner.
      const double centre = scanOf(*world).ranges[90];
      if (exclude) QVERIFY(std::isinf(centre));
      else QVERIFY2(std::abs(centre - 0.25) < 1e-9, qPrintable(QString::number(centre)));
    }
  }

  // Encoders and pose sensors read the joint and the link as they are.
  void encoderAndPose() {
    WorldFixture f;
    auto world = f.build(R"(<world name="w"><gravity xyz="0 0 0"/><terrain type="plane"/>
      <robot name="s" file="robot.xml"/></world>)",
                         scannerRobot(1.0, 0, R"(<actuator name="flag" joint="flag" max_torque="10" max_velocity="30"/>)"));
    QVERIFY(world);
    QCOMPARE(world->submit(JointVelocityCmd{"flag", degToRad(30)}), std::string());
    stepFor(*world, 1.0);
    const auto& enc = std::get<EncoderReading>(world->sensorSample(0, 1).value);
    QCOMPARE(enc.position, world->jointPosition(0, 1));
    QCOMPARE(enc.velocity, world->jointRate(0, 1));
    QVERIFY(std::abs(enc.velocity - degToRad(30)) < 1e-3);
    const auto& pose = std::get<PoseReading>(world->sensorSample(0, 2).value);
    QCOMPARE(pose.pose, world->linkPose(0, 1));
  }

  // Each sensor samples at its own rate: over 1 s at the default step, the
  // 20 Hz laser samples 20 times, the 100 Hz pose 100 times, the encoder
  // (rate 0) every step.
  void ratesAreKept() {
    WorldFixture f;
    auto world = f.build(R"(<world name="w"><gravity xyz="0 0 0"/><terrain type="plane"/>
      <robot name="s" file="robot.xml"/></world>)",
                         scannerRobot(1.0, 0));
    QVERIFY(world);
    int counts[3] = {0, 0, 0};
    for (int64_t i = 0; i < sp::test::stepAt(1.0); ++i) {  // one second
      world->step();
      for (const auto& [robot, sensor] : world->sampledLastStep()) ++counts[sensor];
    }
    QCOMPARE(counts[0], 20);
    QCOMPARE(counts[1], static_cast<int>(sp::test::stepAt(1.0)));  // every step
    QCOMPARE(counts[2], 100);
    QCOMPARE(world->sensorSample(0, 0).step, sp::test::stepAt(1.0));
  }

  // Noise is seeded by the world: the same seed gives the same readings,
  // another seed others, and the spread matches the sigma.
  void seededNoise() {
    auto readings = [](uint64_t seed) {
      WorldFixture f;
      SimParams params;
      params.seed = seed;
      auto world = f.build(R"(<world name="w"><gravity xyz="0 0 0"/><terrain type="plane"/>
        <robot name="s" file="robot.xml"/></world>)",
                           QString::fromStdString(scannerRobot(1.0, 0))
                               .replace(R"(<sensor name="enc" type="encoder" joint="flag"/>)",
                                        R"(<sensor name="enc" type="encoder" joint="flag" noise="0.01"/>)")
                               .toStdString(),
                           params);
      std::vector<double> values;
      for (int i = 0; i < 4000; ++i) {
        world->step();
        values.push_back(std::get<EncoderReading>(world->sensorSample(0, 1).value).position);
      }
      return values;
    };
    const auto a = readings(7), b = readings(7), c = readings(8);
    QCOMPARE(a, b);
    QVERIFY(a != c);
    double sum = 0, sq = 0;
    for (double v : a) {
      sum += v;
      sq += v * v;
    }
    const double mean = sum / static_cast<double>(a.size());
    const double sigma = std::sqrt(sq / static_cast<double>(a.size()) - mean * mean);
    QVERIFY2(std::abs(mean) < 0.001 && std::abs(sigma - 0.01) < 0.0008,
             qPrintable(QString("mean %1 sigma %2").arg(mean).arg(sigma)));
  }

  // A joint holding a 20 kg arm level carries its weight: the force on the
  // arm from the joint is m g upwards.
  void jointForceCarriesWeight() {
    WorldFixture f;
    auto world = f.build(R"(<world name="w"><terrain type="plane"/><robot name="arm" file="robot.xml"/></world>)",
                         R"(<robot name="arm">
      <link name="base" mass="50" xyz="0 0 2"><geom type="box" size="0.3 0.3 0.3"/></link>
      <link name="arm" mass="20" xyz="0.55 0 2"><geom type="box" size="1.0 0.1 0.1"/></link>
      <joint name="fix" type="fixed" parent="world" child="base"/>
      <joint name="shoulder" type="hinge" parent="base" child="arm" xyz="0.05 0 2" axis="0 1 0"/>
      <actuator name="shoulder" joint="shoulder" mode="position" kp="10" ki="2" max_torque="500" max_velocity="90"/>
      <sensor name="f" type="joint_force" joint="shoulder"/>
    </robot>)");
    QVERIFY(world);
    stepFor(*world, 3.0);
    const auto& jf = std::get<JointForceReading>(world->sensorSample(0, 0).value);
    QVERIFY2(std::abs(jf.force.z - 20 * 9.81) < 0.5, qPrintable(QString::number(jf.force.z)));
    QVERIFY(std::abs(jf.force.x) < 0.5 && std::abs(jf.force.y) < 0.5);
  }

  // WorkPartner at rest: its four wheels carry its whole weight, the front
  // pair more than the rear (the torso sits on the front half); the IMU
  // reads +g up and no rotation.
  void workPartnerAtRest() {
    Diagnostics diag;
    auto model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    QVERIFY(model);
    auto world = World::create(*model, SimParams{}, diag);
    stepFor(*world, 2.0);
    const RobotModel& robot = world->robotModel(0);
    // Average the 100 Hz readings over 1 s: the quick solver's contact
    // forces jitter from step to step (each reading already averages 10).
    double wheels[4] = {0, 0, 0, 0};
    Vec3 total;
    const char* names[4] = {"force_fl", "force_fr", "force_rl", "force_rr"};
    const int samples = 100;
    Vec3 specificForce;
    for (int k = 0; k < samples; ++k) {
      stepFor(*world, 0.01);
      specificForce = specificForce +
                      (1.0 / samples) * std::get<ImuReading>(world->sensorSample(0, robot.findSensor("imu")).value).acceleration;
      for (int i = 0; i < 4; ++i) {
        const auto& w = std::get<WheelForceReading>(world->sensorSample(0, robot.findSensor(names[i])).value);
        QCOMPARE(w.contacts, 1);  // a tyre on a plane: one patch point (docs/formats.md, <drive>)
        wheels[i] += w.normal / samples;
        total = total + (1.0 / samples) * w.force;
      }
    }
    // Equilibrium: the ground's forces add up to the weight, straight up.
    // (Single wheels keep some sideways preload from settling, held by
    // static friction; it cancels between them.)
    QVERIFY2(std::hypot(total.x, total.y) < 0.01 * total.z,
             qPrintable(QString("horizontal %1, %2 N").arg(total.x).arg(total.y)));
    const double weight = robot.totalMass() * 9.81;
    const double sum = wheels[0] + wheels[1] + wheels[2] + wheels[3];
    QVERIFY2(std::abs(sum - weight) / weight < 0.01, qPrintable(QString("%1 vs %2").arg(sum).arg(weight)));
    QVERIFY(wheels[0] + wheels[1] > 1.1 * (wheels[2] + wheels[3]));
    const auto& imu = std::get<ImuReading>(world->sensorSample(0, robot.findSensor("imu")).value);
    QVERIFY2(std::abs(specificForce.z - 9.81) < 0.02 && std::hypot(specificForce.x, specificForce.y) < 0.02,
             qPrintable(QString("%1 %2 %3").arg(specificForce.x).arg(specificForce.y).arg(specificForce.z)));
    QVERIFY(std::abs(imu.roll) < 0.01 && std::abs(imu.pitch) < 0.01);
    QVERIFY(norm(imu.angularRate) < 0.01);
  }
};

QTEST_GUILESS_MAIN(TestSensors)
#include "tst_sensors.moc"
