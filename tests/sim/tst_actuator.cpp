// The actuator control law alone, without ODE: modes, limits, PID wind-up.

#include <QTest>

#include "sim/actuator.h"

using namespace sp;

namespace {
ActuatorSpec pidSpec() {
  ActuatorSpec s;
  s.maxTorque = 100;
  s.maxVelocity = 2;
  s.hasPid = true;
  s.kp = 4;
  s.ki = 1;
  s.kd = 0.5;
  return s;
}
}  // namespace

class TestActuator : public QObject {
  Q_OBJECT

 private slots:
  // Velocity mode passes the set-point to the motor, clamped to the limit.
  void velocityModeClampsSpeed() {
    ActuatorSpec spec = pidSpec();
    ActuatorState s;
    s.mode = JointMode::Velocity;
    s.velocity = 5;
    const ActuatorOutput out = updateActuator(spec, s, 0, 0, 0.001);
    QCOMPARE(out.motorVelocity, 2.0);
    QCOMPARE(out.motorMaxForce, 100.0);
    QCOMPARE(out.torque, 0.0);
  }

  // Torque mode turns the motor off and clamps the torque; free does nothing.
  void torqueAndFreeModes() {
    ActuatorSpec spec = pidSpec();
    ActuatorState s;
    s.mode = JointMode::Torque;
    s.torque = -250;
    ActuatorOutput out = updateActuator(spec, s, 0, 0, 0.001);
    QCOMPARE(out.torque, -100.0);
    QCOMPARE(out.motorMaxForce, 0.0);
    s.mode = JointMode::Free;
    out = updateActuator(spec, s, 0, 0, 0.001);
    QCOMPARE(out.torque, 0.0);
    QCOMPARE(out.motorMaxForce, 0.0);
  }

  // The PID output is kp e + ki integral - kd rate (derivative on the
  // measurement), while unsaturated.
  void pidLaw() {
    ActuatorSpec spec = pidSpec();
    ActuatorState s;
    s.mode = JointMode::Position;
    s.target = 0.1;
    const ActuatorOutput out = updateActuator(spec, s, 0.0, 0.2, 0.01);
    QCOMPARE(s.integral, 0.001);
    QVERIFY(std::abs(out.motorVelocity - (4 * 0.1 + 1 * 0.001 - 0.5 * 0.2)) < 1e-15);
  }

  // While the output saturates, the integral does not grow (no wind-up),
  // and it never exceeds max_velocity / ki.
  void pidAntiWindup() {
    ActuatorSpec spec = pidSpec();
    ActuatorState s;
    s.mode = JointMode::Position;
    s.target = 10;  // far away: saturated
    for (int i = 0; i < 1000; ++i) {
      const ActuatorOutput out = updateActuator(spec, s, 0, 0, 0.01);
      QCOMPARE(out.motorVelocity, 2.0);
    }
    QCOMPARE(s.integral, 0.0);
    spec.kp = 0.01;  // unsaturated by kp, so the integral clamp is what limits
    for (int i = 0; i < 100000; ++i) updateActuator(spec, s, 9.9, 0, 0.01);
    QVERIFY(s.integral <= spec.maxVelocity / spec.ki + 1e-12);
  }

  void wrap_data() {
    QTest::addColumn<double>("in");
    QTest::addColumn<double>("out");
    QTest::newRow("inside") << 1.0 << 1.0;
    QTest::newRow("pi stays") << kPi << kPi;
    QTest::newRow("-pi becomes pi") << -kPi << kPi;
    QTest::newRow("340 deg") << degToRad(340) << degToRad(-20);
    QTest::newRow("-3 turns + 10 deg") << degToRad(-1080 + 10) << degToRad(10);
  }
  // Angle wrap of continuous joints lands in (-pi, pi].
  void wrap() {
    QFETCH(double, in);
    QFETCH(double, out);
    QVERIFY(std::abs(wrapAngle(in) - out) < 1e-12);
  }
};

QTEST_GUILESS_MAIN(TestActuator)
#include "tst_actuator.moc"
