#include "app/console/terrain_editor.h"

#include <algorithm>

namespace sp {
namespace {

// The rectangle [i0, i1] x [j0, j1] of `grid` as a patch.
TerrainPatchCmd rectangle(const HeightGrid& grid, int i0, int j0, int i1, int j1) {
  TerrainPatchCmd p;
  p.column = i0;
  p.row = j0;
  p.columns = i1 - i0 + 1;
  p.rows = j1 - j0 + 1;
  p.heights.resize(static_cast<size_t>(p.columns) * static_cast<size_t>(p.rows));
  return patchBefore(grid, p);
}

}  // namespace

std::optional<TerrainPatchCmd> TerrainEditor::dab(Vec2 centre, const Brush& brush) {
  std::optional<TerrainPatchCmd> patch = brushDab(grid_, centre, brush);
  if (!patch) return std::nullopt;
  const int i1 = patch->column + patch->columns - 1, j1 = patch->row + patch->rows - 1;
  if (!stroke_) {
    stroke_ = Open{grid_, patch->column, patch->row, i1, j1};
  } else {
    stroke_->i0 = std::min(stroke_->i0, patch->column);
    stroke_->j0 = std::min(stroke_->j0, patch->row);
    stroke_->i1 = std::max(stroke_->i1, i1);
    stroke_->j1 = std::max(stroke_->j1, j1);
  }
  applyPatch(grid_, *patch);
  return patch;
}

void TerrainEditor::endStroke() {
  if (!stroke_) return;
  const Open& s = *stroke_;
  Stroke done{rectangle(s.start, s.i0, s.j0, s.i1, s.j1), rectangle(grid_, s.i0, s.j0, s.i1, s.j1)};
  stroke_.reset();
  if (done.before == done.after) return;
  ++changes_;
  done_.push_back(std::move(done));
  if (done_.size() > maxLevels_) done_.erase(done_.begin());
  undone_.clear();
}

std::optional<TerrainPatchCmd> TerrainEditor::undo() {
  endStroke();
  if (done_.empty()) return std::nullopt;
  Stroke s = std::move(done_.back());
  done_.pop_back();
  ++changes_;
  applyPatch(grid_, s.before);
  TerrainPatchCmd patch = s.before;
  undone_.push_back(std::move(s));
  return patch;
}

std::optional<TerrainPatchCmd> TerrainEditor::redo() {
  endStroke();
  if (undone_.empty()) return std::nullopt;
  Stroke s = std::move(undone_.back());
  undone_.pop_back();
  ++changes_;
  applyPatch(grid_, s.after);
  TerrainPatchCmd patch = s.after;
  done_.push_back(std::move(s));
  return patch;
}

std::vector<TerrainPatchCmd> splitPatch(const TerrainPatchCmd& patch, size_t maxHeights) {
  std::vector<TerrainPatchCmd> parts;
  const size_t columns = static_cast<size_t>(patch.columns);
  const size_t width = std::max<size_t>(1, std::min(columns, maxHeights));  // columns per block
  const size_t band = std::max<size_t>(1, maxHeights / width);              // rows per band
  for (size_t r0 = 0; r0 < static_cast<size_t>(patch.rows); r0 += band)
    for (size_t c0 = 0; c0 < columns; c0 += width) {
      TerrainPatchCmd p;
      p.column = patch.column + static_cast<int>(c0);
      p.row = patch.row + static_cast<int>(r0);
      p.columns = static_cast<int>(std::min(width, columns - c0));
      p.rows = static_cast<int>(std::min(band, static_cast<size_t>(patch.rows) - r0));
      for (int r = 0; r < p.rows; ++r)
        for (int c = 0; c < p.columns; ++c)
          p.heights.push_back(patch.heights[(r0 + static_cast<size_t>(r)) * columns + c0 + static_cast<size_t>(c)]);
      parts.push_back(std::move(p));
    }
  return parts;
}

}  // namespace sp
