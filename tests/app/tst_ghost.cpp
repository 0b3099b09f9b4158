// The predictive ghost (app/ghost/ghost.h) against a real stand-in over emulated
// slow links: the console session (stand-in on loopback with the delay each
// way, the ghost on its own threads) and a RobotClient driving as the
// console does. Each telemetry frame is compared with what the ghost had
// shown for that frame's robot time.
//
// Criterion, stated before the runs: while the robot moves (driving straight
// at 0.5 m/s, then turning left at 0.25 m/s, then right at 0.5 m/s), the
// median position error is <= 5 cm at
// 0.25 s and 1 s each way (0.5 s and 2 s round trips), on flat ground and on
// the test track. Control: the same run with a ghost that does not apply the
// commands still in flight must fail it at the 2 s round trip.

#include <QTest>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

#include "app/console/console_session.h"
#include "app/state/robot_shapes.h"
#include "app/log/session_log.h"
#include "net/robot_client.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "tests/app/shared_state.h"

using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

struct Seen : sp::test::SharedState {
  bool ready = false, lease = false;
  std::deque<TelemetryMsg> telemetry;  // not yet handed to the session

  RobotClientCallbacks callbacks() {
    RobotClientCallbacks cb;
    cb.connection = [this](ConnectionState s, const std::string&) { add([&] { ready = s == ConnectionState::Ready; }); };
    cb.lease = [this](const LeaseStateMsg& m) { add([&] { lease = m.yours; }); };
    cb.telemetry = [this](const TelemetryMsg& t) { add([&] { telemetry.push_back(t); }); };
    return cb;
  }
};

// What telemetry reports of the robot in `w`.
RobotFrame frameOf(const World& w) { return frameFromReadout(readRobot(w)); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

struct RunResult {
  std::vector<double> moving;  // position errors of frames while the robot moved [m]
  std::vector<double> heading;  // their heading errors [rad]
  int64_t anchors = 0;
  double seconds = 0;  // of the driving
  std::vector<GhostError> all;
  std::string logPath;
  GhostStats stats;
  size_t trail = 0;     // points of the last trail
  size_t maxTrail = 0;  // of the longest trail seen during the drive
  double stopAt = 0;    // [s] robot time the ghost took the stop to arrive at
};

}  // namespace

class TestGhost : public QObject {
  Q_OBJECT

