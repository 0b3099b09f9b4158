// Tests of sp::Pacer (sim/pacer.h) against a fake clock: a plain double the
// test advances the way a sleeping physics thread would see a real one.

#include <QTest>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "sim/pacer.h"

using sp::Pacer;

namespace {

constexpr double kWall0 = 1000.0;        // arbitrary origin of the monotonic clock [s]
constexpr double kMinOversleep = 0.0002; // a sleep ends 0.2..3 ms after its deadline [s]
constexpr double kMaxOversleep = 0.003;

/// Deterministic, irregular wake-up delays in [kMinOversleep, kMaxOversleep).
class Oversleep {
 public:
  double next() {
    const double unit = static_cast<double>(rng_() >> 11) * 0x1.0p-53;  // [0, 1)
    return kMinOversleep + (kMaxOversleep - kMinOversleep) * unit;
  }

 private:
  std::mt19937_64 rng_{20240601};
};

/// The physics thread's loop on a fake clock: ask for the due steps, take
/// them, sleep until the next deadline and wake a little late. One sleep can
/// be made to last `stallFor` longer (the machine froze), waking at exactly
/// deadline + stallFor.
struct FakeLoop {
  explicit FakeLoop(Pacer& p) : pacer(p) {}

  Pacer& pacer;
  double wall = kWall0;
  Oversleep oversleep;
  double stallAt = std::numeric_limits<double>::infinity();
  double stallFor = 0;
  bool stalled = false;
  int64_t dueAfterStall = -1;     // what stepsDue() returned on waking from the stall
  // Worst |sim time - wall time x factor| [s] over the run, since the last
  // resync, measured before and after each pass's steps.
  double worstError = 0;
  int64_t maxDue = 0;

  void runUntil(double end) {
    while (wall < end) {
      const bool wokeFromStall = stalled && dueAfterStall < 0;
      const int64_t due = pacer.stepsDue(wall);
      if (wokeFromStall) dueAfterStall = due;
      worstError = std::max(worstError, std::abs(pacer.lead(wall)));
      pacer.stepped(due);
      worstError = std::max(worstError, std::abs(pacer.lead(wall)));
      maxDue = std::max(maxDue, due);
      const double deadline = std::max(wall, pacer.nextDeadline());
      if (!stalled && deadline >= stallAt) {
        stalled = true;
        wall = deadline + stallFor;
      } else {
        wall = deadline + oversleep.next();
      }
    }
  }

  /// A last pass at the current wall time, as the loop would make on waking.
  void finish() { pacer.stepped(pacer.stepsDue(wall)); }
};

Pacer::Config config(double factor, double maxLag = 0.1) {
  Pacer::Config c;
  c.step = 0.001;
  c.realTimeFactor = factor;
  c.maxLag = maxLag;
  c.maxStepsPerPass = 100;
  return c;
}

}  // namespace

class TestPacer : public QObject {
  Q_OBJECT

 private slots:
  void tracksWallClockOverTenMinutes_data();
  void tracksWallClockOverTenMinutes();
  void stallBeyondMaxLagResyncsOnce_data();
  void stallBeyondMaxLagResyncsOnce();
  void stallBelowMaxLagIsCaughtUp();
  void catchUpIsCappedPerPass();
  void wakingAtEachDeadlineGivesOneStep();
  void aheadOfScheduleGivesNoSteps();
  void startContinuesFromGivenSteps();
  void unpacedRunsFlatOut_data();
  void unpacedRunsFlatOut();
};

void TestPacer::tracksWallClockOverTenMinutes_data() {
  QTest::addColumn<double>("factor");
  QTest::newRow("1x") << 1.0;
  QTest::newRow("2x") << 2.0;
  QTest::newRow("0.5x") << 0.5;
  QTest::newRow("10x") << 10.0;
}

