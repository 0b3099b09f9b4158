// Rehearsal of command sequences on the twin with the flight rules
// (app/rehearse/rehearsal.h, sim/flight_rules.h): a typo is caught with its line, a
// sequence that tips the robot over the test track's bumps fails the
// stability rule after its cause and before the fall, the same drive without
// the cause passes, and the rules file reports its errors by line.

#include <QDir>
#include <QFile>
#include <QTemporaryDir>
#include <QTest>

#include <algorithm>
#include <cmath>

#include "app/rehearse/rehearsal.h"
#include "app/rehearse/sequence_relay.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "tests/app/load_world.h"
#include "sim/rigid.h"
#include "tests/test_files.h"

using namespace sp;

namespace {

std::vector<TimedCommand> parseOrFail(const char* text, const RobotModel& robot) {
  Diagnostics diag;
  auto c = parseCommandSequence(text, "test.seq", diag, &robot);
  if (!c) qFatal("%s", diag.format().c_str());
  return *c;
}

const RuleVerdict& verdict(const RehearsalResult& r, Rule rule) { return r.verdicts[static_cast<int>(rule)]; }

// Driving over the test track's bumps, then folding the two left legs up
// to their limits at t = 3 s: the left side loses its wheels.
constexpr const char* kTip =
    "0.5 drive 0.4 0\n"
    "3.0 target knee_fl -40\n"
    "3.0 target hip_fl 45\n"
    "3.0 target knee_rl -40\n"
    "3.0 target hip_rl -45\n";
constexpr const char* kDrive = "0.5 drive 0.4 0\n";

}  // namespace

class TestRehearsal : public QObject {
  Q_OBJECT

 private slots:
  // Issue 30: a rehearsal from a world's start settles the robot first
  // (worlds place it above the ground: judged there, every sequence failed
  // at t = 0 on the bumpy field), so a stop-only sequence passes on every
  // shipped world, and so it does when the robot starts 6 cm up; a robot
  // that never comes to rest (tilted gravity on the ice: it slides) is its
  // own verdict.
  void worldStartsSettleFirst() {
    int worlds = 0;
    for (const QString& name : QDir("terrains").entryList({"*.world.xml"})) {
      const WorldModel world = loadOrFail(qPrintable("terrains/" + name));
      const RehearsalResult r = rehearse({world, SimParams{}, FlightRules{}, parseOrFail("0.5 stop\n", world.robots[0].model), std::nullopt});
      qInfo("%s: %s, settled in %.3f s", qPrintable(name), r.summary().c_str(), r.settled);
      QVERIFY2(r.passed, qPrintable(name + ": " + QString::fromStdString(r.summary())));
      QVERIFY(r.settled > 0 && r.settled < kSettleLimit);
      ++worlds;
    }
    QCOMPARE(worlds, 8);  // the shipped worlds, the rough field and its unmapped ground among them
    WorldModel high = loadOrFail("terrains/flat.world.xml");
    high.robots[0].pose.p.z += 0.06;
    const RehearsalResult dropped = rehearse({high, SimParams{}, FlightRules{}, parseOrFail("0.5 stop\n", high.robots[0].model), std::nullopt});
    QVERIFY2(dropped.passed, dropped.summary().c_str());
    WorldModel tilted = loadOrFail("terrains/ice.world.xml");
    tilted.gravity = {1.0, 0, -9.81};
    const RehearsalResult sliding = rehearse({tilted, SimParams{}, FlightRules{}, parseOrFail("0.5 stop\n", tilted.robots[0].model), std::nullopt});
    QVERIFY(!sliding.passed);
    QVERIFY2(sliding.error.rfind("the robot did not settle within 5 s of the world's start: its base still moved", 0) == 0,
             sliding.error.c_str());
  }

  void typoCaughtWithItsLine() {
    const WorldModel world = loadOrFail("terrains/test_track.world.xml");
    Diagnostics diag;
    const auto c = parseCommandSequence("0.5 drive 0.4 0\n1.0 drvie 0.4 0\n2.0 drive 0.4 oops\n", "typo.seq", diag,
                                        &world.robots[0].model);
    QVERIFY(!c);
    QCOMPARE(diag.errorCount(), 2);
    QVERIFY2(diag.items()[0].line == 2 && diag.items()[0].message.find("drvie") != std::string::npos,
             diag.format().c_str());
    QCOMPARE(diag.items()[1].line, 3);
  }

