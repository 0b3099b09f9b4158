#pragma once
// Sensor readings of the twin. Each sensor of a robot file is sampled at its
// own rate at step boundaries; World keeps the latest sample of each.
// Frames: "world" is the world frame; "sensor" the sensor's mounting frame
// (its link frame moved by the sensor's pose).

#include <cstdint>
#include <limits>
#include <variant>
#include <vector>

#include "sim/math.h"

namespace sp {

/// Pose of a link's frame in the world. Noise: sigma [m] on each coordinate.
struct PoseReading {
  Pose pose;
  friend bool operator==(const PoseReading&, const PoseReading&) = default;
};

/// A 2-D scan in the sensor's xy plane, beams counter-clockwise from
/// angleMin. A range is +infinity when the beam hit nothing within maxRange,
/// and NaN when it hit something closer than minRange (invalid, as a real
/// scanner reports). Noise: sigma [m] on each hit.
struct LaserReading {
  Pose sensorPose;        ///< in the world, when the scan was taken
  double angleMin = 0;    ///< [rad] of the first beam, about the sensor's z
  double angleStep = 0;   ///< [rad] between beams
  double minRange = 0, maxRange = 0;  ///< [m]
  std::vector<double> ranges;         ///< [m]
  static constexpr double kNoReturn = std::numeric_limits<double>::infinity();
  friend bool operator==(const LaserReading&, const LaserReading&) = default;
};

/// Joint angle [rad] (or position [m]) and rate. Noise: sigma on the angle.
struct EncoderReading {
  double position = 0;
  double velocity = 0;
  friend bool operator==(const EncoderReading&, const EncoderReading&) = default;
};

/// Ground contact on one wheel, summed over its contact joints' feedback and
/// averaged over the steps since the previous sample (a force sensor's
/// low-pass output; ODE's per-step contact forces jitter): `force` is the
/// total force the contacts put on the wheel (world frame); `normal` its
/// component along the contact normals, `tangential` the size of the rest;
/// `contacts` the mean number of contact points. Noise: sigma [N] on normal
/// and tangential.
struct WheelForceReading {
  Vec3 force;
  double normal = 0;
  double tangential = 0;
  int contacts = 0;
  friend bool operator==(const WheelForceReading&, const WheelForceReading&) = default;
};

/// What a joint transmits to its child link (ODE joint feedback), world
/// frame. Noise: sigma [N] on each force component.
struct JointForceReading {
  Vec3 force;   ///< [N]
  Vec3 torque;  ///< [N m], about the child's centre of mass
  friend bool operator==(const JointForceReading&, const JointForceReading&) = default;
};

/// Inclination and inertial readings, sensor frame. `acceleration` is the
/// specific force (what an accelerometer reads: +g upwards at rest),
/// averaged over the sampling period. Noise: the same sigma, in SI units, on
/// every component (roll and pitch [rad], rates [rad/s], accelerations [m/s^2]).
struct ImuReading {
  double roll = 0, pitch = 0;  ///< [rad], of the sensor frame against gravity
  Vec3 angularRate;            ///< [rad/s]
  Vec3 acceleration;           ///< [m/s^2]
  friend bool operator==(const ImuReading&, const ImuReading&) = default;
};

using SensorValue = std::variant<PoseReading, LaserReading, EncoderReading, WheelForceReading,
                                 JointForceReading, ImuReading>;

/// One sample: which sensor, when, and the reading.
struct SensorSample {
  int robot = -1;
  int sensor = -1;    ///< index in the robot's sensors
  int64_t step = -1;  ///< step count when taken; -1 = not sampled yet
  double time = 0;    ///< [s]
  SensorValue value;
  friend bool operator==(const SensorSample&, const SensorSample&) = default;
};

}  // namespace sp
