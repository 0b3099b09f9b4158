#pragma once
// Command sequence files: one timestamped command per line, `#` comments.
// Syntax and examples in docs/formats.md.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/command.h"
#include "sim/diagnostics.h"

namespace sp {

struct RobotModel;
struct WorldModel;

/// Parses one command (without its time) in file syntax. `target` and
/// `velocity` values are degrees (deg/s) for hinge joints and metres (m/s)
/// for slider joints of `robot`; without a robot every joint is taken for a
/// hinge. On error returns nullopt and sets `error` to a message without
/// location.
std::optional<Command> parseCommand(std::string_view text, std::string& error,
                                    const RobotModel* robot = nullptr);

/// Parses a whole sequence held in `text`; `file` names it in diagnostics.
/// All problems are reported; returns nullopt if there is any error.
/// Times must be >= 0 and non-decreasing.
std::optional<std::vector<TimedCommand>> parseCommandSequence(std::string_view text,
                                                              std::string_view file,
                                                              Diagnostics& diag,
                                                              const RobotModel* robot = nullptr);

/// Reads and parses a sequence file.
std::optional<std::vector<TimedCommand>> loadCommandSequence(const std::string& path,
                                                             Diagnostics& diag,
                                                             const RobotModel* robot = nullptr);

/// Checks commands (parsed with the same robot) against a robot, each as
/// checkCommand() does (sim/command_check.h). Returns false on any error;
/// diagnostics carry `file` and each command's line.
bool checkCommands(const std::vector<TimedCommand>& commands, const RobotModel& robot,
                   std::string_view file, Diagnostics& diag);
/// As above against `world`: its first robot for robot commands, its
/// terrain for terrain edits (an edit outside the heightfield, or on a
/// plane, is an error at its line: it would be refused when due).
bool checkCommands(const std::vector<TimedCommand>& commands, const WorldModel& world,
                   std::string_view file, Diagnostics& diag);

}  // namespace sp