  // Criterion, stated before the run: the stability rule fails after the
  // legs start folding (t > 3 s) and before the robot has fallen (its roll
  // first exceeds 30 deg, read from the same rehearsal's path); the same
  // drive without the folding (the control) passes every rule.
  void tippingFailsStabilityBeforeTheFall() {
    RehearsalPlan plan{loadOrFail("terrains/test_track.world.xml"), {}, {}, {}, {}};
    plan.commands = parseOrFail(kTip, plan.world.robots[0].model);
    plan.rules.settle = 5;
    const RehearsalResult tip = rehearse(plan);
    QVERIFY2(tip.error.empty(), tip.error.c_str());
    QVERIFY(!tip.passed);
    double fell = -1;
    for (const RehearsalSample& s : tip.path)
      if (std::abs(s.roll) > degToRad(30)) {
        fell = s.time;
        break;
      }
    const RuleVerdict& stability = verdict(tip, Rule::Stability);
    qInfo("tipping: %s; roll beyond 30 deg at %.2f s", stability.message().c_str(), fell);
    QVERIFY2(fell > 3, "the control of the criterion: the robot must fall");
    QVERIFY2(!stability.passed, stability.message().c_str());
    QVERIFY(stability.time > 3.0);
    QVERIFY(stability.time < fell);

    plan.commands = parseOrFail(kDrive, plan.world.robots[0].model);
    const RehearsalResult drive = rehearse(plan);
    for (const RuleVerdict& v : drive.verdicts) qInfo("drive: %s", v.message().c_str());
    QVERIFY2(drive.passed, drive.summary().c_str());
    QVERIFY(verdict(drive, Rule::Stability).worst > plan.rules.minStabilityMargin);
  }

  // Criterion: with friction, masses, terrain and start perturbed within
  // the default ranges, the test-track drive passes every sample and the
  // tipping sequence (the control) none; the samples land the same on one
  // thread and on two (each is seeded by its index).
  void robustnessSeparatesSafeFromTipping() {
    RehearsalPlan plan{loadOrFail("terrains/test_track.world.xml"), {}, {}, {}, {}};
    plan.rules.settle = 5;
    plan.rules.robustSamples = 4;
    plan.commands = parseOrFail(kDrive, plan.world.robots[0].model);
    const RobustnessResult safe = robustness(plan, 7, 2);
    const RobustnessResult safeOne = robustness(plan, 7, 1);
    qInfo("drive: %d of %d passed, end spread %.3f m", safe.passed, safe.samples, safe.spread);
    QCOMPARE(safe.passed, 4);
    QVERIFY(safe.spread > 0);  // the perturbations do move the robot
    for (int i = 0; i < 4; ++i) QCOMPARE(safe.endPoses[i].p, safeOne.endPoses[i].p);
    plan.commands = parseOrFail(kTip, plan.world.robots[0].model);
    const RobustnessResult tip = robustness(plan, 7, 2);
    qInfo("tipping: %d of %d passed; sample 0: %s", tip.passed, tip.samples, tip.failures[0].c_str());
    QCOMPARE(tip.passed, 0);
    QCOMPARE(tip.refined, 0);  // full profile: nothing to refine
    // As the console runs them: fast, stopped at a failure; each failed
    // sample is judged again at full fidelity, and fails there too.
    plan.fast = plan.stopAtFirstFailure = true;
    const RobustnessResult fastTip = robustness(plan, 7, 2);
    qInfo("tipping, fast: %d of %d passed, %d refined", fastTip.passed, fastTip.samples, fastTip.refined);
    QCOMPARE(fastTip.passed, 0);
    QCOMPARE(fastTip.refined, 4);
  }

