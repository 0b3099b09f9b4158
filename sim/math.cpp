#include "sim/math.h"

namespace sp {

Vec3 normalized(Vec3 a) {
  const double n = norm(a);
  return n > 0 ? (1.0 / n) * a : a;
}

Quat operator*(const Quat& a, const Quat& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
          a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

Quat conjugate(const Quat& q) { return {q.w, -q.x, -q.y, -q.z}; }

Vec3 rotate(const Quat& q, Vec3 v) {
  // v' = v + 2w(u x v) + 2 u x (u x v), u the vector part.
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = 2.0 * cross(u, v);
  return v + q.w * t + cross(u, t);
}

Vec3 tilt(const Quat& q) {
  const Vec3 up = rotate(conjugate(q), {0, 0, 1});
  return {std::atan2(up.y, up.z), std::atan2(-up.x, std::hypot(up.y, up.z)), 0};
}

double heading(const Quat& q) {
  const Vec3 x = rotate(q, {1, 0, 0});
  return std::atan2(x.y, x.x);
}

Quat quatFromAxisAngle(Vec3 axis, double angle) {
  const Vec3 a = normalized(axis);
  const double s = std::sin(angle / 2);
  return {std::cos(angle / 2), a.x * s, a.y * s, a.z * s};
}

Quat quatFromRpy(Vec3 rpy) {
  return quatFromAxisAngle({0, 0, 1}, rpy.z) * quatFromAxisAngle({0, 1, 0}, rpy.y) *
         quatFromAxisAngle({1, 0, 0}, rpy.x);
}

Vec3 rpyFromQuat(const Quat& q) {
  const double sinp = 2 * (q.w * q.y - q.z * q.x);
  return {std::atan2(2 * (q.w * q.x + q.y * q.z), 1 - 2 * (q.x * q.x + q.y * q.y)),
          std::abs(sinp) >= 1 ? std::copysign(kPi / 2, sinp) : std::asin(sinp),
          std::atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))};
}

Pose operator*(const Pose& a, const Pose& b) { return {a.p + rotate(a.q, b.p), a.q * b.q}; }

Pose inverse(const Pose& a) {
  const Quat qi = conjugate(a.q);
  return {-rotate(qi, a.p), qi};
}

}  // namespace sp
