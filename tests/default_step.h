#pragma once
// Step numbers at the default physics step, so tests about logs, snapshots
// and sensor rates follow the default (docs/validation/convergence.md) rather
// than pinning one.

#include <cmath>
#include <cstdint>

#include "sim/params.h"

namespace sp::test {

/// The default physics step [s].
inline double defaultStep() { return SimParams{}.step; }

/// The step at which `seconds` of sim time end at `step` (the default's unless given).
inline int64_t stepAt(double seconds, double step = defaultStep()) { return std::llround(seconds / step); }

}  // namespace sp::test
