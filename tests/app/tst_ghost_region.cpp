// How sure the ghost is (app/ghost/ghost_region.h), on synthetic residuals:
// the conformal layer's arithmetic, its coverage before and after the robot
// changes (with controls: the layer off, its adaptive step off), the
// departure watch, the error scale's sources, and the wheels' clearance over
// the map (the ground's discrepancy departures are judged on).

#include <QTest>

#include <cmath>
#include <random>

#include "app/ghost/ghost_region.h"
#include "app/ghost/in_flight.h"
#include "sim/diagnostics.h"
#include "sim/model_loader.h"

using namespace sp;

namespace {

// Scores of a prediction whose scale is `wrong` times too small: errors are
// 2-D Gaussian with per-axis deviation `wrong` (in units of the scale).
double rayleigh(std::mt19937_64& rng, double wrong) {
  std::normal_distribution<double> n(0, wrong);
  return std::hypot(n(rng), n(rng));
}

// The shares of `count` scores drawn at `wrong` that the layer's levels
// held, 50 a second from robot time `t` on (advanced).
std::vector<double> held(ConformalLayer& layer, std::mt19937_64& rng, double wrong, int count, double& t) {
  std::vector<double> hits(layer.levels().size(), 0);
  for (int k = 0; k < count; ++k, t += 0.02) {
    const double s = rayleigh(rng, wrong);
    for (size_t i = 0; i < hits.size(); ++i) hits[i] += s <= layer.multiplier(i);
    layer.add(t, s);
  }
  for (double& h : hits) h /= count;
  return hits;
}

}  // namespace

class TestGhostRegion : public QObject {
  Q_OBJECT

 private slots:
  // The window's plain quantile (no adaptive step): the ceil((n + 1) p)-th
  // smallest score; below minScores, the Gaussian's.
  void quantileIsTheSplitConformalRank() {
    ConformalLayer::Options o;
    o.levels = {0.5, 0.9};
    o.gamma = 0;
    o.minScores = 10;
    o.window = 1000;
    ConformalLayer layer(o);
    QCOMPARE(layer.multiplier(1), gaussianMultiplier(0.9));
    QVERIFY(std::abs(gaussianMultiplier(0.9) - 2.1460) < 1e-4);
    for (int k = 1; k <= 9; ++k) layer.add(k, 101 - k);
    QCOMPARE(layer.multiplier(1), gaussianMultiplier(0.9));  // 9 < minScores
    for (int k = 10; k <= 100; ++k) layer.add(k, 101 - k);   // 100..1
    QCOMPARE(layer.multiplier(0), 51.0);  // ceil(101 * 0.5) = 51
    QCOMPARE(layer.multiplier(1), 91.0);  // ceil(101 * 0.9) = 91
    // The window forgets: 10 more, 1000 s later, are all there is.
    for (int k = 1; k <= 10; ++k) layer.add(2000 + k, k * 0.5);
    QCOMPARE(layer.scores(), size_t{10});
    QCOMPARE(layer.multiplier(1), 5.0);  // ceil(11 * 0.9) = 10: the largest
  }

  // A scale three times too small: the layer's regions still hold 50 and
  // 90 % of the predictions; the Gaussian regions the scale alone gives
  // (the layer off) hold far less (a control).
  void coverageHoldsWhateverTheScale() {
    std::mt19937_64 rng(7);
    ConformalLayer layer;
    double t = 0;
    held(layer, rng, 3, 1500, t);  // 30 s to learn
    const std::vector<double> share = held(layer, rng, 3, 15000, t);
    qInfo("held: inner %.3f, outer %.3f, departure's %.4f", share[0], share[1], share[2]);
    QVERIFY2(std::abs(share[0] - 0.5) < 0.03, qPrintable(QString::number(share[0])));
    QVERIFY2(std::abs(share[1] - 0.9) < 0.02, qPrintable(QString::number(share[1])));
    QVERIFY2(std::abs(share[2] - 0.99) < 0.005, qPrintable(QString::number(share[2])));
    QVERIFY(std::abs(*layer.coverage(1) - 0.9) < 0.02);  // the layer counts the same
    // Control: the Gaussian region of the scale as given.
    int hits = 0;
    for (int k = 0; k < 15000; ++k) hits += rayleigh(rng, 3) <= gaussianMultiplier(0.9);
    QVERIFY2(hits / 15000.0 < 0.4, qPrintable(QString::number(hits / 15000.0)));
  }

