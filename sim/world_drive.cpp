// Actuation: commands applied at step boundaries, the articulated-steering
// drive (workpartner-facts.md section 3), gaits, and the actuators feeding ODE's
// joint motors.

#include "sim/world_impl.h"

#include <algorithm>
#include <type_traits>
#include <variant>

namespace sp {
using namespace world_detail;

std::array<double, 4> articulatedWheelSpeeds(const DriveGeometry& g, double speed, double wheelRadius) {
  const double gamma = g.articulation;
  if (std::abs(gamma) < 1e-6) {
    const double w = speed / wheelRadius;
    return {w, w, w, w};
  }
  // Instantaneous centre O of the two axle lines (workpartner-facts.md §3):
  // signed radii, positive when O lies to the left (gamma > 0).
  const double s = std::sin(gamma), c = std::cos(gamma);
  const double lf = g.frontLength, lr = g.rearLength;
  const double rRear = (lf + lr * c) / s;
  const double rFront = (lr + lf * c) / s;
  const double rHinge = std::copysign(std::sqrt(lr * lr + rRear * rRear), s);
  const double yawRate = speed / rHinge;
  return {yawRate * (rFront - g.frontTrack / 2) / wheelRadius,
          yawRate * (rFront + g.frontTrack / 2) / wheelRadius,
          yawRate * (rRear - g.rearTrack / 2) / wheelRadius,
          yawRate * (rRear + g.rearTrack / 2) / wheelRadius};
}

double articulationForTurn(const DriveGeometry& g, double speed, double yawRate, double maxAngle) {
  if (yawRate == 0 || speed == 0) return 0;
  // The hinge radius R_H = |speed / yawRate| grows monotonically smaller as
  // gamma grows on (0, pi): bisect for it.
  const double wanted = std::abs(speed / yawRate);
  auto radius = [&](double gamma) {
    const double rRear = (g.frontLength + g.rearLength * std::cos(gamma)) / std::sin(gamma);
    return std::hypot(g.rearLength, rRear);
  };
  double lo = 1e-6, hi = std::min(maxAngle, kPi - 1e-3);
  if (radius(hi) > wanted) return std::copysign(hi, yawRate * speed);  // tighter than the hinge allows
  for (int i = 0; i < 60; ++i) {
    const double mid = (lo + hi) / 2;
    (radius(mid) > wanted ? lo : hi) = mid;
  }
  return std::copysign((lo + hi) / 2, yawRate * speed);
}

void World::applyCommand(const Command& command, int robot) {
  if (const auto* patch = std::get_if<TerrainPatchCmd>(&command)) {
    applyTerrainPatch(*patch);
    return;
  }
  Impl::Robot& rt = impl_->robots[robot];
  const RobotModel& model = robotModel(robot);
  auto actuatorOf = [&](const std::string& joint) { return model.findActuator(joint); };
  auto cancelDriveIfDriveJoint = [&](int actuator) {
    if (rt.legs)
      for (const LegJoints& leg : *rt.legs)
        if (model.actuators[actuator].joint == leg.hip || model.actuators[actuator].joint == leg.knee ||
            model.actuators[actuator].joint == leg.wheel)
          rt.control.gaitActive = false;
    if (!model.drive) return;
    const int joint = model.actuators[actuator].joint;
    const DriveSpec& d = *model.drive;
    if (joint == d.articulation || std::find(d.wheels.begin(), d.wheels.end(), joint) != d.wheels.end())
      rt.control.driveActive = false;
  };
  auto setMode = [&](ActuatorState& s, JointMode mode) {
    if (s.mode != mode) s.integral = 0;
    s.mode = mode;
  };
  std::visit(
      [&](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, JointVelocityCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], JointMode::Velocity);
          rt.control.actuators[a].velocity = c.velocity;
        } else if constexpr (std::is_same_v<T, JointTargetCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], JointMode::Position);
          rt.control.actuators[a].target = c.position;
        } else if constexpr (std::is_same_v<T, JointTorqueCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], JointMode::Torque);
          rt.control.actuators[a].torque = c.torque;
        } else if constexpr (std::is_same_v<T, JointModeCmd>) {
          const int a = actuatorOf(c.joint);
          cancelDriveIfDriveJoint(a);
          setMode(rt.control.actuators[a], c.mode);
        } else if constexpr (std::is_same_v<T, WheelsCmd>) {
          rt.control.driveActive = false;
          rt.control.gaitActive = false;
          for (int w = 0; w < 4; ++w) {
            const int a = actuatorOf(model.joints[model.drive->wheels[w]].name);
            setMode(rt.control.actuators[a], JointMode::Velocity);
            rt.control.actuators[a].velocity = c.omega[w];
          }
        } else if constexpr (std::is_same_v<T, TurnCmd>) {
          rt.control.gaitActive = false;
          rt.control.driveActive = true;
          rt.control.driveByYawRate = true;
          rt.control.driveSpeed = c.speed;
          rt.control.driveYawRate = c.yawRate;
        } else if constexpr (std::is_same_v<T, DriveCmd>) {
          rt.control.gaitActive = false;
          rt.control.driveByYawRate = false;
          rt.control.driveActive = true;
          rt.control.driveSpeed = c.speed;
          rt.control.driveArticulation = c.articulation;
        } else if constexpr (std::is_same_v<T, GaitCmd>) {
          rt.control.driveActive = false;
          rt.control.gaitActive = true;
          rt.control.gait = GaitState{c.gait, 0, steps_};
        } else if constexpr (std::is_same_v<T, TerrainPatchCmd>) {
          // Applied above: it belongs to no robot.
        } else if constexpr (std::is_same_v<T, StopCmd>) {
          // Wheels and speed-driven joints brake; joints with a position
          // controller hold where they are now; free joints stay free.
          rt.control.driveActive = false;
          rt.control.gaitActive = false;
          for (size_t a = 0; a < model.actuators.size(); ++a) {
            ActuatorState& s = rt.control.actuators[a];
            const ActuatorSpec& spec = model.actuators[a];
            if (s.mode == JointMode::Free) continue;
            bool isWheel = false;
            if (model.drive)
              for (int w : model.drive->wheels) isWheel = isWheel || w == spec.joint;
            if (spec.hasPid && spec.kp > 0 && !isWheel) {
              // A position-controlled joint that is moving stops where it is;
              // one that is still (a gripper squeezing a pole, a leg carrying
              // load) keeps its target and so its force.
              const bool moving = std::abs(jointRate(robot, spec.joint)) > 1e-3;
              if (s.mode != JointMode::Position || moving) s.target = jointPosition(robot, spec.joint);
              setMode(s, JointMode::Position);
            } else {
              setMode(s, JointMode::Velocity);
              s.velocity = 0;
            }
          }
        }
      },
      command);
}

