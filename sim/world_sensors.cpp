// Sensor sampling: each sensor at its own rate, wheel forces averaged over
// the steps between samples, noise from the world's own random engine.

#include "sim/world_impl.h"

#include <algorithm>

namespace sp {
using namespace world_detail;

void World::accumulateWheelForces() {
  Impl& m = *impl_;
  for (Impl::Robot& rt : m.robots)
    for (SensorState& st : rt.sensors) ++st.stepsSummed;  // only wheel_force reads it
  for (const Impl::WheelContact& c : m.wheelContacts) {
    SensorState& st = m.robots[c.robot].sensors[c.sensor];
    const dJointFeedback& f = m.contactFeedback[c.feedback];
    const dReal* fv = c.wheelInF1 ? f.f1 : f.f2;
    const Vec3 force{fv[0], fv[1], fv[2]};
    st.forceSum = st.forceSum + force;
    st.normalSum = st.normalSum + dot(force, c.normal) * c.normal;
    ++st.contactSum;
  }
}

void World::sampleSensors() {
  Impl& m = *impl_;
  const double t = time();
  for (size_t r = 0; r < m.robots.size(); ++r) {
    Impl::Robot& rt = m.robots[r];
    const RobotModel& robot = robotModel(static_cast<int>(r));
    for (size_t si = 0; si < robot.sensors.size(); ++si) {
      SensorState& st = rt.sensors[si];
      if (steps_ < st.nextStep) continue;
      if (!options_.sensors && robot.sensors[si].type != SensorType::WheelForce) continue;  // WorldOptions::wheelForces
      const int64_t period = rt.sensorPeriod[si];
      st.nextStep += period;
      const SensorSpec& spec = robot.sensors[si];
      const double sigma = spec.noise;
      auto noise = [&] { return sigma > 0 ? sigma * m.random.normal() : 0.0; };
      SensorSample& out = st.latest;
      out.step = steps_;
      out.time = t;
      switch (spec.type) {
        case SensorType::Pose: {
          PoseReading p{linkPose(static_cast<int>(r), spec.link) * spec.pose};
          if (sigma > 0) p.pose.p = p.pose.p + Vec3{noise(), noise(), noise()};
          out.value = p;
          break;
        }
        case SensorType::Encoder: {
          EncoderReading e{jointPosition(static_cast<int>(r), spec.joint), jointRate(static_cast<int>(r), spec.joint)};
          e.position += noise();
          out.value = e;
          break;
        }
        case SensorType::JointForce: {
          const dJointFeedback& f = rt.jointFeedback[spec.joint];
          // The child is ODE's body 1 (see the joint attach order).
          JointForceReading jf{{f.f1[0], f.f1[1], f.f1[2]}, {f.t1[0], f.t1[1], f.t1[2]}};
          jf.force = jf.force + Vec3{noise(), noise(), noise()};
          out.value = jf;
          break;
        }
        case SensorType::WheelForce: {
          // The mean over the steps since the last sample (accumulateWheelForces).
          WheelForceReading w;
          const double n = std::max(1, st.stepsSummed);
          w.force = (1.0 / n) * st.forceSum;
          const Vec3 normal = (1.0 / n) * st.normalSum;
          w.normal = norm(normal);
          w.tangential = norm(w.force - normal);
          w.contacts = static_cast<int>(std::lround(st.contactSum / n));
          st.forceSum = st.normalSum = Vec3{};
          st.contactSum = st.stepsSummed = 0;
          w.normal += noise();
          w.tangential += noise();
          out.value = w;
          break;
        }
        case SensorType::Imu: {
          const Pose sensor = linkPose(static_cast<int>(r), spec.link) * spec.pose;
          dVector3 v;
          dBodyGetPointVel(rt.bodies[spec.link], sensor.p.x, sensor.p.y, sensor.p.z, v);
          const Vec3 vel{v[0], v[1], v[2]};
          const Vec3 accelWorld = (1.0 / (static_cast<double>(period) * params_.step)) * (vel - st.lastVelocity);
          st.lastVelocity = vel;
          const Quat toSensor = conjugate(sensor.q);
          ImuReading imu;
          imu.acceleration = rotate(toSensor, accelWorld - model_.gravity);
          imu.angularRate = rotate(toSensor, linkAngularVelocity(static_cast<int>(r), spec.link));
          // Roll and pitch from where gravity's "up" lies in the sensor frame.
          const Vec3 tilted = tilt(sensor.q);
          imu.roll = tilted.x;
          imu.pitch = tilted.y;
          imu.roll += noise();
          imu.pitch += noise();
          imu.angularRate = imu.angularRate + Vec3{noise(), noise(), noise()};
          imu.acceleration = imu.acceleration + Vec3{noise(), noise(), noise()};
          out.value = imu;
          break;
        }
        case SensorType::Laser: {
          LaserReading scan;
          scan.sensorPose = linkPose(static_cast<int>(r), spec.link) * spec.pose;
          scan.minRange = spec.minRange;
          scan.maxRange = spec.maxRange;
          scan.angleMin = -spec.fov / 2;
          scan.angleStep = spec.beams > 1 ? spec.fov / (spec.beams - 1) : 0;
          scan.ranges.resize(static_cast<size_t>(spec.beams));
          // The scanner never sees the link it sits in; the rest of its
          // robot only without exclude_self.
          const int excludeLink = spec.excludeSelf ? -1 : spec.link;
          castFan(scan.sensorPose, scan.angleMin, scan.angleStep, spec.maxRange, static_cast<int>(r), excludeLink,
                  scan.ranges);
          for (double& range : scan.ranges) {
            if (std::isfinite(range)) {
              range += noise();
              if (range < spec.minRange) range = std::nan("");
              else if (range > spec.maxRange) range = LaserReading::kNoReturn;
            }
          }
          out.value = std::move(scan);
          break;
        }
      }
      sampledLastStep_.emplace_back(static_cast<int>(r), static_cast<int>(si));
    }
  }
}

const SensorSample& World::sensorSample(int robot, int sensor) const {
  return impl_->robots[robot].sensors[sensor].latest;
}

}  // namespace sp
