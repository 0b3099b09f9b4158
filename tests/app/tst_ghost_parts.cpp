// The predictive ghost's pieces on their own (app/ghost/): its clock
// estimate, the commands in flight, when it holds joints rigid, and the
// record of what it showed against what came. No threads, no physics:
// each is checked against the arithmetic it promises.

#include <QTest>

#include <cmath>

#include "app/ghost/ghost_clock.h"
#include "app/ghost/hold_policy.h"
#include "app/ghost/in_flight.h"
#include "app/ghost/prediction_record.h"
#include "sim/model_loader.h"

using namespace sp;

namespace {

RobotFrame frameAt(double time, std::vector<double> joints, double x = 0) {
  RobotFrame f;
  f.time = time;
  f.base.p = {x, 0, 0.8};
  f.jointPositions = std::move(joints);
  f.jointRates.assign(f.jointPositions.size(), 0);
  return f;
}

const RobotModel& workpartner() {
  static const RobotModel robot = [] {
    Diagnostics diag;
    std::optional<RobotModel> r = loadRobot(std::string(SP_SOURCE_DIR) + "/robots/workpartner.xml", diag);
    if (!r) qFatal("%s", diag.format().c_str());
    return *r;
  }();
  return robot;
}

}  // namespace

class TestGhostParts : public QObject {
  Q_OBJECT

 private slots:
  // The clock: offset = the largest (T - arrival) over the last 2 s (the
  // least-delayed frame), ghost(w) = w + offset + round trip; a frame more
  // than 2 s old no longer counts; the robot's clock going back starts over.
  void clock() {
    GhostClock c;
    QCOMPARE(c.ghostTime(100), 0.0);  // before any frame: the newest frame's time (none: 0)
    QVERIFY(!c.frame(10.0, 100.0, 0.4));  // delayed 0.2 s (offset -90)
    QVERIFY(!c.frame(10.5, 100.3, 0.4));  // delayed less: offset -89.8
    QCOMPARE(c.offset(), -89.8);
    QCOMPARE(c.ghostTime(101.0), 101.0 - 89.8 + 0.4);
    QVERIFY(!c.frame(12.0, 103.0, std::nan("")));  // the -89.8 sample is now 2.7 s old
    QCOMPARE(c.offset(), -91.0);
    QCOMPARE(c.roundTrip(), 0.0);  // unknown round trip: none
    QVERIFY(c.frame(1.0, 104.0, 0.4));  // a reset
    QCOMPARE(c.offset(), -103.0);
    QCOMPARE(c.newest(), 1.0);
  }

  // Commands in flight: seqs count up, from() returns what is not applied
  // yet, forgetBefore() drops what took effect long ago, clear() keeps counting.
  void inFlight() {
    InFlightCommands c;
    QCOMPARE(c.add(DriveCmd{0.5, 0}, 1.0), uint64_t{0});
    QCOMPARE(c.add(StopCmd{}, 2.0), uint64_t{1});
    QCOMPARE(c.add(DriveCmd{0.2, 0}, 3.0), uint64_t{2});
    QCOMPARE(c.from(1).size(), size_t{2});
    QCOMPARE(c.from(1).front().time, 2.0);
    c.forgetBefore(2.5);
    QCOMPARE(c.from(0).size(), size_t{1});
    QCOMPARE(c.from(0).front().seq, uint64_t{2});
    c.clear();
    QVERIFY(c.from(0).empty());
    QCOMPARE(c.add(StopCmd{}, 4.0), uint64_t{3});
    QCOMPARE(c.sent(), uint64_t{4});
  }

