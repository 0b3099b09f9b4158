#pragma once
// Small value types for poses. Right-handed, z up, SI units, radians.

#include <array>
#include <cmath>

namespace sp {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double degToRad(double deg) { return deg * kPi / 180.0; }
inline constexpr double radToDeg(double rad) { return rad * 180.0 / kPi; }

/// A point or vector in a plane (the ground, a grid) [m].
struct Vec2 {
  double x = 0, y = 0;
  friend bool operator==(const Vec2&, const Vec2&) = default;
};

struct Vec3 {
  double x = 0, y = 0, z = 0;

  friend Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
  friend Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
  friend bool operator==(const Vec3&, const Vec3&) = default;
};

inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(Vec3 a) { return std::sqrt(dot(a, a)); }
Vec3 normalized(Vec3 a);

/// Unit quaternion, ODE's order (w, x, y, z).
struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
  friend bool operator==(const Quat&, const Quat&) = default;
};

Quat operator*(const Quat& a, const Quat& b);
Quat conjugate(const Quat& q);
Vec3 rotate(const Quat& q, Vec3 v);
/// Roll about x, then pitch about y, then yaw about z (fixed axes), i.e.
/// R = Rz(yaw) * Ry(pitch) * Rx(roll), as in URDF and SDF.
Quat quatFromRpy(Vec3 rpy);
Vec3 rpyFromQuat(const Quat& q);
Quat quatFromAxisAngle(Vec3 axis, double angle);
/// Where the frame's x axis points in the ground plane [rad] about z
/// (its yaw, well defined for any roll and pitch short of vertical).
double heading(const Quat& q);
/// Roll and pitch [rad] of a frame, from where the world's "up" lies in it
/// (x = roll about the frame's x, y = pitch; z unused): what an IMU and the
/// flight rules report.
Vec3 tilt(const Quat& q);

/// A rigid transform: first rotate, then translate.
struct Pose {
  Vec3 p;
  Quat q;
  friend bool operator==(const Pose&, const Pose&) = default;
};

/// a * b: b expressed in a's parent frame, given b in a's frame.
Pose operator*(const Pose& a, const Pose& b);
Pose inverse(const Pose& a);
inline Vec3 transformPoint(const Pose& a, Vec3 v) { return a.p + rotate(a.q, v); }

}  // namespace sp
