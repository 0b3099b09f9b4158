// A robot that is not its twin (sim/perturbation.h): the deviations are
// drawn from the seed alone, within their ranges, applied where the physics
// feels them, and they change what the robot does.

#include <QTest>

#include <cmath>

#include "sim/model_loader.h"
#include "sim/perturbation.h"
#include "sim/readout.h"
#include "sim/world.h"

using namespace sp;

namespace {

WorldModel flat() {
  Diagnostics diag;
  std::optional<WorldModel> w = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
  if (!w) qFatal("%s", diag.format().c_str());
  return *w;
}

// The rate of wheel joint `wheel` (0..3) after `seconds` of `omega` rad/s.
double wheelRateAfter(const WorldModel& model, double omega, double seconds, int wheel) {
  Diagnostics diag;
  auto world = World::create(model, SimParams{}, diag);
  if (!world) qFatal("%s", diag.format().c_str());
  world->submit(WheelsCmd{{omega, omega, omega, omega}});
  // The mean over the last half second: on its compliant tyres the body
  // rocks by a few tenths of a degree, which the joint's rate (wheel
  // against shank) carries as a +-1.5 % ripple the motor does not make.
  const int steps = static_cast<int>(seconds / world->params().step), window = static_cast<int>(0.5 / world->params().step);
  const size_t joint = static_cast<size_t>(model.robots[0].model.drive->wheels[static_cast<size_t>(wheel)]);
  double sum = 0;
  for (int i = 0; i < steps; ++i) {
    world->step();
    if (i >= steps - window) sum += readRobot(*world).jointRates[joint];
  }
  return sum / window;
}

}  // namespace

class TestPerturbation : public QObject {
  Q_OBJECT

 private slots:
  // The same seed draws the same robot; another seed another.
  void seedAlone() {
    const RobotModel robot = flat().robots[0].model;
    QCOMPARE(drawPerturbation(7, robot).report(robot), drawPerturbation(7, robot).report(robot));
    QVERIFY(drawPerturbation(7, robot).report(robot) != drawPerturbation(8, robot).report(robot));
  }

  // Over 300 seeds every deviation stays within its range and uses it
  // (the extremes reach 80 % of it: not a degenerate draw).
  void withinTheRanges() {
    const RobotModel robot = flat().robots[0].model;
    const PerturbationRanges r;
    double wheelMin = 2, wheelMax = 0, massMin = 2, massMax = 0, comMax = 0, delayMax = 0, biasMax = 0, frictionMin = 2,
           frictionMax = 0;
    for (uint64_t seed = 1; seed <= 300; ++seed) {
      const Perturbation p = drawPerturbation(seed, robot);
      QCOMPARE(p.linkMass.size(), robot.links.size());
      for (double w : p.wheelRadius) wheelMin = std::min(wheelMin, w), wheelMax = std::max(wheelMax, w);
      for (double m : p.linkMass) massMin = std::min(massMin, m), massMax = std::max(massMax, m);
      for (const Vec3& c : p.centreOfMass) comMax = std::max({comMax, std::abs(c.x), std::abs(c.y), std::abs(c.z)});
      frictionMin = std::min(frictionMin, p.friction), frictionMax = std::max(frictionMax, p.friction);
      QVERIFY(std::abs(p.torqueLimit - 1) <= r.torqueLimit && std::abs(p.velocityGain - 1) <= r.velocityGain);
      QVERIFY(p.delay >= 0);
      delayMax = std::max(delayMax, p.delay);
      biasMax = std::max({biasMax, std::abs(p.rollBias), std::abs(p.pitchBias)});
    }
    QVERIFY(wheelMin >= 1 - r.wheelRadius && wheelMax <= 1 + r.wheelRadius);
    QVERIFY(wheelMin < 1 - 0.8 * r.wheelRadius && wheelMax > 1 + 0.8 * r.wheelRadius);
    QVERIFY(massMin >= 1 - r.mass && massMax <= 1 + r.mass && massMin < 1 - 0.8 * r.mass && massMax > 1 + 0.8 * r.mass);
    QVERIFY(comMax <= r.centreOfMass && comMax > 0.8 * r.centreOfMass);
    QVERIFY(frictionMin >= 1 - r.friction && frictionMax <= 1 + r.friction);
    QVERIFY(delayMax <= r.maxDelay && delayMax > 0.8 * r.maxDelay);
    QVERIFY(biasMax <= r.imuBias && biasMax > 0.8 * r.imuBias);
  }

