#pragma once
// The console's terrain editor (issue 16): brush strokes on the world's
// heightfield with many levels of undo and redo. It edits the heights where
// they live (the console session's world: app/console/console_session.h),
// so the console has one terrain, which the scene, the ghost, rehearsals
// and the Terrain dock all read. Each dab is a
// TerrainPatchCmd (sim/terrain_brush.h) for the twins to apply at their next
// step; a stroke (the dabs of one drag) is one undo level, undone by the
// patch of the heights it replaced, bit for bit.
//
//   sp::TerrainEditor editor(world.terrain.grid);   // edits world's heights in place
//   for each mouse move:  if (auto p = editor.dab(point, brush)) send(*p);
//   on release:           editor.endStroke();
//   Undo:                 if (auto p = editor.undo()) send(*p);
//
// Thread: one (the console's GUI thread); plain data.

#include <cstddef>
#include <optional>
#include <vector>

#include "sim/terrain_brush.h"

namespace sp {

class TerrainEditor {
 public:
  /// Edits `grid` in place (it must outlive the editor), keeping up to
  /// `maxLevels` undo levels.
  explicit TerrainEditor(HeightGrid& grid, size_t maxLevels = 200) : grid_(grid), maxLevels_(maxLevels) {}
  TerrainEditor(const TerrainEditor&) = delete;
  TerrainEditor& operator=(const TerrainEditor&) = delete;

  /// The heights as edited so far.
  const HeightGrid& grid() const { return grid_; }
  /// One dab of the current stroke (one begins if none is open): the
  /// patch to apply, already applied here; nullopt when it touches nothing.
  std::optional<TerrainPatchCmd> dab(Vec2 centre, const Brush& brush);
  /// Ends the stroke: one undo level (nothing if it changed nothing). The
  /// redo levels are dropped by a new stroke.
  void endStroke();
  bool inStroke() const { return stroke_.has_value(); }
  /// How much the open stroke has changed the height at `at` (grid frame
  /// [m]); 0 with no stroke open.
  double strokeChange(Vec2 at) const {
    return stroke_ ? grid_.heightAt(at.x, at.y) - stroke_->start.heightAt(at.x, at.y) : 0.0;
  }

  /// The patch that takes the last stroke back (applied here), or nullopt.
  std::optional<TerrainPatchCmd> undo();
  /// The patch that does the last undone stroke again, or nullopt.
  std::optional<TerrainPatchCmd> redo();
  size_t undoLevels() const { return done_.size(); }
  size_t redoLevels() const { return undone_.size(); }
  /// The heights were saved as they are now.
  void markSaved() { saved_ = changes_; }
  /// Strokes, undos or redos since the last markSaved() (or since the
  /// start): what a restart from the world file would lose. Conservative:
  /// undoing back to the saved heights still counts.
  size_t unsavedChanges() const { return changes_ - saved_; }

 private:
  struct Stroke {
    TerrainPatchCmd before, after;  // the same rectangle
  };
  struct Open {
    HeightGrid start;  // the heights when the stroke began
    int i0, j0, i1, j1;  // the samples touched so far (inclusive)
  };
  HeightGrid& grid_;
  size_t maxLevels_;
  std::optional<Open> stroke_;
  std::vector<Stroke> done_, undone_;
  size_t changes_ = 0, saved_ = 0;  // counts strokes, undos and redos
};

/// `patch` cut into row bands (and, for very wide patches, column blocks)
/// of at most `maxHeights` heights each, so each fits one link frame
/// (docs/protocol.md: 64 KiB); applied in order they equal the whole.
std::vector<TerrainPatchCmd> splitPatch(const TerrainPatchCmd& patch, size_t maxHeights);

}  // namespace sp