  // Issue 61: robustness runs draw the robot from what the console knows
  // of it. A parameter a fit observed is drawn about its value with its
  // deviation, one never observed over its prior range; the rules' fixed
  // friction and mass ranges are then not applied (control: without an
  // estimate they are, and the parameters stay). The verdict says so, and
  // a robot known closely ends closer together than one known only by its
  // prior (criterion: 90 % radius at least 3x smaller, stated before the run).
  void robustnessDrawsFromTheEstimate() {
    RehearsalPlan plan{loadOrFail("terrains/flat.world.xml"), {}, {}, {}, {}};
    plan.rules.settle = 3;
    plan.rules.robustStartPosition = plan.rules.robustStartHeading = 0;  // the robot's draws alone
    plan.commands = parseOrFail("0.5 drive 0.6 10\n", plan.world.robots[0].model);
    RobotEstimate known;
    known.observed.fill(true);
    known.sigma.fill(1e-4);
    const size_t kFriction = static_cast<size_t>(CalParam::Friction), kMass = static_cast<size_t>(CalParam::Mass);
    known.sigma[kFriction] = 0.01;
    RobotEstimate prior;  // nothing observed
    RobotEstimate mixed = known;
    mixed.observed[kMass] = false;
    plan.estimate = mixed;
    double lo = 1e9, hi = -1e9, sum = 0, sum2 = 0, massLo = 1e9, massHi = -1e9;
    constexpr int kDraws = 50;
    for (int seed = 0; seed < kDraws; ++seed) {
      const RehearsalPlan p = perturbed(plan, static_cast<uint64_t>(seed));
      QCOMPARE(p.world.defaultContact.mu, plan.world.defaultContact.mu);  // no fixed range on top
      lo = std::min(lo, p.params.calFriction);
      hi = std::max(hi, p.params.calFriction);
      sum += p.params.calFriction;
      sum2 += p.params.calFriction * p.params.calFriction;
      massLo = std::min(massLo, p.params.calMass);
      massHi = std::max(massHi, p.params.calMass);
    }
    const double sd = std::sqrt(sum2 / kDraws - (sum / kDraws) * (sum / kDraws));
    qInfo("friction drawn %.4f..%.4f (sd %.4f, stated 0.01); mass (unobserved) %.3f..%.3f", lo, hi, sd, massLo, massHi);
    QVERIFY(lo > 0.95 && hi < 1.05 && sd > 0.006 && sd < 0.014);
    QVERIFY(massLo >= 1 - calParam(CalParam::Mass).scale && massHi <= 1 + calParam(CalParam::Mass).scale);
    QVERIFY(massHi - massLo > calParam(CalParam::Mass).scale);  // over the prior's range, not the deviation's
    plan.estimate.reset();
    const RehearsalPlan ranges = perturbed(plan, 3);
    QVERIFY(ranges.world.defaultContact.mu != plan.world.defaultContact.mu);
    QCOMPARE(ranges.params.calFriction, 1.0);

    plan.rules.robustSamples = 8;
    plan.fast = plan.stopAtFirstFailure = true;
    plan.estimate = known;
    const RobustnessResult close = robustness(plan, 1, 2);
    plan.estimate = prior;
    const RobustnessResult loose = robustness(plan, 1, 2);
    qInfo("known closely: %s; by the prior: %s", close.verdict().c_str(), loose.verdict().c_str());
    QVERIFY2(close.verdict().rfind("passes in 8 of 8 draws of what the console knows of the robot; 90 % of the ends within ", 0) == 0,
             close.verdict().c_str());
    QVERIFY(close.fromEstimate && loose.fromEstimate);
    QVERIFY(close.within90 && loose.within90);
    QVERIFY(*loose.within90 > 0 && *close.within90 * 3 < *loose.within90);
    plan.estimate.reset();
    QVERIFY(robustness(plan, 1, 2).verdict().find("perturbed rehearsals") != std::string::npos);
  }

