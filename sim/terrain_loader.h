#pragma once
// Loaders for heightfield files: ESRI ASCII grid (.asc), PGM (P2/P5, 8 and 16
// bit), CSV grids, and 1-D profiles (distance,height CSV) extruded sideways.

#include <optional>
#include <string>

#include "sim/diagnostics.h"
#include "sim/file_set.h"
#include "sim/height_grid.h"

namespace sp {

enum class TerrainFormat { Auto, Asc, Pgm, Csv, Profile };

/// Where heights come from and how to scale them. Set by the world file's
/// <terrain> element; see docs/formats.md.
struct TerrainSource {
  std::string path;  ///< resolved file path
  TerrainFormat format = TerrainFormat::Auto;  ///< Auto: by extension (.asc .pgm .csv)
  double width = 0;      ///< x extent [m]; 0 = from the file (asc: (ncols-1)*cellsize; profile: distance span)
  double depth = 0;      ///< y extent [m]; 0 = from the file (asc: (nrows-1)*cellsize); required for csv/pgm; profile: lateral width
  double minHeight = 0;  ///< pgm only: height of grey value 0 [m]
  double maxHeight = 1;  ///< pgm only: height of the maximum grey value [m]
  double resolution = 0.05;  ///< profile only: sample spacing along both axes [m]
};

/// Plausible bounds, checked at load: a side [m] and a height's magnitude [m].
inline constexpr double kMaxTerrainExtent = 1e5;
inline constexpr double kMaxTerrainHeight = 1e5;

/// Reads a height grid. Problems in the file are reported as path:line
/// (or row) errors, all of them, and nullopt is returned when there is any.
/// File rows are stored north first (image order): the first row of the file
/// is the largest y, so the loader flips it into HeightGrid's +y order.
std::optional<HeightGrid> loadHeightGrid(const TerrainSource& source, Diagnostics& diag,
                                         const FileSet* files = nullptr);

}  // namespace sp
