// Same files + same snapshot + same commands => the same state, bit for bit:
// twice in one process, after a restore into the same or a fresh world, in
// two threads at once, and in two processes.

#include <QProcess>
#include <QTest>

#include <cstring>
#include <thread>

#include "tests/default_step.h"
#include "sim/command_file.h"
#include "sim/model_loader.h"
#include "sim/world.h"

using namespace sp;

namespace {

// WorkPartner driving and turning its torso on the bumpy field: contacts on
// a heightfield, all actuator modes, the laser with noise.
const char* kWorld = "terrains/bumpy.world.xml";

WorldModel loadModel() {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(std::string(SP_SOURCE_DIR) + "/" + kWorld, diag);
  if (!model) qFatal("%s", diag.format().c_str());
  return *model;
}

std::unique_ptr<World> build(const WorldModel& model, SimParams params = {}) {
  Diagnostics diag;
  auto world = World::create(model, params, diag);
  if (!world) qFatal("%s", diag.format().c_str());
  return world;
}

/// The command stream: what to submit before step `step`.
void feed(World& world, int64_t step) {
  switch (step) {
    case 200: world.submit(DriveCmd{0.8, degToRad(15)}); break;
    case 700: world.submit(JointTargetCmd{"waist_yaw", degToRad(60)}); break;
    case 1100: world.submit(DriveCmd{0.5, degToRad(-10)}); break;
    case 1500: world.submit(StopCmd{}); break;
    default: break;
  }
}

/// Steps from the world's current step to `until`, recording the hash after
/// every step.
std::vector<uint64_t> run(World& world, int64_t until) {
  std::vector<uint64_t> hashes;
  while (world.stepCount() < until) {
    feed(world, world.stepCount());
    world.step();
    hashes.push_back(world.stateHash());
  }
  return hashes;
}

}  // namespace

class TestDeterminism : public QObject {
  Q_OBJECT

 private slots:
  // ODE's random numbers come from the world's own state (our dRand is live).
  void odeRandomIsPerThread() { QVERIFY(sp::odeRandomIsPerThread()); }

  // Two worlds built from the same model step to identical states.
  void twiceInOneProcess() {
    const WorldModel model = loadModel();
    auto a = build(model), b = build(model);
    const auto ha = run(*a, 2000), hb = run(*b, 2000);
    QCOMPARE(ha, hb);
    QVERIFY(a->health().healthy());
    QVERIFY(a->linkPose(0, 0).p.x > 0.3);  // it did drive
  }

  // The seed matters: another random.seed gives another run (so the world's
  // seed, not a global one, drives the quick stepper and the noise).
  void seedChangesTheRun() {
    const WorldModel model = loadModel();
    SimParams other;
    other.seed = 2;
    auto a = build(model), b = build(model, other);
    QVERIFY(run(*a, 1000).back() != run(*b, 1000).back());
  }

  // The broad phase chosen by the number of geoms does not change the run:
  // with 200 boxes far away (out of every reach) the world's pairs are
  // found by the hash space instead of the simple one, and it steps to the
  // same hashes, step for step.
  void broadPhaseDoesNotChangeTheRun() {
    const WorldModel model = loadModel();
    WorldModel crowded = model;
    for (int i = 0; i < 200; ++i) {
      ObjectSpec rock;
      rock.name = "far_rock_" + std::to_string(i);
      rock.pose.p = {1000.0 + 2 * (i % 20), 2.0 * (i / 20), 5};
      GeomSpec box;
      box.size = {0.5, 0.5, 0.5};
      rock.geoms.push_back(box);
      crowded.objects.push_back(rock);
    }
    auto a = build(model), b = build(crowded);
    QCOMPARE(a->broadPhase(), "simple");
    QCOMPARE(b->broadPhase(), "hash");
    QCOMPARE(run(*a, 1500), run(*b, 1500));
    QVERIFY(a->linkPose(0, 0).p.x > 0.3);  // it did drive
  }

  // A snapshot restored into the same world replays the same future.
  void restoreIntoSameWorld() {
    const WorldModel model = loadModel();
    auto w = build(model);
    run(*w, 900);
    const Snapshot s = w->snapshot();
    const auto first = run(*w, 2000);
    QCOMPARE(w->restore(s), std::string());
    QCOMPARE(w->stepCount(), int64_t{900});
    QCOMPARE(run(*w, 2000), first);
  }