  // Holding the joints no command moves is a speed lever, not another
  // physics: criterion, the held rehearsal of the test-track drive ends
  // within 1 cm and 0.1 deg of the full one with the same verdicts, having
  // held the upper body (a drive commands no arm joint); a sequence that
  // moves an arm keeps that arm's joints.
  void heldRehearsalMatchesTheFullOne() {
    RehearsalPlan plan{loadOrFail("terrains/test_track.world.xml"), {}, {}, {}, {}};
    const RobotModel& robot = plan.world.robots[0].model;
    plan.commands = parseOrFail("0.5 drive 0.4 0\n4 drive 0.4 8\n", robot);
    plan.rules.settle = 4;
    const RehearsalResult held = rehearse(plan);
    plan.holdUnmoved = false;
    const RehearsalResult full = rehearse(plan);
    QCOMPARE(held.heldJoints, static_cast<int>(subtreeJoints(robot, "waist_yaw").size()));
    QCOMPARE(full.heldJoints, 0);
    const Pose a = held.path.back().base, b = full.path.back().base;
    qInfo("held %d joints: %.2f s vs %.2f s; ends %.2f mm, %.4f deg apart", held.heldJoints, held.wallSeconds,
          full.wallSeconds, 1000 * std::hypot(a.p.x - b.p.x, a.p.y - b.p.y),
          radToDeg(std::abs(std::remainder(heading(a.q) - heading(b.q), 2 * kPi))));
    QVERIFY(std::hypot(a.p.x - b.p.x, a.p.y - b.p.y) < 0.01);
    QVERIFY(std::abs(std::remainder(heading(a.q) - heading(b.q), 2 * kPi)) < degToRad(0.1));
    for (int i = 0; i < kRuleCount; ++i) QCOMPARE(held.verdicts[i].passed, full.verdicts[i].passed);
    QCOMPARE(held.path.back().jointPositions.size(), robot.joints.size());  // reported as the full robot's

    const std::vector<int> moved = unmovedJoints(robot, parseOrFail("1 target elbow_l 30\n", robot));
    QVERIFY(std::find(moved.begin(), moved.end(), robot.findJoint("elbow_l")) == moved.end());
    QVERIFY(std::find(moved.begin(), moved.end(), robot.findJoint("waist_yaw")) == moved.end());  // above the elbow
    QVERIFY(std::find(moved.begin(), moved.end(), robot.findJoint("head_pan")) != moved.end());
    QVERIFY(std::find(moved.begin(), moved.end(), robot.findJoint("elbow_r")) != moved.end());
  }

  // Issue 32: joints are welded only while nothing moves them. Criterion
  // (before the run): a drive that raises an arm at 2 s frees the arm then
  // and welds it again once it has rested (two switches at least), the
  // arm reaches its target, and the run ends within 1 cm and 0.1 deg of the
  // full robot's with the same verdicts and nothing refused; the control,
  // the same arm retargeted every 0.4 s to the end, is never welded again.
  void heldJointsAreFreedWhileMoved() {
    RehearsalPlan plan{loadOrFail("terrains/flat.world.xml"), {}, {}, {}, {}};
    const RobotModel& robot = plan.world.robots[0].model;
    plan.commands = parseOrFail("0.5 drive 0.5 0\n2 target shoulder_pitch_l -30\n4 drive 0.5 10\n", robot);
    plan.rules.settle = 5;
    const RehearsalResult held = rehearse(plan);
    plan.holdUnmoved = false;
    const RehearsalResult full = rehearse(plan);
    QVERIFY2(held.error.empty() && held.refused.empty(), held.summary().c_str());
    const Pose a = held.path.back().base, b = full.path.back().base;
    const size_t shoulder = static_cast<size_t>(robot.findJoint("shoulder_pitch_l"));
    qInfo("%d switches: %.2f s vs %.2f s in the full robot; ends %.2f mm, %.4f deg apart; shoulder %.2f deg", held.switches,
          held.wallSeconds, full.wallSeconds, 1000 * std::hypot(a.p.x - b.p.x, a.p.y - b.p.y),
          radToDeg(std::abs(std::remainder(heading(a.q) - heading(b.q), 2 * kPi))),
          radToDeg(held.path.back().jointPositions[shoulder]));
    QVERIFY(held.switches >= 2);
    QCOMPARE(full.switches, 0);
    QVERIFY(std::abs(held.path.back().jointPositions[shoulder] - degToRad(-30)) < degToRad(1));
    QVERIFY(std::hypot(a.p.x - b.p.x, a.p.y - b.p.y) < 0.01);
    QVERIFY(std::abs(std::remainder(heading(a.q) - heading(b.q), 2 * kPi)) < degToRad(0.1));
    for (int i = 0; i < kRuleCount; ++i) QCOMPARE(held.verdicts[i].passed, full.verdicts[i].passed);

    std::string restless = "0.5 drive 0.5 0\n";
    for (int i = 0; i < 20; ++i)
      restless += std::to_string(2 + 0.4 * i) + " target shoulder_pitch_l " + (i % 2 ? "-30\n" : "-10\n");
    plan.commands = parseOrFail(restless.c_str(), robot);
    plan.rules.settle = 0.5;
    plan.holdUnmoved = true;
    const RehearsalResult moving = rehearse(plan);
    QVERIFY2(moving.error.empty() && moving.refused.empty(), moving.summary().c_str());
    QCOMPARE(moving.switches, 1);
  }

