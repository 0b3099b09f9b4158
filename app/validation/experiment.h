#pragma once
// What the validation experiments (one file each: circular_drive.cpp,
// laser_sweep.cpp, pick_and_place.cpp, slippery_surface.cpp,
// test_track.cpp) share: their worlds, the checks of their runs, fits and
// numbers. Internal to app/validation/.

#include <algorithm>
#include <chrono>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "sim/command_file.h"
#include "sim/hash.h"
#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/readout.h"
#include "sim/runner.h"
#include "sim/text.h"
#include "sim/world.h"

#include "app/validation/validation.h"

namespace sp::experiment {

using Clock = std::chrono::steady_clock;

inline std::string num(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

inline WorldModel loadModel(const ValidationOptions& o, const std::string& relative) {
  Diagnostics diag;
  std::optional<WorldModel> model = loadWorld(o.sourceDir + "/" + relative, diag);
  if (!model) throw std::runtime_error(diag.format());
  return *model;
}

inline std::unique_ptr<World> makeWorld(const WorldModel& model, const SimParams& params) {
  Diagnostics diag;
  std::unique_ptr<World> w = World::create(model, params, diag);
  if (!w) throw std::runtime_error(diag.format());
  return w;
}

inline void stepFor(World& w, double seconds) { Runner(w).advanceBy(std::llround(seconds / w.params().step)); }

inline void requireHealthy(const World& w, const std::string& experiment) {
  if (!w.health().healthy())
    throw std::runtime_error(experiment + ": the twin diverged: " + w.health().message());
}

/// The articulation hinge's position in the world (the robot's centre).
inline Vec3 hingePoint(const World& w) {
  const RobotModel& robot = w.robotModel(0);
  const JointSpec& hinge = robot.joints[robot.drive->articulation];
  const Pose parent = w.linkPose(0, hinge.parent) * inverse(robot.links[hinge.parent].pose);
  return transformPoint(parent, hinge.anchor);
}

/// Mean normal forces of the four wheel_force sensors (FL, FR, RL, RR).
inline std::array<double, 4> wheelNormals(const World& w) { return readRobot(w).wheelNormal; }

/// Least-squares circle through points (Kasa): centre and radius.
inline std::pair<Vec3, double> fitCircle(const std::vector<Vec3>& p) {
  double n = static_cast<double>(p.size()), mx = 0, my = 0;
  for (const Vec3& q : p) {
    mx += q.x / n;
    my += q.y / n;
  }
  double suu = 0, svv = 0, suv = 0, suuu = 0, svvv = 0, suvv = 0, svuu = 0;
  for (const Vec3& q : p) {
    const double u = q.x - mx, v = q.y - my;
    suu += u * u, svv += v * v, suv += u * v;
    suuu += u * u * u, svvv += v * v * v, suvv += u * v * v, svuu += v * u * u;
  }
  const double det = suu * svv - suv * suv, b0 = (suuu + suvv) / 2, b1 = (svvv + svuu) / 2;
  const double uc = (b0 * svv - b1 * suv) / det, vc = (suu * b1 - suv * b0) / det;
  return {{uc + mx, vc + my, 0}, std::sqrt(uc * uc + vc * vc + (suu + svv) / n)};
}

inline double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}

/// Centred moving average over `window` samples (the plots show trends;
/// the quick solver's contact forces jitter from step to step).
inline std::vector<double> smooth(const std::vector<double>& v, size_t window) {
  std::vector<double> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    const size_t lo = i >= window / 2 ? i - window / 2 : 0, hi = std::min(v.size(), i + window / 2 + 1);
    double sum = 0;
    for (size_t k = lo; k < hi; ++k) sum += v[k];
    out[i] = sum / static_cast<double>(hi - lo);
  }
  return out;
}

/// Slope of y over x by least squares.
inline double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double mx = mean(x), my = mean(y);
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxx > 0 ? sxy / sxx : 0;
}

}  // namespace sp::experiment
