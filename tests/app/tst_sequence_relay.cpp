// Relaying a rehearsed sequence to a real stand-in over loopback
// (app/rehearse/sequence_relay.h, SEQUENCE / SEQUENCE_STATE / ABORT): a sequence that
// passed is run on board and its hash matches there; a stale start is
// refused; with the stand-in's friction changed behind the console's back
// the guard trips and the robot stops; the robot refuses a sequence whose
// hash does not match its commands or whose command breaks a limit.
//
// The stand-in runs at 2x real time, so the runs take half as long; the
// guard compares robot times, not wall times.

#include <QRegularExpression>
#include <QTemporaryDir>
#include <QTest>

#include <chrono>
#include <cmath>
#include <deque>

#include "app/log/resimulation.h"
#include "app/rehearse/sequence_guard.h"
#include "app/rehearse/sequence_relay.h"
#include "app/log/session_log.h"
#include "app/robot/stand_in.h"
#include "net/robot_client.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "tests/app/shared_state.h"
#include "tests/test_files.h"

using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

struct Seen : sp::test::SharedState {
  bool ready = false, lease = false;
  std::optional<TelemetryMsg> last;
  std::deque<TelemetryMsg> telemetry;
  std::vector<SequenceStateMsg> states;

  RobotClientCallbacks callbacks() {
    RobotClientCallbacks cb;
    cb.connection = [this](ConnectionState s, const std::string&) { add([&] { ready = s == ConnectionState::Ready; }); };
    cb.lease = [this](const LeaseStateMsg& m) { add([&] { lease = m.yours; }); };
    cb.telemetry = [this](const TelemetryMsg& t) {
      add([&] {
        last = t;
        telemetry.push_back(t);
      });
    };
    cb.sequence = [this](const SequenceStateMsg& s) { add([&] { states.push_back(s); }); };
    return cb;
  }
  bool stateSeen(SequenceStateKind kind, std::chrono::milliseconds limit = 20s) {
    return waitFor([&] { return std::any_of(states.begin(), states.end(), [&](auto& s) { return s.state == kind; }); },
                   limit);
  }
};

// A stand-in on `worldFile` with a client holding the lease.
struct Rig {
  std::unique_ptr<StandInRobot> robot;
  Seen seen;
  std::unique_ptr<RobotClient> client;
  std::string logPath;

  bool start(const std::string& worldFile, const QTemporaryDir& dir) {
    StandInOptions o;
    o.worldFile = worldFile;
    o.port = 0;
    o.token = kToken;
    o.realTimeFactor = 2;
    o.logDir = dir.filePath("logs").toStdString();
    Diagnostics diag;
    robot = StandInRobot::create(o, diag);
    if (!robot) {
      qWarning("%s", diag.format().c_str());
      return false;
    }
    if (std::string e = robot->start(); !e.empty()) {
      qWarning("%s", e.c_str());
      return false;
    }
    logPath = robot->logPath();
    RobotClientConfig config;
    config.port = robot->port();
    config.token = kToken;
    config.name = "relay test";
    client = std::make_unique<RobotClient>(config, seen.callbacks());
    client->start();
    if (!seen.waitFor([&] { return seen.ready; }, 20s)) return false;
    client->acquireLease();
    return seen.waitFor([&] { return seen.lease && seen.last.has_value(); }, 20s);
  }
  TelemetryMsg latest() {
    std::lock_guard lock(seen.mutex);
    return *seen.last;
  }
  std::vector<TelemetryMsg> takeTelemetry() {
    std::lock_guard lock(seen.mutex);
    std::vector<TelemetryMsg> out(seen.telemetry.begin(), seen.telemetry.end());
    seen.telemetry.clear();
    return out;
  }
};

WorldModel loadOrFail(const std::string& file) {
  Diagnostics diag;
  std::optional<WorldModel> w = loadWorld(file, diag);
  if (!w) qFatal("%s", diag.format().c_str());
  return *w;
}

