// Tests of sp::readRobot (sim/readout.h): the one read-out of a robot's
// state that telemetry, the session log and validation share.

#include <QTest>

#include <memory>

#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/runner.h"
#include "sim/world.h"

using namespace sp;

namespace {

std::unique_ptr<World> load(const std::string& file, SimParams params = {}) {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(file, diag);
  if (!model) {
    qWarning("%s", diag.format().c_str());
    return nullptr;
  }
  return World::create(*model, params, diag);
}

}  // namespace

class TestReadout : public QObject {
  Q_OBJECT

 private slots:
  // The read-out holds exactly what the World reports, field by field.
  void matchesTheWorld() {
    auto world = load("terrains/flat.world.xml");
    QVERIFY(world);
    Runner runner(*world);
    runner.schedule({{0.0, DriveCmd{0.6, degToRad(15)}, 1}});
    runner.advanceToTime(1.0);
    const RobotReadout r = readRobot(*world);
    QCOMPARE(r.step, world->stepCount());
    QCOMPARE(r.time, world->time());
    QCOMPARE(r.base, world->linkPose(0, 0));
    QCOMPARE(r.baseLinearVelocity, world->linkLinearVelocity(0, 0));
    QCOMPARE(r.baseAngularVelocity, world->linkAngularVelocity(0, 0));
    const RobotModel& robot = world->robotModel(0);
    QCOMPARE(r.jointPositions.size(), robot.joints.size());
    for (size_t j = 0; j < robot.joints.size(); ++j) {
      QCOMPARE(r.jointPositions[j], world->jointPosition(0, static_cast<int>(j)));
      QCOMPARE(r.jointRates[j], world->jointRate(0, static_cast<int>(j)));
    }
    // Moving: a twist that is not zero (so the comparison above means something).
    QVERIFY(norm(r.baseLinearVelocity) > 0.3);
    QVERIFY(std::abs(r.baseAngularVelocity.z) > 0.05);
    QVERIFY(r.health.empty());
  }

  // Wheel forces come from the wheel_force sensors in model order and the
  // inclination from the first IMU.
  void sensorsInModelOrder() {
    auto world = load("terrains/flat.world.xml");
    QVERIFY(world);
    Runner(*world).advanceToTime(1.0);
    const RobotReadout r = readRobot(*world);
    const RobotModel& robot = world->robotModel(0);
    size_t wheel = 0;
    bool imuSeen = false;
    for (size_t i = 0; i < robot.sensors.size(); ++i) {
      const SensorValue& v = world->sensorSample(0, static_cast<int>(i)).value;
      if (robot.sensors[i].type == SensorType::WheelForce && wheel < 4) {
        QCOMPARE(r.wheelNormal[wheel], std::get<WheelForceReading>(v).normal);
        QCOMPARE(r.wheelTangential[wheel], std::get<WheelForceReading>(v).tangential);
        ++wheel;
      } else if (robot.sensors[i].type == SensorType::Imu && !imuSeen) {
        imuSeen = true;
        QCOMPARE(r.roll, std::get<ImuReading>(v).roll);
        QCOMPARE(r.pitch, std::get<ImuReading>(v).pitch);
      }
    }
    QCOMPARE(wheel, size_t{4});
    QVERIFY(r.hasImu);
    // Standing on four wheels: they carry the robot's weight together.
    const double sum = r.wheelNormal[0] + r.wheelNormal[1] + r.wheelNormal[2] + r.wheelNormal[3];
    QVERIFY2(std::abs(sum - robot.totalMass() * 9.81) < 0.25 * robot.totalMass() * 9.81, qPrintable(QString::number(sum)));
  }

  // Dynamic objects only, in model order, where the World has them.
  void dynamicObjectsOnly() {
    auto world = load("terrains/pick_place.world.xml");
    QVERIFY(world);
    world->step();
    const RobotReadout r = readRobot(*world);
    const std::vector<ObjectSpec>& objects = world->model().objects;
    std::vector<ObjectReadout> expected;
    for (size_t i = 0; i < objects.size(); ++i)
      if (!objects[i].isStatic) expected.push_back({objects[i].name, world->objectPose(static_cast<int>(i))});
    QVERIFY(!expected.empty());
    QVERIFY(expected.size() < objects.size());  // the cubes are static
    QCOMPARE(r.objects, expected);
  }

  // A diverged twin says so in the read-out.
  void healthMessage() {
    SimParams params;
    params.maxLinearSpeed = 0.05;
    auto world = load("terrains/flat.world.xml", params);
    QVERIFY(world);
    Runner runner(*world);
    runner.schedule({{0.0, DriveCmd{0.5, 0}, 1}});
    QCOMPARE(runner.advanceToTime(5).stop, RunOutcome::Stop::Diverged);
    QCOMPARE(readRobot(*world).health, world->health().message());
  }
};

QTEST_GUILESS_MAIN(TestReadout)
#include "tst_readout.moc"