  // Applied where the physics feels it: the wheels' round geoms, the link
  // masses and centres of mass, every contact's friction, the wheel motors;
  // the drive's nominal radius (what the controller believes) is unchanged.
  void appliedToTheModel() {
    const WorldModel files = flat();
    const RobotModel& robot = files.robots[0].model;
    const Perturbation p = drawPerturbation(11, robot);
    const WorldModel w = perturbWorld(files, p);
    const RobotModel& perturbed = w.robots[0].model;
    QCOMPARE(perturbed.drive->wheelRadius, robot.drive->wheelRadius);
    for (size_t k = 0; k < 4; ++k) {
      const int joint = robot.drive->wheels[k];
      const size_t link = static_cast<size_t>(robot.joints[static_cast<size_t>(joint)].child);
      for (size_t g = 0; g < robot.links[link].geoms.size(); ++g)
        if (robot.links[link].geoms[g].type == GeomType::Cylinder)
          QCOMPARE(perturbed.links[link].geoms[g].radius, robot.links[link].geoms[g].radius * p.wheelRadius[k]);
      for (size_t a = 0; a < robot.actuators.size(); ++a)
        if (robot.actuators[a].joint == joint) {
          QCOMPARE(perturbed.actuators[a].maxTorque, robot.actuators[a].maxTorque * p.torqueLimit);
          QCOMPARE(perturbed.actuators[a].velocityScale, p.velocityGain);
        }
    }
    for (size_t i = 0; i < robot.links.size(); ++i) {
      QCOMPARE(perturbed.links[i].mass, robot.links[i].mass * p.linkMass[i]);
      QCOMPARE(perturbed.links[i].centreOfMassShift.x, p.centreOfMass[i].x);
    }
    QCOMPARE(w.defaultContact.mu, files.defaultContact.mu * p.friction);
  }

  // A weak motor: one wheel's torque limit times its factor, on top of the
  // seed's; the others and the seed's draws stay (control: no factor, the
  // seed's limit alone). Bad text is refused naming it.
  void weakMotorScalesOneWheel() {
    const WorldModel files = flat();
    const RobotModel& robot = files.robots[0].model;
    Perturbation p = drawPerturbation(11, robot);
    const Perturbation drawn = p;
    QCOMPARE(parseWeakMotor("rl=0.5", p), std::string());
    QCOMPARE(p.torqueLimit, drawn.torqueLimit);
    const WorldModel w = perturbWorld(files, p);
    for (size_t k = 0; k < 4; ++k)
      for (size_t a = 0; a < robot.actuators.size(); ++a)
        if (robot.actuators[a].joint == robot.drive->wheels[k])
          QCOMPARE(w.robots[0].model.actuators[a].maxTorque, robot.actuators[a].maxTorque * p.torqueLimit * (k == 2 ? 0.5 : 1.0));
    QVERIFY(p.report(robot).find("wheel_torque_limit.rl = 0.5\n") != std::string::npos);
    QVERIFY(drawn.report(robot).find("wheel_torque_limit.rl") == std::string::npos);
    for (const char* bad : {"rl", "rear=0.5", "rl=0", "rl=3", "rl=x", "=0.5"}) {
      Perturbation q;
      const std::string why = parseWeakMotor(bad, q);
      QVERIFY2(why.find(std::string("'") + bad + "'") == 0, why.c_str());
      QCOMPARE(q.wheelTorque, (std::array<double, 4>{1, 1, 1, 1}));
    }
  }

  // A sudden change parsed from T,FRICTION,DELAY; what cannot be is
  // refused naming the text and the field, and leaves the change alone.
  void suddenChangeParsed() {
    SuddenChange c;
    QCOMPARE(parseSuddenChange("30,0.7,0.1", c), std::string());
    QCOMPARE(c.at, 30.0);
    QCOMPARE(c.friction, 0.7);
    QCOMPARE(c.delay, 0.1);
    QCOMPARE(c.describe(), std::string("friction x0.7, delay +0.1 s at 30 s"));
    for (const auto& [bad, why] : {std::pair{"30,0,0.1", "friction factor 0: must be > 0"},
                                   std::pair{"30,0.7,-1", "delay -1 s: must be >= 0"},
                                   std::pair{"-1,0.7,0", "at -1 s: must be >= 0"},
                                   std::pair{"30,0.7", "a change is T,FRICTION,DELAY"},
                                   std::pair{"30,0.7,0.1,4", "a change is T,FRICTION,DELAY"},
                                   std::pair{"30,x,0.1", "a change is T,FRICTION,DELAY"}}) {
      SuddenChange d;
      const std::string got = parseSuddenChange(bad, d);
      QVERIFY2(got.find(std::string("'") + bad + "': ") == 0 && got.find(why) != std::string::npos, got.c_str());
      QCOMPARE(d.at, 0.0);
      QCOMPARE(d.friction, 1.0);
    }
  }

  // The robot feels it: its wheels turn (mean over 1-1.5 s) at gain x the commanded speed
  // (within 3 %: its torque limit is perturbed too); control: the twin of
  // the files turns them at the commanded speed within 1 %.
  void theRobotFeelsIt() {
    const WorldModel files = flat();
    const Perturbation p = drawPerturbation(11, files.robots[0].model);
    const WorldModel w = perturbWorld(files, p);
    const double twin = wheelRateAfter(files, 2.0, 1.5, 0);
    const double robot = wheelRateAfter(w, 2.0, 1.5, 0);
    qInfo("wheel FL after 1.5 s at 2 rad/s: twin %.4f, perturbed robot %.4f rad/s (gain %.4f)", twin, robot,
          p.velocityGain);
    QVERIFY(std::abs(twin - 2.0) < 0.02);
    QVERIFY(std::abs(robot - 2.0 * p.velocityGain) < 0.03 * 2.0 * p.velocityGain);
    QVERIFY(std::abs(robot - twin) > 0.05);  // the deviation is felt
  }
};

QTEST_GUILESS_MAIN(TestPerturbation)
#include "tst_perturbation.moc"