// The plan of `text` on `world` from the robot's latest telemetry, rehearsed.
std::pair<RehearsalPlan, RehearsalResult> rehearseFrom(const WorldModel& world, const TelemetryMsg& t, const char* text) {
  RehearsalPlan plan{world, {}, {}, {}, {}};
  Diagnostics diag;
  plan.commands = *parseCommandSequence(text, "relay.seq", diag, &world.robots[0].model);
  std::string why;
  plan.start = startFromTelemetry(t, world.robots[0].model, why);
  if (!plan.start) qFatal("%s", why.c_str());
  RehearsalResult r = rehearse(plan);
  return {plan, r};
}

constexpr const char* kDrive = "0.2 drive 0.6 15\n4 stop\n";

}  // namespace

class TestSequenceRelay : public QObject {
  Q_OBJECT

 private slots:
  // Telemetry the link refused cannot be judged: a sequence sent or running
  // is aborted on it, once; nothing relayed (the control), nothing to abort.
  // A new connection forgets the sequence (issue 59: Simulate from here was
  // "aborted by the guard" against the old robot's sequence).
  void guardOnUnjudgeableTelemetryAndANewRobot() {
    const WorldModel world = loadOrFail(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml");
    SequenceMsg msg;
    msg.hash = "0123456789abcdef";
    msg.commands = "0 drive 0.5 0;5 stop";
    SequenceGuard guard;
    QVERIFY(!guard.cannotJudge("telemetry: not finite: pose[0] = inf"));  // nothing relayed
    guard.relayed(msg, RehearsalResult{}, FlightRules{}, world.robots[0].model);
    const std::optional<GuardDeparture> d = guard.cannotJudge("telemetry: not finite: pose[0] = inf");
    QVERIFY(d);
    QCOMPARE(d->message(), std::string("telemetry the guard cannot judge: telemetry: not finite: pose[0] = inf"));
    QVERIFY(!guard.cannotJudge("again"));  // once
    guard.relayed(msg, RehearsalResult{}, FlightRules{}, world.robots[0].model);
    guard.reset();  // the connection is opened anew
    QCOMPARE(guard.status().phase(), SequenceRelay::Phase::Idle);
    QVERIFY(!guard.cannotJudge("telemetry: not finite"));
  }

  // Criterion: the robot runs the rehearsed sequence whole and reports done
  // under the hash the console computed; the guard, comparing every frame,
  // never trips (the robot's world is the rehearsal's), and the largest
  // departure stays under a tenth of its threshold; the robot's log holds
  // the sequence's commands with source "sequence", in order.
  void passedSequenceRunsWithItsHash() {
    QTemporaryDir dir;
    Rig rig;
    const std::string file = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    QVERIFY(rig.start(file, dir));
    const WorldModel world = loadOrFail(file);
    auto [plan, result] = rehearseFrom(world, rig.latest(), kDrive);
    QVERIFY2(result.passed, result.summary().c_str());
    std::string why;
    const std::optional<SequenceMsg> msg = sequenceMessage(plan, result, why);
    QVERIFY2(msg, why.c_str());
    SequenceRelay relay;
    relay.relayed(*msg, result, plan.rules, world.robots[0].model);
    rig.client->sendSequence(*msg);
    QVERIFY(rig.seen.stateSeen(SequenceStateKind::Accepted));
    QVERIFY(rig.seen.stateSeen(SequenceStateKind::Done, 30s));
    // Guard every frame until the rehearsal's end (its settling time after done).
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (std::chrono::steady_clock::now() < deadline) {
      {
        std::lock_guard lock(rig.seen.mutex);
        for (const SequenceStateMsg& s : rig.seen.states) relay.state(s);
      }
      for (const TelemetryMsg& t : rig.takeTelemetry()) {
        const auto d = relay.guard(t);
        QVERIFY2(!d, d ? d->message().c_str() : "");
      }
      if (relay.phase() == SequenceRelay::Phase::Done && rig.latest().time - 4 > result.duration) break;
      std::this_thread::sleep_for(20ms);
    }
    qInfo("guard compared %d frames: worst %.4f m, %.3f deg", relay.compared(), relay.worstPosition(),
          relay.worstHeading());
    QVERIFY(relay.compared() > 50);
    QVERIFY(relay.worstPosition() < 0.1 * plan.rules.guardPosition);
    {
      std::lock_guard lock(rig.seen.mutex);
      for (const SequenceStateMsg& s : rig.seen.states) QCOMPARE(s.hash, msg->hash);
    }
    rig.client->stop();
    rig.robot->stop();
    std::string error;
    auto log = SessionLogReader::open(rig.logPath, error);
    QVERIFY2(log, error.c_str());
    std::vector<std::string> applied;
    for (const LogCommand& c : log->commands())
      if (c.source == "sequence") applied.push_back(c.text);
    QCOMPARE(applied, (std::vector<std::string>{"drive 0.6 15", "stop"}));
    bool started = false, done = false;
    for (const LogEvent& e : log->events()) {
      started |= e.kind == "sequence" && e.text.starts_with("started " + msg->hash);
      done |= e.kind == "sequence" && e.text == "done " + msg->hash;
    }
    QVERIFY(started && done);
    // Issue 35: a session with a relayed sequence re-simulates too, every
    // hash (the sequence's commands are logged with their steps).
    const std::optional<ResimReport> resim = resimulate(rig.logPath, {}, error);
    QVERIFY2(resim, error.c_str());
    qInfo("re-simulated: %d hashes, %d commands, divergence %s", resim->hashesCompared, resim->commandsApplied,
          resim->divergence ? "yes" : "none");
    QVERIFY(!resim->divergence);
    QVERIFY(resim->hashesCompared >= 5);
    QVERIFY(resim->commandsApplied >= 2);
  }

  // Criterion: with the stand-in's rubber-on-ground friction at 0.02
  // (the console rehearsed on 1.0), the guard trips while the sequence
  // runs, within one telemetry frame of the departure crossing its
  // threshold (the departure it reports is under threshold + 5 cm), and
  // after the ABORT the robot reports the sequence aborted and stands
  // (base speed < 0.05 m/s within 2 s of robot time).
  void guardAbortsWhenTheRobotDeparts() {
    QTemporaryDir dir;
    const std::string flat = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    QFile in(QString::fromStdString(flat));
    QVERIFY(in.open(QIODevice::ReadOnly));
    QByteArray xml = in.readAll();
    xml.replace("<contact a=\"rubber\" b=\"ground\" mu=\"1.0\"/>", "<contact a=\"rubber\" b=\"ground\" mu=\"0.02\"/>");
    xml.replace("<contact default=\"true\" mu=\"0.8\"/>", "<contact default=\"true\" mu=\"0.02\"/>");
    xml.replace("../robots/workpartner.xml", (std::string(SP_SOURCE_DIR) + "/robots/workpartner.xml").c_str());
    const std::string slippery = sp::test::writeFile(dir, "slippery.world.xml", xml);
    Rig rig;
    QVERIFY(rig.start(slippery, dir));
    const WorldModel world = loadOrFail(flat);  // what the console believes
    auto [plan, result] = rehearseFrom(world, rig.latest(), "0.2 drive 1.0 20\n8 stop\n");
    QVERIFY2(result.passed, result.summary().c_str());
    std::string why;
    const std::optional<SequenceMsg> msg = sequenceMessage(plan, result, why);
    QVERIFY(msg);
    SequenceRelay relay;
    relay.relayed(*msg, result, plan.rules, world.robots[0].model);
    rig.client->sendSequence(*msg);
    std::optional<GuardDeparture> departure;
    double previous = 0;  // the departure one frame before the trip
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (!departure && std::chrono::steady_clock::now() < deadline) {
      {
        std::lock_guard lock(rig.seen.mutex);
        for (const SequenceStateMsg& s : rig.seen.states) relay.state(s);
      }
      for (const TelemetryMsg& t : rig.takeTelemetry()) {
        if (departure) break;
        previous = relay.worstPosition();
        departure = relay.guard(t);
      }
      std::this_thread::sleep_for(5ms);
    }
    QVERIFY2(departure, "the guard must trip on a robot that slips");
    qInfo("guard: %s (the frame before: %.3f m)", departure->message().c_str(), previous);
    rig.client->abortSequence(msg->hash, departure->message());
    QVERIFY(departure->what == "position" || departure->what == "heading");
    if (departure->what == "position") {
      QVERIFY(departure->value < plan.rules.guardPosition + 0.05);
      QVERIFY(previous <= plan.rules.guardPosition);
    }
    QVERIFY(departure->time < 8);  // while the sequence ran
    QVERIFY(rig.seen.stateSeen(SequenceStateKind::Aborted));
    const double abortedAt = rig.latest().time;
    QVERIFY(rig.seen.waitFor(
        [&] {
          const TelemetryMsg& t = *rig.seen.last;
          return t.time > abortedAt + 0.5 && t.baseVelocity.size() == 6 &&
                 std::hypot(t.baseVelocity[0], t.baseVelocity[1]) < 0.05;
        },
        10s));
    QVERIFY(rig.latest().time < abortedAt + 2.0 + 0.5);
    std::lock_guard lock(rig.seen.mutex);
    QVERIFY(rig.seen.states.back().reason.find("ABORT from 'relay test'") != std::string::npos);
  }

  // Criterion: a rehearsal from where the robot was, sent after it drove
  // 0.5 m away, is refused as stale and nothing moves; the control, the
  // same sequence rehearsed again from where the robot now stands, is accepted.
  void staleStartRefused() {
    QTemporaryDir dir;
    Rig rig;
    const std::string file = std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml";
    QVERIFY(rig.start(file, dir));
    const WorldModel world = loadOrFail(file);
    auto [plan, result] = rehearseFrom(world, rig.latest(), kDrive);
    std::string why;
    std::optional<SequenceMsg> msg = sequenceMessage(plan, result, why);
    QVERIFY(msg);
    rig.client->sendCommand(DriveCmd{0.5, 0});
    QVERIFY(rig.seen.waitFor([&] { return rig.seen.last->pose.p.x > 0.5; }, 20s));
    rig.client->sendCommand(StopCmd{});
    QVERIFY(rig.seen.waitFor(
        [&] {
          const TelemetryMsg& t = *rig.seen.last;
          return std::hypot(t.baseVelocity[0], t.baseVelocity[1]) < 0.01;
        },
        20s));
    rig.client->sendSequence(*msg);
    QVERIFY(rig.seen.stateSeen(SequenceStateKind::Refused));
    {
      std::lock_guard lock(rig.seen.mutex);
      qInfo("refused: %s", rig.seen.states.back().reason.c_str());
      const QRegularExpressionMatch m = QRegularExpression("^stale rehearsal: the robot is ([0-9.]+) m from its start")
                                            .match(QString::fromStdString(rig.seen.states.back().reason));
      QVERIFY(m.hasMatch());
      QVERIFY(m.captured(1).toDouble() > 0.5);
      rig.seen.states.clear();
    }
    auto [plan2, result2] = rehearseFrom(world, rig.latest(), kDrive);
    msg = sequenceMessage(plan2, result2, why);
    QVERIFY(msg);
    rig.client->sendSequence(*msg);
    QVERIFY(rig.seen.stateSeen(SequenceStateKind::Running));
  }

  // The robot checks what it receives: the hash against the commands, and
  // every command against its limits, naming the command.
  void robotChecksTheSequence() {
    QTemporaryDir dir;
    Rig rig;
    QVERIFY(rig.start(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", dir));
    SequenceMsg m;
    m.commands = "0 drive 0.5 0;2 stop";
    m.hash = "0123456789abcdef";
    m.start = rig.latest().pose;
    m.startPosition = 0.1;
    m.startHeading = 0.1;
    rig.client->sendSequence(m);
    QVERIFY(rig.seen.stateSeen(SequenceStateKind::Refused));
    {
      std::lock_guard lock(rig.seen.mutex);
      QVERIFY2(rig.seen.states.back().reason.find("is not the hash of the commands") != std::string::npos,
               rig.seen.states.back().reason.c_str());
      rig.seen.states.clear();
    }
    m.commands = "0 drive 0.5 0;1 target knee_fl 120;2 stop";
    m.hash = sequenceHash("0 drive 0.5 0\n1 target knee_fl 120\n2 stop\n");
    rig.client->sendSequence(m);
    QVERIFY(rig.seen.stateSeen(SequenceStateKind::Refused));
    std::lock_guard lock(rig.seen.mutex);
    QVERIFY2(rig.seen.states.back().reason.starts_with("command 2: "), rig.seen.states.back().reason.c_str());
  }
};

QTEST_GUILESS_MAIN(TestSequenceRelay)
#include "tst_sequence_relay.moc"
