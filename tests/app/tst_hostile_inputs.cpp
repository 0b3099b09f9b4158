// Hostile files and logs (issue 17): what a file or a log holds may not
// crash, hang or write outside where it should; each case answers with an
// error naming the file (and line) and a non-zero exit, through the real
// command-line tools. Controls: the same files and logs unaltered pass.

#include <sqlite3.h>
#include <sys/stat.h>

#include <QDir>
#include <QElapsedTimer>
#include <QFile>
#include <QProcess>
#include <QRegularExpression>
#include <QTemporaryDir>
#include <QTest>

#include "sim/text.h"

namespace {

struct Run {
  int exit = -1;
  QString out, err;
  qint64 ms = 0;
};

// Runs a tool of the build with a 20 s limit (a hang fails the test).
Run tool(const QString& name, const QStringList& args) {
  QProcess p;
  QElapsedTimer t;
  t.start();
  p.start(QStringLiteral(SP_BINARY_DIR "/app/") + name, args);
  Run r;
  if (!p.waitForFinished(20000)) {
    p.kill();
    p.waitForFinished();
    r.err = QStringLiteral("timed out");
    return r;
  }
  r.exit = p.exitStatus() == QProcess::NormalExit ? p.exitCode() : 128 + p.exitCode();
  r.out = QString::fromUtf8(p.readAllStandardOutput());
  r.err = QString::fromUtf8(p.readAllStandardError());
  r.ms = t.elapsed();
  return r;
}

bool sql(const QString& path, const char* statement) {
  sqlite3* db = nullptr;
  const bool ok = sqlite3_open(path.toUtf8().constData(), &db) == SQLITE_OK &&
                  sqlite3_exec(db, statement, nullptr, nullptr, nullptr) == SQLITE_OK;
  sqlite3_close(db);
  return ok;
}

void write(const QString& path, const QByteArray& text) {
  QFile f(path);
  QVERIFY(f.open(QIODevice::WriteOnly | QIODevice::Truncate));
  f.write(text);
}

}  // namespace