std::optional<DriveGeometry> World::driveGeometry(int robot) const {
  const RobotModel& model = robotModel(robot);
  if (!model.drive) return std::nullopt;
  const Impl::Robot& rt = impl_->robots[robot];
  const DriveSpec& d = *model.drive;
  auto wheelCentre = [&](int w) {
    const dReal* p = dBodyGetPosition(rt.bodies[model.joints[d.wheels[w]].child]);
    return Vec3{p[0], p[1], p[2]};
  };
  auto planar = [](Vec3 a, Vec3 b) { return std::hypot(a.x - b.x, a.y - b.y); };
  dVector3 h;
  dJointGetHingeAnchor(rt.joints[d.articulation], h);
  const Vec3 hinge{h[0], h[1], h[2]};
  const Vec3 fl = wheelCentre(0), fr = wheelCentre(1), rl = wheelCentre(2), rr = wheelCentre(3);
  DriveGeometry g;
  g.frontLength = planar(0.5 * (fl + fr), hinge);
  g.rearLength = planar(0.5 * (rl + rr), hinge);
  g.frontTrack = planar(fl, fr);
  g.rearTrack = planar(rl, rr);
  g.articulation = jointPosition(robot, d.articulation);
  return g;
}

void World::runActuators() {
  Impl& m = *impl_;
  const double dt = params_.step;
  for (size_t r = 0; r < m.robots.size(); ++r) {
    Impl::Robot& rt = m.robots[r];
    const RobotModel& model = robotModel(static_cast<int>(r));
    if (rt.control.driveActive && model.drive) {
      const DriveSpec& d = *model.drive;
      const DriveGeometry geometry = *driveGeometry(static_cast<int>(r));
      if (rt.control.driveByYawRate) {
        const JointSpec& hinge = model.joints[d.articulation];
        const double limit = hinge.limited ? std::min(std::abs(hinge.lower), std::abs(hinge.upper)) : kPi / 2;
        rt.control.driveArticulation =
            articulationForTurn(geometry, rt.control.driveSpeed, rt.control.driveYawRate, limit);
      }
      const std::array<double, 4> w = articulatedWheelSpeeds(geometry, rt.control.driveSpeed, d.wheelRadius);
      for (int i = 0; i < 4; ++i) {
        ActuatorState& s = rt.control.actuators[model.findActuator(model.joints[d.wheels[i]].name)];
        s.mode = JointMode::Velocity;
        s.velocity = w[i];
      }
      ActuatorState& art = rt.control.actuators[model.findActuator(model.joints[d.articulation].name)];
      if (art.mode != JointMode::Position) art.integral = 0;
      art.mode = JointMode::Position;
      art.target = rt.control.driveArticulation;
    }
    if (rt.control.gaitActive && rt.legs) {
      const std::array<LegCommand, 4> legs =
          gaitStep(params_, rt.control.gait, steps_, params_.step, rt.legLength, model.drive->wheelRadius);
      auto actuatorOf = [&](int joint) -> ActuatorState& {
        return rt.control.actuators[model.findActuator(model.joints[joint].name)];
      };
      auto hold = [](ActuatorState& s, double target) {
        if (s.mode != JointMode::Position) s.integral = 0;
        s.mode = JointMode::Position;
        s.target = target;
      };
      for (int i = 0; i < 4; ++i) {
        const LegJoints& leg = (*rt.legs)[i];
        hold(actuatorOf(leg.hip), legs[i].hip);
        hold(actuatorOf(leg.knee), 0);
        ActuatorState& wheel = actuatorOf(leg.wheel);
        switch (legs[i].wheel) {
          case LegCommand::Wheel::Free: wheel.mode = JointMode::Free; break;
          case LegCommand::Wheel::Brake:
            wheel.mode = JointMode::Velocity;
            wheel.velocity = 0;
            break;
          case LegCommand::Wheel::Drive:
            wheel.mode = JointMode::Velocity;
            wheel.velocity = legs[i].wheelSpeed;
            break;
        }
      }
    }
    // Actuated joints: motor set-points and explicit torques.
    std::vector<bool> actuated(model.joints.size(), false);
    for (size_t a = 0; a < model.actuators.size(); ++a) {
      const ActuatorSpec& spec = model.actuators[a];
      const JointSpec& js = model.joints[spec.joint];
      dJointID j = rt.joints[spec.joint];
      actuated[spec.joint] = true;
      const double rate = jointRate(static_cast<int>(r), spec.joint);
      const ActuatorOutput out =
          updateActuator(spec, rt.control.actuators[a], jointPosition(static_cast<int>(r), spec.joint), rate, dt);
      const double torque = out.torque - js.damping * rate;
      if (js.type == JointType::Hinge) {
        dJointSetHingeParam(j, dParamVel, out.motorVelocity);
        dJointSetHingeParam(j, dParamFMax, out.motorMaxForce);
        if (torque != 0) dJointAddHingeTorque(j, torque);
      } else {
        dJointSetSliderParam(j, dParamVel, out.motorVelocity);
        dJointSetSliderParam(j, dParamFMax, out.motorMaxForce);
        if (torque != 0) dJointAddSliderForce(j, torque);
      }
    }
    // Damping of the joints without an actuator.
    for (size_t ji = 0; ji < model.joints.size(); ++ji) {
      const JointSpec& js = model.joints[ji];
      if (actuated[ji] || js.damping <= 0) continue;
      dJointID j = rt.joints[ji];
      switch (js.type) {
        case JointType::Hinge: dJointAddHingeTorque(j, -js.damping * dJointGetHingeAngleRate(j)); break;
        case JointType::Slider: dJointAddSliderForce(j, -js.damping * dJointGetSliderPositionRate(j)); break;
        case JointType::Universal:
          dJointAddUniversalTorques(j, -js.damping * dJointGetUniversalAngle1Rate(j),
                                    -js.damping * dJointGetUniversalAngle2Rate(j));
          break;
        case JointType::Ball:
        case JointType::Fixed: break;
      }
    }
  }
}


