// Terrain editing (issue 16) beyond the brushes' formulas: undo restores the
// heights bit for bit; patches split to fit link frames; the stand-in takes
// edits over a real loopback link (a simulator's capability, announced in
// WELCOME), the robot on edited ground rises, and the session's log
// re-simulates hash for hash. Control: a stand-in behaving as a real robot
// refuses the edit and its robot stays where it was.

#include <QTemporaryDir>
#include <QtTest>

#include <chrono>
#include <deque>
#include <random>

#include "app/log/log_player.h"
#include "app/log/resimulation.h"
#include "app/robot/stand_in.h"
#include "app/console/terrain_editor.h"
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
  double z() {
    std::lock_guard lock(mutex);
    return last->pose.p.z;
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
      const TelemetryMsg before = *rig.seen.last;
      const Vec2 under = gridPoint(model.terrain, {before.pose.p.x, before.pose.p.y});
      const auto patch = brushDab(model.terrain.grid, under, Brush{BrushKind::Raise, 2.5, 0.1, 0, 1});
      QVERIFY(patch);
      const std::vector<TerrainPatchCmd> parts = splitPatch(*patch, 2000);
      QVERIFY(parts.size() >= 2);  // several frames
      for (const TerrainPatchCmd& p : parts) rig.client->sendCommand(p);
      QVERIFY(rig.seen.waitFor([&] { return rig.seen.replies.size() == parts.size(); }, 20s));
      const double z0 = before.pose.p.z;
      const double t0 = rig.seen.last->time;
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