  // The robot changes (its errors double): the adaptive step brings the
  // outer region's coverage back to 85-95 % within 30 s; a plain quantile
  // over a long window (the step off) is still short of it then (a control).
  void coverageComesBackAfterAChange() {
    const auto after = [](double gamma, double window) {
      ConformalLayer::Options o;
      o.gamma = gamma;
      o.window = window;
      ConformalLayer layer(o);
      std::mt19937_64 rng(11);
      double t = 0;
      held(layer, rng, 1, 6000, t);              // 120 s of the old robot
      held(layer, rng, 2.5, 1500, t);            // the first 30 s of the new one
      return held(layer, rng, 2.5, 500, t)[1];   // the next 10 s
    };
    const double adaptive = after(0.005, 20), plain = after(0, 300);
    qInfo("outer region's coverage 30-40 s after the change: adaptive %.3f, plain over 300 s %.3f", adaptive, plain);
    QVERIFY2(adaptive >= 0.85 && adaptive <= 0.95, qPrintable(QString::number(adaptive)));
    QVERIFY2(plain < 0.85, qPrintable(QString::number(plain)));
  }

  void levelsOutsideTheUnitIntervalAreRefused() {
    QCOMPARE(QString::fromStdString(ConformalLayer::checkLevels({0.5, 0.9})), QString());
    QVERIFY(!ConformalLayer::checkLevels({0.0, 0.9}).empty());
    QVERIFY(!ConformalLayer::checkLevels({0.5, 1.0}).empty());
    QVERIFY(!ConformalLayer::checkLevels({0.5, NAN}).empty());
    QVERIFY(!ConformalLayer::checkLevels({0.9, 0.5}).empty());
    QVERIFY(!ConformalLayer::checkLevels({}).empty());
    ConformalLayer::Options o;
    o.levels = {0.5, 1.5};
    QVERIFY_THROWS_EXCEPTION(std::invalid_argument, ConformalLayer{o});
  }

  // Outside the region for `hold` seconds, every frame: a departure, at
  // the first frame outside; a shorter run is none; inside for `clear`
  // seconds clears it; an error below the minimum is never one.
  void departureNeedsHoldFramesOutside() {
    DepartureWatch watch;  // hold 0.5 s, clear 0.5 s, minimum 3 cm
    const Vec3 here{5.1, 0.2, 0};
    double t = 0;
    int began = 0;
    // 0.4 s outside, then inside: nothing.
    for (; t < 0.4; t += 0.02) began += watch.judge(t, here, 0.2, 0.05) == DepartureWatch::Change::Began;
    for (; t < 1.0; t += 0.02) began += watch.judge(t, here, 0.01, 0.05) == DepartureWatch::Change::Began;
    QCOMPARE(began, 0);
    QVERIFY(!watch.departing());
    // Large errors within a larger region: nothing either.
    for (; t < 2.0; t += 0.02) QCOMPARE(watch.judge(t, here, 0.2, 0.3), DepartureWatch::Change::None);
    // Errors beyond a region of millimetres but below the minimum: nothing.
    for (; t < 3.0; t += 0.02) QCOMPARE(watch.judge(t, here, 0.02, 0.002), DepartureWatch::Change::None);
    // 0.6 s outside: a departure, announced at 0.5 s, dated at its first frame.
    const double start = t;
    double announced = -1;
    for (; t < start + 0.6; t += 0.02)
      if (watch.judge(t, here, 0.28, 0.05) == DepartureWatch::Change::Began) announced = t;
    QVERIFY(watch.departing());
    QVERIFY2(announced - start >= 0.5 - 1e-9 && announced - start < 0.52, qPrintable(QString::number(announced - start)));
    QCOMPARE(watch.last()->time, start);
    QCOMPARE(QString::fromStdString(watch.last()->describe()),
             QString("the robot departs from its twin by 28 cm at (5.1, 0.2): the ground or the robot differ from the "
                     "files there"));
    // Back inside: it clears after 0.5 s inside.
    double ended = -1;
    const double back = t;
    for (; t < back + 1; t += 0.02)
      if (watch.judge(t, here, 0.01, 0.05) == DepartureWatch::Change::Ended) ended = t;
    QVERIFY(ended > back + 0.45 && ended < back + 0.55);
    QVERIFY(!watch.departing());
    QCOMPARE(watch.count(), 1);
    QVERIFY(!watch.last()->ground);  // the base alone: the robot differs, the calibration may fit it
    // Under the wheels (the position inside its region): placed at the
    // wheel, said in the ground's words; control: the position's departure
    // above stayed at the base.
    const Vec3 wheel{6.2, 0.6, 0.2};
    const double under = t;
    for (; t < under + 0.6; t += 0.02) watch.judge(t, here, 0.01, 0.05, 0.06, 0.01, wheel);
    QVERIFY(watch.departing());
    QCOMPARE(watch.count(), 2);
    QCOMPARE(watch.last()->where.x, 6.2);
    QVERIFY2(watch.last()->describe().find("a wheel stands 6 cm off the ground the map has there") != std::string::npos,
             watch.last()->describe().c_str());
    QVERIFY(watch.last()->ground);  // a place: the calibration leaves it out
  }