  // The fast profile welds the legs' hips and knees too (rehearsal.fast_hold),
  // the wheels below them turning, until a gait or a command moves them.
  // Criterion: a drive holds the upper body and the 8 leg joints all along
  // in the fast profile and only the upper body in the full one; with a
  // caterpillar gait the legs are freed (not welded all along, a switch);
  // a name the robot lacks is refused naming the key.
  void fastProfileWeldsTheLegs() {
    RehearsalPlan plan{loadOrFail("terrains/flat.world.xml"), {}, {}, {}, {}};
    const RobotModel& robot = plan.world.robots[0].model;
    const int upper = static_cast<int>(subtreeJoints(robot, "waist_yaw").size());
    plan.commands = parseOrFail("0.5 drive 0.5 0\n2 drive 0.5 10\n", robot);
    plan.rules.settle = 1;
    const RehearsalResult full = rehearse(plan);
    plan.fast = true;
    const RehearsalResult fast = rehearse(plan);
    qInfo("drive: %d joints welded all along (full profile %d), %d switches", fast.heldJoints, full.heldJoints,
          fast.switches);
    QCOMPARE(full.heldJoints, upper);
    QCOMPARE(fast.heldJoints, upper + 8);
    QCOMPARE(fast.switches, 0);
    QVERIFY(fast.passed && full.passed);

    plan.commands = parseOrFail("0.5 gait caterpillar\n4 gait off\n", robot);
    const RehearsalResult gait = rehearse(plan);
    qInfo("gait: %d joints welded all along, %d switches; %s", gait.heldJoints, gait.switches, gait.summary().c_str());
    QCOMPARE(gait.heldJoints, upper);
    QVERIFY(gait.switches >= 1);
    QVERIFY(gait.refused.empty());

    plan.params.rehearsalFastHold = "hip_fl,hip_xx";
    const RehearsalResult bad = rehearse(plan);
    QVERIFY(bad.error.find("rehearsal.fast_hold") != std::string::npos);
    QVERIFY(bad.error.find("hip_xx") != std::string::npos);
  }

