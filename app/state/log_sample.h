#pragma once
// A row of a session log (app/log/session_log.h): one state sample at the
// logging rate. A plain value; its conversions are in robot_shapes.h.

#include <array>
#include <cstdint>
#include <vector>

namespace sp {

/// One state sample at the logging rate.
struct LogSample {
  int64_t step = 0;
  double time = 0;                   ///< [s]
  std::array<double, 3> base{};      ///< base link position, world [m]
  std::array<double, 4> quat{1, 0, 0, 0};  ///< base orientation w, x, y, z
  std::vector<double> joints;        ///< positions [rad or m] then velocities
  std::array<double, 4> wheelNormal{};  ///< wheel normal forces FL, FR, RL, RR [N]
  std::array<double, 4> wheelTangential{};  ///< ... and across the normal [N]; 0 in older logs
  double roll = 0, pitch = 0;        ///< [rad]
  friend bool operator==(const LogSample&, const LogSample&) = default;
};

}  // namespace sp
