#pragma once
// The `key = value` properties format shared by the parameters file
// (sim/params.h) and the rehearsal's rules file (sim/flight_rules.h): one
// assignment per line, `#` starts a comment (also after a value), blank lines
// ignored, each key at most once.

#include <functional>
#include <string_view>

#include "sim/diagnostics.h"

namespace sp {

/// Reads every assignment of `contents` (`path` names it in diagnostics) and
/// hands it to `set(key, value, line)`, which reports its own problems and
/// returns false on one. Lines that are no assignment and repeated keys
/// (those `known` accepts; an unknown key is `set`'s to report, each time) are
/// reported here. Returns true when no line had a problem. Reading goes on
/// after a problem, so that a file's errors come in one pass.
bool readProperties(std::string_view contents, std::string_view path, Diagnostics& diag,
                    const std::function<bool(std::string_view key)>& known,
                    const std::function<bool(std::string_view key, std::string_view value, int line)>& set);

}  // namespace sp