  // Issue 32: the fast profile (2 ms, 40 iterations) is a speed lever, not
  // another verdict. Criterion (before the run): on the shipped sequences
  // (demo on flat, pick_place on its world) and the tipping one, each rule
  // passes or fails as in the full profile, in less time; every margin is
  // within 10 % of the full run's on demo (a falling robot's margins after
  // its failure are chaos: the tipping one is held to its verdicts). On pick_place the
  // knee comes within 2.6 deg of its stop and the fast profile brings it
  // 0.3 deg nearer (22 % of that margin, measured): the 10 % is not
  // met there, so that case is held to its verdicts (docs/performance.md,
  // "Rehearsals", has every rule over 24 sequences). The control: a much
  // coarser profile (4 ms, 10 iterations) fails pick_place where the full
  // one passes, and the comparison says so. A fast result is never relayed.
  void fastProfileKeepsTheVerdicts() {
    struct Case {
      const char* world;
      std::string commands;
      bool margins;  // held to margins within 10 % as well as to the verdicts
    };
    const auto file = [](const char* path) {
      QFile f(QStringLiteral(SP_SOURCE_DIR "/") + QString::fromLatin1(path));
      return f.open(QIODevice::ReadOnly) ? f.readAll().toStdString() : std::string();
    };
    const Case cases[] = {{"terrains/flat.world.xml", file("terrains/demo.seq"), true},
                          {"terrains/pick_place.world.xml", file("terrains/pick_place.seq"), false},
                          {"terrains/test_track.world.xml", kTip, false}};
    RehearsalPlan pickPlace;
    RehearsalResult pickPlaceFull;
    for (const Case& c : cases) {
      RehearsalPlan plan{loadOrFail(c.world), {}, {}, {}, {}};
      plan.commands = parseOrFail(c.commands.c_str(), plan.world.robots[0].model);
      const RehearsalResult full = rehearse(plan);
      plan.fast = true;
      plan.refine = false;  // the fast profile's own verdicts
      const RehearsalResult fast = rehearse(plan);
      const ProfileAgreement a = compareProfiles(full, fast);
      qInfo("%s: full %s in %.2f s, fast in %.2f s; verdicts %s, largest margin change %.1f %% (%s)", c.world,
            full.passed ? "passed" : "failed", full.wallSeconds, fast.wallSeconds, a.sameVerdicts ? "the same" : "differ",
            100 * a.largestChange, a.largestRule.c_str());
      QVERIFY(fast.fast && !full.fast);
      QVERIFY2(a.sameVerdicts, a.differ.c_str());
      if (c.margins) QVERIFY2(a.within(0.1), a.largestRule.c_str());
      QVERIFY(fast.wallSeconds < full.wallSeconds);
      if (std::string(c.world).find("pick_place") != std::string::npos) pickPlace = plan, pickPlaceFull = full;
      // Not relayed, even when it passed; the full result is.
      std::string why;
      plan.fast = false;
      QCOMPARE(sequenceMessage(plan, full, why).has_value(), full.passed);
      QVERIFY(!sequenceMessage(plan, fast, why));
      if (fast.passed) QVERIFY(why.find("fast-profile") != std::string::npos);
    }
    QVERIFY(pickPlaceFull.passed);
    pickPlace.params.rehearsalFastStep = 0.004;
    pickPlace.params.rehearsalFastIterations = 10;
    const ProfileAgreement coarse = compareProfiles(pickPlaceFull, rehearse(pickPlace));
    qInfo("4 ms / 10 iterations on pick_place: %s", coarse.differ.c_str());
    QVERIFY(!coarse.sameVerdicts);
  }

  // Where the fast profile is not trusted it is run again at full
  // fidelity: a run that fails a rule, or passes within a rule's
  // rehearsal.refine.* band. Criterion (before the run): the tipping
  // sequence fails, so it comes back refined, its result the full run's to
  // the state hash (margins 0 % apart), `fast` false, never relayed; demo's
  // margins are all outside their bands, so it stays fast; with the yaw
  // rate's band as wide as its limit (60 deg/s) demo is refined too, and is
  // then the full run. (On pick_place, where the knee comes 1.24 deg from
  // its stop margin and the fast profile moves that margin 22 %, the bands
  // refine it: bench_rehearsal, docs/performance.md.)
  void untrustedFastRunsAreRefined() {
    QFile demoFile(QStringLiteral(SP_SOURCE_DIR "/terrains/demo.seq"));
    QVERIFY(demoFile.open(QIODevice::ReadOnly));
    struct Case {
      const char* world;
      std::string commands;
      double yawRateBand;
      bool refined;
    };
    const Case cases[] = {{"terrains/test_track.world.xml", kTip, SimParams{}.refineYawRate, true},
                          {"terrains/flat.world.xml", demoFile.readAll().toStdString(), SimParams{}.refineYawRate, false},
                          {"terrains/flat.world.xml", "", 60, true}};
    RehearsalResult full;
    for (const Case& c : cases) {
      RehearsalPlan plan{loadOrFail(c.world), {}, {}, {}, {}};
      plan.commands = parseOrFail((c.commands.empty() ? cases[1].commands : c.commands).c_str(),
                                  plan.world.robots[0].model);
      plan.params.refineYawRate = c.yawRateBand;
      if (!c.commands.empty()) full = rehearse(plan);  // the last case reuses demo's
      plan.fast = true;
      const RehearsalResult r = rehearse(plan);
      qInfo("%s, yaw rate band %g deg/s: %s in %.2f s (full alone %.2f s); %s", c.world, c.yawRateBand,
            r.refined.empty() ? "fast" : "refined", r.wallSeconds, full.wallSeconds, r.refined.c_str());
      QCOMPARE(!r.refined.empty(), c.refined);
      QCOMPARE(r.fast, !c.refined);
      QCOMPARE(r.passed, full.passed);
      if (c.refined) {
        QCOMPARE(r.endHash, full.endHash);
        QVERIFY(compareProfiles(full, r).within(0.0));
      } else {
        QVERIFY(r.endHash != full.endHash);
      }
      std::string why;
      QVERIFY(!sequenceMessage(plan, r, why));
    }
  }

