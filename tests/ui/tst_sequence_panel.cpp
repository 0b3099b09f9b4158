// The Sequence dock in the console under Xvfb, against its stand-in on
// loopback: errors inline as you type, a rehearsal from the robot's state
// with every rule's verdict, the path and the amber robot in the 3D view, the
// scrubber, Send only for an unchanged passed sequence, and the robot
// running it to the end under the guard.

#include <QDockWidget>
#include <QAbstractScrollArea>
#include <QSlider>
#include <QPlainTextEdit>
#include <QFile>
#include <QPushButton>
#include <QRegularExpression>
#include <QSettings>
#include <QSignalSpy>
#include <QSurfaceFormat>
#include <QTemporaryDir>
#include <QTreeWidget>
#include <QLabel>
#include <QSignalSpy>
#include <QTest>

#include <chrono>
#include <cmath>
#include <mutex>
#include <thread>

#include "app/console/console_session.h"
#include "app/rehearse/sequence_relay.h"
#include "app/robot/stand_in.h"
#include "net/robot_client.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "ui/robot_connection.h"
#include "app/log/session_log.h"
#include "tests/ui/console_fixture.h"
#include "tests/ui/readable.h"
#include "ui/main_window.h"
#include "ui/scene_view.h"
#include "ui/jobs/sequence/sequence_panel.h"

using namespace sp;

