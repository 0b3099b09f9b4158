#pragma once
// Writing terrains (issue 16): a height grid as an ESRI ASCII grid (.asc), a
// 16-bit PGM (.pgm) or a CSV grid (.csv), readable by sim/terrain_loader.h,
// and the world file that uses it. Files are written whole to a temporary
// name beside the target and renamed over it, so a failed save never leaves
// half a file behind.
//
//   std::string error;
//   if (!sp::saveHeightGrid("terrains/mine.asc", grid, error)) show(error);
//   sp::saveWorldWithTerrain(world.file, "terrains/mine.world.xml", "terrains/mine.asc", grid, error);

#include <string>

#include "sim/height_grid.h"
#include "sim/terrain_loader.h"

namespace sp {

/// The grid in `format` (Asc, Pgm or Csv; Auto: by the extension of
/// `pathForFormat`). Asc and Csv hold every height exactly (shortest
/// round-trip text); Pgm quantises to 16 bits between the grid's lowest and
/// highest height (`pgmMin`, `pgmMax` are set to them: the world file's
/// min_height and max_height). "" and `error` for a format it cannot write.
std::string heightGridText(const HeightGrid& grid, TerrainFormat format, double* pgmMin, double* pgmMax,
                           std::string& error);

/// The format a path's extension names (.asc, .pgm, .csv), else Auto.
TerrainFormat formatOf(const std::string& path);

/// Writes `text` to `path` through a temporary file and a rename.
bool writeFileAtomically(const std::string& path, const std::string& text, std::string& error);

/// Saves the grid to `path` in the format its extension names.
bool saveHeightGrid(const std::string& path, const HeightGrid& grid, std::string& error);

/// Writes `outWorld`: the world file `world` with its <terrain> turned into a
/// heightfield of `terrainFile` (format by extension; its width and depth,
/// the PGM height range) and relative paths (the terrain's, the robots')
/// rewritten for the new file's folder. Everything else is kept as written.
bool saveWorldWithTerrain(const std::string& world, const std::string& outWorld, const std::string& terrainFile,
                          const HeightGrid& grid, std::string& error);

}  // namespace sp
