#include "sim/command_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <system_error>

#include "sim/command_check.h"
#include "sim/math.h"
#include "sim/gait.h"
#include "sim/robot_model.h"
#include "sim/terrain_brush.h"
#include "sim/text.h"

// Units in sequence files: `target` and `velocity` take degrees and deg/s on
// hinge joints and metres and m/s on slider joints, so parsing needs the
// robot to know which is which (without one, every joint reads as a hinge);
// drive articulation in degrees, drive speed in m/s, wheel speeds in rad/s
// (as customary for wheels), torques in N m (forces in N on sliders).

namespace sp {
namespace {

/// Arguments of one command; number() records the first bad one.
constexpr double kMaxCommandValue = 1e6;

struct ArgReader {
  std::string_view command;
  std::vector<std::string_view> args;
  std::string error;
  const RobotModel* robot = nullptr;

  /// Argument `v` as a value of the joint named by argument `j`: degrees
  /// converted to radians, unless the robot says the joint is a slider.
  double jointValue(size_t j, size_t v) {
    const double x = number(v);
    const int joint = robot ? robot->findJoint(args[j]) : -1;
    if (joint >= 0 && robot->joints[joint].type == JointType::Slider) return x;
    return degToRad(x);
  }

  double number(size_t i) {
    const std::optional<double> v = parseReal(args[i]);
    if (!v && error.empty()) error = std::string(command) + ": bad number '" + std::string(args[i]) + "'";
    // Checked without a robot too (a sequence file alone): no speed, angle,
    // rate or torque of a command is a million of its units.
    if (v && std::abs(*v) > kMaxCommandValue && error.empty())
      error = std::string(command) + ": " + std::string(args[i]) + " is not a plausible value (beyond +-1e6)";
    return v && std::abs(*v) <= kMaxCommandValue ? *v : 0;
  }
  std::string word(size_t i) const { return std::string(args[i]); }
  Gait gait(size_t i) {
    for (Gait g : {Gait::Off, Gait::Caterpillar, Gait::Rolking})
      if (args[i] == toString(g)) return g;
    if (error.empty())
      error = std::string(command) + ": unknown gait '" + std::string(args[i]) + "' (expected off, caterpillar or rolking)";
    return Gait::Off;
  }
  JointMode mode(size_t i) {
    for (JointMode m : {JointMode::Velocity, JointMode::Position, JointMode::Torque, JointMode::Free})
      if (args[i] == toString(m)) return m;
    if (error.empty())
      error = std::string(command) + ": unknown mode '" + std::string(args[i]) +
              "' (expected velocity, position, torque or free)";
    return JointMode::Free;
  }
};

/// One command of the file syntax: its name, arguments and how to build it.
struct Syntax {
  std::string_view name;
  size_t arity;
  std::string_view help;  // the arguments, for the arity message
  Command (*build)(ArgReader& a);
};

// Braced initializers evaluate left to right, so the first bad argument is
// the one reported.
const Syntax kSyntax[] = {
    {"drive", 2, "speed m/s, articulation deg",
     [](ArgReader& a) -> Command { return DriveCmd{a.number(0), degToRad(a.number(1))}; }},
    {"wheels", 4, "front-left, front-right, rear-left, rear-right rad/s",
     [](ArgReader& a) -> Command { return WheelsCmd{{a.number(0), a.number(1), a.number(2), a.number(3)}}; }},
    {"target", 2, "joint, angle deg or position m",
     [](ArgReader& a) -> Command { return JointTargetCmd{a.word(0), a.jointValue(0, 1)}; }},
    {"velocity", 2, "joint, velocity deg/s or m/s",
     [](ArgReader& a) -> Command { return JointVelocityCmd{a.word(0), a.jointValue(0, 1)}; }},
    {"torque", 2, "joint, torque N m",
     [](ArgReader& a) -> Command { return JointTorqueCmd{a.word(0), a.number(1)}; }},
    {"mode", 2, "joint, velocity|position|torque|free",
     [](ArgReader& a) -> Command { return JointModeCmd{a.word(0), a.mode(1)}; }},
    {"stop", 0, "", [](ArgReader&) -> Command { return StopCmd{}; }},
    {"turn", 2, "speed m/s, yaw rate deg/s",
     [](ArgReader& a) -> Command { return TurnCmd{a.number(0), degToRad(a.number(1))}; }},
    {"gait", 1, "off|caterpillar|rolking", [](ArgReader& a) -> Command { return GaitCmd{a.gait(0)}; }},
};

/// `terrain COLUMN ROW COLUMNS ROWS HEIGHT...`: a patch of heights [m],
/// row by row; the count must be COLUMNS x ROWS.
std::optional<Command> parseTerrainPatch(const std::vector<std::string_view>& words, std::string& error) {
  if (words.size() < 6) {
    error = "terrain: expected column, row, columns, rows and columns x rows heights in m, got " +
            std::to_string(words.size() - 1) + " arguments";
    return std::nullopt;
  }
  TerrainPatchCmd c;
  int* fields[4] = {&c.column, &c.row, &c.columns, &c.rows};
  const char* names[4] = {"column", "row", "columns", "rows"};
  for (int i = 0; i < 4; ++i) {
    const std::string_view w = words[static_cast<size_t>(i) + 1];
    int value = 0;
    const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), value);
    if (ec != std::errc() || end != w.data() + w.size() || value < 0 || (i >= 2 && value == 0)) {
      error = std::string("terrain: bad ") + names[i] + " '" + std::string(w) + "' (expected a whole number" +
              (i >= 2 ? " > 0)" : " >= 0)");
      return std::nullopt;
    }
    *fields[i] = value;
  }
  const size_t expected = static_cast<size_t>(c.columns) * static_cast<size_t>(c.rows);
  if (words.size() - 5 != expected) {
    error = "terrain: " + std::to_string(c.columns) + " x " + std::to_string(c.rows) + " patch needs " +
            std::to_string(expected) + " heights, got " + std::to_string(words.size() - 5);
    return std::nullopt;
  }
  c.heights.reserve(expected);
  for (size_t i = 5; i < words.size(); ++i) {
    const std::optional<double> h = parseReal(words[i]);
    if (!h || !std::isfinite(*h)) {
      error = "terrain: bad height '" + std::string(words[i]) + "'";
      return std::nullopt;
    }
    c.heights.push_back(*h);
  }
  return Command{std::move(c)};
}

}  // namespace

