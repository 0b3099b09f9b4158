// CSV export of a session log: one file per stream, headers with units, and
// every file read back by Python's csv module with rows as wide as headers.

#include <QProcess>
#include <QStandardPaths>
#include <QTemporaryDir>
#include <QTest>
#include <fstream>
#include <sstream>

#include "app/run/headless_runner.h"
#include "app/log/log_export.h"
#include "tests/app/demo_log.h"

using namespace sp;

namespace {


std::string firstLine(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

// Logs a 1.5 s run of the demo sequence on flat ground to `path`.
bool logRun(const std::string& path) {
  const auto report = sp::test::logDemoRun(path, 1.5, {"rate.log=100"});
  return report && report->health.healthy();
}

}  // namespace

class TestLogExport : public QObject {
  Q_OBJECT

 private slots:
  // Each stream gets its file, and each header names the columns with units.
  void writesOneCsvPerStream() {
    QTemporaryDir dir;
    const std::string log = dir.filePath("session.sqlite").toStdString();
    QVERIFY(logRun(log));
    const std::string out = dir.filePath("csv").toStdString();
    std::string error;
    std::vector<std::string> written;
    QVERIFY2(exportLogCsv(log, out, error, &written), error.c_str());
    QCOMPARE(written.size(), size_t{4});

    const std::string samples = firstLine(out + "/samples.csv");
    QVERIFY2(samples.rfind("step,time_s,base_x_m,base_y_m,base_z_m,base_qw,base_qx,base_qy,base_qz,", 0) == 0,
             samples.c_str());
    QVERIFY2(samples.find("_pos_rad,") != std::string::npos, samples.c_str());
    QVERIFY2(samples.find("_vel_rad_s,") != std::string::npos, samples.c_str());
    QVERIFY2(samples.find("joint_0") == std::string::npos, samples.c_str());  // named from the robot
    const std::string tail = "wheel_fl_normal_N,wheel_fr_normal_N,wheel_rl_normal_N,wheel_rr_normal_N,roll_rad,pitch_rad";
    QVERIFY2(samples.size() > tail.size() && samples.substr(samples.size() - tail.size()) == tail, samples.c_str());
    const std::string laser = firstLine(out + "/laser.csv");
    QVERIFY2(laser.rfind("step,time_s,angle_min_rad,angle_step_rad,range_000_m,range_001_m", 0) == 0, laser.c_str());
    QCOMPARE(firstLine(out + "/commands.csv"), std::string("step,time_s,source,text"));
    QCOMPARE(firstLine(out + "/events.csv"), std::string("step,time_s,kind,text"));
  }

  // Python's csv module reads every file: rows as wide as the header, every
  // numeric column parses as a float, and the command text survives quoting.
  void pythonCsvReadsIt() {
    const QString python = QStandardPaths::findExecutable("python3");
    if (python.isEmpty()) QSKIP("python3 not installed");
    QTemporaryDir dir;
    const std::string log = dir.filePath("session.sqlite").toStdString();
    QVERIFY(logRun(log));
    const std::string out = dir.filePath("csv").toStdString();
    std::string error;
    QVERIFY2(exportLogCsv(log, out, error), error.c_str());
    const char* script = R"(
import csv, sys, os
d = sys.argv[1]
counts = {}
for name in ("samples", "laser", "commands", "events"):
    with open(os.path.join(d, name + ".csv"), newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    for r in body:
        assert len(r) == len(header), (name, len(r), len(header))
        for h, v in zip(header, r):
            if h not in ("source", "text", "kind") and v != "":
                float(v)
    counts[name] = len(body)
with open(os.path.join(d, "commands.csv"), newline="") as f:
    cmds = list(csv.DictReader(f))
assert cmds[0]["source"] == "sequence", cmds
assert cmds[0]["text"].startswith("drive"), cmds
assert counts["samples"] == 151, counts
assert counts["laser"] > 0, counts
print("ok")
)";
    QProcess p;
    p.start(python, {"-c", script, QString::fromStdString(out)});
    QVERIFY(p.waitForFinished(60000));
    QVERIFY2(p.exitCode() == 0, p.readAllStandardError().constData());
    QCOMPARE(p.readAllStandardOutput().trimmed(), QByteArray("ok"));
  }

  // A missing log is refused with a message naming it, and nothing is written.
  void refusesMissingLog() {
    QTemporaryDir dir;
    const std::string log = dir.filePath("missing.sqlite").toStdString();
    std::string error;
    QVERIFY(!exportLogCsv(log, dir.filePath("csv").toStdString(), error));
    QVERIFY2(error.find(log) != std::string::npos, error.c_str());
  }
};

QTEST_GUILESS_MAIN(TestLogExport)
#include "tst_log_export.moc"
