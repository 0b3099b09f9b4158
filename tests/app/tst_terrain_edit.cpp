// Terrain editing (issue 16) beyond the brushes' formulas: undo restores the
// heights bit for bit; patches split to fit link frames; the stand-in takes
// edits over a real loopback link (a simulator's capability, announced in
// WELCOME), the robot on edited ground rises, and the session's log
// re-simulates hash for hash. Control: a stand-in behaving as a real robot
// refuses the edit and its robot stays where it was.

#include <QTemporaryDir>
#include <QTest>

#include <chrono>
#include <cmath>
#include <deque>
#include <random>

#include "app/log/log_player.h"
#include "app/log/resimulation.h"
#include "app/robot/stand_in.h"
#include "app/console/terrain_editor.h"
#include "app/console/terrain_limits.h"
#include "net/frame.h"
#include "net/robot_client.h"
#include "sim/command.h"
#include "sim/model_loader.h"
#include "sim/world.h"
#include "tests/app/shared_state.h"

using namespace sp;
using namespace sp::net;
using namespace std::chrono_literals;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";
const std::string kTrack = std::string(SP_SOURCE_DIR) + "/terrains/test_track.world.xml";

WorldModel track() {
  Diagnostics diag;
  std::optional<WorldModel> w = loadWorld(kTrack, diag);
  if (!w) qFatal("%s", diag.format().c_str());
  return *w;
}

struct Seen : sp::test::SharedState {
  bool ready = false, lease = false;
  std::optional<TelemetryMsg> last;
  std::vector<ReplyMsg> replies;
  RobotClientCallbacks callbacks() {
    RobotClientCallbacks cb;
    cb.connection = [this](ConnectionState s, const std::string&) { add([&] { ready = s == ConnectionState::Ready; }); };
    cb.lease = [this](const LeaseStateMsg& m) { add([&] { lease = m.yours; }); };
    cb.telemetry = [this](const TelemetryMsg& t) { add([&] { last = t; }); };
    cb.reply = [this](const ReplyMsg& r) { add([&] { replies.push_back(r); }); };
    return cb;
  }
  double z() { return latest().pose.p.z; }
  /// The newest frame, copied under the lock (the client's thread writes it).
  TelemetryMsg latest() {
    std::lock_guard lock(mutex);
    return *last;
  }
};

// A stand-in on the test track (terrain edits on or off) with a client
// holding the lease; the robot settled on the ground.
struct Rig {
  std::unique_ptr<StandInRobot> robot;
  Seen seen;
  std::unique_ptr<RobotClient> client;
  bool start(bool terrainEdits, const QTemporaryDir& dir) {
    StandInOptions o;
    o.worldFile = kTrack;
    o.port = 0;
    o.token = kToken;
    o.realTimeFactor = 2;
    o.terrainEdits = terrainEdits;
    o.logDir = dir.filePath("logs").toStdString();
    Diagnostics diag;
    robot = StandInRobot::create(o, diag);
    if (!robot || !robot->start().empty()) return false;
    RobotClientConfig config;
    config.port = robot->port();
    config.token = kToken;
    config.name = "terrain test";
    client = std::make_unique<RobotClient>(config, seen.callbacks());
    client->start();
    if (!seen.waitFor([&] { return seen.ready; }, 20s)) return false;
    client->acquireLease();
    if (!seen.waitFor([&] { return seen.lease && seen.last.has_value(); }, 20s)) return false;
    return seen.waitFor([&] { return seen.last->time > 1.5; }, 20s);  // settled
  }
};

}  // namespace

class TestTerrainEdit : public QObject {
  Q_OBJECT

