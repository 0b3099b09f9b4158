// Editing the terrain in the console under Xvfb (issue 16), as an operator
// does: Terrain dock, Edit terrain, a drag with the left button in the 3D
// view over the ground by the robot. The drawn mesh, the console's world
// and the robot (the window's stand-in, a simulator that announces
// terrain_edit) all follow; Undo restores the heights bit for bit and the
// robot settles back; Save writes a terrain and a world that load as edited.

#include <QFile>
#include <QMouseEvent>
#include <QRegularExpression>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QSignalSpy>
#include <QTest>

#include <algorithm>
#include <cmath>

#include "app/console/console_session.h"
#include "sim/model_loader.h"
#include "tests/ui/console_fixture.h"
#include "ui/jobs/drive/control_panel.h"
#include "ui/main_window.h"
#include "ui/scene_view.h"
#include "ui/jobs/terrain/terrain_panel.h"

using namespace sp;

namespace {

void mouse(QWidget* w, QEvent::Type type, QPointF at, Qt::MouseButtons buttons) {
  QMouseEvent e(type, at, w->mapToGlobal(at), type == QEvent::MouseMove ? Qt::NoButton : Qt::LeftButton, buttons,
                Qt::NoModifier);
  QApplication::sendEvent(w, &e);
}

}  // namespace

