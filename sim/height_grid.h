#pragma once
// A terrain heightfield: a regular grid of heights over a width x depth
// rectangle centred on the terrain origin, linearly interpolated over the two
// triangles of each cell exactly as ODE's heightfield is.

#include <cstddef>
#include <vector>

namespace sp {

/// Grid axes: column index i grows with +x, row index j grows with +y.
/// Sample (i, j) sits at x = -width/2 + i*width/(columns-1),
///                       y = -depth/2 + j*depth/(rows-1).
/// Each cell is split by its diagonal from (i, j) to (i+1, j+1).
/// Plain value type; not thread-safe for concurrent writes.
struct HeightGrid {
  int columns = 0;    ///< samples along x, >= 2
  int rows = 0;       ///< samples along y, >= 2
  double width = 0;   ///< extent along x [m], > 0
  double depth = 0;   ///< extent along y [m], > 0
  std::vector<double> heights;  ///< rows*columns values [m], index j*columns + i

  double& at(int i, int j) { return heights[static_cast<std::size_t>(j) * columns + i]; }
  double at(int i, int j) const { return heights[static_cast<std::size_t>(j) * columns + i]; }
  double spacingX() const { return width / (columns - 1); }
  double spacingY() const { return depth / (rows - 1); }
  double minHeight() const;
  double maxHeight() const;

  /// Height at (x, y) in the grid frame, interpolated on the cell's triangle;
  /// points outside the rectangle take the nearest edge value.
  double heightAt(double x, double y) const;
};

}  // namespace sp
