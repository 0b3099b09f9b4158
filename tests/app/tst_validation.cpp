// The founding paper's experiments in their quick versions, with the targets
// asserted (docs/validation/report.md has the full runs).

#include <QtTest>

#include <algorithm>
#include <cmath>
#include <vector>

#include "app/validation/validation.h"

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

// A copy of the ice world and the robot, the world's text without `cut`;
// returns the copy's source folder ("" on failure). The folder lives as long
// as the test process.
std::string makeCopyWithout(const std::string& sourceDir, const std::string& cut) {
  static QTemporaryDir dir;
  QFile world(QString::fromStdString(sourceDir + "/terrains/ice.world.xml"));
  if (!dir.isValid() || !world.open(QIODevice::ReadOnly)) return {};
  QString text = QString::fromUtf8(world.readAll());
  if (!text.contains(QString::fromStdString(cut))) return {};
  text.remove(QString::fromStdString(cut));
  QDir(dir.path()).mkpath("terrains");
  QDir(dir.path()).mkpath("robots");
  QFile out(dir.filePath("terrains/ice.world.xml"));
  if (!out.open(QIODevice::WriteOnly) || out.write(text.toUtf8()) < 0) return {};
  out.close();
  if (!QFile::copy(QString::fromStdString(sourceDir + "/robots/workpartner.xml"), dir.filePath("robots/workpartner.xml")))
    return {};
  return dir.path().toStdString();
}

// Every judged metric passes except the known failures (indices into
// r.metrics), which must fail: the report says why each does (issue 29:
// the paper's numbers judged before the physics meets them). A change that
// makes one pass, or another fail, shows here.
void verifyVerdicts(const ExperimentResult& r, const std::vector<size_t>& knownFailures = {}) {
  QVERIFY(!r.metrics.empty());
  QVERIFY(!r.plots.empty());
  for (size_t i = 0; i < r.metrics.size(); ++i) {
    const Metric& m = r.metrics[i];
    qInfo("%zu %s%s", i, m.judged ? (m.pass ? "pass " : "FAIL ") : "info ", qPrintable(describe(m)));
  }
  for (size_t i : knownFailures) {
    QVERIFY(i < r.metrics.size());
    QVERIFY2(r.metrics[i].judged && !r.metrics[i].pass, qPrintable("a known failure passed: " + describe(r.metrics[i])));
  }
  for (size_t i = 0; i < r.metrics.size(); ++i)
    if (std::find(knownFailures.begin(), knownFailures.end(), i) == knownFailures.end())
      QVERIFY2(!r.metrics[i].judged || r.metrics[i].pass, qPrintable(describe(r.metrics[i])));
}

void verifyAll(const ExperimentResult& r) { verifyVerdicts(r); }

}  // namespace

class TestValidation : public QObject {
  Q_OBJECT

 private slots:
  // 1. The hinge's path radius matches articulated-steering kinematics
  // within 0.5 % at 10, 20 and 30 degrees against the measured hinge angle.
  // Against the commanded angle (also judged, issue 29) it misses at 10
  // and 20 degrees today (known failures: -1.4 % at 10 degrees quick).
  void circularDrive() { verifyVerdicts(sp::circularDrive(quick()), {1, 3}); }

  // 2. One judged criterion: the range error against the commanded pose
  // grows linearly in time (R^2 >= 0.9), as the paper saw. It does not here
  // (it passes through zero at the wall's normal): a known failure, stated
  // in the report. Exact ranges against the true pose (tst_sensors tests
  // the ray caster), the angle error's linear growth (a velocity loop's
  // constant error) and the per-metre agreement of the walls (an identity)
  // cannot fail, so they are for the record only.
  void laserSweep() {
    const ExperimentResult r = sp::laserSweep(quick());
    QCOMPARE(r.metrics.size(), size_t{4});
    QCOMPARE(std::count_if(r.metrics.begin(), r.metrics.end(), [](const Metric& m) { return m.judged; }), 1);
    verifyVerdicts(r, {2});
  }

