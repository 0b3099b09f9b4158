#include "app/console/terrain_limits.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sp {

std::optional<DrivableLimits> drivableLimits(const WorldModel& world, int robot) {
  if (robot < 0 || static_cast<size_t>(robot) >= world.robots.size()) return std::nullopt;
  const RobotModel& model = world.robots[static_cast<size_t>(robot)].model;
  if (!model.drive || model.drive->wheelRadius <= 0) return std::nullopt;
  const DriveSpec& drive = *model.drive;
  // The tyres' material: the first geom's of the first wheel that has one.
  std::string tyre;
  for (int j : drive.wheels)
    if (j >= 0)
      for (const GeomSpec& g : model.links[static_cast<size_t>(model.joints[static_cast<size_t>(j)].child)].geoms)
        if (tyre.empty()) tyre = g.material;
  DrivableLimits l;
  l.mu = world.contactFor(tyre, world.terrain.material).mu;
  double torque = 0;
  for (int j : drive.wheels) {
    const int a = j >= 0 ? model.findActuator(model.joints[static_cast<size_t>(j)].name) : -1;
    if (a >= 0) torque += model.actuators[static_cast<size_t>(a)].maxTorque;
  }
  const double weight = model.totalMass() * std::hypot(world.gravity.x, world.gravity.y, world.gravity.z);
  const double grip = std::atan(l.mu);
  const double motors = weight > 0 ? std::asin(std::min(1.0, torque / drive.wheelRadius / weight)) : grip;
  l.motorBound = motors < grip;
  l.maxSlope = std::min(grip, motors);
  l.maxStep = drive.wheelRadius * (1 - std::cos(l.maxSlope));
  char text[160];
  std::snprintf(text, sizeof text, "wheels %.2f m, grip mu %.2f, %.0f N m of wheel torque for %.0f kg",
                drive.wheelRadius, l.mu, torque, model.totalMass());
  l.basis = text;
  return l;
}

std::string TerrainRisk::message(const DrivableLimits& limits) const {
  char text[200];
  std::snprintf(text, sizeof text, "a %.2f m rise over %.2f m (%.0f deg): the robot climbs %.0f deg (%s), a wheel rolls up %.2f m",
                rise, run, grade() * 180 / kPi, limits.maxSlope * 180 / kPi,
                limits.motorBound ? "its motors' limit" : "its grip's limit", limits.maxStep);
  return text;
}

std::optional<TerrainRisk> strokeRisk(const HeightGrid& grid, const TerrainPatchCmd& patch, const DrivableLimits& limits,
                                      double wheelRadius) {
  if (grid.columns < 2 || grid.rows < 2 || patch.columns < 1 || patch.rows < 1) return std::nullopt;
  const auto height = [&](int i, int j) {
    const int k = i - patch.column, r = j - patch.row;
    if (k >= 0 && k < patch.columns && r >= 0 && r < patch.rows)
      return patch.heights[static_cast<size_t>(r) * static_cast<size_t>(patch.columns) + static_cast<size_t>(k)];
    return grid.at(i, j);
  };
  constexpr double kWorse = 1e-3;  // [m]: what a stroke must add to a rise to have made it
  // Runs up to a wheel's diameter: a rise spread over a few fine samples
  // is as much a step to a wheel as one between two coarse ones.
  const double sx = grid.spacingX(), sy = grid.spacingY();
  const int kx = std::max(1, static_cast<int>(2 * wheelRadius / sx)), ky = std::max(1, static_cast<int>(2 * wheelRadius / sy));
  const int i0 = std::max(0, patch.column - kx), j0 = std::max(0, patch.row - ky);
  const int i1 = std::min(grid.columns - 1, patch.column + patch.columns - 1 + kx);
  const int j1 = std::min(grid.rows - 1, patch.row + patch.rows - 1 + ky);
  const double tanLimit = std::tan(limits.maxSlope);
  std::optional<TerrainRisk> worst;
  const auto consider = [&](int ia, int ja, int ib, int jb, double run) {
    const double rise = std::abs(height(ib, jb) - height(ia, ja));
    if (rise <= limits.maxStep || rise <= tanLimit * run) return;  // a wheel takes it, or the robot climbs it
    if (rise <= std::abs(grid.at(ib, jb) - grid.at(ia, ja)) + kWorse) return;  // it was there before
    if (worst && rise * worst->run <= worst->rise * run) return;    // not steeper than the worst so far
    worst = TerrainRisk{rise, run, {-grid.width / 2 + (ia + ib) * sx / 2, -grid.depth / 2 + (ja + jb) * sy / 2}};
  };
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      for (int k = 1; k <= kx && i + k <= i1; ++k) consider(i, j, i + k, j, k * sx);
      for (int k = 1; k <= ky && j + k <= j1; ++k) consider(i, j, i, j + k, k * sy);
    }
  return worst;
}

}  // namespace sp