class TestHostileInputs : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    QVERIFY(dir_.isValid());
    log_ = dir_.filePath(QStringLiteral("good.splog"));
    const Run r = tool(QStringLiteral("simpartner-sim"), {"run", "--world", SP_SOURCE_DIR "/terrains/flat.world.xml",
                                                         "--duration", "2", "--rtf", "max", "--log", log_});
    QVERIFY2(r.exit == 0, qPrintable(r.err));
  }

  // A robot file that is a device, a folder or a pipe: read, /dev/zero
  // never ends; each is an error at the world's line, at once.
  void robotFileNotRegular_data() {
    QTest::addColumn<QString>("file");
    QTest::newRow("device") << QStringLiteral("/dev/zero");
    QTest::newRow("folder") << QStringLiteral("/tmp");
    QTest::newRow("pipe") << QStringLiteral("pipe.xml");
  }
  void robotFileNotRegular() {
    QFETCH(QString, file);
    QTemporaryDir dir;
    QVERIFY(mkfifo(dir.filePath(QStringLiteral("pipe.xml")).toUtf8().constData(), 0600) == 0);
    const QString world = dir.filePath(QStringLiteral("w.world.xml"));
    write(world, "<world name=\"w\" version=\"1\">\n  <terrain type=\"plane\"/>\n  <robot name=\"r\" file=\"" +
                     file.toUtf8() + "\"/>\n</world>\n");
    for (const char* command : {"check", "run"}) {
      const Run r = tool(QStringLiteral("simpartner-sim"),
                         QString(command) == "check" ? QStringList{"check", world}
                                                     : QStringList{"run", "--world", world, "--duration", "0.1"});
      QVERIFY2(r.exit == 1, qPrintable(r.err));
      QVERIFY2(r.err.contains(world + ":3: error: robot 'r': robot file '" + file + "' is not a regular file"),
               qPrintable(r.err));
    }
  }

  // An empty robot file's error has a line for editors to jump to.
  void emptyFileHasALine() {
    const QString empty = dir_.filePath(QStringLiteral("empty.xml"));
    write(empty, "");
    const Run r = tool(QStringLiteral("simpartner-sim"), {"check", empty});
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.err.contains(empty + ":1: error: XML syntax: empty document"), qPrintable(r.err));
  }

  // Runs that would simulate nothing and say they succeeded are refused.
  void nothingSimulatedIsRefused() {
    const QString world = QStringLiteral(SP_SOURCE_DIR "/terrains/flat.world.xml");
    Run r = tool(QStringLiteral("simpartner-sim"), {"run", "--world", world, "--duration", "inf"});
    QCOMPARE(r.exit, 2);
    QVERIFY2(r.err.contains("--duration: expected a finite positive number, got 'inf'"), qPrintable(r.err));
    r = tool(QStringLiteral("simpartner-sim"), {"run", "--world", world, "--set", "physics.step=1e-300"});
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.err.contains("physics.step: must be >= 1e-05, got 1e-300"), qPrintable(r.err));
    r = tool(QStringLiteral("simpartner-sim"), {"run", "--world", world, "--duration", "0.05", "--rtf", "max"});
    QVERIFY2(r.exit == 0, qPrintable(r.err));  // control
  }

  // resim on untrusted logs. Control: the log as written re-simulates (0).
  void resimOfAlteredLogs() {
    Run r = tool(QStringLiteral("simpartner-sim"), {"resim", log_});
    QVERIFY2(r.exit == 0 && r.out.contains("no divergence"), qPrintable(r.err));

    // No hashes: no verdict, not "no divergence".
    const QString noHashes = dir_.filePath(QStringLiteral("nohashes.splog"));
    QVERIFY(QFile::copy(log_, noHashes) && sql(noHashes, "DELETE FROM hashes"));
    r = tool(QStringLiteral("simpartner-sim"), {"resim", noHashes});
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.err.contains(noHashes + ": the log holds no state hash"), qPrintable(r.err));

    // A hash at step 2^62 would run for ages: refused at once.
    const QString far = dir_.filePath(QStringLiteral("far.splog"));
    QVERIFY(QFile::copy(log_, far) && sql(far, "INSERT INTO hashes(step, hash) VALUES (4611686018427387904, 5)"));
    r = tool(QStringLiteral("simpartner-sim"), {"resim", far});
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.err.contains("step 4611686018427387904 lies beyond the log's last snapshot"), qPrintable(r.err));
    QVERIFY(r.ms < 10000);

    // A damaged snapshot: the file and the step named.
    const QString bad = dir_.filePath(QStringLiteral("badsnap.splog"));
    QVERIFY(QFile::copy(log_, bad) && sql(bad, "UPDATE snapshots SET data = X'00112233' WHERE step = 0"));
    r = tool(QStringLiteral("simpartner-sim"), {"resim", bad});
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.err.contains(bad + ": the snapshot at step 0: not a snapshot"), qPrintable(r.err));

    // A logged file name that climbs out of any folder: re-simulation holds
    // the logged files in memory, reads none from disk and writes nothing.
    // The climbing name is refused, named in the error (the robot it
    // refers to is not among the logged files at the place it points to),
    // and no file appears anywhere in the test's folder or beyond it.
    const QString outside = dir_.filePath(QStringLiteral("outside"));
    const QString climbing = dir_.filePath(QStringLiteral("climb.splog"));
    const QByteArray name = ("../../../../.." + outside + "/evil.world.xml").toUtf8();
    QVERIFY(QFile::copy(log_, climbing) &&
            sql(climbing, ("UPDATE meta SET value = '" + name + "' WHERE key = 'world_file'").constData()));
    const QStringList before = QDir(dir_.path()).entryList(QDir::AllEntries | QDir::NoDotAndDotDot);
    r = tool(QStringLiteral("simpartner-sim"), {"resim", climbing});
    qInfo("climbing world_file: exit %d: %s", r.exit, qPrintable(r.err.left(300)));
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.err.contains(climbing + ": cannot rebuild the logged world") && r.err.contains(QString::fromUtf8(name)),
             qPrintable(r.err));
    QCOMPARE(QDir(dir_.path()).entryList(QDir::AllEntries | QDir::NoDotAndDotDot), before);
    QVERIFY(!QFile::exists(outside));
    // The control: a name that is on no disk either, beside the logged
    // robot's folder, re-simulates from the logged contents.
    const QString plain = dir_.filePath(QStringLiteral("plain.splog"));
    QVERIFY(QFile::copy(log_, plain) &&
            sql(plain, "UPDATE meta SET value = '" SP_SOURCE_DIR "/terrains/not-on-disk.world.xml' WHERE key = 'world_file'"));
    r = tool(QStringLiteral("simpartner-sim"), {"resim", plain});
    QCOMPARE(r.exit, 0);
    QVERIFY2(r.out.contains("no divergence"), qPrintable(r.out));
    QVERIFY(!QFile::exists(SP_SOURCE_DIR "/terrains/not-on-disk.world.xml"));
  }

  // Errors cut a quoted value longer than 80 characters to 80 and its
  // length: a 5 MB value is not echoed. Apostrophes are not quotes.
  void longValuesAreCut() {
    const QByteArray huge(5000000, 'x');
    const QString params = dir_.filePath(QStringLiteral("big.params"));
    write(params, "physics.solver = " + huge + "\n");
    const QString seq = dir_.filePath(QStringLiteral("big.seq"));
    write(seq, "0 drive " + QByteArray(5000000, '9') + " 0\n");
    for (const QString& file : {params, seq}) {
      const Run r = tool(QStringLiteral("simpartner-sim"), {"check", file});
      QCOMPARE(r.exit, 1);
      QVERIFY2(r.err.size() < 400 && r.err.contains(QStringLiteral("\u2026' (5000000 characters)")), qPrintable(r.err.left(400)));
    }
    QCOMPARE(sp::cutLongQuotes("the robot's file '" + std::string(100, 'a') + "' and 'b'"),
             "the robot's file '" + std::string(80, 'a') + "\u2026' (100 characters) and 'b'");
    QCOMPARE(sp::cutLongQuotes("got 'short' and 'don't'"), std::string("got 'short' and 'don't'"));
  }

  // Values check used to accept and run aborted on (SIGABRT, exit 134):
  // each is an error at its line now, for check and for run. Control: the
  // same files with plausible values run (exit 0).
  void implausibleFileValues_data() {
    QTest::addColumn<QByteArray>("link");     // the robot's link element
    QTest::addColumn<QByteArray>("terrain");  // the world's terrain element
    QTest::addColumn<QByteArray>("asc");      // the terrain file, if any
    QTest::addColumn<QString>("message");
    const QByteArray link = R"(<link name="base" mass="5" xyz="0 0 1"><geom type="sphere" radius="0.2"/></link>)";
    const QByteArray plane = R"(<terrain type="plane"/>)";
    const QByteArray asc = "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\n0 0 0\n0 0 0\n0 0 0\n";
    QTest::newRow("link mass") << QByteArray(link).replace("mass=\"5\"", "mass=\"1e300\"") << plane << QByteArray()
                               << "mass: 1e+300 is not a plausible value";
    QTest::newRow("geom radius") << QByteArray(link).replace("radius=\"0.2\"", "radius=\"1e300\"") << plane
                                 << QByteArray() << "radius: 1e+300 is not a plausible value";
    QTest::newRow("link xyz") << QByteArray(link).replace("xyz=\"0 0 1\"", "xyz=\"1e300 0 1\"") << plane
                              << QByteArray() << "xyz: 1e+300 is not a plausible value";
    QTest::newRow("asc cellsize") << link << QByteArray(R"(<terrain type="heightfield" file="t.asc"/>)")
                                  << QByteArray(asc).replace("cellsize 1", "cellsize 1e308")
                                  << "the terrain spans inf x inf m: at most 1e+05 m a side";
    QTest::newRow("pgm heights") << link
                                 << QByteArray(R"(<terrain type="heightfield" file="t.pgm" width="4" depth="4" min_height="-1e308" max_height="1e308"/>)")
                                 << QByteArray() << "min_height: -1e+308 is not a plausible value";
    QTest::newRow("heightfield width") << link
                                       << QByteArray(R"(<terrain type="heightfield" file="t.asc" width="1e300"/>)") << asc
                                       << "width: 1e+300 is not a plausible value";
    QTest::newRow("control") << link << QByteArray(R"(<terrain type="heightfield" file="t.asc"/>)") << asc << QString();
  }
  void implausibleFileValues() {
    QFETCH(QByteArray, link);
    QFETCH(QByteArray, terrain);
    QFETCH(QByteArray, asc);
    QFETCH(QString, message);
    QTemporaryDir dir;
    write(dir.filePath(QStringLiteral("r.xml")), "<robot name=\"r\" version=\"1\">\n  " + link + "\n</robot>\n");
    write(dir.filePath(QStringLiteral("t.asc")), asc);
    write(dir.filePath(QStringLiteral("t.pgm")), QByteArray("P2\n2 2\n255\n0 1\n2 3\n"));
    const QString world = dir.filePath(QStringLiteral("w.world.xml"));
    write(world, "<world name=\"w\" version=\"1\">\n  " + terrain + "\n  <robot name=\"r\" file=\"r.xml\"/>\n</world>\n");
    for (const QStringList& args : {QStringList{"check", world},
                                    QStringList{"run", "--world", world, "--duration", "0.2", "--rtf", "max"}}) {
      const Run r = tool(QStringLiteral("simpartner-sim"), args);
      if (message.isEmpty()) {
        QVERIFY2(r.exit == 0, qPrintable(r.err));
      } else {
        QVERIFY2(r.exit == 1 && r.err.contains(message), qPrintable(QString::number(r.exit) + " " + r.err));
        QVERIFY2(r.err.contains(QRegularExpression(QStringLiteral("\\.(xml|asc):\\d+: error: |\\.asc: error: "))), qPrintable(r.err));
      }
    }
  }

  // A CSV that cannot be written whole (a full disk: /dev/full) fails
  // loudly. Control: the same run to a file exits 0.
  void csvOnAFullDisk() {
    const QString world = QStringLiteral(SP_SOURCE_DIR "/terrains/flat.world.xml");
    Run r = tool(QStringLiteral("simpartner-sim"),
                 {"run", "--world", world, "--duration", "0.5", "--rtf", "max", "--csv", "/dev/full"});
    QCOMPARE(r.exit, 4);
    QVERIFY2(r.err.contains("/dev/full: error: writing the CSV failed"), qPrintable(r.err));
    r = tool(QStringLiteral("simpartner-sim"), {"run", "--world", world, "--duration", "0.5", "--rtf", "max", "--csv",
                                                dir_.filePath(QStringLiteral("ok.csv"))});
    QVERIFY2(r.exit == 0, qPrintable(r.err));
  }

  // Implausible command values are errors even without a robot to check
  // limits against. Control: a plausible drive passes.
  void implausibleCommandValues() {
    const QString seq = dir_.filePath(QStringLiteral("huge.seq"));
    write(seq, "0 drive 1e300 0\n1 turn 1e300 10\n");
    Run r = tool(QStringLiteral("simpartner-sim"), {"check", seq});
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.err.contains(seq + ":1: error: drive: 1e300 is not a plausible value") &&
                 r.err.contains(seq + ":2: error: turn: 1e300 is not a plausible value"),
             qPrintable(r.err));
    write(seq, "0 drive 0.5 0\n1 turn 0.3 10\n");
    r = tool(QStringLiteral("simpartner-sim"), {"check", seq});
    QVERIFY2(r.exit == 0, qPrintable(r.err));
  }

  // Issue 30: a terrain edit outside the world's 81 x 81 heightfield is
  // refused at its line by check, run and rehearse (it used to vanish: 0
  // errors, "0 commands applied", exit 0), and on a plane world too.
  // Control: the same edit inside the grid checks, runs and rehearses.
  void terrainEditsOutsideTheGrid() {
    const QString bumpy = QStringLiteral(SP_SOURCE_DIR "/terrains/bumpy.world.xml");
    const QString flat = QStringLiteral(SP_SOURCE_DIR "/terrains/flat.world.xml");
    const QString seq = dir_.filePath(QStringLiteral("edit.seq"));
    write(seq, "0.2 terrain 200 200 2 2 0.1 0.1 0.1 0.1\n");
    const QString outside = seq + ":1: error: terrain: the patch (columns 200..201, rows 200..201) lies outside the 81 x 81 heightfield";
    for (const QStringList& args : {QStringList{"check", bumpy, seq},
                                    QStringList{"run", "--world", bumpy, "--commands", seq, "--rtf", "max", "--duration", "1"},
                                    QStringList{"rehearse", "--world", bumpy, "--commands", seq}}) {
      const Run r = tool(QStringLiteral("simpartner-sim"), args);
      QVERIFY2(r.exit == 1 && r.err.contains(outside), qPrintable(args.join(' ') + ": " + r.err));
    }
    Run r = tool(QStringLiteral("simpartner-sim"), {"check", flat, seq});
    QVERIFY2(r.exit == 1 && r.err.contains(seq + ":1: error: terrain: the world's terrain is a plane"), qPrintable(r.err));
    write(seq, "0.2 terrain 10 10 2 2 0.1 0.1 0.1 0.1\n");
    for (const QStringList& args : {QStringList{"check", bumpy, seq},
                                    QStringList{"run", "--world", bumpy, "--commands", seq, "--rtf", "max", "--duration", "1"}}) {
      r = tool(QStringLiteral("simpartner-sim"), args);
      QVERIFY2(r.exit == 0, qPrintable(args.join(' ') + ": " + r.err));
    }
    QVERIFY2(r.out.contains("1 commands applied"), qPrintable(r.out));
  }

  // logcheck: a log without its samples is not ok. Control: the log is.
  void logcheckWantsSamples() {
    Run r = tool(QStringLiteral("simpartner-logcheck"), {log_});
    QVERIFY2(r.exit == 0 && r.out.startsWith("ok"), qPrintable(r.out));
    const QString empty = dir_.filePath(QStringLiteral("nosamples.splog"));
    QVERIFY(QFile::copy(log_, empty) && sql(empty, "DELETE FROM samples"));
    r = tool(QStringLiteral("simpartner-logcheck"), {empty});
    QCOMPARE(r.exit, 1);
    QVERIFY2(r.out.contains(empty + ": no samples"), qPrintable(r.out));
    const QString dropped = dir_.filePath(QStringLiteral("dropped.splog"));
    QVERIFY(QFile::copy(log_, dropped) && sql(dropped, "DROP TABLE samples"));
    r = tool(QStringLiteral("simpartner-logcheck"), {dropped});
    QCOMPARE(r.exit, 1);
  }

 private:
  QTemporaryDir dir_;
  QString log_;
};

QTEST_GUILESS_MAIN(TestHostileInputs)
#include "tst_hostile_inputs.moc"
