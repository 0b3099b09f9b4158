#include "sim/terrain_brush.h"

#include <algorithm>
#include <cmath>

#include "sim/robot_model.h"

namespace sp {

const char* brushName(BrushKind kind) {
  switch (kind) {
    case BrushKind::Raise: return "raise";
    case BrushKind::Lower: return "lower";
    case BrushKind::Smooth: return "smooth";
    case BrushKind::Flatten: return "flatten";
    case BrushKind::Noise: return "noise";
  }
  return "?";
}

double brushWeight(double distance, double radius) {
  if (!(radius > 0) || !(distance < radius)) return 0;
  const double q = distance / radius;
  const double a = 1 - q * q;
  return a * a;
}

Vec2 gridPoint(const TerrainSpec& terrain, Vec2 world) {
  const double yaw = heading(terrain.pose.q);
  const double dx = world.x - terrain.pose.p.x, dy = world.y - terrain.pose.p.y;
  return {std::cos(yaw) * dx + std::sin(yaw) * dy, -std::sin(yaw) * dx + std::cos(yaw) * dy};
}

Vec2 worldPoint(const TerrainSpec& terrain, Vec2 grid) {
  const double yaw = heading(terrain.pose.q);
  return {terrain.pose.p.x + std::cos(yaw) * grid.x - std::sin(yaw) * grid.y,
          terrain.pose.p.y + std::sin(yaw) * grid.x + std::cos(yaw) * grid.y};
}

namespace {

// A value in [-1, 1] from the seed and the sample: splitmix64's finaliser,
// so neighbouring samples are unrelated and every run draws the same.
double noiseAt(uint32_t seed, int i, int j) {
  uint64_t z = (static_cast<uint64_t>(seed) << 40) ^ (static_cast<uint64_t>(static_cast<uint32_t>(i)) << 20) ^
               static_cast<uint64_t>(static_cast<uint32_t>(j)) ^ 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) / static_cast<double>(1ULL << 53) * 2.0 - 1.0;
}

// The mean of sample (i, j) and its neighbours on the grid.
double neighbourMean(const HeightGrid& g, int i, int j) {
  double sum = 0;
  int n = 0;
  for (int b = std::max(0, j - 1); b <= std::min(g.rows - 1, j + 1); ++b)
    for (int a = std::max(0, i - 1); a <= std::min(g.columns - 1, i + 1); ++a) {
      sum += g.at(a, b);
      ++n;
    }
  return sum / n;
}

}  // namespace

std::optional<TerrainPatchCmd> brushDab(const HeightGrid& grid, Vec2 centre, const Brush& brush) {
  if (!(brush.radius > 0) || !std::isfinite(brush.radius) || !std::isfinite(centre.x) || !std::isfinite(centre.y) ||
      grid.columns < 2 || grid.rows < 2)
    return std::nullopt;
  // Sample (i, j) sits at -width/2 + i * spacingX (sim/height_grid.h).
  const double sx = grid.spacingX(), sy = grid.spacingY();
  const double ci = (centre.x + grid.width / 2) / sx, cj = (centre.y + grid.depth / 2) / sy;
  const int i0 = std::max(0, static_cast<int>(std::ceil(ci - brush.radius / sx)));
  const int i1 = std::min(grid.columns - 1, static_cast<int>(std::floor(ci + brush.radius / sx)));
  const int j0 = std::max(0, static_cast<int>(std::ceil(cj - brush.radius / sy)));
  const int j1 = std::min(grid.rows - 1, static_cast<int>(std::floor(cj + brush.radius / sy)));
  if (i0 > i1 || j0 > j1) return std::nullopt;

  TerrainPatchCmd patch;
  patch.column = i0;
  patch.row = j0;
  patch.columns = i1 - i0 + 1;
  patch.rows = j1 - j0 + 1;
  patch.heights.reserve(static_cast<size_t>(patch.columns) * static_cast<size_t>(patch.rows));
  const double fraction = std::clamp(brush.strength, 0.0, 1.0);
  bool touched = false;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double h = grid.at(i, j);
      const double w = brushWeight(std::hypot((i - ci) * sx, (j - cj) * sy), brush.radius);
      touched = touched || w > 0;
      double next = h;
      switch (brush.kind) {
        case BrushKind::Raise: next = h + brush.strength * w; break;
        case BrushKind::Lower: next = h - brush.strength * w; break;
        case BrushKind::Smooth: next = h + fraction * w * (neighbourMean(grid, i, j) - h); break;
        case BrushKind::Flatten: next = h + fraction * w * (brush.target - h); break;
        case BrushKind::Noise: next = h + brush.strength * w * noiseAt(brush.seed, i, j); break;
      }
      patch.heights.push_back(std::isfinite(next) ? next : h);
    }
  if (!touched) return std::nullopt;
  return patch;
}

TerrainPatchCmd patchBefore(const HeightGrid& grid, const TerrainPatchCmd& patch) {
  TerrainPatchCmd before = patch;
  for (int r = 0; r < patch.rows; ++r)
    for (int k = 0; k < patch.columns; ++k)
      before.heights[static_cast<size_t>(r) * static_cast<size_t>(patch.columns) + static_cast<size_t>(k)] =
          grid.at(patch.column + k, patch.row + r);
  return before;
}

void applyPatch(HeightGrid& grid, const TerrainPatchCmd& patch) {
  for (int r = 0; r < patch.rows; ++r)
    for (int k = 0; k < patch.columns; ++k)
      grid.at(patch.column + k, patch.row + r) =
          patch.heights[static_cast<size_t>(r) * static_cast<size_t>(patch.columns) + static_cast<size_t>(k)];
}

}  // namespace sp