 private slots:
  // 30 strokes of every brush (fixed seed), undone: the heights are the
  // original ones bit for bit, in the editor and in a World that applied
  // the same patches; redone: the edited ones again.
  void undoRestoresBitForBit() {
    const WorldModel model = track();
    const HeightGrid original = model.terrain.grid;
    HeightGrid heights = original;  // the editor edits these in place
    TerrainEditor editor(heights);
    Diagnostics diag;
    std::unique_ptr<World> world = World::create(model, {}, diag);
    QVERIFY2(world, diag.format().c_str());
    std::mt19937 rng(16);
    std::uniform_real_distribution<double> x(-original.width / 2, original.width / 2), y(-original.depth / 2, original.depth / 2);
    for (int s = 0; s < 30; ++s) {
      const Brush brush{static_cast<BrushKind>(s % 5), 0.3 + 0.05 * (s % 7), s % 5 >= 2 && s % 5 <= 3 ? 0.5 : 0.02, 0.2,
                        static_cast<uint32_t>(s)};
      const Vec2 from{x(rng), y(rng)};
      for (int d = 0; d < 6; ++d)
        if (auto p = editor.dab({from.x + 0.1 * d, from.y}, brush)) world->submit(*p);
      editor.endStroke();
    }
    world->step();
    const HeightGrid edited = editor.grid();
    QCOMPARE(world->terrainGrid()->heights, edited.heights);
    QCOMPARE(heights.heights, edited.heights);  // in place: the grid it was given is the one edited
    QVERIFY(edited.heights != original.heights);
    QCOMPARE(editor.undoLevels(), size_t{30});
    while (auto p = editor.undo()) world->submit(*p);
    world->step();
    QCOMPARE(editor.grid().heights, original.heights);
    QCOMPARE(world->terrainGrid()->heights, original.heights);
    QCOMPARE(editor.redoLevels(), size_t{30});
    while (auto p = editor.redo()) world->submit(*p);
    world->step();
    QCOMPARE(editor.grid().heights, edited.heights);
    QCOMPARE(world->terrainGrid()->heights, edited.heights);
    // A new stroke drops the redo levels; old levels beyond the limit go.
    HeightGrid smallHeights = original;
    TerrainEditor small(smallHeights, 3);
    for (int s = 0; s < 5; ++s) {
      small.dab({0.5 * s, 0}, Brush{BrushKind::Raise, 0.4, 0.01, 0, 1});
      small.endStroke();
    }
    QCOMPARE(small.undoLevels(), size_t{3});
  }

  // Issue 31: what WorkPartner can drive over, from its files, and the
  // stroke check built on it. The limits follow the formulas of
  // app/console/terrain_limits.h: on flat.world (mu 1.0) the motors bind
  // the slope (4 x 60 N m at 0.2 m for about 230 kg: about 32 deg, below
  // grip's 45), on ice (mu 0.025) grip does (1.4 deg).
  void drivableLimitsFromTheFiles() {
    Diagnostics diag;
    const auto flat = loadWorld(SP_SOURCE_DIR "/terrains/flat.world.xml", diag);
    const auto ice = loadWorld(SP_SOURCE_DIR "/terrains/ice.world.xml", diag);
    QVERIFY2(flat && ice, diag.format().c_str());
    const auto onFlat = drivableLimits(*flat), onIce = drivableLimits(*ice);
    QVERIFY(onFlat && onIce);
    qInfo("flat: slope %.1f deg, step %.3f m (%s); ice: slope %.2f deg, step %.4f m", radToDeg(onFlat->maxSlope),
          onFlat->maxStep, onFlat->basis.c_str(), radToDeg(onIce->maxSlope), onIce->maxStep);
    QCOMPARE(onFlat->mu, 1.0);
    QVERIFY(onFlat->motorBound);
    QVERIFY(std::abs(radToDeg(onFlat->maxSlope) - 32) < 1.5);
    QVERIFY(std::abs(onFlat->maxStep - 0.2 * (1 - std::cos(onFlat->maxSlope))) < 1e-12);
    QVERIFY(!onIce->motorBound);
    QVERIFY(std::abs(onIce->maxSlope - std::atan(0.025)) < 1e-12);
    WorldModel none = *flat;
    none.robots[0].model.drive.reset();
    QVERIFY(!drivableLimits(none));
  }