  // A run outside survives a frame inside (a wheel unloaded for a frame at
  // a hollow's edge): 0.36 s out, one frame in, 0.3 s out is a departure,
  // dated at the first run's start; control: 0.2 s inside between the two
  // runs (beyond the 0.1 s gap) ends the first, and neither is one.
  void departureSurvivesAFrameInside_data() {
    QTest::addColumn<double>("inside");
    QTest::addColumn<bool>("departs");
    QTest::newRow("one frame inside") << 0.02 << true;
    QTest::newRow("control: 0.2 s inside") << 0.2 << false;
  }
  void departureSurvivesAFrameInside() {
    QFETCH(double, inside);
    QFETCH(bool, departs);
    DepartureWatch watch;
    const Vec3 here{1, 0, 0}, wheel{1.5, 0.4, 0.2};
    double t = 10;
    for (; t < 10.36 - 1e-9; t += 0.02) watch.judge(t, here, 0.01, 0.05, 0.05, 0.02, wheel);
    const double back = t;
    for (; t < back + inside - 1e-9; t += 0.02) watch.judge(t, here, 0.01, 0.05, 0.004, 0.02, wheel);
    const double again = t;
    for (; t < again + 0.3 - 1e-9; t += 0.02) watch.judge(t, here, 0.01, 0.05, 0.05, 0.02, wheel);
    QCOMPARE(watch.departing(), departs);
    if (departs) QCOMPARE(watch.last()->time, 10.0);
  }

  // The scale: the floor for a robot standing, growing with speed x horizon
  // along the path, with a change of speed whose arrival is uncertain, and
  // with the terrain's uncertainty.
  void scaleGrowsWithItsSources() {
    ErrorModel m;
    m.terrain = 0;  // a plane
    QCOMPARE(errorScale({2, 0, 0}, m), m.floor);
    const double moving = errorScale({2, 0.5, 0}, m);
    QVERIFY(moving > m.floor);
    QVERIFY(errorScale({4, 0.5, 0}, m) > moving);
    QVERIFY(errorScale({2, 0.5, 0.5}, m) > moving);
    ErrorModel rough = m;
    rough.terrain = 0.01;
    QVERIFY(errorScale({2, 0.5, 0}, rough) > moving);
    // Along the path alone: speed x horizon x the speed's deviation.
    ErrorModel along{};
    along.floor = along.curvature = along.arrival = along.terrain = 0;
    along.speed = 0.02;
    QCOMPARE(errorScale({2, 0.5, 0}, along), 0.5 * 2 * 0.02);
  }