  // Drives the stand-in (world, `delay` each way) for three phases of
  // `phase` seconds: straight, left, right; every frame goes
  // through the session (which anchors the ghost) on this thread.
  // `tail` [s]: how long it goes on after the stop has come back.
  RunResult drive(const std::string& world, double delay, bool inFlight, const QString& logDir = {}, double jitter = 0,
                  bool arm = false, double tail = 0.5) {
    RunResult result;
    ConsoleSessionOptions o;
    o.world = std::string(SP_SOURCE_DIR) + "/" + world;
    o.token = kToken;
    o.log = !logDir.isEmpty();
    o.logDir = logDir.toStdString();
    o.delay = delay;
    o.jitter = jitter;
    // The deadman must outlast the emulated link's jitter-free gaps; the
    // defaults of docs/protocol.md's table for a planetary link.
    o.overrides = {"link.deadman=0.5"};
    o.ghostOptions.inFlight = inFlight;
    ConsoleSession session(o);
    const std::string error = session.start();
    if (!error.empty()) {
      qWarning("%s", error.c_str());
      return result;
    }
    Seen seen;
    RobotClientConfig config;
    config.port = session.endpoint().port;
    config.token = kToken;
    config.name = "ghost test";
    RobotClient client(config, seen.callbacks());
    client.start();
    if (!seen.waitFor([&] { return seen.ready; }, 20s)) return result;
    client.acquireLease();
    if (!seen.waitFor([&] { return seen.lease; }, 20s)) return result;

    // Speed and steering change at every phase: a ghost that ignores the
    // commands in flight is a round trip late with each change.
    const std::vector<Command> phases = {DriveCmd{0.5, 0}, DriveCmd{0.25, degToRad(12)}, DriveCmd{0.5, degToRad(-12)},
                                         StopCmd{}};
    // With the left turn, an arm swung forward: the ghost must move what it
    // held rigid (ghost.hold) and carry the shifted load.
    const Command armForward = JointTargetCmd{"shoulder_pitch_l", degToRad(-60)};
    const double phase = 2.5;
    const auto start = std::chrono::steady_clock::now();
    const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
    // Hands what arrived to the session, as the console does all along.
    const auto takeTelemetry = [&](const std::function<void(const TelemetryMsg&)>& each) {
      std::deque<TelemetryMsg> batch;
      seen.waitFor([&] { return !seen.telemetry.empty(); }, 20ms);
      {
        std::lock_guard lock(seen.mutex);
        batch.swap(seen.telemetry);
      }
      for (const TelemetryMsg& t : batch) {
        session.telemetry(t, elapsed(), client.stats().rttMs / 1000);
        each(t);
      }
    };
    // The console has been reading telemetry before the operator drives.
    while (session.ghost()->viewVersion() == 0 && elapsed() < 10) takeTelemetry([](const TelemetryMsg&) {});
    size_t sent = 0;
    // Until the stop has come back in telemetry: a round trip after the last phase.
    const double t0 = elapsed(), end = t0 + phase * 3 + 2 * delay + tail;
    while (elapsed() < end) {
      if (sent < phases.size() && elapsed() - t0 >= phase * static_cast<double>(sent)) {
        client.sendCommand(phases[sent], 0, session.robot());
        if (std::holds_alternative<StopCmd>(phases[sent])) result.stopAt = session.ghost()->ghostTime(Ghost::now());
        session.commandSent(phases[sent]);
        if (arm && sent == 1) {
          client.sendCommand(armForward, 0, session.robot());
          session.commandSent(armForward);
        }
        ++sent;
      }
      takeTelemetry([&](const TelemetryMsg& t) {
        const std::optional<GhostError>& e = session.lastPrediction();
        if (!e) return;
        result.all.push_back(*e);
        const double speed = t.baseVelocity.size() == 6 ? std::hypot(t.baseVelocity[0], t.baseVelocity[1]) : 0;
        if (speed > 0.1) {
          result.moving.push_back(e->position);
          result.heading.push_back(e->heading);
        }
      });
      result.maxTrail = std::max(result.maxTrail, session.ghost()->view().trail.size());
    }
    result.seconds = elapsed() - t0;
    result.anchors = session.ghost()->stats().anchors;
    result.stats = session.ghost()->stats();
    result.trail = session.ghost()->view().trail.size();
    result.logPath = session.logPath();
    client.stop();
    return result;
  }

 private slots:
  void predictsOverDelay_data() {
    QTest::addColumn<QString>("world");
    QTest::addColumn<double>("delay");   // each way [s]
    QTest::addColumn<double>("jitter");  // +- on it [s], each way, per frame
    QTest::addColumn<bool>("arm");       // an arm moved with the left turn
    QTest::addColumn<bool>("inFlight");  // the ghost applies commands still in flight
    QTest::addColumn<bool>("pass");      // expected against the 5 cm criterion
    QTest::newRow("flat, 0.5 s round trip") << "terrains/flat.world.xml" << 0.25 << 0.0 << false << true << true;
    QTest::newRow("flat, 2 s round trip") << "terrains/flat.world.xml" << 1.0 << 0.0 << false << true << true;
    QTest::newRow("test track, 0.5 s round trip") << "terrains/test_track.world.xml" << 0.25 << 0.0 << false << true << true;
    QTest::newRow("test track, 2 s round trip") << "terrains/test_track.world.xml" << 1.0 << 0.0 << false << true << true;
    QTest::newRow("control: flat, 2 s, commands in flight ignored")
        << "terrains/flat.world.xml" << 1.0 << 0.0 << false << false << false;
    // Issue 35: the link's jitter (each frame its own delay: the planetary
    // link of docs/protocol.md) and a joint command as well as drives.
    QTest::newRow("flat, 2 s +- 0.1 s round trip, an arm moved")
        << "terrains/flat.world.xml" << 1.0 << 0.05 << true << true << true;
  }

