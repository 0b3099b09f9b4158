// Tests of sp::Runner (sim/runner.h): the one step loop the headless runner,
// re-simulation, the stand-in and validation share.

#include <QTest>

#include <memory>

#include "sim/model_loader.h"
#include "sim/runner.h"
#include "sim/world.h"

using namespace sp;

namespace {

// The runner's boundaries at a known step: 1 ms, whatever the default.
SimParams oneMillisecond() {
  SimParams p;
  p.step = 0.001;
  return p;
}

std::unique_ptr<World> flatWorld(SimParams params = oneMillisecond()) {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld("terrains/flat.world.xml", diag);
  if (!model) {
    qWarning("%s", diag.format().c_str());
    return nullptr;
  }
  return World::create(*model, params, diag);
}

}  // namespace

class TestRunner : public QObject {
  Q_OBJECT

 private slots:
  // advanceTo / advanceBy / advanceToTime land on exactly the step asked for.
  void advancesToTheStepAsked() {
    auto world = flatWorld();
    QVERIFY(world);
    Runner runner(*world);
    QCOMPARE(runner.advanceTo(25).steps, int64_t{25});
    QCOMPARE(world->stepCount(), int64_t{25});
    QCOMPARE(runner.advanceBy(5).stop, RunOutcome::Stop::Reached);
    QCOMPARE(world->stepCount(), int64_t{30});
    runner.advanceToTime(0.1);  // 1 ms steps
    QCOMPARE(world->stepCount(), int64_t{100});
    // Asking for a step already passed does nothing.
    QCOMPARE(runner.advanceTo(50).steps, int64_t{0});
    QCOMPARE(world->stepCount(), int64_t{100});
  }

  // A command by time is submitted at the first boundary at or after its
  // time, before the step from there; one exactly on a boundary at it.
  void commandsByTimeAtTheFirstBoundaryAfter() {
    auto world = flatWorld();
    QVERIFY(world);
    Runner runner(*world);
    runner.schedule({{0.0105, DriveCmd{0.5, 0}, 3}, {0.020, StopCmd{}, 4}});
    std::vector<std::pair<int64_t, int>> submitted;  // (step, line)
    runner.setSubmitHook([&](const ScheduledCommand& c, const std::string& why) {
      QVERIFY(why.empty());
      submitted.emplace_back(world->stepCount(), c.line);
    });
    runner.advanceTo(30);
    QCOMPARE(submitted.size(), size_t{2});
    QCOMPARE(submitted[0], std::make_pair(int64_t{11}, 3));
    QCOMPARE(submitted[1], std::make_pair(int64_t{20}, 4));
    QCOMPARE(runner.commandsApplied(), 2);
    QCOMPARE(runner.pending(), size_t{0});
  }

  // The runner steps exactly as the hand-written loop it replaced: submit
  // what is due, then step; the state hashes agree bit for bit.
  void sameStateAsAHandWrittenLoop() {
    const std::vector<TimedCommand> seq = {{0.05, DriveCmd{0.8, 0}, 1}, {0.3, DriveCmd{0.8, degToRad(20)}, 2}};
    auto a = flatWorld(), b = flatWorld();
    QVERIFY(a && b);
    const double x0 = a->linkPose(0, 0).p.x;
    Runner runner(*a);
    runner.schedule(seq);
    runner.advanceToTime(0.6);
    size_t next = 0;
    while (b->stepCount() < 600) {
      while (next < seq.size() && seq[next].time <= b->time() + 1e-9) QVERIFY(b->submit(seq[next++].command).empty());
      b->step();
    }
    QCOMPARE(a->stepCount(), b->stepCount());
    QCOMPARE(a->stateHash(), b->stateHash());
    // And the commands mattered: the robot moved.
    QVERIFY2(a->linkPose(0, 0).p.x - x0 > 0.1, qPrintable(QString::number(a->linkPose(0, 0).p.x - x0)));
  }

  // Step-keyed commands (from a log) apply at their step; skipBefore()
  // drops those before a restored snapshot's step.
  void commandsByStepAndSkipBefore() {
    auto world = flatWorld();
    QVERIFY(world);
    Runner runner(*world);
    runner.schedule(ScheduledCommand{DriveCmd{0.2, 0}, 0, 5});
    runner.schedule(ScheduledCommand{StopCmd{}, 0, 12});
    std::vector<int64_t> steps;
    runner.setSubmitHook([&](const ScheduledCommand&, const std::string&) { steps.push_back(world->stepCount()); });
    runner.skipBefore(10);
    runner.advanceTo(20);
    QCOMPARE(steps, std::vector<int64_t>{12});
  }

  // The monitor sees every step and can stop the run where it is.
  void monitorStops() {
    auto world = flatWorld();
    QVERIFY(world);
    Runner runner(*world);
    int64_t seen = 0;
    runner.setMonitor([&](const World& w) {
      ++seen;
      return w.stepCount() < 7;
    });
    const RunOutcome out = runner.advanceTo(100);
    QCOMPARE(out.stop, RunOutcome::Stop::Monitor);
    QCOMPARE(out.steps, int64_t{7});
    QCOMPARE(seen, int64_t{7});
    QCOMPARE(world->stepCount(), int64_t{7});
  }

  // A diverging twin stops the advance at the step that diverged; the
  // monitor sees that step, and commands due later are not submitted.
  void stopsOnHealth() {
    SimParams params;
    params.maxLinearSpeed = 0.05;  // driving at 0.5 m/s breaks it within a second
    auto world = flatWorld(params);
    QVERIFY(world);
    Runner runner(*world);
    runner.schedule({{0.0, DriveCmd{0.5, 0}, 1}, {5.0, StopCmd{}, 2}});
    int64_t lastSeen = -1;
    runner.setMonitor([&](const World& w) {
      lastSeen = w.stepCount();
      return true;
    });
    const RunOutcome out = runner.advanceToTime(10);
    QCOMPARE(out.stop, RunOutcome::Stop::Diverged);
    QVERIFY(!world->health().healthy());
    QCOMPARE(world->health().kind, HealthReport::Kind::Speed);
    QCOMPARE(lastSeen, world->stepCount());
    QCOMPARE(world->health().step, world->stepCount());
    QVERIFY(world->time() < 5.0);
    QCOMPARE(runner.commandsApplied(), 1);
    QCOMPARE(runner.pending(), size_t{1});
    // Advancing again does nothing on a diverged twin.
    QCOMPARE(runner.advanceBy(10).steps, int64_t{0});
  }

  // A command the World refuses is reported with the reason and not counted.
  void refusedCommandsReported() {
    auto world = flatWorld();
    QVERIFY(world);
    Runner runner(*world);
    runner.schedule({{0.0, JointTargetCmd{"no_such_joint", 0}, 9}});
    QString reason;
    runner.setSubmitHook([&](const ScheduledCommand&, const std::string& why) { reason = QString::fromStdString(why); });
    runner.advanceBy(1);
    QCOMPARE(reason, QString("unknown joint 'no_such_joint'"));
    QCOMPARE(runner.commandsApplied(), 0);
  }
};

QTEST_GUILESS_MAIN(TestRunner)
#include "tst_runner.moc"
