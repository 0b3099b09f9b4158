// Sweeps (app/sweep/sweep.h): the manifest is what a task reads, a sample gives
// the same end hash on threads of one process and in a process of its own
// (as a job array's task runs), missing and failed tasks are named and a
// resume runs only those. Real files in a temporary folder, the real
// `simpartner-sim` through QProcess.

#include <QProcess>
#include <QProcessEnvironment>
#include <QTest>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/default_step.h"
#include "app/log/resimulation.h"
#include "app/sweep/sweep.h"
#include "tests/app/sweep_results.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/world.h"

using namespace sp;
using sp::test::readText;
using sp::test::sweepHashes;

namespace {

int runSim(const QStringList& args, QString* output = nullptr) {
  QProcess p;
  p.setProcessChannelMode(QProcess::MergedChannels);
  p.start(QStringLiteral(SP_BINARY_DIR "/app/simpartner-sim"), args);
  if (!p.waitForFinished(120000)) return -1;
  if (output) *output = QString::fromUtf8(p.readAll());
  return p.exitStatus() == QProcess::NormalExit ? p.exitCode() : -1;
}

}  // namespace

class TestSweep : public QObject {
  Q_OBJECT

  QTemporaryDir tmp_;
  std::string seq_;

  SweepSpec spec(uint64_t seed) const {
    SweepSpec s;
    s.world = SP_SOURCE_DIR "/terrains/flat.world.xml";
    s.commands = seq_;
    s.vary = {{"physics.iterations", 20, 60}, {"physics.erp", 0.3, 0.6}};
    s.samples = 4;
    s.seed = seed;
    return s;
  }

 private slots:
  void initTestCase() {
    QVERIFY(tmp_.isValid());
    seq_ = tmp_.filePath("short.seq").toStdString();
    std::ofstream(seq_) << "0 drive 0.5 10\n1.5 stop\n";
  }

  // The manifest: one line per sample with its seed and --set values,
  // integer keys drawn whole, and read back as written; bad input named.
  void manifest() {
    const std::string dir = tmp_.filePath("manifest").toStdString();
    std::string error;
    QVERIFY2(createSweep(dir, spec(7), error), error.c_str());
    SweepSpec read;
    std::vector<SweepSample> samples;
    QVERIFY2(readSweep(dir, read, samples, error), error.c_str());
    QCOMPARE(samples.size(), size_t{4});
    QCOMPARE(read.seed, uint64_t{7});
    for (const SweepSample& s : samples) {
      QCOMPARE(s.sets.size(), size_t{2});
      QVERIFY(s.sets[0].rfind("physics.iterations=", 0) == 0);
      const double it = std::stod(s.sets[0].substr(19)), erp = std::stod(s.sets[1].substr(12));
      QVERIFY(it >= 20 && it <= 60 && it == std::floor(it));
      QVERIFY(erp >= 0.3 && erp <= 0.6);
    }
    QVERIFY(samples[0].seed != samples[1].seed);
    QVERIFY(!createSweep(dir, spec(7), error));  // not overwritten
    QVERIFY(error.find("a sweep is there already") != std::string::npos);

    SweepVary v;
    QCOMPARE(parseVary("physics.step=2:1", v), std::string("--vary physics.step=2:1: LO is above HI"));
    QVERIFY(!parseVary("physics.step", v).empty());
    SweepSpec bad = spec(1);
    bad.vary = {{"no.such.key", 0, 1}};
    QVERIFY(!createSweep(tmp_.filePath("bad").toStdString(), bad, error));
    QVERIFY2(error.find("no.such.key") != std::string::npos, error.c_str());
    bad = spec(1);
    bad.vary = {{"physics.iterations", 0, 10}};  // 0 iterations is refused
    QVERIFY(!createSweep(tmp_.filePath("bad2").toStdString(), bad, error));
    QVERIFY2(error.find("physics.iterations") != std::string::npos, error.c_str());

    // A damaged manifest is named at its line.
    std::string text = readText(dir + "/manifest.txt");
    text.replace(text.find("sample 2 "), 9, "sample 9 ");
    std::ofstream(dir + "/manifest.txt") << text;
    QVERIFY(!readSweep(dir, read, samples, error));
    QVERIFY2(error.find("manifest.txt:13: error:") != std::string::npos, error.c_str());
  }

