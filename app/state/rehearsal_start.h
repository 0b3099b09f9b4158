#pragma once
// Where a rehearsal starts (app/rehearse/): the robot's state as telemetry
// or a log reports it. A plain value, so that what reads it from a log or a
// link need not know the rehearsal.

#include <string>
#include <utility>
#include <vector>

#include "sim/math.h"
#include "sim/rigid.h"
#include "sim/world.h"

namespace sp {

/// The robot's state to rehearse from, as telemetry reports it.
struct RehearsalStart {
  Pose base;
  Vec3 baseLinear, baseAngular;        ///< world frame [m/s], [rad/s]
  std::vector<double> jointPositions;  ///< model joint order
  std::vector<double> jointRates;
  std::vector<std::pair<std::string, Pose>> objects;  ///< dynamic objects by name
};

/// Puts robot 0 of `world` in `start` (links' poses and velocities, the
/// objects named) with its controllers holding that pose: position joints
/// target where they are, velocity joints 0. `held`: the world runs this
/// rigid form of the robot (start joints are the full robot's). "" or why
/// the state does not fit.
std::string placeRobot(World& world, const RehearsalStart& start, const RigidRobot* held = nullptr);

}  // namespace sp