  // A snapshot restored into a fresh world built from the same files
  // continues exactly as the original.
  void restoreIntoFreshWorld() {
    const WorldModel model = loadModel();
    auto original = build(model);
    run(*original, 1200);
    const Snapshot s = original->snapshot();
    auto fresh = build(loadModel());
    QCOMPARE(fresh->restore(s), std::string());
    QCOMPARE(fresh->stateHash(), original->stateHash());
    QCOMPARE(run(*fresh, 2000), run(*original, 2000));
    // The sensors too: the same latest laser scan, noise included.
    const int laser = fresh->robotModel(0).findSensor("laser");
    const auto& a = std::get<LaserReading>(fresh->sensorSample(0, laser).value);
    const auto& b = std::get<LaserReading>(original->sensorSample(0, laser).value);
    QCOMPARE(a.ranges.size(), b.ranges.size());
    QVERIFY(std::memcmp(a.ranges.data(), b.ranges.data(), a.ranges.size() * sizeof(double)) == 0);
  }

  // Two worlds stepping at the same time in two threads reproduce a
  // sequential run exactly.
  void twoThreadsAtOnce() {
    const WorldModel model = loadModel();
    auto reference = build(model);
    const auto expected = run(*reference, 2000);
    std::vector<uint64_t> ha, hb;
    std::thread ta([&] {
      auto w = build(model);
      ha = run(*w, 2000);
    });
    std::thread tb([&] {
      auto w = build(model);
      hb = run(*w, 2000);
    });
    ta.join();
    tb.join();
    QCOMPARE(ha, expected);
    QCOMPARE(hb, expected);
  }

  // The ghost: a world forked from the twin's snapshot runs ahead in another
  // thread while the twin keeps stepping, and predicts the twin's state
  // exactly (same commands, same step).
  void forkedGhostPredictsExactly() {
    const WorldModel model = loadModel();
    auto twin = build(model);
    run(*twin, 600);
    const Snapshot fork = twin->snapshot();
    uint64_t predicted = 0;
    std::thread ghostThread([&] {
      auto ghost = build(model);
      if (ghost->restore(fork).empty()) predicted = run(*ghost, 1800).back();
    });
    const uint64_t actual = run(*twin, 1800).back();
    ghostThread.join();
    QCOMPARE(predicted, actual);
  }

  // Two processes running the same files and commands print the same final
  // state hash, and it is the one this process computes.
  void acrossProcesses() {
    const QString exe = QStringLiteral(SP_BINARY_DIR "/app/simpartner-sim");
    const QStringList args = {"run", "--world", kWorld, "--commands", "terrains/demo.seq", "--duration", "3",
                              "--rtf", "max", "--quiet"};
    QStringList hashes;
    for (int i = 0; i < 2; ++i) {
      QProcess p;
      p.start(exe, args);
      QVERIFY(p.waitForFinished(120000));
      QCOMPARE(p.exitCode(), 0);
      const QString out = QString::fromUtf8(p.readAllStandardOutput());
      const qsizetype at = out.indexOf("state hash ");
      QVERIFY2(at >= 0, qPrintable(out));
      hashes << out.mid(at + 11, 16);
    }
    QCOMPARE(hashes[0], hashes[1]);

    // The same run in this process.
    const WorldModel model = loadModel();
    auto w = build(model);
    Diagnostics diag;
    const RobotModel& robot = model.robots[0].model;
    auto seq = loadCommandSequence(std::string(SP_SOURCE_DIR) + "/terrains/demo.seq", diag, &robot);
    QVERIFY(seq);
    size_t next = 0;
    while (w->stepCount() < sp::test::stepAt(3.0)) {
      while (next < seq->size() && (*seq)[next].time <= w->time() + 1e-9) w->submit((*seq)[next++].command);
      w->step();
    }
    QCOMPARE(hashes[0], QString("%1").arg(w->stateHash(), 16, 16, QChar('0')));
  }
};

QTEST_GUILESS_MAIN(TestDeterminism)
#include "tst_determinism.moc"
