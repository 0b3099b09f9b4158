// Console jobs plug in through the context alone (ui/console_context.h):
// a toy job installed into a running console gets a dock and a menu item,
// sees the live feed, commands the robot through the sink and runs work in
// the background; and while a replay is shown nothing the operator does at
// the keys or controls reaches the live robot. Real window under Xvfb, real
// stand-in on loopback, a real session log.

#include <QAction>
#include <QApplication>
#include <QCommandLineParser>
#include <QComboBox>
#include <QDockWidget>
#include <QLabel>
#include <QMenu>
#include <QMenuBar>
#include <QTemporaryDir>
#include <QTest>

#include <atomic>
#include <thread>

#include "app/console/console_session.h"
#include "net/robot_client.h"
#include "tests/app/demo_log.h"
#include "tests/ui/console_fixture.h"
#include "ui/background_jobs.h"
#include "ui/console_context.h"
#include "ui/jobs/jobs.h"
#include "ui/jobs/drive/control_panel.h"
#include "ui/jobs/replay/replay_panel.h"
#include "ui/link_panel.h"
#include "ui/robot_connection.h"
#include "ui/robot_feed.h"

using namespace sp;

namespace {

// A job that knows nothing of MainWindow: everything through the context.
class ToyJob : public ConsoleJob {
  Q_OBJECT

 public:
  QString name() const override { return QStringLiteral("toy"); }
  // Its own command-line option, which the window knows nothing of.
  QList<QCommandLineOption> commandLineOptions() const override {
    return {QCommandLineOption(QStringLiteral("toy-greeting"), QStringLiteral("What the toy dock says."),
                               QStringLiteral("TEXT"))};
  }
  QString takeCommandLine(const QCommandLineParser& parser) override {
    if (!parser.isSet(QStringLiteral("toy-greeting"))) return {};
    greeting_ = parser.value(QStringLiteral("toy-greeting"));
    return greeting_.isEmpty() ? QStringLiteral("<command line>: error: --toy-greeting: empty") : QString();
  }
  void install(ConsoleContext& context) override {
    context_ = &context;
    label_ = new QLabel(greeting_);
    dock_ = context.host().addDock(QStringLiteral("Toy"), QStringLiteral("toyDock"), label_, DockPlace::Side, true);
    action_ = new QAction(QStringLiteral("Toy drive"), this);
    connect(action_, &QAction::triggered, this, [this] { refusal_ = context_->sendCommand(DriveCmd{0.2, 0}); });
    context.host().addMenuAction(QStringLiteral("&Tools"), action_);
    connect(&context.feeds(), &FeedSwitch::frame, this, [this](const RobotFrame& f) {
      ++frames_;
      lastX_ = f.base.p.x;
    });
  }
  QString greeting_ = QStringLiteral("toy");
  ConsoleContext* context_ = nullptr;
  QLabel* label_ = nullptr;
  QDockWidget* dock_ = nullptr;
  QAction* action_ = nullptr;
  int frames_ = 0;
  double lastX_ = 0;
  QString refusal_ = QStringLiteral("not tried");
};

}  // namespace

