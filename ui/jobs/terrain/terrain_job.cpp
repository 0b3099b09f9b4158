#include "ui/jobs/terrain/terrain_job.h"

#include "app/console/console_session.h"
#include "sim/terrain_brush.h"
#include "app/console/terrain_editor.h"
#include "ui/jobs/terrain/terrain_panel.h"
#include "ui/scene_view.h"

namespace sp {

void TerrainJob::install(ConsoleContext& context) {
  context_ = &context;
  panel_ = new TerrainPanel;
  context.host().addDock(tr("Terrain"), QStringLiteral("terrainDock"), panel_, DockPlace::Side, true);

  SceneView& scene = context.scene();
  connect(panel_, &TerrainPanel::editingChanged, this, [this](bool on) {
    context_->scene().setTerrainEditing(on);
    if (on) context_->status(tr("Terrain editing: the left button paints; right drag and wheel move the camera"), 8000);
  });
  connect(panel_, &TerrainPanel::brushRadiusChanged, &scene, &SceneView::setBrushRadius);
  scene.setBrushRadius(panel_->brush().radius);
  connect(panel_, &TerrainPanel::pickRequested, &scene, &SceneView::pickGround);
  connect(&scene, &SceneView::groundPicked, panel_, [this](const Vec3& g) { panel_->setFlattenHeight(g.z); });
  connect(&scene, &SceneView::terrainDab, panel_, &TerrainPanel::dabAt);
  connect(&scene, &SceneView::terrainHover, panel_, &TerrainPanel::hoverAt);
  connect(panel_, &TerrainPanel::riskChanged, &scene, &SceneView::setBrushWarning);
  connect(&scene, &SceneView::terrainStrokeEnded, panel_, &TerrainPanel::endStroke);
  connect(panel_, &TerrainPanel::strokeEnded, &scene, &SceneView::finishTerrainEdit);
  connect(panel_, &TerrainPanel::patch, this, &TerrainJob::apply);
  connect(panel_, &TerrainPanel::openWorldRequested, this,
          [this](const QString& path) { context_->host().openWorld(path, false); });

  // A new world is edited from its file's heights; the same world shown
  // again after a replay keeps the edits and their undo history.
  connect(&context, &ConsoleContext::worldChanged, this, [this](const WorldModel&, bool fresh) {
    if (fresh) panel_->setTerrain(context_->session().world(), context_->terrainEditor());
  });
  connect(&context, &ConsoleContext::stateChanged, this, [this] {
    // While a replay is shown the view shows the log's ground: no editing the live terrain.
    const bool replaying = context_->state().replaying();
    if (replaying && panel_->isEnabled()) panel_->setEditing(false);
    panel_->setEnabled(!replaying);
    updateReach();
  });
}

void TerrainJob::apply(const TerrainPatchCmd& patch) {
  if (context_->editTerrain(patch)) ++edits_;
}

void TerrainJob::updateReach() {
  if (context_->robotTakesTerrainEdits())
    panel_->setReach(context_->state().leaseHeld()
                         ? tr("Edits reach the robot's twin (a simulator) and the console's.")
                         : tr("Take control to edit the robot's twin too; now only the console's twin."));
  else
    panel_->setReach(tr("The robot does not take terrain edits (a real robot, or not connected): only the "
                        "console's twin, ghost and rehearsals see them."));
}

}  // namespace sp