// The resistance's hold. Snow in front of a wheel resists its travel with
// up to C x N; below that it holds the wheel where it is, giving way
// elastically by up to kHoldTravel before it yields, as a bristle or
// reset-integrator friction model does (Haessig and Friedland, "On the
// modeling and simulation of friction", J. Dyn. Sys. Meas. Control 113,
// 1991). An explicit force: a static resistance posed to ODE's iterative
// solver as a constraint (an LMotor on the wheel, as before) left the
// stalled robot creeping at 0.0059 m/s at 40 iterations, 0.0006 at 200
// (the rows on a 9 kg wheel never settle against the 230 kg robot in 40
// sweeps; ODE 0.16's quick step neither warm-starts nor keeps an order),
// so the solver, not the snow, set how fast it went (issue 29). The
// hold's deflection is state (RobotControlState::resistanceHold); its
// stiffness C N / kHoldTravel, its damping that times kHoldDamping.
constexpr double kHoldTravel = 0.0005;  // [m]: small against any distance the robot drives
constexpr double kHoldDamping = 0.01;   // [s]: damps the hold's ring at the robot's mass

void World::applyMotionResistance() {
  Impl& m = *impl_;
  const Vec3 g = model_.gravity;
  const double gn = norm(g);
  const Vec3 up = gn > 0 ? (-1.0 / gn) * g : Vec3{0, 0, 1};
  for (size_t r = 0; r < m.robots.size(); ++r) {
    Impl::Robot& rt = m.robots[r];
    for (size_t l = 0; l < rt.bodies.size(); ++l) {
      double force = rt.control.resistance[l];
      double& hold = rt.control.resistanceHold[l];
      const int joint = rt.jointAbove[l];
      if (force <= 0 || joint < 0 || dJointGetType(rt.joints[static_cast<size_t>(joint)]) != dJointTypeHinge) {
        hold = 0;  // off the snow: the next contact holds afresh
        continue;
      }
      // The wheel's rolling direction, horizontal: across its axle.
      dVector3 a;
      dJointGetHingeAxis(rt.joints[static_cast<size_t>(joint)], a);
      Vec3 along = cross(up, Vec3{a[0], a[1], a[2]});
      along = along - dot(along, up) * up;
      if (norm(along) < 1e-6) {  // axle upright: it does not roll on the ground
        hold = 0;
        continue;
      }
      along = (1.0 / norm(along)) * along;
      const dReal* v = dBodyGetLinearVel(rt.bodies[l]);
      const double speed = dot(Vec3{v[0], v[1], v[2]}, along);
      if (rt.control.resistanceShare[l] < 1) {
        // Rolling wheels only: the share of its travel the wheel rolls.
        const double rolled = std::abs(jointRate(static_cast<int>(r), joint)) * rt.rollRadius[l];
        force *= std::clamp(rolled / std::max(std::abs(speed), 1e-3), 0.0, 1.0);
      }
      // The last step's travel (semi-implicit Euler moved the hub by
      // speed x step); beyond kHoldTravel the snow yields and the hold
      // slides along (the reset): the force is then C N against the travel.
      hold = std::clamp(hold + speed * params_.step, -kHoldTravel, kHoldTravel);
      const double stiffness = force / kHoldTravel;
      const double f = std::clamp(-stiffness * (hold + kHoldDamping * speed), -force, force);
      dBodyAddForce(rt.bodies[l], f * along.x, f * along.y, f * along.z);
    }
  }
}

void World::updateMotionResistance() {
  Impl& m = *impl_;
  for (Impl::Robot& rt : m.robots) {
    std::fill(rt.control.resistance.begin(), rt.control.resistance.end(), 0.0);
    std::fill(rt.control.resistanceShare.begin(), rt.control.resistanceShare.end(), 1.0);
  }
  for (const Impl::ResistingContact& c : m.resisting) {
    const dJointFeedback& f = m.contactFeedback[c.feedback];
    const dReal* force = c.wheelInF1 ? f.f1 : f.f2;
    const double normal = std::max(0.0, dot(Vec3{force[0], force[1], force[2]}, c.normal));
    RobotControlState& rc = m.robots[static_cast<size_t>(c.robot)].control;
    rc.resistance[static_cast<size_t>(c.link)] += c.c * normal;
    if (!c.sliding) rc.resistanceShare[static_cast<size_t>(c.link)] = 0;
  }
}

}  // namespace sp
