#pragma once
// Loads robot and world XML files (docs/formats.md, schemas in sim/schema/)
// into immutable models. Every problem of a file is reported in one pass as
// `file:line: error: message`; a model is returned only when there is none.

#include <optional>
#include <string>
#include <string_view>

#include "sim/diagnostics.h"
#include "sim/file_set.h"
#include "sim/robot_model.h"

namespace sp {

/// Reads a robot file, from `files` when it holds it, else from the disk
/// (sim/file_set.h; null `files`: the disk alone). Thread-safe (no shared state).
std::optional<RobotModel> loadRobot(const std::string& path, Diagnostics& diag, const FileSet* files = nullptr);

/// Parses robot XML held in memory; `file` names it in diagnostics.
std::optional<RobotModel> parseRobot(std::string_view xml, std::string_view file,
                                     Diagnostics& diag);

/// Reads a world file and the robot and terrain files it names (paths
/// relative to the world file), each from `files` when it holds it, else
/// from the disk.
std::optional<WorldModel> loadWorld(const std::string& path, Diagnostics& diag, const FileSet* files = nullptr);

/// Parses world XML held in memory; relative paths resolve against `baseDir`
/// and the files they name are read as loadWorld() reads them.
std::optional<WorldModel> parseWorld(std::string_view xml, std::string_view file,
                                     std::string_view baseDir, Diagnostics& diag, const FileSet* files = nullptr);

/// What a file is, by its root element: "robot", "world", or "" (not XML or
/// another root). Used by `simpartner-sim check` to pick a loader.
std::string xmlRootName(const std::string& path);

}  // namespace sp
