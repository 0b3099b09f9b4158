// Gait controllers alone: legs found from the <drive>, phase sequences,
// smooth hip targets, braced and free wheels, and the wheel keeping pace with
// a reaching foot.

#include <QTest>

#include <cmath>

#include "sim/gait.h"
#include "sim/model_loader.h"

using namespace sp;

class TestGait : public QObject {
  Q_OBJECT

 private slots:
  // WorkPartner's legs are found from its wheels: hip, knee, wheel per leg.
  void findsWorkPartnerLegs() {
    Diagnostics diag;
    auto robot = loadRobot(std::string(SP_SOURCE_DIR) + "/robots/workpartner.xml", diag);
    QVERIFY(robot);
    auto legs = findLegs(*robot);
    QVERIFY(legs);
    const char* names[4][3] = {{"hip_fl", "knee_fl", "wheel_fl"},
                               {"hip_fr", "knee_fr", "wheel_fr"},
                               {"hip_rl", "knee_rl", "wheel_rl"},
                               {"hip_rr", "knee_rr", "wheel_rr"}};
    for (int i = 0; i < 4; ++i) {
      QCOMPARE(robot->joints[(*legs)[i].hip].name, std::string(names[i][0]));
      QCOMPARE(robot->joints[(*legs)[i].knee].name, std::string(names[i][1]));
      QCOMPARE(robot->joints[(*legs)[i].wheel].name, std::string(names[i][2]));
    }
  }

  // Caterpillar: the two pairs alternate between bracing (braked) and
  // rolling (free), and the hips sweep smoothly between +-swing.
  void caterpillarAlternates() {
    SimParams p;
    GaitState s{Gait::Caterpillar, 0, 0};
    const double dt = 0.001, swing = degToRad(p.caterpillarHipSwing);
    const auto steps = std::llround(p.caterpillarPhaseTime / dt);
    double lastHip = swing;
    for (int64_t k = 0; k < 2 * steps; ++k) {
      const auto legs = gaitStep(p, s, k, dt, 0.6, 0.2);
      const bool firstHalf = k < steps;
      QCOMPARE(legs[0].wheel, firstHalf ? LegCommand::Wheel::Free : LegCommand::Wheel::Brake);
      QCOMPARE(legs[2].wheel, firstHalf ? LegCommand::Wheel::Brake : LegCommand::Wheel::Free);
      QCOMPARE(legs[0].hip, legs[1].hip);
      QCOMPARE(legs[2].hip, -legs[0].hip);
      QVERIFY(std::abs(legs[0].hip - lastHip) < 0.01);  // no jumps
      lastHip = legs[0].hip;
    }
    QVERIFY(std::abs(lastHip - swing) < 1e-3);  // back where it started after a cycle
  }

  // Rolking: one leg at a time in the order RL, FL, RR, FR, its wheel
  // driven at the foot's speed, the others free; then a braked body phase.
  void rolkingOrder() {
    SimParams p;
    GaitState s{Gait::Rolking, 0, 0};
    const double dt = 0.001;
    const int expected[4] = {2, 0, 3, 1};
    int64_t step = 0;
    for (int phase = 0; phase < 4; ++phase) {
      const auto legs = gaitStep(p, s, step + std::llround(p.rolkingLegTime / dt / 2), dt, 0.6, 0.2);
      for (int leg = 0; leg < 4; ++leg)
        QCOMPARE(legs[leg].wheel, leg == expected[phase] ? LegCommand::Wheel::Drive : LegCommand::Wheel::Free);
      // Mid-reach the hip moves fastest; the wheel matches the foot:
      // L cos(hip) |d hip/dt| / r with d hip/dt = swing * pi / T.
      const double rate = 2 * degToRad(p.rolkingHipSwing) * kPi / 2 / p.rolkingLegTime;
      QVERIFY(std::abs(legs[expected[phase]].wheelSpeed - 0.6 * rate / 0.2) < 1e-3);
      step += std::llround(p.rolkingLegTime / dt);
      gaitStep(p, s, step, dt, 0.6, 0.2);  // enter the next phase
    }
    const auto body = gaitStep(p, s, step + 10, dt, 0.6, 0.2);
    for (const LegCommand& leg : body) QCOMPARE(leg.wheel, LegCommand::Wheel::Brake);
  }
};

QTEST_GUILESS_MAIN(TestGait)
#include "tst_gait.moc"