  // The stroke check warns of a sharp ridge and not of what the robot
  // drives: on level ground (0.1 m samples, flat.world's grip) a 0.3 m
  // raise of 0.15 m is flagged (higher than a wheel rolls up, steeper than
  // the robot climbs), a 2 m one of 0.15 m is not (a gentle hill), nor is a
  // 0.3 m one of 0.02 m (a bump a wheel takes). A stroke beside a steep
  // rise already there, not making it worse, is not flagged either. The
  // grid is not touched.
  void strokeRiskSeesRidgesNotHills() {
    Diagnostics diag;
    const auto flat = loadWorld(SP_SOURCE_DIR "/terrains/flat.world.xml", diag);
    QVERIFY(flat);
    const auto limits = drivableLimits(*flat);
    QVERIFY(limits);
    HeightGrid grid{101, 101, 10.0, 10.0, std::vector<double>(101 * 101, 0.0)};
    const auto risk = [&](Vec2 at, double radius, double height) {
      const auto patch = brushDab(grid, at, Brush{BrushKind::Raise, radius, height, 0, 1});
      return patch ? strokeRisk(grid, *patch, *limits, 0.2) : std::nullopt;
    };
    const auto ridge = risk({2, 0}, 0.3, 0.15);
    QVERIFY(ridge);
    qInfo("ridge: %s", ridge->message(*limits).c_str());
    QVERIFY(ridge->rise > limits->maxStep && ridge->grade() > limits->maxSlope);
    QVERIFY(std::abs(ridge->at.x - 2) < 0.5);
    QVERIFY(!risk({2, 0}, 2.0, 0.15));
    QVERIFY(!risk({2, 0}, 0.3, 0.02));
    // A 0.2 m wall along x = -3 (the terrain's own), a gentle stroke 1 m off.
    for (int j = 0; j < 101; ++j)
      for (int i = 0; i < 101; ++i) grid.at(i, j) = i >= 20 ? 0.0 : 0.2;
    QVERIFY(!risk({-2.0, 0}, 0.5, 0.005));
    QVERIFY(risk({-3.2, 0}, 0.3, 0.15));  // control: a ridge on top of it is the stroke's
    QCOMPARE(grid.at(50, 50), 0.0);
  }

  // Verification of the warning against the twin: what the check lets
  // pass, WorkPartner drives over. Criterion (before the run): on a flat
  // heightfield (0.05 m samples) a step as high as 0.9 x the step limit
  // across its path, driven at 0.3 m/s for 8 s, ends with both front
  // wheels beyond it and the twin healthy; the control, a step of 0.18 m
  // (flagged), is not crossed. Before tyres met heightfields as spheres
  // (world_contacts.cpp) a step of 1 cm threw a wheel 9 cm into the ground.
  void whatPassesTheCheckIsDriven() {
    const WorldModel flat = [] {
      Diagnostics diag;
      return *loadWorld(SP_SOURCE_DIR "/terrains/flat.world.xml", diag);
    }();
    const auto limits = drivableLimits(flat);
    QVERIFY(limits);
    const auto crosses = [&](double step) {
      WorldModel w = flat;
      HeightGrid g{201, 41, 10.0, 2.0, {}};
      g.heights.assign(201 * 41, 0.0);
      const HeightGrid level = g;
      for (int j = 0; j < 41; ++j)
        for (int i = 0; i < 201; ++i)
          if (-5.0 + 0.05 * i >= 1.2) g.at(i, j) = step;  // the step 0.65 m ahead of the front axle
      w.terrain.kind = TerrainSpec::Kind::Heightfield;
      w.terrain.grid = g;
      Diagnostics diag;
      auto world = World::create(w, {}, diag);
      if (!world) qFatal("%s", diag.format().c_str());
      const TerrainPatchCmd whole{0, 0, 201, 41, g.heights};
      const bool flagged = strokeRisk(level, whole, *limits, 0.2).has_value();  // the step as a stroke on level ground
      world->submit(DriveCmd{0.3, 0});
      for (int k = 0; k < 8000; ++k) world->step();
      const RobotModel& robot = world->robotModel(0);
      const double fl = world->linkPose(0, robot.findLink("wheel_fl")).p.x;
      const double fr = world->linkPose(0, robot.findLink("wheel_fr")).p.x;
      qInfo("a %.3f m step: flagged %d, front wheels at x = %.2f, %.2f m (the step at 1.2 m), healthy %d", step, flagged,
            fl, fr, world->health().healthy());
      if (!world->health().healthy()) qInfo("%s", world->health().message().c_str());
      return std::make_pair(flagged, std::min(fl, fr) > 1.2 + 0.2 && world->health().healthy());
    };
    const auto [smallFlagged, smallCrossed] = crosses(0.9 * limits->maxStep);
    QVERIFY(!smallFlagged);
    QVERIFY(smallCrossed);
    const auto [bigFlagged, bigCrossed] = crosses(0.18);
    QVERIFY(bigFlagged);
    QVERIFY(!bigCrossed);
  }