  void predictsOverDelay() {
    QFETCH(QString, world);
    QFETCH(double, delay);
    QFETCH(double, jitter);
    QFETCH(bool, arm);
    QFETCH(bool, inFlight);
    QFETCH(bool, pass);
    const RunResult r = drive(world.toStdString(), delay, inFlight, {}, jitter, arm);
    // Enough frames while moving to take a median of: 7.5 s at 50 Hz.
    QVERIFY2(r.moving.size() > 200, qPrintable(QString::number(r.moving.size())));
    const double m = median(r.moving);
    const double rate = static_cast<double>(r.anchors) / r.seconds;
    qInfo("median position error %.1f mm, heading %.2f deg over %zu frames while moving; max %.1f mm; "
          "%.1f re-anchorings/s",
          m * 1000, radToDeg(median(r.heading)), r.moving.size(),
          *std::max_element(r.moving.begin(), r.moving.end()) * 1000, rate);
    qInfo("%lld trails, the last %.0f ms for %zu points (longest %zu); last re-anchoring %.0f ms over %.2f s",
          static_cast<long long>(r.stats.trails), r.stats.trailMs, r.trail, r.maxTrail, r.stats.anchorMs,
          r.stats.anchorSpan);
    QCOMPARE(m <= 0.05, pass);
    // The trail (the path ahead) keeps coming: 5 s ahead in 0.1 s steps,
    // 51 points, the last one too. A trail whose world diverges ends there
    // (Ghost: "up to where it diverged"): once in CI the last one on the
    // test track ended after 26 points, and the bound was loosened to 2.
    // The cause was the twin's, not the test's: ODE's cylinder-heightfield
    // contact threw a wheel into the ground at the track's creases (a 1 cm
    // step diverged the twin); tyres now meet heightfields as spheres
    // (sim/world_contacts.cpp), and the bound is whole again (6 of 6 runs
    // of both track rows gave 51 when it was restored).
    QVERIFY(r.stats.trails > 10);
    QCOMPARE(r.maxTrail, size_t{51});
    QCOMPARE(r.trail, size_t{51});
    // Re-anchoring kept going (a stall would show as a handful).
    QVERIFY2(rate > 5, qPrintable(QString::number(rate)));
  }

  // The ghost holds the upper body rigid (ghost.hold) but draws it as the
  // newest telemetry reports it: an arm bent on the robot is bent on the
  // ghost, every joint of the full robot is in the view.
  void heldLinksDrawnAsReported() {
    Diagnostics diag;
    const auto world = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    QVERIFY2(world, diag.format().c_str());
    auto robot = World::create(*world, SimParams{}, diag);
    QVERIFY(robot);
    std::string error;
    auto ghost = Ghost::create(*world, SimParams{}, error);
    QVERIFY2(ghost, error.c_str());
    // Welded at the first frame's pose: the arm straight.
    QVERIFY(!ghost->anchor(frameOf(*robot), 0.1));  // nothing shown yet to compare with
    QTRY_VERIFY_WITH_TIMEOUT(ghost->viewVersion() > 0, 5000);
    const size_t elbow = static_cast<size_t>(world->robots[0].model.findJoint("elbow_l"));
    QCOMPARE(ghost->view().jointPositions[elbow], 0.0);
    // The robot bends its elbow; the ghost's drawn elbow follows telemetry.
    QCOMPARE(robot->submit(JointTargetCmd{"elbow_l", degToRad(40)}), std::string());
    for (int i = 0; i < 2000; ++i) QVERIFY(robot->step());
    const RobotFrame bent = frameOf(*robot);
    QVERIFY(std::abs(bent.jointPositions[elbow]) > degToRad(5));
    ghost->anchor(bent, 0.1);
    QTRY_VERIFY_WITH_TIMEOUT(ghost->view().time > bent.time, 5000);
    const GhostView v = ghost->view();
    QCOMPARE(v.problem, std::string());
    QCOMPARE(v.jointPositions.size(), bent.jointPositions.size());
    QCOMPARE(v.jointPositions[elbow], bent.jointPositions[elbow]);
  }