  // Each sample ends in the same state (hash) when the sweep runs on two
  // threads and when every task runs as its own process, as a job array's
  // would. Control: another seed draws other samples and other hashes.
  void sameResultsWhereverTasksRun() {
    const std::string local = tmp_.filePath("local").toStdString(), tasks = tmp_.filePath("tasks").toStdString();
    std::string error;
    QVERIFY2(createSweep(local, spec(3), error), error.c_str());
    QVERIFY(runSweepLocal(local, {}, 2, error));
    const SweepSummary s = collectSweep(local, error);
    QVERIFY2(error.empty(), error.c_str());
    QCOMPARE(s.done, 4);
    QVERIFY(s.missing.empty() && s.failed.empty());
    for (const char* plot : {"end_positions.svg", "margins.svg"}) {
      QVERIFY(readText(local + "/" + plot).find("<svg") != std::string::npos);
      QVERIFY(readText(local + "/report.md").find(plot) != std::string::npos);
    }

    QVERIFY2(createSweep(tasks, spec(3), error), error.c_str());
    for (int i = 0; i < 4; ++i) {
      QString out;
      QCOMPARE(runSim({"sweep-task", QString::fromStdString(tasks), QString::number(i)}, &out), 0);
    }
    QCOMPARE(runSim({"collect", QString::fromStdString(tasks)}), 0);
    const std::vector<std::string> a = sweepHashes(local), b = sweepHashes(tasks);
    QCOMPARE(a.size(), size_t{4});  // before reading them: a short file fails the test, not the process
    qInfo("end hashes: %s %s %s %s", a[0].c_str(), a[1].c_str(), a[2].c_str(), a[3].c_str());
    QCOMPARE(a, b);

    const std::string other = tmp_.filePath("other").toStdString();
    QVERIFY2(createSweep(other, spec(4), error), error.c_str());
    QVERIFY(runSweepLocal(other, {}, 2, error));
    collectSweep(other, error);
    const std::vector<std::string> c = sweepHashes(other);
    QCOMPARE(c.size(), size_t{4});
    for (size_t i = 0; i < 4; ++i) QVERIFY(c[i] != a[i]);
  }

  // A task that never ran is missing, one whose sample cannot run failed;
  // collect names both and exits 4; --resume runs only those and leaves
  // the others' files alone.
  void missingAndFailedTasksRerun() {
    const std::string dir = tmp_.filePath("resume").toStdString();
    std::string error;
    QVERIFY2(createSweep(dir, spec(5), error), error.c_str());
    // Sample 1 asks for an impossible value (a hand-edited manifest): it fails to run.
    const std::string manifest = readText(dir + "/manifest.txt");
    std::string broken = manifest;
    const size_t at = broken.find("physics.iterations=", broken.find("sample 1 "));
    broken.replace(at, broken.find(' ', at) - at, "physics.iterations=0");
    std::ofstream(dir + "/manifest.txt") << broken;
    QVERIFY(runSweepLocal(dir, {0, 1, 3}, 2, error));  // 2 never runs
    QString out;
    QCOMPARE(runSim({"collect", QString::fromStdString(dir)}, &out), 4);
    qInfo("%s", qPrintable(out.trimmed()));
    const SweepSummary s = collectSweep(dir, error);
    QCOMPARE(s.missing, std::vector<int>{2});
    QCOMPARE(s.failed, std::vector<int>{1});
    const std::string report = readText(dir + "/report.md");
    QVERIFY(report.find("Missing (never ran): 2") != std::string::npos);
    QVERIFY(report.find("task 1: error:") != std::string::npos && report.find("physics.iterations") != std::string::npos);
    QCOMPARE(pendingTasks(dir, error), (std::vector<int>{1, 2}));

    // Mended, resumed: only 1 and 2 run.
    std::ofstream(dir + "/manifest.txt") << manifest;
    const auto written = std::filesystem::last_write_time(dir + "/results/0.tsv");
    const std::string result3 = readText(dir + "/results/3.tsv");
    QCOMPARE(runSim({"sweep", "--resume", QString::fromStdString(dir), "--jobs", "2"}, &out), 0);
    QCOMPARE(std::filesystem::last_write_time(dir + "/results/0.tsv"), written);
    QCOMPARE(readText(dir + "/results/3.tsv"), result3);
    QVERIFY(pendingTasks(dir, error).empty());
    QCOMPARE(collectSweep(dir, error).done, 4);
  }

