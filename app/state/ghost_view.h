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
  // How sure the ghost is (app/ghost/ghost_region.h).
  double scale = 0;          ///< [m] the error scale of the state shown (0: none)
  double inner = 0, outer = 0;  ///< [m] radii of the inner and outer regions about `base`
  double innerLevel = 0.5, outerLevel = 0.9;  ///< their levels (ghost.region.*)
  std::vector<double> trailBand;  ///< [m] the outer region's radius at each trail point
  std::string departure;     ///< "" or the departure on now, for the operator
  uint64_t commands = 0;     ///< of the commands sent (commandsSent()), how many this state has had
};

}  // namespace sp
