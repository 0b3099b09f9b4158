#pragma once
// The console's fourth job: editing the terrain under the running robot.
// The Terrain dock (ui/jobs/terrain/terrain_panel.h) paints with brushes in
// the 3D view; each edit goes to the console's world (app/console/
// console_session.h: what is drawn, rehearsed and saved, and the ghost), to
// the other jobs (ConsoleContext::terrainEdited) and, when the robot is a
// simulator that takes edits and this console holds the lease, to the
// robot's twin. Disabled while a replay is shown: the view shows the log's
// ground then.
//
// Thread: GUI thread only.

#include <cstddef>
#include <cstdint>

#include "ui/console_context.h"

namespace sp {

class TerrainPanel;

class TerrainJob : public ConsoleJob {
  Q_OBJECT

 public:
  using ConsoleJob::ConsoleJob;
  QString name() const override { return QStringLiteral("terrain"); }
  void install(ConsoleContext& context) override;
  TerrainPanel* panel() const { return panel_; }
  /// Terrain edits applied since the start (each dab, undo or redo).
  int64_t edits() const { return edits_; }

 private:
  void apply(const TerrainPatchCmd& patch);
  void updateReach();

  ConsoleContext* context_ = nullptr;
  TerrainPanel* panel_ = nullptr;
  int64_t edits_ = 0;
};

}  // namespace sp