std::optional<Command> parseCommand(std::string_view text, std::string& error, const RobotModel* robot) {
  const std::vector<std::string_view> words = splitWords(text);
  if (words.empty()) {
    error = "empty command";
    return std::nullopt;
  }
  if (words[0] == "terrain") return parseTerrainPatch(words, error);
  for (const Syntax& s : kSyntax) {
    if (words[0] != s.name) continue;
    ArgReader reader{s.name, {words.begin() + 1, words.end()}, {}, robot};
    if (reader.args.size() != s.arity) {
      const std::string got = ", got " + std::to_string(reader.args.size());
      error = std::string(s.name) +
              (s.arity == 0 ? ": expected no arguments" + got
                            : ": expected " + std::to_string(s.arity) + " arguments (" + std::string(s.help) +
                                  ")" + got);
      return std::nullopt;
    }
    Command command = s.build(reader);
    if (!reader.error.empty()) {
      error = reader.error;
      return std::nullopt;
    }
    return command;
  }
  error = "unknown command '" + std::string(words[0]) + "'";
  return std::nullopt;
}

std::optional<std::vector<TimedCommand>> parseCommandSequence(std::string_view text, std::string_view file,
                                                              Diagnostics& diag, const RobotModel* robot) {
  std::vector<TimedCommand> commands;
  bool ok = true;
  std::optional<double> previousTime;
  int line = 0;
  for (size_t pos = 0; pos <= text.size();) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view content = text.substr(pos, end - pos);
    pos = end + 1;
    ++line;
    content = trim(content.substr(0, content.find('#')));
    if (content.empty()) continue;

    const size_t split = std::min(content.find_first_of(" \t\r\v\f"), content.size());
    const std::string_view timeText = content.substr(0, split);
    const std::string_view rest = trim(content.substr(split));
    const std::optional<double> time = parseReal(timeText);
    if (!time) {
      diag.error(file, line, "bad time '" + std::string(timeText) + "'");
      ok = false;
      continue;
    }
    if (*time < 0) {
      diag.error(file, line, "time must be >= 0");
      ok = false;
      continue;
    }
    if (previousTime && *time < *previousTime) {
      diag.error(file, line, "time " + shortestText(*time) + " is before the previous command's time " +
                                 shortestText(*previousTime));
      ok = false;
      continue;
    }
    previousTime = time;
    if (rest.empty()) {
      diag.error(file, line, "expected a command after the time");
      ok = false;
      continue;
    }
    std::string error;
    std::optional<Command> command = parseCommand(rest, error, robot);
    if (!command) {
      diag.error(file, line, error);
      ok = false;
      continue;
    }
    commands.push_back({*time, std::move(*command), line});
  }
  if (!ok) return std::nullopt;
  return commands;
}

std::optional<std::vector<TimedCommand>> loadCommandSequence(const std::string& path, Diagnostics& diag,
                                                             const RobotModel* robot) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    diag.error(path, 0, "cannot open command sequence file");
    return std::nullopt;
  }
  std::string text;
  char chunk[4096];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) text.append(chunk, static_cast<size_t>(in.gcount()));
  if (in.bad()) {  // a directory, say
    diag.error(path, 0, "cannot read command sequence file");
    return std::nullopt;
  }
  return parseCommandSequence(text, path, diag, robot);
}

bool checkCommands(const std::vector<TimedCommand>& commands, const RobotModel& robot, std::string_view file,
                   Diagnostics& diag) {
  bool ok = true;
  for (const TimedCommand& c : commands) {
    CommandCheck check = checkCommand(c.command, robot);
    if (!check.ok()) {
      diag.error(file, c.line, std::move(check.message));
      ok = false;
    }
  }
  return ok;
}

bool checkCommands(const std::vector<TimedCommand>& commands, const WorldModel& world, std::string_view file,
                   Diagnostics& diag) {
  bool ok = true;
  const HeightGrid* grid = world.terrain.kind == TerrainSpec::Kind::Plane ? nullptr : &world.terrain.grid;
  for (const TimedCommand& c : commands) {
    std::string why;
    if (const auto* patch = std::get_if<TerrainPatchCmd>(&c.command)) why = patchFits(grid, *patch);
    else if (world.robots.empty()) why = "the world has no robot for this command";
    else why = checkCommand(c.command, world.robots[0].model).message;
    if (why.empty()) continue;
    diag.error(file, c.line, std::move(why));
    ok = false;
  }
  return ok;
}

}  // namespace sp
