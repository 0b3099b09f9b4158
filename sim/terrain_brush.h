#pragma once
// Terrain brushes (issue 16): one dab of a brush at a point of a heightfield
// becomes a TerrainPatchCmd, the edit command the twin applies at its next
// step, logs and re-simulates. The brush only computes heights; applying
// them is the World's (physics) and the view's (mesh) business.
//
// Every brush weighs its effect by a smooth falloff of the distance d from
// the brush centre, w(d) = (1 - (d/r)^2)^2 for d < r and 0 beyond (1 at the
// centre, flat at the rim, so strokes leave no ridge). With s the strength
// and h a sample's height:
//
//   raise    h + s w                      s in m per dab
//   lower    h - s w
//   smooth   h + min(1, s) w (m - h)       m: the mean of the sample and its
//                                          (up to 8) neighbours, before the dab
//   flatten  h + min(1, s) w (target - h)  target: a picked height [m]
//   noise    h + s w n(i, j)               n in [-1, 1]: a hash of the seed
//                                          and the sample, the same each run
//
//   sp::Brush b{sp::BrushKind::Raise, 2.0, 0.05};
//   if (auto patch = sp::brushDab(grid, {x, y}, b)) world.submit(*patch);

#include <cstdint>
#include <optional>
#include <string>

#include "sim/command.h"
#include "sim/height_grid.h"
#include "sim/math.h"

namespace sp {

struct TerrainSpec;

enum class BrushKind { Raise, Lower, Smooth, Flatten, Noise };
/// "raise", "lower", "smooth", "flatten", "noise".
const char* brushName(BrushKind kind);

struct Brush {
  BrushKind kind = BrushKind::Raise;
  double radius = 1.0;    ///< [m], > 0
  double strength = 0.02; ///< raise/lower/noise: [m] per dab at the centre; smooth/flatten: fraction, 0..1
  double target = 0;      ///< flatten: the height to flatten to [m], in the grid's own heights
  uint32_t seed = 1;      ///< noise
};

/// The falloff w(d) above.
double brushWeight(double distance, double radius);

/// A point in the grid frame [m] (as HeightGrid::heightAt takes it) from the
/// world frame: the grid is centred on the terrain's pose, turned by its yaw.
Vec2 gridPoint(const TerrainSpec& terrain, Vec2 world);
/// The inverse: the world point of grid point `grid`.
Vec2 worldPoint(const TerrainSpec& terrain, Vec2 grid);

/// One dab at `centre` (grid frame [m]): the patch covering the samples
/// within the radius, with their new heights; nullopt when no sample lies
/// within it (off the grid) or the brush is not valid (radius <= 0 or not
/// finite). Heights that would not be finite stay as they are.
std::optional<TerrainPatchCmd> brushDab(const HeightGrid& grid, Vec2 centre, const Brush& brush);

/// "" if `patch` fits `grid` (null: the terrain is a plane), else why not
/// ("terrain: ..."). World::checkTerrainPatch is this on its own grid.
std::string patchFits(const HeightGrid* grid, const TerrainPatchCmd& patch);

/// The heights a patch would replace: the inverse edit (for undo).
TerrainPatchCmd patchBefore(const HeightGrid& grid, const TerrainPatchCmd& patch);
/// Writes a patch's heights into `grid` (the caller checked it fits).
void applyPatch(HeightGrid& grid, const TerrainPatchCmd& patch);

}  // namespace sp