  // The console's "Robustness on cluster": the plan (its world with an
  // edited heightfield, parameters, rules, a start in motion) written as a
  // sweep equals the console's local robustness() sample for sample: the
  // same verdicts and end positions, bit for bit.
  void consoleRobustnessAsSweep() {
    Diagnostics diag;
    std::optional<WorldModel> world = loadWorld(SP_SOURCE_DIR "/terrains/test_track.world.xml", diag);
    QVERIFY2(world, diag.format().c_str());
    // An edit in the console: a 3 cm hump across the track 1.6-2.2 m along, where the robot drives.
    HeightGrid& grid = world->terrain.grid;
    for (int j = 0; j < grid.rows; ++j)
      for (int i = 0; i < grid.columns; ++i)
        if (const double x = i * grid.spacingX(); x >= 1.6 && x <= 2.2) grid.at(i, j) += 0.03;
    std::optional<std::vector<TimedCommand>> commands = loadCommandSequence(seq_, diag, &world->robots[0].model);
    QVERIFY2(commands, diag.format().c_str());
    SimParams params;
    params.erp = 0.45;
    FlightRules rules;
    rules.robustSamples = 3;
    // The start: the robot after 0.5 s of driving.
    auto robot = World::create(*world, params, diag);
    QVERIFY(robot);
    QCOMPARE(robot->submit(DriveCmd{0.4, 0}), std::string());
    for (int64_t i = 0; i < sp::test::stepAt(0.5); ++i) QVERIFY(robot->step());
    const RobotReadout r = readRobot(*robot);
    RehearsalStart start{r.base, r.baseLinearVelocity, r.baseAngularVelocity, r.jointPositions, r.jointRates, {}};
    const RehearsalPlan plan{*world, params, rules, *commands, start};

    const RobustnessResult local = robustness(plan, 1, 2);
    const std::string dir = tmp_.filePath("console").toStdString();
    std::string error;
    QVERIFY2(createSweepFromPlan(dir, plan, 1, error), error.c_str());
    QVERIFY(readText(dir + "/manifest.txt").find("start_base ") != std::string::npos);
    QVERIFY(runSweepLocal(dir, {}, 2, error));
    const SweepSummary s = collectSweep(dir, error);
    QCOMPARE(s.done, 3);
    QCOMPARE(s.passed, local.passed);
    // Bit for bit (docs/sweeps.md): each sample's end-state hash, the
    // whole state, not positions compared within a tolerance.
    const std::vector<std::string> hashes = sweepHashes(dir);
    QCOMPARE(hashes.size(), size_t{3});
    for (size_t i = 0; i < 3; ++i) QCOMPARE(hashes[i], hashHex(local.endHashes[i]));
    QVERIFY(hashes[0] != hashes[1] && hashes[1] != hashes[2] && hashes[0] != hashes[2]);  // the draws differ
    std::istringstream csv(readText(dir + "/results.csv"));
    std::string line;
    std::getline(csv, line);
    for (int i = 0; i < 3 && std::getline(csv, line); ++i) {
      std::vector<std::string> f;
      std::istringstream row(line);
      for (std::string cell; std::getline(row, cell, ',');) f.push_back(cell);
      QVERIFY2(f.size() >= 3, line.c_str());  // a short row fails the test, not the process
      QCOMPARE(f[2], std::string(local.samplePassed[static_cast<size_t>(i)] ? "true" : "false"));
    }
    // Control: the same sweep without the terrain edit ends elsewhere.
    RehearsalPlan unedited = plan;
    std::optional<WorldModel> original = loadWorld(SP_SOURCE_DIR "/terrains/test_track.world.xml", diag);
    unedited.world = *original;
    const RobustnessResult other = robustness(unedited, 1, 2);
    QVERIFY(other.endPoses[0].p.x != local.endPoses[0].p.x || other.endPoses[0].p.y != local.endPoses[0].p.y);
  }

