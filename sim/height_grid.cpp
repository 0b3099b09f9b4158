#include "sim/height_grid.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace sp {

double HeightGrid::minHeight() const {
  return heights.empty() ? 0.0 : *std::min_element(heights.begin(), heights.end());
}

double HeightGrid::maxHeight() const {
  return heights.empty() ? 0.0 : *std::max_element(heights.begin(), heights.end());
}

double HeightGrid::heightAt(double x, double y) const {
  assert(columns >= 2 && rows >= 2 && width > 0 && depth > 0);
  assert(heights.size() == static_cast<size_t>(rows) * static_cast<size_t>(columns));
  if (columns < 2 || rows < 2 || heights.size() != static_cast<size_t>(rows) * columns) return 0.0;

  // Continuous sample coordinates, clamped so that outside points take the
  // nearest edge value.
  const double fx = std::clamp((x + width / 2) / spacingX(), 0.0, double(columns - 1));
  const double fy = std::clamp((y + depth / 2) / spacingY(), 0.0, double(rows - 1));
  const int i = std::min(static_cast<int>(fx), columns - 2);
  const int j = std::min(static_cast<int>(fy), rows - 2);
  const double u = fx - i;  // in [0, 1] across the cell along x
  const double v = fy - j;  // in [0, 1] across the cell along y

  // The diagonal from (i, j) to (i+1, j+1) splits the cell along u == v.
  const double h00 = at(i, j);
  const double h11 = at(i + 1, j + 1);
  if (u >= v) {
    // Triangle (i, j), (i+1, j), (i+1, j+1).
    const double h10 = at(i + 1, j);
    return h00 + u * (h10 - h00) + v * (h11 - h10);
  }
  // Triangle (i, j), (i, j+1), (i+1, j+1).
  const double h01 = at(i, j + 1);
  return h00 + v * (h01 - h00) + u * (h11 - h01);
}

}  // namespace sp