  // A command's timing counts only when it takes effect within the
  // prediction's horizon; a drive before it sets the speed it changes.
  // The wheels' clearance over the map, from the base's pose and the
  // joints' positions: 0 on the ground, the step's height where the map
  // has ground the wheel is not on; the discrepancy leaves out a wheel the
  // twin lifted. Control: the same robot 4 cm higher reads 4 cm everywhere.
  void wheelClearanceAndTheGroundsDiscrepancy() {
    Diagnostics diag;
    const std::optional<RobotModel> robot = loadRobot(SP_SOURCE_DIR "/robots/workpartner.xml", diag);
    QVERIFY2(robot, diag.format().c_str());
    const std::vector<double> joints(robot->joints.size(), 0.0);
    const Pose base = robot->links[0].pose;  // the model's frame on the ground z = 0
    const auto flat = [](double, double) { return 0.0; };
    const WheelClearances standing = wheelClearances(*robot, flat, base, joints);
    for (double c : standing) QVERIFY2(std::abs(c) < 1e-9, qPrintable(QString::number(c)));
    // A map with a 6 cm block under the front-left wheel (x > 0, y > 0).
    const auto block = [](double x, double y) { return x > 0.3 && y > 0.2 ? 0.06 : 0.0; };
    const WheelClearances onBlock = wheelClearances(*robot, block, base, joints);
    QVERIFY2(std::abs(onBlock[0] + 0.06) < 1e-9, qPrintable(QString::number(onBlock[0])));
    for (size_t k = 1; k < 4; ++k) QVERIFY(std::abs(onBlock[k]) < 1e-9);
    QVERIFY(std::abs(groundDiscrepancy(standing, onBlock) - 0.06) < 1e-9);
    // Bent knees lower the hubs: the clearance follows the joints.
    std::vector<double> bent = joints;
    const int knee = robot->findJoint("knee_fl");
    QVERIFY(knee >= 0);
    bent[static_cast<size_t>(knee)] = 0.3;
    const WheelClearances kneeling = wheelClearances(*robot, flat, base, bent);
    QVERIFY2(std::abs(kneeling[0]) > 0.005, qPrintable(QString::number(kneeling[0])));
    QVERIFY(std::abs(kneeling[1]) < 1e-9);
    // A wheel the twin had lifted (a gait) is not compared.
    WheelClearances lifted = standing;
    lifted[0] = 0.08;
    QCOMPARE(groundDiscrepancy(lifted, onBlock), 0.0);
    const WheelClearances unknown{kNoClearance, kNoClearance, kNoClearance, kNoClearance};
    QCOMPARE(groundDiscrepancy(standing, unknown), 0.0);
    // Control: the whole robot 4 cm up.
    Pose up = base;
    up.p.z += 0.04;
    const WheelClearances raised = wheelClearances(*robot, flat, up, joints);
    for (double c : raised) QVERIFY(std::abs(c - 0.04) < 1e-9);
    QVERIFY(std::abs(groundDiscrepancy(standing, raised) - 0.04) < 1e-9);
  }

  void timingCountsCommandsWithinTheHorizon() {
    InFlightCommands in;
    in.add(DriveCmd{0.5, 0}, 1.0);
    in.add(DriveCmd{0.25, 0}, 5.0);
    const auto all = in.upTo(100);
    QCOMPARE(all.size(), size_t{2});
    QCOMPARE(commandTiming(all, 2.0, 4.0, 0.5, 1.1), 0.0);     // neither within (2, 4]
    QCOMPARE(commandTiming(all, 4.0, 6.0, 0.5, 1.1), 0.25);    // the slowing: |0.25 - 0.5|
    QCOMPARE(commandTiming(all, 0.0, 6.0, 0.5, 1.1), 0.75);    // both: 0.5 from standing, then 0.25
    // Forgotten commands leave their set-point behind.
    in.forgetBefore(3.0);
    QCOMPARE(commandTiming(in.upTo(100), 4.0, 6.0, 0.5, 1.1), 0.25);
  }
};

QTEST_GUILESS_MAIN(TestGhostRegion)
#include "tst_ghost_region.moc"
