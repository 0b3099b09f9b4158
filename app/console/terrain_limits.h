#pragma once
// What a robot can drive over, and whether a terrain edit asks more of it
// (issue 31): the console warns before a brush stroke makes a slope the
// robot cannot climb or a step a wheel cannot roll up.
//
// The limits come from the robot's and world's files, for a drive robot:
//
//   slope  a = min(atan mu, asin(sum of wheel torques / (r m g)))  grip or motors
//   step   r (1 - cos a)
//
// with mu the tyre-ground friction, r the wheel radius and m the robot's
// mass. A wheel meeting a step's edge touches it with the normal tilted by
// b from vertical, cos b = 1 - h/r: it stands on a local slope of b, and
// rolls up while that is a slope its share of the robot could climb.
// Conservative: the other wheels' push, or a leg lifting the wheel, takes
// more, so this is a warning, not a refusal.
//
//   auto limits = sp::drivableLimits(world);
//   if (auto risk = sp::strokeRisk(grid, patch, *limits)) warn(risk->message());
//
// Thread: any; plain functions of their arguments.

#include <cmath>
#include <optional>
#include <string>

#include "sim/command.h"
#include "sim/height_grid.h"
#include "sim/robot_model.h"

namespace sp {

struct DrivableLimits {
  double maxSlope = 0;   ///< [rad]
  double maxStep = 0;    ///< [m]
  double mu = 0;         ///< the tyre-ground friction they came from
  bool motorBound = false;  ///< the slope is the motors' limit, not grip's
  /// "wheels 0.20 m, grip mu 1.0, 4 x 60 N m for 230 kg": for the operator.
  std::string basis;
};

/// The limits of `world`'s robot `robot` on its terrain; nullopt when it
/// has no drive (nothing to say).
std::optional<DrivableLimits> drivableLimits(const WorldModel& world, int robot = 0);

struct TerrainRisk {
  double rise = 0;  ///< [m]
  double run = 0;   ///< [m] over which it rises
  Vec2 at;          ///< grid frame [m]: the midpoint of the two samples
  double grade() const { return std::atan2(rise, run); }
  /// "a 0.15 m rise over 0.10 m (56 deg): the robot climbs 32 deg (its
  /// motors' limit), a wheel rolls up 0.06 m"
  std::string message(const DrivableLimits& limits) const;
};

/// The steepest rise that `patch` makes on `grid` (within the patch's
/// rectangle and a wheel's diameter around it), measured between samples
/// up to a wheel's diameter apart along x or y, that is both higher than
/// a wheel rolls up and steeper than the robot climbs, and higher than the
/// same two samples rose before (the terrain's own steps are not the
/// stroke's); nullopt when there is none. `grid` is not changed.
std::optional<TerrainRisk> strokeRisk(const HeightGrid& grid, const TerrainPatchCmd& patch, const DrivableLimits& limits,
                                      double wheelRadius);

}  // namespace sp
