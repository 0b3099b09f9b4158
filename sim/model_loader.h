#pragma once
// Loads robot and world XML files (docs/formats.md, schemas in sim/schema/)
// into immutable models. Every problem of a file is reported in one pass as
// `file:line: error: message`; a model is returned only when there is none.

#include <optional>
#include <string>
#include <string_view>

#include "sim/diagnostics.h"
#include "sim/robot_model.h"

namespace sp {

/// Reads a robot file. Thread-safe (no shared state).
std::optional<RobotModel> loadRobot(const std::string& path, Diagnostics& diag);

/// Parses robot XML held in memory; `file` names it in diagnostics.
std::optional<RobotModel> parseRobot(std::string_view xml, std::string_view file,
                                     Diagnostics& diag);

/// Reads a world file and the robot and terrain files it names (paths
/// relative to the world file).
std::optional<WorldModel> loadWorld(const std::string& path, Diagnostics& diag);

/// Parses world XML held in memory; relative paths resolve against `baseDir`.
std::optional<WorldModel> parseWorld(std::string_view xml, std::string_view file,
                                     std::string_view baseDir, Diagnostics& diag);

/// What a file is, by its root element: "robot", "world", or "" (not XML or
/// another root). Used by `simpartner-sim check` to pick a loader.
std::string xmlRootName(const std::string& path);

}  // namespace sp
