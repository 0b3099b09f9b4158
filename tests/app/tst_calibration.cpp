// Calibration from telemetry (app/calibration/calibration.h) against robots
// that are not their twin: a robot world perturbed in known ways drives a
// known sequence, its telemetry is fitted, and the fit is judged against
// the hidden truth.
//
// Criteria, stated before the runs (issue 28):
//   - one hidden parameter (every wheel's radius -2 %) is recovered within
//     0.3 % from a 10 s drive; the other parameters stay within their
//     deviations of the files' (they are not there to be found);
//   - a straight-line drive on grip leaves friction unobserved (and its
//     value the files'); the same robot turning observes it is not claimed;
//   - a fit the physics cannot follow (telemetry of a robot whose wheels
//     are 50 % larger, beyond calibration.wheel_radius's bounds) is refused
//     and the previous values kept; the control with 2 % is accepted;
//   - a window without driving is refused and says what is missing;
//   - `simpartner-sim calibrate LOG` on a straight-line log prints friction
//     as unobserved and writes a parameters file that loads.

#include <QtTest>

#include <cmath>

#include "app/calibration/calibration.h"
#include "app/calibration/recorded_drive.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"

using namespace sp;

namespace {

WorldModel loadWorldFile(const std::string& name) {
  Diagnostics diag;
  std::optional<WorldModel> w = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/" + name, diag);
  if (!w) qFatal("%s", diag.format().c_str());
  return *w;
}

// The ghost's physics, as the console fits it.
SimParams ghostProfile() {
  SimParams p;
  p.step = p.ghostStep;
  p.iterations = p.ghostIterations;
  return p;
}

std::vector<TimedCommand> commands(const WorldModel& world, const char* text) {
  std::vector<TimedCommand> out;
  Diagnostics diag;
  std::optional<std::vector<TimedCommand>> seq = parseCommandSequence(text, "<test>", diag, &world.robots[0].model);
  if (!seq) qFatal("%s", diag.format().c_str());
  return *seq;
}

const char* const kDriveAndTurn =
    "0.5 drive 0.6 0\n"
    "3.5 drive 0.6 15\n"
    "6.5 drive 0.6 -15\n";
const char* const kStraight = "0.5 drive 0.6 0\n";

Perturbation none(const WorldModel& world) {
  Perturbation p;
  const size_t links = world.robots[0].model.links.size();
  p.linkMass.assign(links, 1.0);
  p.centreOfMass.assign(links, Vec3{});
  return p;
}

void print(const CalibrationFit& fit) {
  qInfo("fit: %d segments, %d twin runs, %.0f ms, cost %.3g -> %.3g%s%s", fit.segments, fit.twinRuns, fit.wallMs,
        fit.costBefore, fit.costAfter, fit.refused.empty() ? "" : ", refused: ", fit.refused.c_str());
  for (size_t i = 0; i < kCalParams; ++i)
    qInfo("  %-32s %.5f +- %.5f %s", calParams()[i].key, fit.value[i], fit.sigma[i], fit.observed[i] ? "" : "unobserved");
}

}  // namespace

class TestCalibration : public QObject {
  Q_OBJECT

 private slots:
  void recoversOneHiddenWheelRadius() {
    const WorldModel world = loadWorldFile("flat.world.xml");
    Perturbation p = none(world);
    p.wheelRadius = {0.98, 0.98, 0.98, 0.98};
    const RecordedDrive d = recordDrive(world, SimParams{}, p, commands(world, kDriveAndTurn), 10.0);
    QVERIFY2(d.problem.empty(), d.problem.c_str());
    const CalibrationFit fit = fitCalibration(world, ghostProfile(), d.frames, d.commands, filesCalValues());
    print(fit);
    QVERIFY2(fit.refused.empty(), fit.refused.c_str());
    QVERIFY(fit.observed[0]);
    QVERIFY2(std::abs(fit.value[0] - 0.98) <= 0.003 * 0.98, qPrintable(QString::number(fit.value[0], 'f', 5)));
  }
  void debugCost() {
    const WorldModel world = loadWorldFile("flat.world.xml");
    Perturbation p = none(world);
    p.wheelRadius = {0.98, 0.98, 0.98, 0.98};
    const RecordedDrive d = recordDrive(world, SimParams{}, p, commands(world, kDriveAndTurn), 10.0);
    for (double r : {0.96, 0.97, 0.98, 0.99, 1.0}) {
      CalValues v = filesCalValues();
      v[0] = r;
      CalibrationOptions o;
      o.iterations = 0;
      for (SimParams prof : {ghostProfile(), SimParams{}}) {
        const CalibrationFit fit = fitCalibration(world, prof, d.frames, d.commands, v, o);
        qInfo("r %.3f step %.3f cost %.4f", r, prof.step, fit.costBefore);
      }
    }
  }
};

QTEST_GUILESS_MAIN(TestCalibration)
#include "tst_calibration.moc"
