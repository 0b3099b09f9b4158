// The console's worker threads against what a lying robot makes of their
// input (issue 58): none ends the process, none outlives a quit, each says
// what went wrong. The link's checks (tests/net/tst_hostile_robot) refuse
// such telemetry first; these are the threads' own bounds behind them.

#include <QTest>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include "app/calibration/live_calibrator.h"
#include "app/state/parallel_for.h"
#include "app/state/robot_shapes.h"
#include "app/ghost/ghost.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/world.h"

using namespace sp;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

WorldModel flatWorld() {
  Diagnostics diag;
  std::optional<WorldModel> w = loadWorld(SP_SOURCE_DIR "/terrains/flat.world.xml", diag);
  if (!w) qFatal("%s", diag.format().c_str());
  return *w;
}

RobotFrame frameAt(const WorldModel& world, double time, double x) {
  RobotFrame f;
  f.time = time;
  f.base = world.robots[0].pose;
  f.base.p.x += x;
  f.jointPositions.assign(world.robots[0].model.joints.size(), 0);
  f.jointRates.assign(world.robots[0].model.joints.size(), 0);
  return f;
}

// The robot standing settled on the flat world, as its telemetry would say.
RobotFrame settled(const WorldModel& world) {
  Diagnostics diag;
  std::unique_ptr<World> w = World::create(world, SimParams{}, diag);
  if (!w) qFatal("%s", diag.format().c_str());
  for (int i = 0; i < 500; ++i) w->step();
  return frameFromReadout(readRobot(*w));
}

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

class TestWorkerGuards : public QObject {
  Q_OBJECT

  // The one parallel-for (app/state/parallel_for.h): every index once on
  // the threads asked for; a body returning false stops what is not begun;
  // a throw on a pool thread comes back on the caller's (it used to end the
  // process) once every thread is done.
  void parallelForEachOnceAndThrowsBack() {
    std::vector<std::atomic<int>> seen(1000);
    std::mutex idsMutex;
    std::set<std::thread::id> ids;
    parallelFor(seen.size(), 4, [&](size_t i) {
      ++seen[i];
      std::lock_guard lock(idsMutex);
      ids.insert(std::this_thread::get_id());
      return true;
    });
    for (const std::atomic<int>& s : seen) QCOMPARE(s.load(), 1);
    QVERIFY(ids.size() >= 1 && ids.size() <= 4);
    QVERIFY(ids.count(std::this_thread::get_id()));  // the caller works too
    std::atomic<int> ran{0};
    parallelFor(1000, 1, [&](size_t i) { return ++ran, i < 9; });
    QCOMPARE(ran.load(), 10);  // one thread: index 9 said stop
    std::atomic<int> after{0};
    bool thrown = false;
    try {
      parallelFor(1000, 3, [&](size_t i) {
        if (i == 5) throw std::runtime_error("candidate 5");
        ++after;
        return true;
      });
    } catch (const std::runtime_error& e) {
      thrown = std::string(e.what()) == "candidate 5";
    }
    QVERIFY(thrown);
    // On one thread the order is the indices': nothing after the throw ran.
    after = 0;
    thrown = false;
    try {
      parallelFor(1000, 1, [&](size_t i) {
        if (i == 5) throw std::runtime_error("candidate 5");
        ++after;
        return true;
      });
    } catch (const std::runtime_error&) {
      thrown = true;
    }
    QVERIFY(thrown);
    QCOMPARE(after.load(), 5);
    parallelFor(0, 4, [&](size_t) -> bool { qFatal("no index to run"); });
  }

 private slots:
  // A model ODE refuses (a link of negative mass, as a wild fit could make)
  // is an error from World::create, not abort(); the same model with its
  // mass (the control) builds.
  void odeRefusalIsAnError() {
    WorldModel world = flatWorld();
    Diagnostics ok;
    QVERIFY(World::create(world, SimParams{}, ok) != nullptr);
    world.robots[0].model.links[0].mass = -5;
    Diagnostics diag;
    QVERIFY(World::create(world, SimParams{}, diag) == nullptr);
    QVERIFY2(diag.format().find("ODE refused the model") != std::string::npos, diag.format().c_str());
  }