  // The laser's criteria can fail: a line through noise-free points is
  // R^2 = 1, a flat series with jitter is not growing; an error proportional
  // to the range agrees per metre at 3 and 9 m, a constant range bias
  // (not proportional) disagrees by 200 %.
  void laserCriteriaCanFail() {
    std::vector<double> t, line, flat, dA, dB, eA, eB, biasA, biasB;
    for (int i = 0; i < 100; ++i) {
      t.push_back(0.05 * i);
      line.push_back(-0.01 - 0.004 * t.back());
      flat.push_back(-0.02 + (i % 2 ? 0.001 : -0.001));
      const double phi = -0.7 + 0.014 * i;  // the beam's angle to the wall's normal
      dA.push_back(3 / std::cos(phi));
      dB.push_back(9 / std::cos(phi));
      eA.push_back(dA.back() * std::tan(phi) * 1e-3);
      eB.push_back(dB.back() * std::tan(phi) * 1e-3);
      biasA.push_back(0.002);
      biasB.push_back(0.002);
    }
    QVERIFY(std::abs(linearFit(t, line).r2 - 1) < 1e-12);
    QVERIFY(std::abs(linearFit(t, line).slope + 0.004) < 1e-12);
    QVERIFY(linearFit(t, flat).r2 < 0.95);  // control: no growth
    QVERIFY(proportionalityMismatch({t, dA, eA}, {t, dB, eB}, 0.5e-3) < 1e-9);
    const double bias = proportionalityMismatch({t, dA, biasA}, {t, dB, biasB}, 0.5e-3);
    QVERIFY2(bias > 1.9, qPrintable(QString::number(bias)));  // control: a constant bias is 200 % off
    // Samples missing from one series (a beam out of range) are skipped, not misaligned.
    std::vector<double> t2(t.begin() + 10, t.end()), d2(dB.begin() + 10, dB.end()), e2(eB.begin() + 10, eB.end());
    QVERIFY(proportionalityMismatch({t, dA, eA}, {t2, d2, e2}, 0.5e-3) < 1e-9);
  }

  // The convergence study's settings: good ones parse, each bad item is
  // named; a setting is within tolerance only when every figure is within
  // 10 % of the reference's (a figure 11 % off fails it: the control).
  void convergenceSettingsAndTolerance() {
    std::string error;
    const auto good = parsePhysicsSettings("0.001/40,0.0005/200,0.00025/exact", error);
    QVERIFY2(good, error.c_str());
    QCOMPARE(good->size(), size_t{3});
    QCOMPARE((*good)[1].iterations, 200);
    QVERIFY((*good)[2].exact);
    for (const char* bad : {"0.001/40", "0.001/40,abc/20", "0.001/40,0.001/0", "0.001/40,1/20", "0.001/40,0.001/exakt",
                            "0.001/40,", "nan/40,0.001/40"}) {
      QVERIFY2(!parsePhysicsSettings(bad, error), bad);
      QVERIFY2(error.rfind("--convergence: ", 0) == 0, error.c_str());
    }
    ConvergenceStudy study;
    study.settings = *good;
    study.figures = {"a", "b"};
    study.values = {{1.09, -0.5}, {1.11, -0.5}, {1.0, -0.46}};
    QVERIFY(study.withinTolerance(0));
    QVERIFY(!study.withinTolerance(1));  // 11 % off on the first figure
    study.values[2][1] = -0.4;           // the second now 25 % off in both
    QVERIFY(!study.withinTolerance(0));
  }

  // 3. The pole is picked, carried and laid down to stay; the front wheels
  // carry more, and the pole (the same pose with and without it) loads the
  // front while unloading the rear, the two adding up to its weight.
  void pickAndPlace() { verifyAll(sp::pickAndPlace(quick())); }

  // 4. On mu 0.025 with a motion resistance C = 0.03: the paper's speeds,
  // each within a factor of 1.5, in its order, and a rolling speed that is
  // not the solver's creep (<= 10 % change at 200 iterations). Known
  // failures today: rolling 1.8 x the paper's, and it is the creep (issue
  // 29's wheel-ground model). Control: the same world without the
  // resistance rolls at the wheels' surface speed, 50 x the paper's.
  void slipperySurface() {
    verifyVerdicts(sp::slipperySurface(quick()), {0, 4});
    ValidationOptions o = quick();
    o.sourceDir = makeCopyWithout(o.sourceDir, "motion_resistance=\"0.03\"");
    QVERIFY(!o.sourceDir.empty());
    const ExperimentResult bare = sp::slipperySurface(o);
    qInfo("without motion resistance: %s", qPrintable(describe(bare.metrics[0])));
    QVERIFY(!bare.metrics[0].pass);
    QVERIFY(bare.metrics[0].ours > 0.15);  // rolling, not slipping
  }

  // 5. Each bump slows the climb and speeds the descent, and unloads the
  // front axle on the climb; the controls (the same places on flat ground,
  // the track's flat stretches) fail the same tests, which the metrics
  // named "control" assert.
  void testTrack() {
    const ExperimentResult r = sp::testTrack(quick());
    int controls = 0;
    for (const Metric& m : r.metrics) controls += m.quantity.rfind("control:", 0) == 0;
    QCOMPARE(controls, 4);
    verifyAll(r);
  }
};

QTEST_GUILESS_MAIN(TestValidation)
#include "tst_validation.moc"
