#pragma once
// A small versioned binary form of sp::Snapshot for the session log:
// little-endian uint64/int64/doubles (doubles bit for bit, NaN payloads
// included), so a decoded snapshot restores exactly what was encoded.
//
// Layout: "SPSN", uint32 version (1), then every field of Snapshot in
// declaration order; vectors and strings carry a uint64 length, variants a
// uint8 index. The terrain heights are stored when the snapshot has them.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/world.h"

namespace sp {

inline constexpr uint32_t kSnapshotCodecVersion = 3;  // 2: motion resistance per link; 3: its hold (1 and 2 are still read)

/// Serializes a snapshot. Thread: any; pure function.
std::vector<uint8_t> encodeSnapshot(const Snapshot& snapshot);

/// Parses what encodeSnapshot wrote. Returns nullopt and sets `error` (if
/// not null) on a wrong magic, an unknown version or truncated data.
/// Thread: any; pure function.
std::optional<Snapshot> decodeSnapshot(const std::vector<uint8_t>& data, std::string* error = nullptr);

}  // namespace sp