  // A prediction that runs past the map's edge (beyond it the physics has
  // no ground: the twin falls) says so in words about the map, not the
  // solver's "in the ground by 0.26 m" (bench_region once drove a robot
  // there). The robot stands 2 m inside the bumpy field's edge, driving
  // towards it with the ghost 2 s ahead; control: driving away from it.
  void predictionOffTheMapSaysSo_data() {
    QTest::addColumn<double>("speed");
    QTest::addColumn<bool>("said");
    QTest::newRow("towards the edge") << 0.6 << true;
    QTest::newRow("control: away from it") << -0.6 << false;
  }
  void predictionOffTheMapSaysSo() {
    QFETCH(double, speed);
    QFETCH(bool, said);
    Diagnostics diag;
    auto world = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/bumpy.world.xml", diag);
    QVERIFY2(world, diag.format().c_str());
    world->robots[0].pose.p = {7.0, 0, 0.2};  // the front axle 2 m from x = 10 m; let down onto the ground below
    auto robot = World::create(*world, SimParams{}, diag);
    QVERIFY2(robot, diag.format().c_str());
    for (int i = 0; i < 1500; ++i) QVERIFY(robot->step());
    std::string error;
    auto ghost = Ghost::create(*world, SimParams{}, error);
    QVERIFY2(ghost, error.c_str());
    const double roundTrip = 4;  // the ghost shows 2 s ahead
    ghost->anchor(frameOf(*robot), roundTrip);
    QTRY_VERIFY_WITH_TIMEOUT(ghost->viewVersion() > 0, 5000);
    const Command drive = DriveCmd{speed, 0};
    QCOMPARE(robot->submit(drive), std::string());
    ghost->commandSent(drive);
    std::string problem;
    const auto start = std::chrono::steady_clock::now();
    // Up to 3 s of the robot's driving, in real time: it stays on the map
    // (its front axle, 1 m ahead of the base, short of x = 9.5 m).
    while (robot->time() < 4.5 && problem.find("leaves the map") == std::string::npos) {
      for (int i = 0; i < 20; ++i) QVERIFY(robot->step());
      ghost->anchor(frameOf(*robot), roundTrip);
      std::this_thread::sleep_until(start + std::chrono::duration<double>(robot->time() - 1.5));
      problem = ghost->view().problem;
    }
    const double x = readRobot(*robot).base.p.x;
    qInfo("robot at x = %.2f m at %.2f s; the ghost's problem: '%s'", x, robot->time(), problem.c_str());
    QVERIFY(x + 1 < 9.5);
    QCOMPARE(problem.find("the ghost's prediction leaves the map at (") == 0, said);
    if (!said) QCOMPARE(problem, std::string());
  }

  // The legs are held (ghost.hold) only while the robot keeps them still:
  // a crouch sent switches the ghost to the full robot, which bends its
  // knees a round trip before the robot does (a held ghost draws the knees
  // as reported: they would stay straight); once the robot has held the
  // crouch still for 1 s the ghost holds again, welded crouched, and drives
  // on from there.
  void crouchSwitchesToTheFullRobot() {
    Diagnostics diag;
    const auto world = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    QVERIFY2(world, diag.format().c_str());
    const RobotModel& model = world->robots[0].model;
    auto robot = World::create(*world, SimParams{}, diag);
    QVERIFY(robot);
    std::string error;
    auto ghost = Ghost::create(*world, SimParams{}, error);
    QVERIFY2(ghost, error.c_str());
    const double roundTrip = 0.4;
    const size_t knee = static_cast<size_t>(model.findJoint("knee_fl"));
    const double start = Ghost::now();
    std::deque<std::pair<double, Command>> inFlight;  // (robot time it arrives, command)
    std::vector<double> errors;
    // Runs the robot in real time to robot time `until`, a frame every 20 ms.
    const auto runTo = [&](double until, const std::function<void()>& each) {
      while (robot->time() < until - 1e-9) {
        for (int i = 0; i < 20; ++i) {
          while (!inFlight.empty() && inFlight.front().first <= robot->time() + 1e-9) {
            QCOMPARE(robot->submit(inFlight.front().second), std::string());
            inFlight.pop_front();
          }
          QVERIFY(robot->step());
        }
        const RobotFrame f = frameOf(*robot);
        // The frame arrives half a round trip after the robot sent it.
        std::this_thread::sleep_until(std::chrono::steady_clock::time_point(
            std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                std::chrono::duration<double>(start + f.time + roundTrip / 2))));
        if (const auto e = ghost->anchor(f, roundTrip); e && std::hypot(f.baseLinearVelocity.x, f.baseLinearVelocity.y) > 0.1)
          errors.push_back(e->position);
        if (each) each();
      }
    };
    const auto send = [&](const Command& c) {
      ghost->commandSent(c);
      inFlight.emplace_back(ghost->ghostTime(Ghost::now()), c);
    };
    runTo(1.5, {});
    QTRY_VERIFY_WITH_TIMEOUT(ghost->stats().anchors > 5, 5000);
    QVERIFY(ghost->stats().held);
    const int64_t twins = ghost->stats().twins;
    QCOMPARE(twins, int64_t{1});

