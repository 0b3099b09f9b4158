#include "sim/terrain_file.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "sim/text.h"

namespace sp {

TerrainFormat formatOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".asc") return TerrainFormat::Asc;
  if (ext == ".pgm") return TerrainFormat::Pgm;
  if (ext == ".csv") return TerrainFormat::Csv;
  return TerrainFormat::Auto;
}

std::string heightGridText(const HeightGrid& g, TerrainFormat format, double* pgmMin, double* pgmMax,
                           std::string& error) {
  std::string out;
  // Files are north first: the last row of the grid (largest y) comes first.
  const auto rowsNorthFirst = [&](const char* separator) {
    for (int j = g.rows - 1; j >= 0; --j) {
      for (int i = 0; i < g.columns; ++i) {
        if (i) out += separator;
        out += shortestText(g.at(i, j));
      }
      out += '\n';
    }
  };
  switch (format) {
    case TerrainFormat::Asc:
      // The cellsize is x's spacing; the world file gives width and depth,
      // so a grid spaced differently along y loads as it was.
      out += "ncols " + std::to_string(g.columns) + "\nnrows " + std::to_string(g.rows) + "\nxllcenter " +
             shortestText(-g.width / 2) + "\nyllcenter " + shortestText(-g.depth / 2) + "\ncellsize " +
             shortestText(g.spacingX()) + "\n";
      rowsNorthFirst(" ");
      return out;
    case TerrainFormat::Csv:
      out += "# " + std::to_string(g.columns) + " x " + std::to_string(g.rows) + " heights [m], north row first\n";
      rowsNorthFirst(",");
      return out;
    case TerrainFormat::Pgm: {
      const double lo = g.minHeight(), hi = g.maxHeight();
      if (pgmMin) *pgmMin = lo;
      if (pgmMax) *pgmMax = hi;
      out += "P5\n# SimPartner terrain: heights " + shortestText(lo) + " to " + shortestText(hi) + " m\n" +
             std::to_string(g.columns) + " " + std::to_string(g.rows) + "\n65535\n";
      for (int j = g.rows - 1; j >= 0; --j)
        for (int i = 0; i < g.columns; ++i) {
          const double f = hi > lo ? (g.at(i, j) - lo) / (hi - lo) : 0.0;
          const auto v = static_cast<unsigned>(std::lround(std::clamp(f, 0.0, 1.0) * 65535));
          out += static_cast<char>(v >> 8);
          out += static_cast<char>(v & 0xff);
        }
      return out;
    }
    default:
      error = "cannot write this terrain format: save as .asc, .pgm or .csv";
      return {};
  }
}

bool writeFileAtomically(const std::string& path, const std::string& text, std::string& error) {
  const std::string temporary = path + ".saving";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    if (!out) {
      std::remove(temporary.c_str());
      error = path + ": cannot write the file";
      return false;
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::remove(temporary.c_str());
    error = path + ": cannot write the file: " + ec.message();
    return false;
  }
  return true;
}

bool saveHeightGrid(const std::string& path, const HeightGrid& grid, std::string& error) {
  const std::string text = heightGridText(grid, formatOf(path), nullptr, nullptr, error);
  if (text.empty()) {
    error = path + ": " + error;
    return false;
  }
  return writeFileAtomically(path, text, error);
}

namespace {

// `file` (relative to `fromDir`, or absolute) as seen from `toDir`.
std::string rebased(const std::string& file, const std::filesystem::path& fromDir, const std::filesystem::path& toDir) {
  const std::filesystem::path p(file);
  std::error_code ec;
  const std::filesystem::path target = std::filesystem::weakly_canonical(p.is_absolute() ? p : fromDir / p, ec);
  const std::filesystem::path base = std::filesystem::weakly_canonical(toDir, ec);
  const std::filesystem::path relative = target.lexically_relative(base);
  return relative.empty() ? target.string() : relative.string();
}

}  // namespace

bool saveWorldWithTerrain(const std::string& world, const std::string& outWorld, const std::string& terrainFile,
                          const HeightGrid& grid, std::string& error) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(world.c_str()) != tinyxml2::XML_SUCCESS) {
    error = world + ": cannot read the world file: " + (doc.ErrorStr() ? doc.ErrorStr() : "");
    return false;
  }
  tinyxml2::XMLElement* root = doc.RootElement();
  tinyxml2::XMLElement* terrain = root ? root->FirstChildElement("terrain") : nullptr;
  if (!terrain) {
    error = world + ": no <terrain> element";
    return false;
  }
  const std::filesystem::path fromDir = std::filesystem::path(world).parent_path();
  const std::filesystem::path toDir = std::filesystem::path(outWorld).parent_path();
  // The terrain: a heightfield of the new file, whatever it was.
  for (const char* a : {"file", "format", "width", "depth", "resolution", "min_height", "max_height"})
    terrain->DeleteAttribute(a);
  terrain->SetAttribute("type", "heightfield");
  terrain->SetAttribute("file", rebased(terrainFile, ".", toDir.empty() ? "." : toDir).c_str());
  terrain->SetAttribute("width", shortestText(grid.width).c_str());
  terrain->SetAttribute("depth", shortestText(grid.depth).c_str());
  if (formatOf(terrainFile) == TerrainFormat::Pgm) {
    terrain->SetAttribute("min_height", shortestText(grid.minHeight()).c_str());
    terrain->SetAttribute("max_height", shortestText(grid.maxHeight()).c_str());
  }
  // The robots' files, where the new world file will look for them.
  for (tinyxml2::XMLElement* r = root->FirstChildElement("robot"); r; r = r->NextSiblingElement("robot"))
    if (const char* file = r->Attribute("file"))
      r->SetAttribute("file", rebased(file, fromDir.empty() ? "." : fromDir, toDir.empty() ? "." : toDir).c_str());
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return writeFileAtomically(outWorld, printer.CStr(), error);
}

}  // namespace sp