// Ten minutes of irregular wake-ups: sim time stays within one step plus one
// wake-up of wall x factor throughout, ends within 1 ms, and never resyncs.
void TestPacer::tracksWallClockOverTenMinutes() {
  QFETCH(double, factor);
  Pacer pacer(config(factor));
  pacer.start(kWall0);
  FakeLoop loop{pacer};
  loop.runUntil(kWall0 + 600);
  loop.finish();

  const double step = 0.001;
  const double wallElapsed = loop.wall - kWall0;
  QVERIFY2(loop.worstError <= step + kMaxOversleep * factor + 1e-9,
           qPrintable(QString("worst error %1 s").arg(loop.worstError)));
  QVERIFY2(std::abs(pacer.simTime() - wallElapsed * factor) <= 0.001,
           qPrintable(QString("sim %1 s, wall x factor %2 s").arg(pacer.simTime()).arg(wallElapsed * factor)));
  QCOMPARE(pacer.resyncCount(), int64_t(0));
  QCOMPARE(pacer.slippedTime(), 0.0);
  QVERIFY(loop.maxDue < 100);  // the per-pass cap never had to act
  QVERIFY(std::abs(pacer.achievedFactor(loop.wall) - factor) <= 1e-5 * factor);
}

void TestPacer::stallBeyondMaxLagResyncsOnce_data() {
  QTest::addColumn<double>("factor");
  QTest::newRow("1x") << 1.0;
  QTest::newRow("2x") << 2.0;
  QTest::newRow("0.5x") << 0.5;
}

// A 0.5 s stall (maxLag 0.1 s) triggers exactly one resync instead of a
// catch-up burst. The stall begins at a step's deadline D with the sim one
// step short of it, so on waking at D + 0.5 the sim is behind by
// step/factor + 0.5 wall seconds; the resync gives up all of it:
// slippedTime = 0.5 x factor + step sim seconds. Afterwards the pacer tracks
// the clock again, and sim time = wall x factor - slippedTime.
void TestPacer::stallBeyondMaxLagResyncsOnce() {
  QFETCH(double, factor);
  const double step = 0.001;
  Pacer pacer(config(factor));
  pacer.start(kWall0);
  FakeLoop loop{pacer};
  loop.stallAt = kWall0 + 10;
  loop.stallFor = 0.5;
  loop.runUntil(kWall0 + 20);
  loop.finish();

  QVERIFY(loop.stalled);
  QCOMPARE(loop.dueAfterStall, int64_t(0));  // no burst on waking
  QCOMPARE(pacer.resyncCount(), int64_t(1));
  const double expectedSlip = 0.5 * factor + step;
  QVERIFY2(std::abs(pacer.slippedTime() - expectedSlip) <= 1e-9,
           qPrintable(QString("slipped %1 s, expected %2 s").arg(pacer.slippedTime(), 0, 'g', 17).arg(expectedSlip)));
  QVERIFY2(loop.worstError <= step + kMaxOversleep * factor + 1e-9,
           qPrintable(QString("worst error %1 s").arg(loop.worstError)));
  const double wallElapsed = loop.wall - kWall0;
  QVERIFY(std::abs(pacer.simTime() - (wallElapsed * factor - pacer.slippedTime())) <= step);
}

// A stall shorter than maxLag is caught up in one pass: every missed step
// (90 ms of stall plus the step that was due) runs, nothing is slipped.
void TestPacer::stallBelowMaxLagIsCaughtUp() {
  Pacer pacer(config(1.0));
  pacer.start(kWall0);
  FakeLoop loop{pacer};
  loop.stallAt = kWall0 + 10;
  loop.stallFor = 0.09;
  loop.runUntil(kWall0 + 20);
  loop.finish();

  QCOMPARE(loop.dueAfterStall, int64_t(91));
  QCOMPARE(pacer.resyncCount(), int64_t(0));
  QCOMPARE(pacer.slippedTime(), 0.0);
  QVERIFY(std::abs(pacer.simTime() - (loop.wall - kWall0)) <= 0.001);
}

