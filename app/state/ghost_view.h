#pragma once
// What the predictive ghost (app/ghost/ghost.h) shows: a plain value the
// views draw; its conversion to a RobotFrame is in robot_shapes.h.

#include <cstdint>
#include <string>
#include <vector>

#include "sim/math.h"
#include "sim/readout.h"

namespace sp {

/// What the ghost shows now.
struct GhostView {
  int64_t version = 0;       ///< counts views; 0 = none yet (no telemetry)
  double time = 0;           ///< [s] robot time shown
  double span = 0;           ///< [s] how far ahead of the newest telemetry that is
  Pose base;                 ///< link 0 in the world
  std::vector<double> jointPositions;  ///< model joint order
  std::vector<ObjectReadout> objects;  ///< dynamic objects
  std::vector<Vec3> trail;   ///< the base's path on the ground (x, y, terrain height) from `time` on, every 0.1 s, over ghost.horizon
  double trailTime = 0;      ///< [s] robot time the trail starts at
  std::string problem;       ///< "" or why the ghost cannot predict (it diverged, a bad frame)
  uint64_t commands = 0;     ///< of the commands sent (commandsSent()), how many this state has had
};

}  // namespace sp
