// The founding paper's experiments in their quick versions, with the targets
// asserted (docs/validation/report.md has the full runs).

#include <QTest>

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>
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

// A copy of robots/ and terrains/ with `file`'s text edited: each `from`
// (which must occur) replaced by its `to`; returns the copy's source folder
// ("" on failure). A perturbed model for a control: a criterion must fail
// on it for a physical reason. The folders live as long as the process.
std::string makeVariant(const std::string& sourceDir, const QString& file,
                        const std::vector<std::pair<QString, QString>>& edits) {
  static std::vector<std::unique_ptr<QTemporaryDir>> dirs;
  dirs.push_back(std::make_unique<QTemporaryDir>());
  const QDir source(QString::fromStdString(sourceDir)), copy(dirs.back()->path());
  if (!dirs.back()->isValid()) return {};
  for (const QString sub : {"robots", "terrains"}) {
    copy.mkpath(sub);
    for (const QString& name : QDir(source.filePath(sub)).entryList(QDir::Files))
      if (!QFile::copy(source.filePath(sub + "/" + name), copy.filePath(sub + "/" + name))) return {};
  }
  QFile in(copy.filePath(file));
  if (!in.open(QIODevice::ReadOnly)) return {};
  QString text = QString::fromUtf8(in.readAll());
  in.close();
  for (const auto& [from, to] : edits) {
    if (!text.contains(from)) return {};
    text.replace(from, to);
  }
  QFile out(copy.filePath(file));
  if (!out.open(QIODevice::WriteOnly | QIODevice::Truncate) || out.write(text.toUtf8()) < 0) return {};
  return copy.path().toStdString();
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
  // Against the commanded angle (also judged, issue 29) too: -0.31 % at 10
  // degrees (the quick suite records as long as the full one, so that it
  // gives the full suite's verdicts).
  void circularDrive() { verifyAll(sp::circularDrive(quick())); }

  // Control (a perturbed world, issue 29): on glare ice (tyres on the
  // ground at mu 0.003: 0.03 m/s^2 of grip, where the circles at 0.5 m/s
  // need 0.04-0.12) the robot slides outwards, so the kinematic criterion,
  // which assumes rolling without side slip, must fail at every angle
  // (+124 to +168 % today). At mu 0.01, which should hold the 10 and 20
  // degree circles, 10 degrees still failed (+4 %) and 20 passed: the
  // tyres fight (their speeds are the model's), so a control this close to
  // the grip would not say why it fails.
  void circularDriveControl() {
    ValidationOptions o = quick();
    o.sourceDir = makeVariant(o.sourceDir, "terrains/flat.world.xml",
                              {{R"(<contact a="rubber" b="ground" mu="1.0"/>)", R"(<contact a="rubber" b="ground" mu="0.003"/>)"}});
    QVERIFY(!o.sourceDir.empty());
    const ExperimentResult r = sp::circularDrive(o);
    for (size_t i : {0, 2, 4}) {
      qInfo("on ice: %s", qPrintable(describe(r.metrics[i])));
      QVERIFY2(r.metrics[i].judged && !r.metrics[i].pass, qPrintable(describe(r.metrics[i])));
    }
  }

  // 2. Judged: numerics only. The paper's linear growth is its integrator's
  // error, which a converged twin must not share (at 200 iterations the
  // torso drifts at a sixth of the default's rate), so the line through the
  // range error is for the record with the other identities (exact ranges
  // against the true pose, tst_sensors tests the ray caster; the per-metre
  // agreement of the walls). What is judged is the solver's share of the
  // range error, the default against 200 iterations: 2.5 mm, within the
  // scanner's 10 mm noise. Control in the report: the ghost's physics
  // (4 ms, 20 iterations), 72 mm, must fail it.
  void laserSweep() {
    const ExperimentResult r = sp::laserSweep(quick());
    QCOMPARE(r.metrics.size(), size_t{6});
    QCOMPARE(r.metrics[3].basis, Basis::Solver);
    QCOMPARE(r.metrics[4].basis, Basis::Control);
    QCOMPARE(std::count_if(r.metrics.begin(), r.metrics.end(), [](const Metric& m) { return m.judged; }), 2);
    verifyAll(r);
    QVERIFY2(r.metrics[4].ours > 2 * r.metrics[3].ours, qPrintable(describe(r.metrics[4])));
  }

  // The laser's record figures are computed right (the report's reading
  // of them rests on these): a line through noise-free points is R^2 = 1, a flat series with jitter is not growing; an error proportional
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
    // A figure near zero states its tolerance in its unit: 0.1 of a
    // reference at 0.02 admits -0.05, not 0.15 (which 10 % would refuse both).
    study.absolute = {0, 0.1};
    study.values = {{1.0, -0.05}, {1.0, 0.15}, {1.0, 0.02}};
    QVERIFY(study.withinTolerance(0));
    QVERIFY(!study.withinTolerance(1));
    QVERIFY(study.figureWithin(1, 0));
  }

  // 3. The pole is picked, carried and laid down to stay; the front wheels
  // carry more, and the pole (the same pose with and without it) loads the
  // front while unloading the rear, the two adding up to its weight.
  void pickAndPlace() { verifyAll(sp::pickAndPlace(quick())); }

  // Control: a robot whose front body is 28 kg lighter and rear body 28 kg
  // heavier (its batteries moved back) is not front-heavy: the standing
  // share criterion must fail, the pole's criteria (the same pose with and
  // without it) still pass.
  void pickAndPlaceControl() {
    ValidationOptions o = quick();
    o.sourceDir = makeVariant(o.sourceDir, "robots/workpartner.xml",
                              {{R"(name="rear_body" mass="62")", R"(name="rear_body" mass="90")"},
                               {R"(name="front_body" mass="48")", R"(name="front_body" mass="20")"}});
    QVERIFY(!o.sourceDir.empty());
    const ExperimentResult r = sp::pickAndPlace(o);
    qInfo("batteries back: %s", qPrintable(describe(r.metrics[0])));
    verifyVerdicts(r, {0});
  }

  // 4. On mu 0.025 with a motion resistance C = 0.03: the paper's speeds,
  // each within a factor of 1.5, in its order, and a rolling speed that is
  // not the solver's creep (within 10 % or a tenth of the paper's figure
  // at 200 iterations). Known failure: rolling, which stands (converged)
  // where the paper's robot crept at 0.0038 m/s. Control: the same world
  // without the resistance rolls at the wheels' surface speed, 50 x the
  // paper's; at 20 iterations the rolling figure is the solver's.
  void slipperySurface() {
    verifyVerdicts(sp::slipperySurface(quick()), {0});
    ValidationOptions o = quick();
    o.sourceDir = makeVariant(o.sourceDir, "terrains/ice.world.xml", {{"motion_resistance=\"0.03\"", ""}});
    QVERIFY(!o.sourceDir.empty());
    const ExperimentResult bare = sp::slipperySurface(o);
    qInfo("without motion resistance: %s", qPrintable(describe(bare.metrics[0])));
    QVERIFY(!bare.metrics[0].pass);
    QVERIFY(bare.metrics[0].ours > 0.15);  // rolling, not slipping
    // The convergence criterion's control: at 20 iterations the stalled
    // robot creeps (0.0009 m/s against 0.0001 at 200).
    ValidationOptions coarse = quick();
    coarse.params.iterations = 20;
    const ExperimentResult crept = sp::slipperySurface(coarse);
    qInfo("at 20 iterations: %s", qPrintable(describe(crept.metrics[4])));
    QCOMPARE(crept.metrics[4].basis, Basis::Solver);
    QVERIFY(!crept.metrics[4].pass);
  }

  // 5. Over each bump the robot's centre slows and speeds up (the body
  // pitches under the hinge, 0.6 m above the axles: the wheels do not
  // slip), and the front axle unloads on the climb; the controls (the same
  // places on flat ground, the track's lead-in, its flat stretches' loads)
  // fail the same tests, which the metrics named "control" assert.
  void testTrack() {
    const ExperimentResult r = sp::testTrack(quick());
    int controls = 0;
    for (const Metric& m : r.metrics) controls += m.quantity.rfind("control:", 0) == 0;
    QCOMPARE(controls, 6);
    verifyAll(r);
    // The mechanism the report states, pinned: the wheels roll (any slip is
    // a few percent at a bump's edge) and the pitch rate explains what the
    // hinge gains or loses on them.
    int mechanism = 0;
    for (const Metric& m : r.metrics) {
      if (m.quantity.find("largest slip") != std::string::npos) QVERIFY2(m.ours < 10, qPrintable(describe(m)));
      if (m.quantity.find("pitch rate") != std::string::npos) QVERIFY2(m.ours > 0.9, qPrintable(describe(m)));
      mechanism += m.quantity.find("largest slip") != std::string::npos || m.quantity.find("pitch rate") != std::string::npos;
    }
    QCOMPARE(mechanism, 2);
  }
};

QTEST_GUILESS_MAIN(TestValidation)
#include "tst_validation.moc"
