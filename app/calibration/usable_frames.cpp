#include "app/calibration/usable_frames.h"

#include <cmath>

namespace sp::calibration_detail {

std::vector<RobotFrame> usableFrames(const std::vector<RobotFrame>& in, double window) {
  std::vector<RobotFrame> f;
  const double from = in.empty() || window <= 0 ? -1e300 : in.back().time - window;
  for (const RobotFrame& r : in)
    if (r.time >= from && r.health.empty() && !r.estop && !r.failsafe && (f.empty() || r.time > f.back().time))
      f.push_back(r);
  for (size_t i = 0; i < f.size(); ++i) {
    if (f[i].hasBaseVelocity) continue;
    const RobotFrame& a = f[i == 0 ? 0 : i - 1];
    const RobotFrame& b = f[i + 1 < f.size() ? i + 1 : i];
    const double dt = b.time - a.time;
    if (dt <= 0) continue;
    f[i].baseLinearVelocity = (1 / dt) * (b.base.p - a.base.p);
    // Rotation vector of a -> b, world frame.
    Quat d = b.base.q * conjugate(a.base.q);
    if (d.w < 0) d = Quat{-d.w, -d.x, -d.y, -d.z};
    const double s = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    const double angle = 2 * std::atan2(s, d.w);
    f[i].baseAngularVelocity = s > 1e-12 ? (angle / dt / s) * Vec3{d.x, d.y, d.z} : Vec3{};
    f[i].hasBaseVelocity = true;
  }
  return f;
}

}  // namespace sp::calibration_detail