class TestSequencePanel : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    if (QGuiApplication::platformName() == QLatin1String("offscreen"))
      QSKIP("the 3D view needs an X server: run under xvfb-run");
    QVERIFY(dir_.isValid());
    const QString error = test::startConsole(dir_, QStringLiteral(SP_SOURCE_DIR "/terrains/flat.world.xml"), options_, window_);
    QVERIFY2(error.isEmpty(), qPrintable(error));
    QTRY_VERIFY_WITH_TIMEOUT(window_->lastTelemetry().has_value(), 20000);
    QTRY_VERIFY_WITH_TIMEOUT(test::sequencePanel(*window_)->sendButton() != nullptr, 1000);
  }
  void cleanupTestCase() { window_.reset(); }

  // Safety path: the guard must not wait on the window. Criterion: with
  // the GUI thread blocked (sleeping, no events) from the moment the
  // sequence is sent, a stand-in whose friction was changed behind the
  // console's back (0.02 instead of 1.0) still reports the sequence aborted
  // by the guard's ABORT before the GUI thread wakes, 6 s later. A monitor
  // client on its own thread watches.
  void guardAbortsWithTheGuiBlocked() {
    const QString flat = QStringLiteral(SP_SOURCE_DIR "/terrains/flat.world.xml");
    QFile in(flat);
    QVERIFY(in.open(QIODevice::ReadOnly));
    QByteArray xml = in.readAll();
    xml.replace("mu=\"1.0\"", "mu=\"0.02\"").replace("mu=\"0.8\"", "mu=\"0.02\"");
    xml.replace("../robots/workpartner.xml", SP_SOURCE_DIR "/robots/workpartner.xml");
    const QString slippery = dir_.filePath(QStringLiteral("slippery.world.xml"));
    QFile out(slippery);
    QVERIFY(out.open(QIODevice::WriteOnly) && out.write(xml) == xml.size());
    out.close();
    StandInOptions so;
    so.worldFile = slippery.toStdString();
    so.port = 0;
    so.token = "00112233445566778899aabbccddeeff";
    so.log = false;
    Diagnostics diag;
    auto robot = StandInRobot::create(so, diag);
    QVERIFY2(robot, diag.format().c_str());
    QVERIFY(robot->start().empty());

    net::RobotClientConfig config;
    config.port = robot->port();
    config.token = so.token;
    config.name = "guarded console";
    RobotConnection connection;
    std::optional<net::TelemetryMsg> last;
    connect(&connection, &RobotConnection::telemetry, this, [&](const net::TelemetryMsg& t) { last = t; });
    connection.open(config);
    connection.acquireLease();
    QTRY_VERIFY_WITH_TIMEOUT(connection.stats().leaseHeld && last.has_value(), 20000);

    // A monitor on its own thread: when did the robot say "aborted"?
    std::mutex mutex;
    std::optional<std::chrono::steady_clock::time_point> abortedAt;
    std::string reason;
    std::optional<net::SequenceStateKind> lastState;
    net::RobotClientConfig mc = config;
    mc.name = "monitor";
    mc.role = net::Role::Monitor;
    net::RobotClientCallbacks cb;
    cb.sequence = [&](const net::SequenceStateMsg& m) {
      std::lock_guard lock(mutex);
      lastState = m.state;
      if (m.state == net::SequenceStateKind::Aborted && !abortedAt) {
        abortedAt = std::chrono::steady_clock::now();
        reason = m.reason;
      }
    };
    net::RobotClient monitor(mc, cb);
    monitor.start();
    QTRY_VERIFY_WITH_TIMEOUT(monitor.stats().connected, 20000);

    Diagnostics d2;
    const WorldModel world = *loadWorld(flat.toStdString(), d2);  // what the console believes
    RehearsalPlan plan{world, {}, {}, {}, {}};
    plan.commands = *parseCommandSequence("0.2 drive 1.0 20\n8 stop\n", "s.seq", d2, &world.robots[0].model);
    std::string why;
    plan.start = startFromTelemetry(*last, world.robots[0].model, why);
    const RehearsalResult result = rehearse(plan);
    QVERIFY(result.passed);
    const std::optional<net::SequenceMsg> msg = sequenceMessage(plan, result, why);
    QVERIFY(msg);
    connection.guard()->relayed(*msg, result, plan.rules, world.robots[0].model);
    connection.sendSequence(*msg);
    std::this_thread::sleep_for(std::chrono::seconds(6));  // the GUI thread blocked: no event is processed
    const auto woke = std::chrono::steady_clock::now();
    {
      std::lock_guard lock(mutex);
      QVERIFY2(abortedAt.has_value(), "the robot must have aborted while the GUI thread slept");
      QVERIFY(*abortedAt < woke);
      qInfo("aborted while the GUI slept: %s", reason.c_str());
      QVERIFY(reason.find("ABORT from 'guarded console': guard: ") != std::string::npos);
    }
    QSignalSpy tripped(&connection, &RobotConnection::guardTripped);
    QTRY_COMPARE(tripped.size(), 1);  // the window hears of it once it runs again

    // The control: the same departure with the guard not armed for it goes
    // on while the GUI sleeps (nothing else aborts it).
    QTRY_VERIFY_WITH_TIMEOUT(std::hypot(last->baseVelocity[0], last->baseVelocity[1]) < 0.02, 20000);
    plan.start = startFromTelemetry(*last, world.robots[0].model, why);
    const RehearsalResult again = rehearse(plan);
    const std::optional<net::SequenceMsg> second = sequenceMessage(plan, again, why);
    QVERIFY(second && second->hash == msg->hash);  // the same text: the same hash
    {
      std::lock_guard lock(mutex);
      abortedAt.reset();
    }
    connection.sendSequence(*second);
    std::this_thread::sleep_for(std::chrono::seconds(6));
    {
      std::lock_guard lock(mutex);
      QVERIFY2(!abortedAt.has_value(), reason.c_str());
      QVERIFY(lastState == net::SequenceStateKind::Running);  // it runs, unguarded: the control is not vacuous
    }
    monitor.stop();
    connection.close();
    robot->stop();
  }

  // At 1280x800 the Sequence dock shows everything whole, nothing below
  // the fold (issue 59: with a typo the editor shrank to two lines, the
  // reason was cut in half, Watch, Send and Abort fell below the fold);
  // with a failed rule its verdict's row shows whole, failed rules first.
  void fitsAt1280x800() {
    QCOMPARE(window_->size(), QSize(1280, 800));
    SequencePanel* p = test::sequencePanel(*window_);
    window_->findChild<QDockWidget*>(QStringLiteral("sequenceDock"))->raise();
    p->setText(QStringLiteral("1.0 drive 0.5 0\n2.0 drvie 0.5 0\n6.0 stop\n"));
    QTRY_VERIFY(!p->errors().isEmpty());
    QTest::qWait(100);  // laid out
    QStringList bad = test::unreadable(p);
    QVERIFY2(bad.isEmpty(), qPrintable("with a typo:\n" + bad.join('\n')));
    QVERIFY(p->findChild<QPlainTextEdit*>()->height() >= 4 * p->fontMetrics().lineSpacing());
    // A rule that fails: full speed with the hinge at its 30 degrees.
    p->setText(QStringLiteral("0.2 drive 1.94 30\n6.0 stop\n"));
    QTRY_VERIFY2(p->errors().isEmpty() && p->rehearseButton()->isEnabled(), qPrintable(p->errors().join('\n')));
    QSignalSpy rehearsed(p, &SequencePanel::rehearsed);
    QVERIFY2(p->rehearse(), qPrintable(p->status()));
    QVERIFY2(rehearsed.wait(60000), qPrintable(p->status()));
    QVERIFY2(!rehearsed.at(0).at(0).toBool(), "the control: this sequence must fail a rule");
    QTest::qWait(100);
    bad = test::unreadable(p);
    QVERIFY2(bad.isEmpty(), qPrintable("with a failed rule:\n" + bad.join('\n')));
    QTreeWidget* verdicts = p->verdictList();
    QTreeWidgetItem* first = verdicts->topLevelItem(0);
    QVERIFY(first);
    QVERIFY2(first->foreground(0).color() == QColor(190, 0, 0), qPrintable(first->text(1)));  // failed first
    const QRect row = verdicts->visualItemRect(first);
    QVERIFY2(verdicts->viewport()->rect().contains(row), qPrintable(first->text(1)));
    QVERIFY2(row.height() >= verdicts->fontMetrics().boundingRect(QRect(0, 0, verdicts->columnWidth(1) - 10, 1000),
                                                                   Qt::TextWordWrap, first->text(1)).height(),
             qPrintable(first->text(1)));
  }

  // A typing error is marked on its line as soon as the text is checked;
  // Rehearse refuses it and says which line.
  void typoMarkedInline() {
    SequencePanel* p = test::sequencePanel(*window_);
    p->setText(QStringLiteral("1.0 drive 0.5 0\n2.0 drvie 0.5 0\n3.0 target knee_fl 120\n"));
    QCOMPARE(p->markedLines(), (QList<int>{2}));
    QVERIFY2(p->errors().size() == 1 && p->errors()[0].startsWith("line 2: unknown command 'drvie'"),
             qPrintable(p->errors().join('\n')));
    QVERIFY(!p->rehearse());
    QVERIFY(p->status().contains("line 2"));
    // Disabled means disabled, with the reason beside it (issue 31: the
    // button looked enabled and its refusal landed out of view).
    QVERIFY(!p->rehearseButton()->isEnabled());
    auto* why = p->findChild<QLabel*>(QStringLiteral("sequenceWhy"));
    QVERIFY(why && why->isVisibleTo(p));
    QVERIFY2(why->text().contains(QLatin1String("line 2: unknown command 'drvie'")), qPrintable(why->text()));
    // Fixed, the limits are checked next: knee_fl's range is [-40, 80] deg.
    p->setText(QStringLiteral("1.0 drive 0.5 0\n2.0 drive 0.5 0\n3.0 target knee_fl 120\n"));
    QCOMPARE(p->markedLines(), (QList<int>{3}));
    QVERIFY(p->errors()[0].contains("outside joint 'knee_fl' limits"));
  }

  // Criterion: the rehearsal passes with ten verdicts, all passed (after
  // the fast profile's preview, which cannot be sent); the 3D
  // view draws its path (> 10 points) and the amber robot where the
  // scrubber is (within 1 mm of the rehearsed base there); an edit disables
  // Send; sent unchanged, the robot runs it to done with the guard quiet,
  // and the session log holds the rehearsal and the relay.
  void rehearseScrubAndSend() {
    SequencePanel* p = test::sequencePanel(*window_);
    p->setText(QStringLiteral("0.2 drive 0.5 10\n3.0 stop\n"));
    QVERIFY(p->errors().isEmpty());
    QSignalSpy rehearsed(p, &SequencePanel::rehearsed);
    // Issue 32: the fast profile's verdicts come first, Send still off and
    // the status saying the full-fidelity rehearsal runs; then the full one.
    bool previewSendable = true, previewFast = false;
    QString previewStatus;
    int previewsBeforeFull = 0;
    const QMetaObject::Connection seen = connect(p, &SequencePanel::previewed, this, [&] {
      previewSendable = p->sendButton()->isEnabled();
      previewFast = p->result() && p->result()->fast;
      previewStatus = p->status();
      previewsBeforeFull += rehearsed.isEmpty();
    });
    QTest::mouseClick(p->rehearseButton(), Qt::LeftButton);
    QVERIFY(rehearsed.wait(30000));
    disconnect(seen);
    QVERIFY2(rehearsed.at(0).at(0).toBool(), qPrintable(p->status()));
    QCOMPARE(previewsBeforeFull, 1);
    QVERIFY(previewFast && !previewSendable);
    QVERIFY2(previewStatus.contains("full-fidelity rehearsal, the one Send relays, is running"), qPrintable(previewStatus));
    QVERIFY(!p->result()->fast);
    QCOMPARE(p->verdictList()->topLevelItemCount(), kRuleCount);
    for (int i = 0; i < kRuleCount; ++i)
      QVERIFY2(p->result()->verdicts[i].passed, p->result()->verdicts[i].message().c_str());
    SceneView* scene = window_->sceneView();
    QTRY_VERIFY(scene->drawnRehearsalPathPoints() > 10);
    p->scrubTo(2.0);
    QCOMPARE(p->scrubTime(), 2.0);
    const std::optional<RehearsalSample> at = p->result()->at(2.0);
    QVERIFY(at);
    QTRY_VERIFY(std::hypot(scene->drawnRehearsalBasePose().p.x - at->base.p.x,
                           scene->drawnRehearsalBasePose().p.y - at->base.p.y) < 1e-3);
    QTRY_VERIFY(scene->rehearsalRobotDrawn());  // scrubbed 2 s ahead of the robot: drawn

    // Robustness here (issue 61): the draws come from what the console
    // knows of the robot (its calibration, the prior where nothing is fitted
    // yet), the verdict says so, and the rehearsed path gets its band.
    QCOMPARE(scene->drawnRehearsalBand(), size_t(0));
    QVERIFY(p->checkRobustness());
    QTRY_VERIFY_WITH_TIMEOUT(!p->busy(), 120000);
    QVERIFY2(p->status().contains("draws of what the console knows of the robot; 90 % of the ends within"), qPrintable(p->status()));
    QTRY_VERIFY(scene->drawnRehearsalBand() == scene->drawnRehearsalPathPoints());
    QVERIFY(scene->drawnRehearsalBand() > 10);

    // Robustness on cluster: the same perturbed rehearsals written as a sweep
    // (app/sweep/sweep.h), from the robot's state; no cluster answers here, so the
    // status names the folder and what sbatch said, or the command to run.
    const QString sweep = dir_.filePath("cluster-sweep");
    QVERIFY(p->robustnessOnCluster(sweep));
    QTRY_VERIFY_WITH_TIMEOUT(!p->busy(), 120000);
    QVERIFY2(p->status().contains(sweep), qPrintable(p->status()));
    QFile manifest(sweep + "/manifest.txt");
    QVERIFY(manifest.open(QIODevice::ReadOnly));
    const QString text = QString::fromUtf8(manifest.readAll());
    QVERIFY(text.contains(QStringLiteral("\nsamples %1\n").arg(FlightRules{}.robustSamples)));
    QVERIFY(text.contains("\nstart_base ") && text.contains("\nsample 0 1\n"));
    QVERIFY(QFile::exists(sweep + "/sequence.seq") && QFile::exists(sweep + "/flight.rules"));

    QTRY_VERIFY(p->sendButton()->isEnabled());
    p->setText(QStringLiteral("0.2 drive 0.5 11\n3.0 stop\n"));
    QVERIFY(!p->sendButton()->isEnabled());
    QVERIFY(!p->send());
    QVERIFY(p->status().contains("changed since its rehearsal"));
    // Back to the very text rehearsed: it may go (the robot refuses it if
    // it has moved since, as a stale rehearsal).
    p->setText(QStringLiteral("0.2 drive 0.5 10\n3.0 stop\n"));
    QVERIFY(p->sendButton()->isEnabled());
    QTest::mouseClick(p->sendButton(), Qt::LeftButton);
    QTRY_COMPARE_WITH_TIMEOUT(p->relay().phase(), SequenceRelay::Phase::Done, 20000);
    QTest::qWait(2500);  // the guard watches the settling time too
    QVERIFY2(p->relay().compared() > 50, qPrintable(QString::number(p->relay().compared())));
    QVERIFY(p->relay().worstPosition() < 0.05);
    QVERIFY(p->status().contains("done on the robot"));
    // The run ended: the amber robot is not drawn any more, its path is
    // (issue 31: it stood where last scrubbed, in the follow camera's way).
    QTRY_VERIFY(!scene->rehearsalRobotDrawn());
    QVERIFY(scene->drawnRehearsalPathPoints() > 10);

    // The log: the rehearsals, the relay, the robot's run of it.
    const QString log = window_->logPath();
    window_.reset();  // the stand-in stops: its log is complete
    std::string error;
    auto reader = SessionLogReader::open(log.toStdString(), error);
    QVERIFY2(reader, error.c_str());
    QStringList kinds;
    for (const LogEvent& e : reader->events()) kinds << QString::fromStdString(e.kind + ": " + e.text);
    const QString all = kinds.join('\n');
    QVERIFY2(all.contains(QRegularExpression("rehearsal: [0-9a-f]{16} passed")), qPrintable(all));
    QVERIFY2(all.contains(QRegularExpression("relay: sent [0-9a-f]{16} \\(2 commands\\)")), qPrintable(all));
    QVERIFY2(all.contains(QRegularExpression("sequence: done [0-9a-f]{16}")), qPrintable(all));
  }

 private:
  QTemporaryDir dir_;
  ConsoleOptions options_;
  std::unique_ptr<MainWindow> window_;
};

int main(int argc, char** argv) { return sp::test::glTestMain<TestSequencePanel>(argc, argv); }

#include "tst_sequence_panel.moc"