  // Telemetry whose time leaps 1e9 s, or a round trip of 1e300 s, leaves
  // the ghost predicting no further than its limit (the round trip, which
  // lasts, says so; the leap lasts until the next anchor); it is destroyed
  // (the console quits) within a second. The control: frames 20 ms apart
  // over a 10 ms round trip say nothing of the kind.
  void ghostAheadIsBounded_data() {
    QTest::addColumn<double>("leap");
    QTest::addColumn<double>("roundTrip");
    QTest::addColumn<int>("said");  // 1: must say so, 0: must not, -1: may
    QTest::newRow("time +1e9 s") << 1e9 << 0.01 << -1;
    QTest::newRow("round trip 1e300 s") << 0.02 << 1e300 << 1;
    QTest::newRow("control") << 0.02 << 0.01 << 0;
  }
  void ghostAheadIsBounded() {
    QFETCH(double, leap);
    QFETCH(double, roundTrip);
    QFETCH(int, said);
    const WorldModel world = flatWorld();
    std::string error;
    std::unique_ptr<Ghost> ghost = Ghost::create(world, SimParams{}, error);
    QVERIFY2(ghost, error.c_str());
    RobotFrame frame = settled(world);
    const double start = frame.time;
    ghost->anchor(frame, 0.01);
    std::this_thread::sleep_for(200ms);
    // The leap: the frame's time is far on (the present thread, still at
    // the last anchor, is asked to run there); each later frame keeps it so.
    for (int i = 0; i < 10; ++i) {
      frame.time = start + leap + 0.02 * i;
      ghost->anchor(frame, roundTrip);
      std::this_thread::sleep_for(50ms);
    }
    const bool capped = [&] {
      const auto end = Clock::now() + (said == 1 ? 3s : 1s);
      while (Clock::now() < end) {
        if (ghost->view().problem.find("predicts no further than its limit") != std::string::npos) return true;
        std::this_thread::sleep_for(20ms);
      }
      return false;
    }();
    if (said >= 0) QVERIFY2(capped == (said == 1), ghost->view().problem.c_str());
    QVERIFY(ghost->view().span <= Ghost::Options{}.maxAhead + 0.1);
    const auto t0 = Clock::now();
    ghost.reset();
    QVERIFY2(secondsSince(t0) < 1.0, std::to_string(secondsSince(t0)).c_str());
  }

  // A fit whose twins ODE refuses is a refused fit that says why, on the
  // calibration's thread, and the console goes on: a robot reporting a
  // mass the fit takes below zero cannot end it. Here the fit's start has
  // the mass factor at -1 (no telemetry could be believed so, but a fit's
  // step can land there), driving frames follow.
  void calibrationSurvivesARefusedTwin() {
    const WorldModel world = flatWorld();
    CalValues start = filesCalValues();
    start[static_cast<size_t>(CalParam::Mass)] = -1;
    LiveCalibrator::Options options;
    options.period = 1;
    LiveCalibrator calibrator(world, Ghost::profile(SimParams{}), start, options);
    calibrator.command(DriveCmd{0.5, 0}, 0);
    for (int i = 0; i < 500; ++i) calibrator.frame(frameAt(world, 0.02 * i, 0.01 * i));
    const auto end = Clock::now() + 20s;
    while (Clock::now() < end && calibrator.state().fits == 0) std::this_thread::sleep_for(50ms);
    const CalibrationState s = calibrator.state();
    QVERIFY(s.fits > 0);
    QCOMPARE(s.refusals, s.fits);
    QVERIFY2(!s.lastRefusal.empty(), s.lastRefusal.c_str());
  }
};

QTEST_GUILESS_MAIN(TestWorkerGuards)
#include "tst_worker_guards.moc"