  // Which runs untrusted() sends back: a failed rule, a refused command, a
  // margin inside its band; not one outside it, nor a collision rule that
  // passed (no distance to a limit: its margin is 0).
  void untrustedNamesWhy() {
    SimParams params;
    RehearsalResult r;
    r.passed = true;
    RuleVerdict stability;
    stability.rule = Rule::Stability;
    stability.limit = 0.05;
    stability.worst = 0.05 + params.refineStability * 1.01;
    RuleVerdict collision;
    collision.rule = Rule::Collision;
    r.verdicts = {stability, collision};
    QCOMPARE(untrusted(r, params), std::string());
    r.verdicts[0].worst = 0.05 + params.refineStability * 0.99;
    QVERIFY(untrusted(r, params).find("stability") == 0);
    r.verdicts[0].worst = 0.2;
    r.verdicts[1].passed = false;
    r.passed = false;
    QCOMPARE(untrusted(r, params), std::string("collision failed"));
    r.verdicts[1].passed = r.passed = true;
    r.refused = {"line 2 at 1 s: no such joint"};
    QCOMPARE(untrusted(r, params), std::string("a command was refused"));
  }

  // A margin keeps its side of the limit: a run whose centre of mass came
  // 3 cm outside the support polygon (worst -0.03 m, limit 0.05) is 0.108 m
  // from one that stayed 0.078 m inside, not the same 0.02 m from the limit
  // (as |limit| - |worst| had it). Upper bounds on signed values compare
  // magnitudes.
  void profileMarginsKeepTheirSide() {
    const auto verdict = [](Rule rule, double worst, double limit) {
      RuleVerdict v;
      v.rule = rule;
      v.worst = worst;
      v.limit = limit;
      v.passed = rule == Rule::Stability || rule == Rule::JointLimit ? worst >= limit : std::abs(worst) <= limit;
      return v;
    };
    QCOMPARE(ruleMargin(verdict(Rule::Stability, -0.03, 0.05)), -0.08);
    QCOMPARE(ruleMargin(verdict(Rule::JointLimit, 2.5, 1)), 1.5);
    QCOMPARE(ruleMargin(verdict(Rule::YawRate, -21.5, 60)), 38.5);
    QCOMPARE(ruleMargin(verdict(Rule::Speed, 2.0, 1.94)), 1.94 - 2.0);
    RehearsalResult full, fast;
    full.verdicts = {verdict(Rule::Stability, -0.03, 0.05), verdict(Rule::YawRate, -30, 60)};
    fast.verdicts = {verdict(Rule::Stability, 0.078, 0.05), verdict(Rule::YawRate, 30, 60)};
    const ProfileAgreement a = compareProfiles(full, fast);
    QVERIFY(!a.sameVerdicts);
    QCOMPARE(a.largestRule, std::string("stability"));
    QVERIFY(std::abs(a.largestChange - 0.108 / 0.08) < 1e-12);
    // The control: the same runs with the fast one 1 mm closer than the full.
    fast.verdicts[0] = verdict(Rule::Stability, -0.031, 0.05);
    const ProfileAgreement b = compareProfiles(full, fast);
    QVERIFY(b.sameVerdicts);
    QVERIFY(std::abs(b.largestChange - 0.001 / 0.08) < 1e-12);
  }