  // The console's cluster robustness with a calibration's estimate: the
  // manifest keeps it (read back as written; a damaged line named), and
  // every sample equals robustness()'s, drawn from the estimate. Control:
  // the ranges' draws end elsewhere.
  void clusterRobustnessDrawsFromTheEstimate() {
    Diagnostics diag;
    std::optional<WorldModel> world = loadWorld(SP_SOURCE_DIR "/terrains/flat.world.xml", diag);
    QVERIFY2(world, diag.format().c_str());
    std::optional<std::vector<TimedCommand>> commands = loadCommandSequence(seq_, diag, &world->robots[0].model);
    QVERIFY2(commands, diag.format().c_str());
    FlightRules rules;
    rules.robustSamples = 2;
    RehearsalPlan plan{*world, SimParams{}, rules, *commands, std::nullopt};
    RobotEstimate estimate;
    for (size_t i = 0; i < kCalParams; ++i) estimate.sigma[i] = 0.01 * static_cast<double>(i + 1);
    estimate.observed[static_cast<size_t>(CalParam::WheelRadius)] = true;
    estimate.observed[static_cast<size_t>(CalParam::TorqueRL)] = true;
    plan.estimate = estimate;

    const std::string dir = tmp_.filePath("estimate").toStdString();
    std::string error;
    QVERIFY2(createSweepFromPlan(dir, plan, 1, error), error.c_str());
    SweepSpec read;
    std::vector<SweepSample> samples;
    QVERIFY2(readSweep(dir, read, samples, error), error.c_str());
    QVERIFY(read.estimate);
    QVERIFY(read.estimate->sigma == estimate.sigma);
    QVERIFY(read.estimate->observed == estimate.observed);
    QVERIFY(runSweepLocal(dir, {}, 2, error));
    const SweepSummary sum = collectSweep(dir, error);
    QCOMPARE(sum.done, 2);
    QVERIFY(readText(dir + "/report.md").find("drawn from what the console knows of it") != std::string::npos);
    const RobustnessResult local = robustness(plan, 1, 2);
    QVERIFY(local.fromEstimate);
    const std::vector<std::string> hashes = sweepHashes(dir);
    QCOMPARE(hashes.size(), size_t{2});
    for (size_t i = 0; i < 2; ++i) QCOMPARE(hashes[i], hashHex(local.endHashes[i]));
    RehearsalPlan ranges = plan;
    ranges.estimate.reset();
    const RobustnessResult other = robustness(ranges, 1, 2);
    QVERIFY(hashHex(other.endHashes[0]) != hashes[0]);

    // A damaged estimate line is named at its line and key.
    std::string text = readText(dir + "/manifest.txt");
    const size_t at = text.find("estimate calibration.delay ");
    QVERIFY(at != std::string::npos);
    text.replace(at, 27, "estimate calibration.dealy ");
    std::ofstream(dir + "/manifest.txt") << text;
    QVERIFY(!readSweep(dir, read, samples, error));
    QVERIFY2(error.find("manifest.txt:") != std::string::npos && error.find("calibration.dealy") != std::string::npos,
             error.c_str());
    text.replace(at, 27, "estimate calibration.delay ");
    const size_t sigma = text.find(' ', at + 27);
    text.replace(at + 27, sigma - at - 27, "-1");
    std::ofstream(dir + "/manifest.txt") << text;
    QVERIFY(!readSweep(dir, read, samples, error));
    QVERIFY2(error.find("the deviation must be finite") != std::string::npos, error.c_str());
  }

  // The job array script and its index list.
  void slurmScript() {
    QCOMPARE(slurmArrayList({0, 1, 2, 3, 5, 7, 8}), std::string("0-3,5,7-8"));
    QCOMPARE(slurmArrayList({4}), std::string("4"));
    QCOMPARE(slurmArrayList({3, 1, 2, 2}), std::string("1-3"));
    const std::string dir = tmp_.filePath("slurm").toStdString();
    std::string error;
    QVERIFY2(createSweep(dir, spec(1), error), error.c_str());
    QVERIFY2(writeSlurmScript(dir, SP_BINARY_DIR "/app/simpartner-sim", error), error.c_str());
    const std::string script = readText(dir + "/sweep.sbatch");
    QVERIFY(script.rfind("#!/bin/sh\n", 0) == 0);
    QVERIFY(script.find("#SBATCH --output=" + dir + "/logs/%a.out") != std::string::npos);
    QVERIFY(script.find("exec '" SP_BINARY_DIR "/app/simpartner-sim' sweep-task '" + dir + "'") != std::string::npos);
    // The task reads its index from Slurm's environment.
    QProcess p;
    QProcessEnvironment env = QProcessEnvironment::systemEnvironment();
    env.insert("SLURM_ARRAY_TASK_ID", "0");
    p.setProcessEnvironment(env);
    p.start("/bin/sh", {QString::fromStdString(dir + "/sweep.sbatch")});
    QVERIFY(p.waitForFinished(120000));
    QCOMPARE(p.exitCode(), 0);
    QCOMPARE(readText(dir + "/status/0"), std::string("ok\n"));
  }
};

QTEST_GUILESS_MAIN(TestSweep)
#include "tst_sweep.moc"