  // Split into parts of at most 2000 heights, each part's COMMAND text fits
  // a link frame, and applied in order they equal the whole patch.
  void patchesSplitToFitFrames() {
    const WorldModel model = track();
    const auto whole = brushDab(model.terrain.grid, {0, 0}, Brush{BrushKind::Noise, 1.9, 0.05, 0, 3});
    QVERIFY(whole && whole->heights.size() > 4000);
    const std::vector<TerrainPatchCmd> parts = splitPatch(*whole, 2000);
    QVERIFY(parts.size() >= 2);
    HeightGrid a = model.terrain.grid, b = model.terrain.grid;
    applyPatch(a, *whole);
    for (const TerrainPatchCmd& p : parts) {
      QVERIFY(p.heights.size() <= 2000);
      QVERIFY(toText(Command{p}, nullptr).size() < kMaxPayloadSize - 100);
      applyPatch(b, p);
    }
    QCOMPARE(b.heights, a.heights);
  }

  // Over a real loopback link: the stand-in announces terrain_edit, takes a
  // 0.1 m raise under the robot (in frame-sized parts), and the robot rises
  // with the ground (criterion: 0.07-0.13 m, the brush's 0.1 m less its
  // falloff under the wheels); its log re-simulates with every hash equal
  // and the edits among the commands. Control: a stand-in as a real robot
  // announces nothing, refuses the edit (invalid, "simulator edit") and its
  // robot stays within 5 mm.
  void standInTakesEditsOverTheLink() {
    const WorldModel model = track();
    QTemporaryDir dir;
    for (bool edits : {true, false}) {
      Rig rig;
      QVERIFY(rig.start(edits, dir));
      QCOMPARE(rig.client->stats().robotCapabilities, std::string(edits ? "terrain_edit" : ""));
      const TelemetryMsg before = rig.seen.latest();
      const Vec2 under = gridPoint(model.terrain, {before.pose.p.x, before.pose.p.y});
      const auto patch = brushDab(model.terrain.grid, under, Brush{BrushKind::Raise, 2.5, 0.1, 0, 1});
      QVERIFY(patch);
      const std::vector<TerrainPatchCmd> parts = splitPatch(*patch, 2000);
      QVERIFY(parts.size() >= 2);  // several frames
      for (const TerrainPatchCmd& p : parts) rig.client->sendCommand(p);
      QVERIFY(rig.seen.waitFor([&] { return rig.seen.replies.size() == parts.size(); }, 20s));
      const double z0 = before.pose.p.z;
      const double t0 = rig.seen.latest().time;
      QVERIFY(rig.seen.waitFor([&] { return rig.seen.last->time > t0 + 2.0; }, 20s));  // settled again
      const double rise = rig.seen.z() - z0;
      {
        std::lock_guard lock(rig.seen.mutex);
        qInfo("%s: %zu parts, first reply '%s'; the robot rose %.4f m", edits ? "stand-in" : "as a real robot",
              parts.size(), rig.seen.replies[0].reason.c_str(), rise);
        for (const ReplyMsg& r : rig.seen.replies)
          QCOMPARE(r.status, edits ? ReplyStatus::Ok : ReplyStatus::Invalid);
        if (!edits) QVERIFY(rig.seen.replies[0].reason.find("simulator edit") != std::string::npos);
      }
      if (edits) QVERIFY(rise > 0.07 && rise < 0.13);
      else QVERIFY(std::abs(rise) < 0.005);
      const std::string log = rig.robot->logPath();
      rig.client->stop();
      rig.robot->stop();
      if (!edits) continue;
      std::string error;
      const std::optional<ResimReport> r = resimulate(log, {}, error);
      QVERIFY2(r, error.c_str());
      qInfo("re-simulated: %d hashes, %d commands", r->hashesCompared, r->commandsApplied);
      QVERIFY(!r->divergence && r->hashesCompared >= 2);
      QCOMPARE(r->commandsApplied, static_cast<int>(parts.size()));
      // Replayed, the ground is as loaded before the edit and edited after it.
      auto player = LogPlayer::open(log, error);
      QVERIFY2(player, error.c_str());
      QCOMPARE(player->terrainEditsAt(player->startTime()), size_t{0});
      QCOMPARE(player->terrainEditsAt(player->endTime()), parts.size());
      HeightGrid expected = model.terrain.grid;
      applyPatch(expected, *patch);
      QCOMPARE(player->terrainAfter(parts.size()).heights, expected.heights);
      QCOMPARE(player->terrainAfter(0).heights, model.terrain.grid.heights);
    }
  }
};

QTEST_GUILESS_MAIN(TestTerrainEdit)
#include "tst_terrain_edit.moc"