  // A failed rule decides the verdict: stopped there, the tipping sequence
  // fails as the whole run does, on the same rule, and in less time.
  void stopsAtTheFirstFailure() {
    RehearsalPlan plan{loadOrFail("terrains/test_track.world.xml"), {}, {}, {}, {}};
    plan.commands = parseOrFail(kTip, plan.world.robots[0].model);
    plan.rules.settle = 5;
    const RehearsalResult whole = rehearse(plan);
    plan.stopAtFirstFailure = true;
    const RehearsalResult stopped = rehearse(plan);
    qInfo("whole %.2f s (%s), stopped %.2f s at %.2f s of %.2f (%s)", whole.wallSeconds, whole.summary().c_str(),
          stopped.wallSeconds, stopped.path.back().time, stopped.duration, stopped.summary().c_str());
    QVERIFY(!whole.passed && !stopped.passed);
    QVERIFY(stopped.stoppedEarly && !whole.stoppedEarly);
    QCOMPARE(stopped.summary(), whole.summary());
    QVERIFY(stopped.path.back().time < stopped.duration - 1);
    // Control: a sequence that passes runs to its end.
    plan.commands = parseOrFail(kDrive, plan.world.robots[0].model);
    const RehearsalResult drive = rehearse(plan);
    QVERIFY(drive.passed && !drive.stoppedEarly);
  }

  void rulesFileErrorsNameTheirLines() {
    FlightRules rules;
    Diagnostics diag;
    QVERIFY(!parseFlightRules("# rules\nattitude.max_roll = 20\nattitude.max_rol = 3\nspeed.max = fast\n"
                              "attitude.max_roll = 21\ncollision.allowed = a b\n",
                              "my.rules", rules, diag));
    QCOMPARE(diag.errorCount(), 4);
    QCOMPARE(diag.items()[0].format(), std::string("my.rules:3: error: unknown key 'attitude.max_rol'"));
    QCOMPARE(diag.items()[1].line, 4);
    QVERIFY(diag.items()[2].message.find("duplicate") != std::string::npos);
    QCOMPARE(diag.items()[3].line, 6);
    QCOMPARE(rules.maxRoll, FlightRules{}.maxRoll);  // nothing applied

    // The shipped file is the defaults, key for key.
    FlightRules shipped;
    shipped.maxRoll = -1;
    Diagnostics d2;
    QVERIFY2(loadFlightRules("config/flight.rules", shipped, d2), d2.format().c_str());
    QCOMPARE(flightRulesText(shipped), flightRulesText(FlightRules{}));
  }

  void supportMarginIsGeometry() {
    const std::vector<Vec3> square = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
    QCOMPARE(supportMargin({1, 1, 5}, square), 1.0);
    QCOMPARE(supportMargin({1, 0.25, 0}, square), 0.25);
    QCOMPARE(supportMargin({3, 1, 0}, square), -1.0);
    QCOMPARE(supportMargin({1, 1, 0}, {{0, 0, 0}, {2, 2, 0}}), -0.0);  // on a diagonal pair's line
    QCOMPARE(supportMargin({1, 0, 0}, {{0, 0, 0}, {2, 2, 0}}), -std::sqrt(0.5));
  }

  void sequenceHashNamesTheText() {
    const WorldModel world = loadOrFail("terrains/flat.world.xml");
    const RobotModel& robot = world.robots[0].model;
    const auto a = parseOrFail("1 drive 0.5 10\n2.5 stop\n", robot);
    const auto b = parseOrFail("1.0   drive 0.50 10.0   # same\n2.5 stop\n", robot);
    const auto c = parseOrFail("1 drive 0.5 11\n2.5 stop\n", robot);
    QCOMPARE(sequenceText(a, &robot), std::string("1 drive 0.5 10\n2.5 stop\n"));
    QCOMPARE(sequenceHash(sequenceText(a, &robot)), sequenceHash(sequenceText(b, &robot)));
    QVERIFY(sequenceHash(sequenceText(a, &robot)) != sequenceHash(sequenceText(c, &robot)));
  }
};

QTEST_GUILESS_MAIN(TestRehearsal)
#include "tst_rehearsal.moc"