  // Holding: the first frame holds (and builds); a held joint moving past
  // the band for a frame switches to the full robot; held again only after
  // a still second; a command to a held joint, or a gait, in flight stops
  // holding unless the robot is latched; a weld 0.05 rad off is redone.
  void holdPolicy() {
    const RobotModel& robot = workpartner();
    const int knee = robot.findJoint("knee_fl");
    QVERIFY(knee >= 0);
    HoldPolicy p({knee}, robot);
    const auto tick = [](int k) { return k / 10.0; };  // frames every 0.1 s
    std::vector<double> q(robot.joints.size(), 0.0);
    HoldDecision d = p.decide(frameAt(tick(0), q), {}, {}, nullptr, false);
    QVERIFY(d.hold && d.rebuild);
    std::string error;
    const std::optional<RigidRobot> weld = holdRigid(robot, q, {knee}, error);
    QVERIFY2(weld, error.c_str());
    d = p.decide(frameAt(tick(1), q), {}, {}, &*weld, true);
    QVERIFY(d.hold && !d.rebuild);
    q[static_cast<size_t>(knee)] = 0.04;  // beyond the still band from the last second's frames
    d = p.decide(frameAt(tick(2), q), {}, {}, &*weld, true);
    QVERIFY(!d.hold && d.rebuild);
    for (int k = 3; k <= 11; ++k) {
      d = p.decide(frameAt(tick(k), q), {}, {}, nullptr, true);
      QVERIFY2(!d.hold, qPrintable(QString::number(k)));  // still for less than a second
    }
    d = p.decide(frameAt(tick(12), q), {}, {}, nullptr, true);
    QVERIFY(d.hold && d.rebuild);  // still for a second now (0.2 .. 1.2 s)
    const std::vector<SentCommand> toKnee{{0, 1.4, JointTargetCmd{"knee_fl", 0.3}}};
    QVERIFY(!p.decide(frameAt(tick(13), q), {}, toKnee, nullptr, true).hold);
    RobotFrame latched = frameAt(tick(14), q);
    latched.estop = true;
    QVERIFY(p.decide(latched, {}, toKnee, nullptr, true).hold);  // a latched robot refuses it
    const std::vector<SentCommand> gait{{1, 1.5, GaitCmd{Gait::Rolking}}};
    QVERIFY(!p.decide(frameAt(tick(15), q), gait, {}, nullptr, true).hold);
    QVERIFY(!p.decide(frameAt(tick(16), q), {}, {}, nullptr, true).hold);  // the gait is still in effect
    QVERIFY(p.movesHeld(JointTargetCmd{"knee_fl", 0}));
    QVERIFY(!p.movesHeld(JointTargetCmd{"knee_fr", 0}));
    QVERIFY(!p.movesHeld(DriveCmd{0.5, 0}));
    // A weld 0.06 rad off the reported knee is redone.
    HoldPolicy fresh({knee}, robot);
    q[static_cast<size_t>(knee)] = 0.06;
    d = fresh.decide(frameAt(0, q), {}, {}, &*weld, true);
    QVERIFY(d.hold && d.rebuild);
  }

  // The record: a frame between two shown states is compared with their
  // interpolation; one with nothing shown within 0.1 s is not compared;
  // the median and the worst are over the last 10 s of robot time.
  void predictionRecord() {
    PredictionRecord r;
    QVERIFY(!r.median());
    Pose a, b;
    a.p = {0, 0, 0};
    b.p = {1, 0, 0};
    r.shown(1.00, 0.5, a);
    r.shown(1.08, 0.5, b);
    const std::optional<GhostError> e = r.compare(frameAt(1.02, {}, 0.3));  // shown at 1.02: x = 0.25
    QVERIFY(e);
    QVERIFY(std::abs(e->position - 0.05) < 1e-12);
    QCOMPARE(e->made, 0.5);
    QVERIFY(!r.compare(frameAt(1.5, {}, 0)));  // nothing shown near 1.5
    r.shown(30, 29, a);
    r.shown(30.05, 29, a);
    QVERIFY(r.compare(frameAt(30.02, {}, 0.1)));
    const auto m = r.median();
    QVERIFY(m);
    QVERIFY(std::abs(m->first - 0.1) < 1e-12);  // the 1.02 s error is over 10 s old
    // The worst over the same window: one jump of 1.2 m among small errors
    // leaves the median small and shows in the worst (issue 31).
    for (int i = 0; i < 5; ++i) {
      r.shown(31 + i, 30, a);
      r.shown(31.05 + i, 30, a);
      QVERIFY(r.compare(frameAt(31.02 + i, {}, i == 2 ? 1.2 : 0.01)));
    }
    QVERIFY(r.median()->first < 0.11);
    QVERIFY(std::abs(*r.worstPosition() - 1.2) < 1e-12);
  }
};

QTEST_GUILESS_MAIN(TestGhostParts)
#include "tst_ghost_parts.moc"