// Behind by less than maxLag but by more steps than maxStepsPerPass: the
// backlog is worked off over several capped passes, without a resync.
void TestPacer::catchUpIsCappedPerPass() {
  Pacer pacer(config(1.0, /*maxLag=*/1.0));
  pacer.start(0.0);
  for (int pass = 0; pass < 3; ++pass) {
    QCOMPARE(pacer.stepsDue(0.3), int64_t(100));
    pacer.stepped(100);
  }
  QCOMPARE(pacer.stepsDue(0.3), int64_t(0));
  QCOMPARE(pacer.resyncCount(), int64_t(0));
  QCOMPARE(pacer.steps(), int64_t(300));
}

// Waking exactly at nextDeadline() always yields exactly one step (rounding
// neither skips a step nor leaves the caller spinning), over 10 min at 1x.
void TestPacer::wakingAtEachDeadlineGivesOneStep() {
  Pacer pacer(config(1.0));
  pacer.start(kWall0);
  QCOMPARE(pacer.stepsDue(kWall0), int64_t(0));
  QCOMPARE(pacer.nextDeadline(), kWall0 + 0.001);
  QCOMPARE(pacer.stepsDue(kWall0 + 0.00099), int64_t(0));
  int64_t wrong = 0;
  for (int i = 0; i < 600000; ++i) {
    const int64_t due = pacer.stepsDue(pacer.nextDeadline());
    if (due != 1) ++wrong;
    pacer.stepped(due);
  }
  QCOMPARE(wrong, int64_t(0));
  QCOMPARE(pacer.steps(), int64_t(600000));
  QCOMPARE(pacer.resyncCount(), int64_t(0));
}

// Steps taken beyond the schedule never make stepsDue() negative; the lead
// shows how far ahead the sim is, and the deadline waits for the schedule.
void TestPacer::aheadOfScheduleGivesNoSteps() {
  Pacer pacer(config(1.0));
  pacer.start(0.0);
  pacer.stepped(50);
  QCOMPARE(pacer.stepsDue(0.01), int64_t(0));
  QVERIFY(std::abs(pacer.lead(0.01) - 0.04) <= 1e-12);
  QVERIFY(std::abs(pacer.nextDeadline() - 0.051) <= 1e-12);
}

// start() with steps already done (after a pause or a loaded snapshot)
// schedules from that count, not from zero.
void TestPacer::startContinuesFromGivenSteps() {
  Pacer pacer(config(2.0));
  pacer.start(5.0, 1000);
  QCOMPARE(pacer.steps(), int64_t(1000));
  QCOMPARE(pacer.simTime(), 1.0);
  QCOMPARE(pacer.stepsDue(5.010), int64_t(20));
  pacer.stepped(20);
  QVERIFY(std::abs(pacer.achievedFactor(5.010) - 2.0) <= 1e-9);
}

void TestPacer::unpacedRunsFlatOut_data() {
  QTest::addColumn<double>("factor");
  QTest::newRow("0 (max)") << 0.0;
  QTest::newRow("negative") << -1.0;
}

// Unpaced (factor <= 0): every pass gets maxStepsPerPass whatever the clock,
// there is no deadline to sleep to, and achievedFactor reports the speed.
void TestPacer::unpacedRunsFlatOut() {
  QFETCH(double, factor);
  Pacer pacer(config(factor));
  QVERIFY(!pacer.paced());
  pacer.start(kWall0);
  double wall = kWall0;
  for (int pass = 0; pass < 1000; ++pass) {
    QCOMPARE(pacer.stepsDue(wall), int64_t(100));
    pacer.stepped(100);
    QCOMPARE(pacer.nextDeadline(), -std::numeric_limits<double>::infinity());
    wall += 0.002;  // 100 steps (0.1 sim s) in 2 ms of wall time
  }
  QCOMPARE(pacer.steps(), int64_t(100000));
  QVERIFY(std::abs(pacer.achievedFactor(wall) - 50.0) <= 1e-6);
  QCOMPARE(pacer.lead(wall), 0.0);
  QCOMPARE(pacer.resyncCount(), int64_t(0));
}

QTEST_GUILESS_MAIN(TestPacer)
#include "tst_pacer.moc"