class TestJobs : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() { QVERIFY(dir_.isValid()); }

  // A job declares its own command-line option: the console's parser
  // takes it beside the others and the job its value, the window untouched
  // (issue 60: adding --no-calibration edited MainWindow). A bad value is
  // the job's to refuse; the built-in jobs' options reach them the same way
  // (--monitor: no lease taken). Control: without the toy job the option
  // is unknown to the parser.
  void toyJobTakesItsOwnOption() {
    const QStringList arguments = {QStringLiteral("simpartner"), QStringLiteral("--toy-greeting"),
                                   QStringLiteral("hello"), QStringLiteral("--monitor")};
    {
      QCommandLineParser bare;
      addJobOptions(bare, builtInJobs());
      QVERIFY(!bare.parse(arguments));
      QVERIFY2(bare.errorText().contains(QLatin1String("toy-greeting")), qPrintable(bare.errorText()));
    }
    {
      ConsoleJobs jobs;
      jobs.push_back(std::make_unique<ToyJob>());
      QCommandLineParser parser;
      addJobOptions(parser, jobs);
      QVERIFY(parser.parse({QStringLiteral("simpartner"), QStringLiteral("--toy-greeting"), QString()}));
      QCOMPARE(takeJobOptions(parser, jobs), QStringLiteral("<command line>: error: --toy-greeting: empty"));
    }
    ConsoleJobs jobs = builtInJobs();
    jobs.push_back(std::make_unique<ToyJob>());
    QCommandLineParser parser;
    addJobOptions(parser, jobs);
    QVERIFY2(parser.parse(arguments), qPrintable(parser.errorText()));
    QCOMPARE(takeJobOptions(parser, jobs), QString());
    ConsoleOptions o;
    o.log = false;
    std::unique_ptr<MainWindow> w;
    QCOMPARE(test::startConsole(dir_, QStringLiteral("terrains/flat.world.xml"), o, w, std::move(jobs)), QString());
    ToyJob* toy = w->job<ToyJob>();
    QVERIFY(toy);
    QCOMPARE(toy->label_->text(), QStringLiteral("hello"));
    QTRY_VERIFY_WITH_TIMEOUT(toy->frames_ > 25, 10000);
    QVERIFY(!test::linkPanel(*w)->leaseHeld());
  }

  // A toy job installed into the running console through the context
  // alone: its dock is in the window and the View menu, its menu item in a
  // menu of its own, it sees frames, its command drives the robot, and the
  // background runner returns its result on the GUI thread.
  void toyJobPlugsIn() {
    ConsoleOptions o;
    std::unique_ptr<MainWindow> w;
    QCOMPARE(test::startConsole(dir_, QStringLiteral("terrains/flat.world.xml"), o, w), QString());
    auto* toy = static_cast<ToyJob*>(w->installJob(std::make_unique<ToyJob>()));
    QCOMPARE(w->job<ToyJob>(), toy);
    QCOMPARE(w->findChild<QDockWidget*>(QStringLiteral("toyDock")), toy->dock_);
    bool inView = false, inTools = false;
    for (QAction* a : w->menuBar()->actions()) {
      if (!a->menu()) continue;
      for (QAction* item : a->menu()->actions()) {
        inView |= a->text() == QStringLiteral("&View") && item == toy->dock_->toggleViewAction();
        inTools |= a->text() == QStringLiteral("&Tools") && item == toy->action_;
      }
    }
    QVERIFY(inView && inTools);
    QTRY_VERIFY_WITH_TIMEOUT(toy->frames_ > 10 && test::linkPanel(*w)->leaseHeld(), 10000);
    const double x0 = toy->lastX_;
    toy->action_->trigger();
    QCOMPARE(toy->refusal_, QString());
    QTRY_VERIFY_WITH_TIMEOUT(toy->lastX_ - x0 > 0.05, 10000);  // the robot moved, seen through the feed

    // Background work: progress reported, the result back on the GUI thread.
    BackgroundJobs& jobs = toy->context_->background();
    std::atomic<bool> onWorker{false};
    double progress = -1;
    bool done = false;
    connect(&jobs, &BackgroundJobs::progressed, this, [&](int, double f) { progress = f; });
    const int id = jobs.run(toy, QStringLiteral("toy work"), [&](const BackgroundJobs::Progress& report) {
      onWorker = QThread::currentThread() != qApp->thread();
      report(0.5);
      return std::function<void()>([&] { done = QThread::currentThread() == qApp->thread(); });
    });
    QTRY_VERIFY(!jobs.running(id));
    QVERIFY(onWorker && done);
    QCOMPARE(progress, 0.5);
    // A cancelled job's result is dropped (control for `done` above).
    bool late = false;
    std::atomic<bool> go{false};
    const int cancelled = jobs.run(toy, QStringLiteral("cancelled"), [&](const BackgroundJobs::Progress& report) {
      while (!go) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      report(1);
      return std::function<void()>([&] { late = true; });
    });
    jobs.cancel(cancelled);
    go = true;
    QTRY_VERIFY(!jobs.running(cancelled));
    QVERIFY(!late);
    w->close();
  }

  // Issue 27: while a replay is shown, the drive keys and controls act on
  // nothing live. Criterion: no COMMAND leaves the console while the replay
  // is shown (keys, Space, the sink), the status says why; the live robot
  // is still known (no false "no data"), Esc closing an open list does not
  // e-stop it; after the replay closes the same key sends again (control).
  void replayDrivesNothing() {
    const std::string log = dir_.filePath(QStringLiteral("demo.splog")).toStdString();
    QVERIFY(test::logDemoRun(log, 3));
    ConsoleOptions o;
    std::unique_ptr<MainWindow> w;
    QCOMPARE(test::startConsole(dir_, QStringLiteral("terrains/flat.world.xml"), o, w), QString());
    QTRY_VERIFY_WITH_TIMEOUT(w->telemetryReceived() > 10 && test::linkPanel(*w)->leaseHeld(), 10000);
    QCOMPARE(test::openLog(*w, QString::fromStdString(log), true), QString());
    QVERIFY(w->replaying());
    QVERIFY(!test::controlPanel(*w)->controlsEnabled());
    QVERIFY(w->bannerText().contains(QStringLiteral("Replay of demo.splog")));

    const uint64_t sent = w->connection()->stats().commandsSent;
    const int64_t frames = w->telemetryReceived();
    w->sceneView()->setFocus();
    for (Qt::Key key : {Qt::Key_Up, Qt::Key_Up, Qt::Key_W, Qt::Key_Space}) QTest::keyClick(w->sceneView(), key);
    QVERIFY(!w->context().sendCommand(DriveCmd{0.1, 0}).isEmpty());
    // Esc that closes an open list (the replay's signal list) is not an e-stop.
    auto* signalList = test::replayPanel(*w)->findChild<QComboBox*>();
    QVERIFY(signalList);
    signalList->showPopup();
    QTRY_VERIFY(QApplication::activePopupWidget());
    QTest::keyClick(QApplication::activePopupWidget(), Qt::Key_Escape);
    QTRY_VERIFY(!QApplication::activePopupWidget());
    QTest::qWait(1000);  // telemetry goes on meanwhile
    QCOMPARE(w->connection()->stats().commandsSent, sent);
    QVERIFY(w->telemetryReceived() > frames + 20);
    QVERIFY(!w->consoleState().stale());
    QVERIFY(!w->consoleState().estop());
    QVERIFY(!w->lastTelemetry()->estop);
    QVERIFY(!w->findChild<QLabel*>(QStringLiteral("staleLabel"))->isVisible());
    qInfo("during the replay: %llu commands sent, %lld frames received",
          static_cast<unsigned long long>(w->connection()->stats().commandsSent - sent),
          static_cast<long long>(w->telemetryReceived() - frames));

    // Control: the replay closed, the same key drives the live robot.
    test::replayPanel(*w)->close();
    QVERIFY(!w->replaying());
    QTRY_VERIFY(test::controlPanel(*w)->controlsEnabled());
    QTest::keyClick(w->sceneView(), Qt::Key_Up);
    QTRY_VERIFY_WITH_TIMEOUT(w->connection()->stats().commandsSent > sent, 3000);
    w->close();
  }

 private:
  QTemporaryDir dir_;
};

int main(int argc, char** argv) { return sp::test::glTestMain<TestJobs>(argc, argv); }

#include "tst_jobs.moc"
