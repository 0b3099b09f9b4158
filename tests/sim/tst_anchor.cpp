// Re-anchoring a twin from what a robot reports (sim/kinematics.h
// linkMotions, World::setRobotMotion): the state rebuilt from base pose and
// twist and joint positions and rates, against the twin's own, link by
// link; and the prediction error it causes.

#include <QTest>

#include <algorithm>
#include <cmath>

#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/world.h"

using namespace sp;

namespace {

std::unique_ptr<World> makeWorld(const char* file) {
  Diagnostics diag;
  auto model = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/" + file, diag);
  if (!model) qFatal("%s", diag.format().c_str());
  return World::create(*model, SimParams{}, diag);
}

void run(World& world, double seconds) {
  const auto n = std::llround(seconds / world.params().step);
  for (int64_t i = 0; i < n; ++i) world.step();
}

double angleBetween(const Quat& a, const Quat& b) {
  const double d = std::abs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
  return 2 * std::acos(std::min(1.0, d));
}

// The motions a report gives: base pose and twist, joint positions and rates.
std::vector<LinkMotion> fromReport(const World& world, bool withRates = true) {
  const RobotReadout r = readRobot(world);
  std::vector<double> rates = r.jointRates;
  if (!withRates) std::fill(rates.begin(), rates.end(), 0.0);
  return linkMotions(world.robotModel(0), r.base, withRates ? r.baseLinearVelocity : Vec3{},
                     withRates ? r.baseAngularVelocity : Vec3{}, r.jointPositions, rates);
}

// The robot driving and turning with its arms moving: every joint type and
// the articulation in play.
void driveAndWave(World& world) {
  world.submit(DriveCmd{0.5, degToRad(12)});
  world.submit(JointTargetCmd{"elbow_l", degToRad(40)});
  world.submit(JointTargetCmd{"shoulder_pitch_r", degToRad(-30)});
}

}  // namespace

class TestAnchor : public QObject {
  Q_OBJECT

 private slots:
  // Link by link, the rebuilt poses match the twin's own within a
  // millimetre; the rebuilt angular velocities differ from the twin's only by
  // its joints' constraint error (the quick stepper lets joints wobble off
  // their axes by up to 0.3 rad/s, which no report carries): several times
  // less than a rebuild that ignores the reported rates (the control).
  void reconstructionMatchesTheTwin() {
    auto world = makeWorld("flat.world.xml");
    driveAndWave(*world);
    run(*world, 2.0);
    struct Worst {
      double pos = 0, ang = 0, lin = 0, rot = 0;
    };
    const auto compare = [&](bool withRates) {
      const std::vector<LinkMotion> rebuilt = fromReport(*world, withRates);
      Worst w;
      for (size_t l = 1; l < rebuilt.size(); ++l) {
        const int link = static_cast<int>(l);
        const Pose truth = world->linkPose(0, link);
        w.pos = std::max(w.pos, norm(rebuilt[l].pose.p - truth.p));
        w.ang = std::max(w.ang, angleBetween(rebuilt[l].pose.q, truth.q));
        // Relative to the base, so the control differs only in the joints.
        const Vec3 baseLin = world->linkLinearVelocity(0, 0), baseRot = world->linkAngularVelocity(0, 0);
        const Vec3 relTrue = world->linkAngularVelocity(0, link) - baseRot;
        const Vec3 relRebuilt = rebuilt[l].angular - rebuilt[0].angular;
        w.rot = std::max(w.rot, norm(relRebuilt - relTrue));
        const Vec3 linTrue = world->linkLinearVelocity(0, link) - baseLin - cross(baseRot, truth.p - world->linkPose(0, 0).p);
        const Vec3 linRebuilt = rebuilt[l].linear - rebuilt[0].linear - cross(rebuilt[0].angular, rebuilt[l].pose.p - rebuilt[0].pose.p);
        w.lin = std::max(w.lin, norm(linRebuilt - linTrue));
      }
      return w;
    };
    const Worst with = compare(true), without = compare(false);
    qInfo("worst link: position %.2e m, orientation %.2e rad; twist relative to the base: linear %.3f m/s, "
          "angular %.3f rad/s (rates ignored: %.3f m/s, %.3f rad/s)",
          with.pos, with.ang, with.lin, with.rot, without.lin, without.rot);
    QVERIFY(with.pos < 2e-3);
    QVERIFY(with.ang < 5e-3);
    QVERIFY(with.rot < without.rot / 5);
    // The linear part is printed, not judged: there the joints' wobble
    // (cm/s) is larger than what the slowly moving joints contribute.
  }

  // A fresh twin anchored from the report at 2 s, given the same commands,
  // follows the original for 3 s more within a few centimetres; anchored
  // from poses alone (twist and rates zero) it does not: the twist matters.
  void anchoredTwinPredicts() {
    auto truth = makeWorld("flat.world.xml");
    driveAndWave(*truth);
    run(*truth, 2.0);
    const auto errorAfter = [&](bool withRates) {
      auto ghost = makeWorld("flat.world.xml");
      driveAndWave(*ghost);
      ghost->step();  // the commands take effect
      const std::string error = ghost->setRobotMotion(0, fromReport(*truth, withRates));
      if (!error.empty()) qFatal("%s", error.c_str());
      auto copy = makeWorld("flat.world.xml");
      copy->restore(truth->snapshot());
      run(*copy, 3.0);
      run(*ghost, 3.0);
      const Pose a = copy->linkPose(0, 0), b = ghost->linkPose(0, 0);
      return std::hypot(a.p.x - b.p.x, a.p.y - b.p.y);
    };
    const double anchored = errorAfter(true), posesOnly = errorAfter(false);
    qInfo("base position error after 3 s: anchored %.4f m, from poses alone %.4f m", anchored, posesOnly);
    QVERIFY(anchored < 0.03);
    QVERIFY(posesOnly > 2 * anchored);  // the control
  }

  // Bad input changes nothing and says why.
  void badInputRefused() {
    auto world = makeWorld("flat.world.xml");
    const uint64_t before = world->stateHash();
    QCOMPARE(QString::fromStdString(world->setRobotMotion(0, {})), QString("expected 28 links, got 0"));
    std::vector<LinkMotion> motions = fromReport(*world);
    motions[3].linear.x = std::nan("");
    QCOMPARE(QString::fromStdString(world->setRobotMotion(0, motions)), QString("a link's pose or velocity is not finite"));
    QCOMPARE(QString::fromStdString(world->setRobotMotion(1, motions)), QString("no robot 1"));
    QCOMPARE(world->stateHash(), before);
  }
};

QTEST_GUILESS_MAIN(TestAnchor)
#include "tst_anchor.moc"