class TestTerrainPanel : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    if (QGuiApplication::platformName() == QLatin1String("offscreen"))
      QSKIP("the 3D view needs an X server: run under xvfb-run");
    QVERIFY(dir_.isValid());
    const QString error =
        test::startConsole(dir_, QStringLiteral(SP_SOURCE_DIR "/terrains/test_track.world.xml"), options_, window_);
    QVERIFY2(error.isEmpty(), qPrintable(error));
    QTRY_VERIFY_WITH_TIMEOUT(window_->lastTelemetry().has_value() && test::controlPanel(*window_)->controlsEnabled(), 20000);
    QTRY_VERIFY_WITH_TIMEOUT(window_->lastTelemetry()->time > 2.0, 20000);  // settled on the track
  }
  void cleanupTestCase() { window_.reset(); }

  // Criteria (before the run): a drag of the raise brush (radius 1.5 m,
  // 0.05 m a dab) beside the robot changes the console's world exactly as
  // the editor's grid (bit for bit), the drawn mesh follows (its vertex at
  // the dab's sample is the edited height, 1e-6 m: floats), and the robot,
  // on raised ground, rises at least 3 cm. Undo: the world's heights are the
  // loaded ones bit for bit, the mesh too, and the robot settles back within
  // 1 cm of where it stood.
  void paintUndoAndSave() {
    MainWindow& w = *window_;
    TerrainPanel* t = test::terrainPanel(w);
    SceneView* view = w.sceneView();
    QVERIFY(t->editable());
    Diagnostics diag;
    const HeightGrid loaded = loadWorld(SP_SOURCE_DIR "/terrains/test_track.world.xml", diag)->terrain.grid;
    const double z0 = w.lastTelemetry()->pose.p.z;

    t->setBrush(Brush{BrushKind::Raise, 1.5, 0.05, 0, 1});
    t->setEditing(true);
    QVERIFY(view->terrainEditing());
    // The pixel whose ground is nearest the robot's base, 0.4 m behind it
    // (between its axles): the brush is put down under the robot.
    const Pose base = w.lastTelemetry()->pose;
    QPointF centre;
    double best = 1e9;
    for (int y = 0; y < view->height(); y += 8)
      for (int x = 0; x < view->width(); x += 8)
        if (const std::optional<Vec3> g = view->groundAt(QPointF(x, y))) {
          const double d = std::hypot(g->x - (base.p.x - 0.4), g->y - base.p.y);
          if (d < best) best = d, centre = QPointF(x, y);
        }
    QVERIFY(best < 0.2);
    const std::optional<Vec3> ground = view->groundAt(centre);
    QVERIFY(ground);
    qInfo("painting at %.2f, %.2f (robot at %.2f, %.2f)", ground->x, ground->y, w.lastTelemetry()->pose.p.x,
          w.lastTelemetry()->pose.p.y);
    mouse(view, QEvent::MouseButtonPress, centre, Qt::LeftButton);
    for (int k = 1; k <= 20; ++k) {
      mouse(view, QEvent::MouseMove, centre + QPointF(4.0 * k, 0), Qt::LeftButton);
      QTest::qWait(16);
    }
    mouse(view, QEvent::MouseButtonRelease, centre + QPointF(80, 0), Qt::NoButton);
    QVERIFY(test::terrainEdits(w) >= 2);
    QCOMPARE(t->editor()->undoLevels(), size_t{1});
    const HeightGrid& edited = t->editor()->grid();
    QVERIFY(edited.heights != loaded.heights);
    QCOMPARE(w.session()->world()->terrain.grid.heights, edited.heights);
    // One terrain: the dock edits the console's world's heights themselves, no copy.
    QCOMPARE(&edited, &w.session()->world()->terrain.grid);
    const Vec2 at = gridPoint(w.session()->world()->terrain, {base.p.x, base.p.y});  // the sample under the robot
    const int i = static_cast<int>(std::lround((at.x + edited.width / 2) / edited.spacingX()) / 2 * 2);  // a drawn sample (every 2nd)
    const int j = static_cast<int>(std::lround((at.y + edited.depth / 2) / edited.spacingY()) / 2 * 2);
    QVERIFY(view->drawnTerrainHeight(i, j).has_value());
    QVERIFY(std::abs(*view->drawnTerrainHeight(i, j) - edited.at(i, j)) < 1e-6);
    QVERIFY(edited.at(i, j) - loaded.at(i, j) > 0.05);
    QTRY_VERIFY_WITH_TIMEOUT(w.lastTelemetry()->pose.p.z - z0 > 0.03, 10000);
    qInfo("raised %.3f m under the brush; the robot rose %.3f m", edited.at(i, j) - loaded.at(i, j),
          w.lastTelemetry()->pose.p.z - z0);
    // The ghost's twin has the edit too: its trail lies on the edited ground
    // (the trail's points are its world's terrain heights), not the loaded.
    const TerrainSpec& terrain = w.session()->world()->terrain;
    const auto groundOf = [&](const HeightGrid& g, const Vec3& p) {
      const Vec2 q = gridPoint(terrain, {p.x, p.y});
      return g.heightAt(q.x, q.y) + terrain.pose.p.z;
    };
    QTRY_VERIFY_WITH_TIMEOUT(!w.session()->ghost()->view().trail.empty() &&
                                 std::abs(w.session()->ghost()->view().trail.front().z -
                                          groundOf(edited, w.session()->ghost()->view().trail.front())) < 1e-9,
                             10000);
    const Vec3 trailStart = w.session()->ghost()->view().trail.front();
    QVERIFY(groundOf(edited, trailStart) - groundOf(loaded, trailStart) > 0.03);

    // Save: the terrain and a world using it load as edited.
    const QString csv = dir_.filePath(QStringLiteral("edited.csv")), world = dir_.filePath(QStringLiteral("edited.world.xml"));
    QCOMPARE(t->save(csv, world), QString());
    const std::optional<WorldModel> saved = loadWorld(world.toStdString(), diag);
    QVERIFY2(saved, diag.format().c_str());
    QCOMPARE(saved->terrain.grid.heights, edited.heights);

    t->undo();
    QCOMPARE(t->editor()->redoLevels(), size_t{1});
    QCOMPARE(w.session()->world()->terrain.grid.heights, loaded.heights);
    QVERIFY(std::abs(*view->drawnTerrainHeight(i, j) - loaded.at(i, j)) < 1e-6);
    QTRY_VERIFY_WITH_TIMEOUT(std::abs(w.lastTelemetry()->pose.p.z - z0) < 0.01, 10000);
    t->setEditing(false);
    QVERIFY(!view->terrainEditing());
  }

  // Issue 31: before painting, the dock says what a dab would do where the
  // cursor is, and warns when it would make a rise the robot cannot drive.
  // Criteria (before the run): hovering 2 m ahead of the robot with a sharp
  // raise (0.3 m, 0.15 m a dab) shows "a dab +0.12..0.15 m" (the sample
  // nearest the cursor: it is off the centre by up to half a sample), the amber warning
  // and riskChanged(true), and leaves the heights alone; the same place
  // with a gentle brush (2 m, 0.005 m) shows no warning (riskChanged(false)).
  void hoverPreviewsAndWarns() {
    MainWindow& w = *window_;
    TerrainPanel* t = test::terrainPanel(w);
    SceneView* view = w.sceneView();
    const HeightGrid before = t->editor()->grid();
    QSignalSpy risk(t, &TerrainPanel::riskChanged);
    t->setBrush(Brush{BrushKind::Raise, 0.3, 0.15, 0, 1});
    t->setEditing(true);
    const Pose base = w.lastTelemetry()->pose;
    const double heading = std::atan2(2 * (base.q.w * base.q.z + base.q.x * base.q.y),
                                      1 - 2 * (base.q.y * base.q.y + base.q.z * base.q.z));
    const Vec2 target{base.p.x + 2 * std::cos(heading), base.p.y + 2 * std::sin(heading)};
    QPointF pixel;
    double best = 1e9;
    for (int y = 0; y < view->height(); y += 6)
      for (int x = 0; x < view->width(); x += 6)
        if (const std::optional<Vec3> g = view->groundAt(QPointF(x, y))) {
          const double d = std::hypot(g->x - target.x, g->y - target.y);
          if (d < best) best = d, pixel = QPointF(x, y);
        }
    QVERIFY(best < 0.3);
    mouse(view, QEvent::MouseMove, pixel, Qt::NoButton);
    qInfo("preview: %s | %s", qPrintable(t->previewText()), qPrintable(t->riskText()));
    // The dab's change at the sample nearest the cursor: 0.15 m at the centre, less off it.
    const QRegularExpressionMatch dab = QRegularExpression(QStringLiteral("a dab \\+(\\d\\.\\d+) m")).match(t->previewText());
    QVERIFY2(dab.hasMatch(), qPrintable(t->previewText()));
    QVERIFY(dab.captured(1).toDouble() > 0.12 && dab.captured(1).toDouble() <= 0.15);
    QVERIFY(t->riskText().contains(QStringLiteral("A dab here would make")));
    QCOMPARE(risk.count(), 1);
    QCOMPARE(risk.last().at(0).toBool(), true);
    QCOMPARE(t->editor()->grid().heights, before.heights);  // a preview paints nothing
    t->setBrush(Brush{BrushKind::Raise, 2.0, 0.005, 0, 1});
    mouse(view, QEvent::MouseMove, pixel + QPointF(1, 0), Qt::NoButton);
    QVERIFY2(t->riskText().isEmpty(), qPrintable(t->riskText()));
    QCOMPARE(risk.count(), 2);
    QCOMPARE(risk.last().at(0).toBool(), false);
    t->setEditing(false);
  }

  // New and Import write a terrain and a world that load: a flat 4 x 2 m
  // terrain at 0.3 m is 41 x 21 samples all at 0.3; the test track's
  // profile imported is the test track's grid; a file that is not there is
  // named in the error and nothing is written.
  void newAndImport() {
    TerrainPanel* t = test::terrainPanel(*window_);
    Diagnostics diag;
    const QString csv = dir_.filePath(QStringLiteral("new.asc")), world = dir_.filePath(QStringLiteral("new.world.xml"));
    QCOMPARE(t->createNew(4, 2, 0.1, 0.3, csv, world), QString());
    std::optional<WorldModel> made = loadWorld(world.toStdString(), diag);
    QVERIFY2(made, diag.format().c_str());
    QCOMPARE(made->terrain.grid.columns, 41);
    QCOMPARE(made->terrain.grid.rows, 21);
    QVERIFY(std::all_of(made->terrain.grid.heights.begin(), made->terrain.grid.heights.end(),
                        [](double h) { return h == 0.3; }));
    const QString track = dir_.filePath(QStringLiteral("track.csv")), trackWorld = dir_.filePath(QStringLiteral("track.world.xml"));
    QCOMPARE(t->import(QStringLiteral(SP_SOURCE_DIR "/terrains/test_track.csv"), true, 0, 4, 0.05, track, trackWorld),
             QString());
    made = loadWorld(trackWorld.toStdString(), diag);
    QVERIFY2(made, diag.format().c_str());
    const std::optional<WorldModel> original = loadWorld(SP_SOURCE_DIR "/terrains/test_track.world.xml", diag);
    QCOMPARE(made->terrain.grid.heights, original->terrain.grid.heights);
    const QString missing = dir_.filePath(QStringLiteral("nothing.csv"));
    const QString error = t->import(missing, false, 4, 4, 0.05, dir_.filePath(QStringLiteral("x.csv")),
                                    dir_.filePath(QStringLiteral("x.world.xml")));
    QVERIFY2(error.contains(QStringLiteral("nothing.csv")), qPrintable(error));
    QVERIFY(!QFile::exists(dir_.filePath(QStringLiteral("x.world.xml"))));
  }

 private:
  QTemporaryDir dir_;
  ConsoleOptions options_;
  std::unique_ptr<MainWindow> window_;
};

int main(int argc, char** argv) { return sp::test::glTestMain<TestTerrainPanel>(argc, argv); }

#include "tst_terrain_panel.moc"
