#pragma once
// The parameters a run, the console's twins or the stand-in start from.

#include <optional>
#include <string>
#include <vector>

#include "sim/diagnostics.h"
#include "sim/params.h"

namespace sp {

/// Loads the parameters: defaults, then the file, then the overrides.
std::optional<SimParams> loadRunParams(const std::string& paramsFile,
                                       const std::vector<std::string>& overrides, Diagnostics& diag);

}  // namespace sp
