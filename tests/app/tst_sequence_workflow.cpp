// A sequence's way from text to the robot without Qt's widgets
// (app/rehearse/sequence_workflow.h), on real rehearsals in the flat world:
// the text's problems by line; nothing to rehearse without a world or a
// command; Send's gate: not before a rehearsal, not after the text or the
// terrain changed (and again once the text is back), not from a pinned
// start, not without the link; a passed, current rehearsal goes; a failed
// one does not (the relay refuses it).

#include <QTest>

#include "app/rehearse/sequence_workflow.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "tests/app/load_world.h"
#include "sim/world.h"

using namespace sp;

namespace {

const char* const kDrive = "0.2 drive 0.3 0\n1.5 stop\n";

}  // namespace

class TestSequenceWorkflow : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() { world_ = loadOrFail(SP_SOURCE_DIR "/terrains/flat.world.xml"); }

  void problemsByLine() {
    SequenceWorkflow flow;
    flow.check("0.2 drive 0.3 0\n1.0 fly 3\n", &world_);
    QCOMPARE(flow.problems().size(), size_t(1));
    QCOMPARE(flow.problems()[0].line, 2);
    flow.check("0.2 drive 0.3 0\n1.0 stop\n2.0 target no_such_joint 5\n", &world_);
    QCOMPARE(flow.problems().size(), size_t(1));
    QCOMPARE(flow.problems()[0].line, 3);
    QVERIFY(flow.problems()[0].message.find("no_such_joint") != std::string::npos);
    flow.check(kDrive, &world_);
    QVERIFY(flow.problems().empty());
    flow.check("1.0 fly 3\n", nullptr);  // nothing to judge against
    QVERIFY(flow.problems().empty());
  }

  void nothingToRehearse() {
    SequenceWorkflow flow;
    std::string why;
    QVERIFY(!flow.plan(kDrive, nullptr, SimParams{}, FlightRules{}, std::nullopt, why));
    QVERIFY(why.find("no world") != std::string::npos);
    QVERIFY(!flow.plan("# only a comment\n", &world_, SimParams{}, FlightRules{}, std::nullopt, why));
    QVERIFY(why.find("no command") != std::string::npos);
    QVERIFY(flow.plan(kDrive, &world_, SimParams{}, FlightRules{}, std::nullopt, why));
  }

  void sendsOnlyACurrentPassedRehearsal() {
    SequenceWorkflow flow;
    QVERIFY(flow.sendRefusal(kDrive, true).find("rehearse the sequence first") == 0);
    std::string why;
    std::optional<RehearsalPlan> plan = flow.plan(kDrive, &world_, SimParams{}, FlightRules{}, std::nullopt, why);
    QVERIFY2(plan, why.c_str());
    const RehearsalResult result = rehearse(*plan);
    QVERIFY2(result.passed, result.summary().c_str());
    flow.rehearsed(std::move(*plan), result, kDrive, false);
    QVERIFY(flow.current(kDrive));
    QCOMPARE(flow.sendRefusal(kDrive, true), std::string());
    std::optional<net::SequenceMsg> msg = flow.message(why);
    QVERIFY2(msg, why.c_str());
    QVERIFY(!msg->hash.empty());
    QVERIFY(flow.rehearsalLogLine().find(msg->hash + " passed (2 commands") == 0);
    QVERIFY(flow.path().size() > 10);
    QVERIFY(flow.envelope().empty());  // no robustness runs yet

    QVERIFY(flow.sendRefusal(kDrive, false).find("cannot take a sequence now") != std::string::npos);
    const std::string edited = "0.2 drive 0.3 1\n1.5 stop\n";
    QVERIFY(!flow.current(edited));
    QVERIFY(flow.sendRefusal(edited, true).find("changed since its rehearsal") != std::string::npos);
    QCOMPARE(flow.sendRefusal(kDrive, true), std::string());  // the very text rehearsed: it may go

    QVERIFY(flow.terrainEdited());
    QVERIFY(!flow.terrainEdited());  // stale already
    QVERIFY(!flow.current(kDrive));
    QVERIFY(flow.sendRefusal(kDrive, true).find("terrain was edited") != std::string::npos);
  }

  void aPinnedStartIsAWhatIf() {
    SequenceWorkflow flow;
    // The robot settled at the world's start, a metre further on (a logged moment).
    Diagnostics diag;
    std::unique_ptr<World> settled = World::create(world_, SimParams{}, diag);
    QVERIFY2(settled, diag.format().c_str());
    for (int i = 0; i < 500; ++i) QVERIFY(settled->step());
    RehearsalStart start;
    start.base = settled->linkPose(0, 0);
    start.base.p.x += 1;
    for (size_t j = 0; j < world_.robots[0].model.joints.size(); ++j)
      start.jointPositions.push_back(settled->jointPosition(0, static_cast<int>(j)));
    start.jointRates.assign(start.jointPositions.size(), 0.0);
    flow.pin({start, world_, SimParams{}, "a log at 3 s"});
    std::string why;
    std::optional<RehearsalPlan> plan = flow.plan(kDrive, nullptr, SimParams{}, FlightRules{}, std::nullopt, why);
    QVERIFY2(plan, why.c_str());  // the pinned world is the one rehearsed in
    QVERIFY(plan->start);
    QCOMPARE(plan->start->base.p.x, start.base.p.x);
    const RehearsalResult result = rehearse(*plan);
    QVERIFY2(result.passed, result.summary().c_str());
    flow.rehearsed(std::move(*plan), result, kDrive, true);
    QVERIFY(flow.sendRefusal(kDrive, true).find("rehearsed from a logged moment") != std::string::npos);
    flow.unpin();
    QVERIFY(!flow.pinned());
  }

  // The control of the gate: a failed rehearsal of the current text is not
  // sent (the gate says so, and the relay refuses it too).
  void aFailedRehearsalIsNotSent() {
    SequenceWorkflow flow;
    FlightRules strict;
    strict.maxSpeed = 0.1;  // the drive's 0.3 m/s breaks it
    std::string why;
    std::optional<RehearsalPlan> plan = flow.plan(kDrive, &world_, SimParams{}, strict, std::nullopt, why);
    QVERIFY(plan);
    const RehearsalResult result = rehearse(*plan);
    QVERIFY(!result.passed);
    flow.rehearsed(std::move(*plan), result, kDrive, false);
    QVERIFY(flow.sendRefusal(kDrive, true).find("the rehearsal failed") == 0);
    QVERIFY(!flow.message(why));  // and the relay, asked all the same, refuses it too
    QVERIFY2(!why.empty(), why.c_str());
  }

 private:
  WorldModel world_;
};

QTEST_GUILESS_MAIN(TestSequenceWorkflow)
#include "tst_sequence_workflow.moc"