    for (const char* leg : {"fl", "fr"}) {
      send(JointTargetCmd{std::string("hip_") + leg, degToRad(18.6)});
      send(JointTargetCmd{std::string("knee_") + leg, degToRad(-37.2)});
    }
    for (const char* leg : {"rl", "rr"}) {
      send(JointTargetCmd{std::string("hip_") + leg, degToRad(-18.6)});
      send(JointTargetCmd{std::string("knee_") + leg, degToRad(37.2)});
    }
    // Before the crouch reaches the robot, the ghost bends its knee.
    double lead = 0;
    const double arrives = inFlight.front().first;
    runTo(arrives - 0.05, [&] {
      const GhostView v = ghost->view();
      if (v.jointPositions.size() > knee)
        lead = std::max(lead, std::abs(v.jointPositions[knee] - readRobot(*robot).jointPositions[knee]));
    });
    qInfo("before the crouch arrived: the ghost's knee led the robot's by %.1f deg; %lld twins built",
          radToDeg(lead), static_cast<long long>(ghost->stats().twins));
    QVERIFY(!ghost->stats().held);
    QVERIFY(lead > degToRad(10));
    // The crouch done (about 2 s) and held still for 1 s: held again, crouched.
    runTo(arrives + 4.5, {});
    QTRY_VERIFY_WITH_TIMEOUT(ghost->stats().held, 2000);
    QVERIFY(ghost->stats().twins >= twins + 2);
    QVERIFY(std::abs(readRobot(*robot).jointPositions[knee] - degToRad(-37.2)) < degToRad(2));
    // Driving on crouched: the held ghost predicts it.
    send(DriveCmd{0.5, degToRad(10)});
    runTo(robot->time() + 3, {});
    QVERIFY2(errors.size() > 50, qPrintable(QString::number(errors.size())));
    qInfo("driving crouched: median position error %.1f mm over %zu frames; held %d", median(errors) * 1000,
          errors.size(), ghost->stats().held);
    QVERIFY(median(errors) < 0.05);
    QVERIFY(ghost->stats().held);
    QCOMPARE(ghost->view().problem, std::string());
  }

  void badHoldRefused_data() {
    QTest::addColumn<QString>("hold");
    QTest::addColumn<QString>("error");
    QTest::newRow("unknown joint") << "waist_yaw,nope" << "ghost.hold: the robot has no joint 'nope'";
    QTest::newRow("a wheel") << "wheel_fl" << "ghost.hold: joint 'wheel_fl' drives the robot and cannot be held";
    QTest::newRow("the articulation") << "hip_fl,articulation"
                                      << "ghost.hold: joint 'articulation' drives the robot and cannot be held";
  }

  void badHoldRefused() {
    QFETCH(QString, hold);
    QFETCH(QString, error);
    Diagnostics diag;
    const auto world = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    QVERIFY2(world, diag.format().c_str());
    SimParams params;
    params.ghostHold = hold.toStdString();
    std::string why;
    QVERIFY(!Ghost::create(*world, params, why));
    QCOMPARE(QString::fromStdString(why), error);
    params.ghostHold = "none";
    QVERIFY(Ghost::create(*world, params, why));
  }

  // Issue 61: the regions' levels must ascend (inner, outer, departure);
  // each key alone is checked for (0, 1) where it is read (tst_params).
  void regionLevelsMustAscend() {
    Diagnostics diag;
    const auto world = loadWorld(std::string(SP_SOURCE_DIR) + "/terrains/flat.world.xml", diag);
    QVERIFY2(world, diag.format().c_str());
    SimParams params;
    params.ghostRegionInner = 0.95;
    std::string why;
    QVERIFY(!Ghost::create(*world, params, why));
    QCOMPARE(QString::fromStdString(why),
             QString("ghost.region.inner (0.95), ghost.region.outer (0.9) and ghost.region.departure (0.99) must ascend"));
    params.ghostRegionInner = 0.5;
    QVERIFY2(Ghost::create(*world, params, why), why.c_str());
  }

  // Issue 59: "the ghost error spikes to ~25 cm at every stop with no delay
  // at all". Criterion, stated before the runs: from the stop's arrival on,
  // for 2 s, every frame is within 2 cm of what the ghost showed for its
  // time. Control: a ghost that ignores the commands in flight over a 1 s
  // each-way link drives on past the stop for a round trip and fails it.
  void stopIsPredicted_data() {
    QTest::addColumn<double>("delay");   // each way [s]
    QTest::addColumn<bool>("inFlight");  // the ghost applies commands still in flight
    QTest::addColumn<bool>("pass");
    QTest::newRow("no delay") << 0.0 << true << true;
    QTest::newRow("0.25 s each way") << 0.25 << true << true;
    QTest::newRow("control: 1 s each way, commands in flight ignored") << 1.0 << false << false;
  }

  void stopIsPredicted() {
    QFETCH(double, delay);
    QFETCH(bool, inFlight);
    QFETCH(bool, pass);
    const RunResult r = drive("terrains/flat.world.xml", delay, inFlight, {}, 0, false, 2.0);
    QVERIFY(r.stopAt > 0);
    double worst = 0;
    int frames = 0;
    for (const GhostError& e : r.all)
      if (e.time >= r.stopAt && e.time <= r.stopAt + 2) {
        worst = std::max(worst, e.position);
        ++frames;
      }
    qInfo("over the 2 s from the stop's arrival (robot time %.2f s): %d frames, the largest error %.1f mm", r.stopAt,
          frames, worst * 1000);
    // With no delay the ghost shows the robot's present, rarely a frame's
    // future: about one frame in four has a shown state after it to be
    // compared with (PredictionRecord::compare interpolates, it does not
    // extrapolate).
    QVERIFY2(frames >= (delay > 0 ? 80 : 10), qPrintable(QString::number(frames)));
    QCOMPARE(worst <= 0.02, pass);
  }

  // The predictions go into the session's log, as the session saw them.
  void predictionsAreLogged() {
    QTemporaryDir dir;
    QVERIFY(dir.isValid());
    const RunResult r = drive("terrains/flat.world.xml", 0.25, true, dir.path());
    QVERIFY(!r.all.empty());
    QVERIFY(!r.logPath.empty());
    std::string error;
    auto reader = SessionLogReader::open(r.logPath, error);
    QVERIFY2(reader, error.c_str());
    const std::vector<LogPrediction> logged = reader->predictionsBetween(0, 1e9);
    QCOMPARE(logged.size(), r.all.size());
    std::vector<double> lookahead;
    for (const LogPrediction& p : logged) lookahead.push_back(p.time - p.made);
    // It looked ahead over the round trip (0.5 s) and the telemetry's age.
    QVERIFY2(median(lookahead) >= 0.5, qPrintable(QString::number(median(lookahead))));
    for (size_t i = 0; i < logged.size(); i += 50) {
      QCOMPARE(logged[i].time, r.all[i].time);
      QCOMPARE(logged[i].made, r.all[i].made);
      QCOMPARE(logged[i].base[0], r.all[i].predicted.p.x);
      QCOMPARE(logged[i].positionError, r.all[i].position);
      QCOMPARE(logged[i].headingError, r.all[i].heading);
    }
  }
};

QTEST_GUILESS_MAIN(TestGhost)
#include "tst_ghost.moc"
