// A sweep on a real Slurm cluster: a one-node cluster started by
// scripts/slurm_cluster.sh, the real `simpartner-sim sweep --slurm`
// submitting a job array of 8 samples; the results equal a local run's,
// sample for sample (the same end hashes); a resume submits only the tasks
// that did not run. The cluster is stopped in cleanup (jobs cancelled, then
// the daemons by pid), also when a check fails.

#include <unistd.h>

#include <QProcess>
#include <QProcessEnvironment>
#include <QStandardPaths>
#include <QTest>

#include <fstream>
#include <set>

#include "tests/app/sweep_results.h"

using namespace std::chrono_literals;

class TestSweepSlurm : public QObject {
  Q_OBJECT

  QTemporaryDir tmp_;
  QString cluster_;
  QProcessEnvironment env_ = QProcessEnvironment::systemEnvironment();

  int run(const QString& program, const QStringList& args, QString* output = nullptr, int timeoutMs = 120000) {
    QProcess p;
    p.setProcessEnvironment(env_);
    p.setProcessChannelMode(QProcess::MergedChannels);
    p.start(program, args);
    if (!p.waitForFinished(timeoutMs)) {
      p.kill();
      p.waitForFinished();
      return -1;
    }
    const QString out = QString::fromUtf8(p.readAll());
    if (output) *output = out;
    if (p.exitCode() != 0) qInfo("%s %s: %s", qPrintable(program), qPrintable(args.join(' ')), qPrintable(out.trimmed()));
    return p.exitStatus() == QProcess::NormalExit ? p.exitCode() : -1;
  }
  int sim(const QStringList& args, QString* output = nullptr) {
    return run(QStringLiteral(SP_BINARY_DIR "/app/simpartner-sim"), args, output);
  }
  // Waits until the cluster has no job left (at most `seconds`).
  bool drained(int seconds) {
    for (int i = 0; i < seconds * 5; ++i) {
      QString out;
      if (run("squeue", {"-h"}, &out, 10000) == 0 && out.trimmed().isEmpty()) return true;
      QThread::msleep(200);
    }
    return false;
  }

 private slots:
  void initTestCase() {
    if (geteuid() != 0) QSKIP("a one-node Slurm cluster needs root (slurmd starts the jobs)");
    for (const char* tool : {"sbatch", "squeue", "slurmctld", "slurmd", "munged"})
      if (QStandardPaths::findExecutable(tool).isEmpty() &&
          QStandardPaths::findExecutable(tool, {"/usr/sbin", "/sbin"}).isEmpty())
        QFAIL(qPrintable(QString("%1 is not installed: run scripts/install-deps.sh").arg(tool)));
    QVERIFY(tmp_.isValid());
    cluster_ = tmp_.filePath("cluster");
    QString out;
    QCOMPARE(run(SP_SOURCE_DIR "/scripts/slurm_cluster.sh", {"start", cluster_}, &out, 60000), 0);
    env_.insert("SLURM_CONF", cluster_ + "/slurm.conf");
  }

  void cleanupTestCase() {
    if (cluster_.isEmpty()) return;
    QCOMPARE(run(SP_SOURCE_DIR "/scripts/slurm_cluster.sh", {"stop", cluster_}, nullptr, 60000), 0);
    QVERIFY(!QFile::exists(cluster_ + "/slurmctld.pid"));
  }

  // 8 samples as a job array equal the same sweep run locally, hash for
  // hash; a resume submits only the two tasks that were wiped, and they
  // come back with their hashes.
  void arrayEqualsLocal() {
    const QString seq = tmp_.filePath("short.seq");
    std::ofstream(seq.toStdString()) << "0 drive 0.5 10\n1.5 stop\n";
    const QStringList spec = {"--world", SP_SOURCE_DIR "/terrains/flat.world.xml", "--commands", seq,
                              "--vary", "physics.iterations=20:60", "--vary", "physics.erp=0.3:0.6",
                              "--samples", "8", "--seed", "11"};
    const QString onCluster = tmp_.filePath("cluster-sweep"), local = tmp_.filePath("local-sweep");
    QString out;
    QCOMPARE(sim(QStringList{"sweep"} + spec + QStringList{"--out", onCluster, "--slurm"}, &out), 0);
    QVERIFY2(out.contains("submitted job array"), qPrintable(out));
    QVERIFY(drained(180));
    QCOMPARE(sim({"collect", onCluster}, &out), 0);
    QCOMPARE(sim(QStringList{"sweep"} + spec + QStringList{"--out", local, "--jobs", "2"}, &out), 0);
    const std::vector<std::string> a = sp::test::sweepHashes(onCluster.toStdString()), b = sp::test::sweepHashes(local.toStdString());
    QCOMPARE(a.size(), size_t{8});
    QCOMPARE(a, b);
    // Eight draws, eight end states: equal hashes would mean the samples
    // were not perturbed (or one ran eight times), and equality above nothing.
    QCOMPARE(std::set<std::string>(a.begin(), a.end()).size(), size_t{8});
    for (int i = 0; i < 8; ++i) QVERIFY(QFile::exists(onCluster + QString("/logs/%1.out").arg(i)));

    // Two tasks lost (a node died): collect names them, a resume submits only those.
    for (int i : {2, 5}) {
      QVERIFY(QFile::remove(onCluster + QString("/status/%1").arg(i)));
      QVERIFY(QFile::remove(onCluster + QString("/results/%1.tsv").arg(i)));
      QVERIFY(QFile::remove(onCluster + QString("/logs/%1.out").arg(i)));
    }
    QCOMPARE(sim({"collect", onCluster}, &out), 4);
    QVERIFY(sp::test::readText((onCluster + "/report.md").toStdString()).find("Missing (never ran): 2, 5") != std::string::npos);
    const QDateTime untouched = QFileInfo(onCluster + "/logs/0.out").lastModified();
    QCOMPARE(sim({"sweep", "--resume", onCluster, "--slurm"}, &out), 0);
    QVERIFY2(out.contains("submitted job array"), qPrintable(out));
    QVERIFY(drained(120));
    QCOMPARE(sim({"collect", onCluster}, &out), 0);
    QCOMPARE(sp::test::sweepHashes(onCluster.toStdString()), b);
    int logs = 0;
    for (int i = 0; i < 8; ++i) logs += QFile::exists(onCluster + QString("/logs/%1.out").arg(i));
    QCOMPARE(logs, 8);
    QCOMPARE(QFileInfo(onCluster + "/logs/0.out").lastModified(), untouched);  // task 0 did not run again
  }
};

QTEST_GUILESS_MAIN(TestSweepSlurm)
#include "tst_sweep_slurm.moc"
