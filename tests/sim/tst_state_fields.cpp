// The state fields listed once (sim/state_fields.h): what the state hash
// takes is what the list marks hashed, and nothing else.

#include <QTest>

#include "sim/model_loader.h"
#include "sim/state_fields.h"
#include "sim/world.h"

using namespace sp;

namespace {

// Counts the fields a visitor sees, hashed and not.
struct Count {
  int hashed = 0, unhashed = 0, pairs = 0;
  template <class T, bool H>
  void operator()(const T&, std::bool_constant<H>) {
    (H ? hashed : unhashed) += 1;
  }
  // The motion resistance pair is a field of its own kind (hashed where non-zero).
  void resistance(const std::vector<double>&, const std::vector<double>&, const std::vector<double>&) { ++pairs; }
};

std::unique_ptr<World> drivingWorld() {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
  if (!model) qFatal("%s", diag.format().c_str());
  auto world = World::create(*model, SimParams{}, diag);
  if (!world) qFatal("%s", diag.format().c_str());
  world->submit(DriveCmd{0.5, 0.1});
  for (int i = 0; i < 300; ++i) world->step();
  return world;
}

}  // namespace

class TestStateFields : public QObject {
  Q_OBJECT

 private slots:
  // The lists have the fields the structs have, hashed as documented.
  void listsCoverTheStructs() {
    Count body, actuator, control, sensor;
    const BodyState b;
    const ActuatorState a;
    const RobotControlState rc;
    const SensorState ss;
    visitState(b, body);
    visitState(a, actuator);
    visitState(rc, control);
    visitState(ss, sensor);
    QCOMPARE(body.hashed, 4);
    QCOMPARE(body.unhashed, 0);
    QCOMPARE(actuator.hashed, 5);
    QCOMPARE(control.hashed, 8);
    QCOMPARE(control.pairs, 1);
    QCOMPARE(sensor.hashed, 3);
    QCOMPARE(sensor.unhashed, 4);
  }

  // A snapshot restored with one hashed field changed hashes differently;
  // with an unhashed field (a sensor's last reading) changed, the same.
  void hashTakesTheHashedFields() {
    auto world = drivingWorld();
    const Snapshot s = world->snapshot();
    const uint64_t hash = world->stateHash();
    QCOMPARE(world->restore(s), std::string());
    QCOMPARE(world->stateHash(), hash);  // control: restoring alone changes nothing

    Snapshot integral = s;
    integral.robots[0].actuators[0].integral += 1e-9;
    QCOMPARE(world->restore(integral), std::string());
    QVERIFY(world->stateHash() != hash);

    Snapshot summed = s;
    summed.sensors[0][0].stepsSummed += 1;
    QCOMPARE(world->restore(summed), std::string());
    QVERIFY(world->stateHash() != hash);

    Snapshot lastReading = s;
    lastReading.sensors[0][0].lastVelocity.x += 1;
    lastReading.sensors[0][0].contactSum += 3;
    QCOMPARE(world->restore(lastReading), std::string());
    QCOMPARE(world->stateHash(), hash);
  }
};

QTEST_GUILESS_MAIN(TestStateFields)
#include "tst_state_fields.moc"
