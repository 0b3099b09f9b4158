#pragma once
// The physics twin: an ODE world built from a WorldModel, stepped at a fixed
// step with commands applied at step boundaries.
//
// Threading: a World is owned by one thread at a time (the physics thread);
// no method may be called concurrently. Several Worlds may step at the same
// time in different threads: each owns its ODE world, space, threading
// implementation and random state (see docs/architecture.md, determinism).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/actuator.h"
#include "sim/command.h"
#include "sim/diagnostics.h"
#include "sim/params.h"
#include "sim/robot_model.h"

namespace sp {

/// The articulated-steering geometry of a robot with a <drive>, measured
/// from its current pose (legs move, so it changes).
struct DriveGeometry {
  double frontLength = 0;  ///< hinge to front axle centre, in the ground plane [m]
  double rearLength = 0;   ///< hinge to rear axle centre [m]
  double frontTrack = 0;   ///< front wheel centre to wheel centre [m]
  double rearTrack = 0;    ///< rear [m]
  double articulation = 0; ///< current hinge angle [rad], > 0 turns left
};

/// Wheel angular velocities [rad/s] (FL, FR, RL, RR) so that all four wheels
/// roll without side slip around the turn centre of the articulated-steering
/// kinematics (docs/architecture.md), with `speed` [m/s] at the hinge.
std::array<double, 4> articulatedWheelSpeeds(const DriveGeometry& g, double speed, double wheelRadius);

class World {
 public:
  /// Builds the ODE world. Returns nullptr with diagnostics if the model
  /// cannot be built (it was checked by the loader, so this is rare).
  static std::unique_ptr<World> create(const WorldModel& model, const SimParams& params,
                                       Diagnostics& diag);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// Checks a command against robot `robot` and queues it for the next step
  /// boundary. Returns "" when accepted, else why it was rejected (nothing
  /// is queued then).
  std::string submit(const Command& command, int robot = 0);

  /// Advances one fixed step: applies queued commands, runs the actuators,
  /// collides, steps ODE.
  void step();

  double time() const { return static_cast<double>(steps_) * params_.step; }
  int64_t stepCount() const { return steps_; }
  const SimParams& params() const { return params_; }
  const WorldModel& model() const { return model_; }

  // State read-out (valid between steps).
  int robotCount() const { return static_cast<int>(model_.robots.size()); }
  const RobotModel& robotModel(int robot) const { return model_.robots[robot].model; }
  /// Link frame (not the centre of mass) in the world frame.
  Pose linkPose(int robot, int link) const;
  Vec3 linkLinearVelocity(int robot, int link) const;   ///< of the link origin [m/s]
  Vec3 linkAngularVelocity(int robot, int link) const;  ///< [rad/s]
  /// Centre of mass of the whole robot, world frame.
  Vec3 robotCentreOfMass(int robot) const;
  double jointPosition(int robot, int joint) const;  ///< [rad] or [m]; 0 for ball/fixed
  double jointRate(int robot, int joint) const;      ///< [rad/s] or [m/s]
  const ActuatorState& actuatorState(int robot, int actuator) const;
  /// Steering geometry now; nullopt if the robot has no <drive>.
  std::optional<DriveGeometry> driveGeometry(int robot) const;
  Pose objectPose(int object) const;
  /// Number of contact points in the last step.
  int contactCount() const { return lastContactCount_; }

  // Terrain. Edits reach the physics at the next collision: ODE reads the
  // heights through a callback, so no geom is rebuilt.
  const HeightGrid* terrainGrid() const;
  /// Terrain height at world (x, y): the plane's or the heightfield's.
  double terrainHeight(double x, double y) const;
  /// Replaces heights of the heightfield (same size). Returns false if the
  /// terrain is a plane or the size differs.
  bool setTerrainHeights(const std::vector<double>& heights);

 private:
  struct Impl;
  World(const WorldModel& model, const SimParams& params);
  bool build(Diagnostics& diag);
  void applyCommand(const Command& command, int robot);
  void runActuators();
  void collide();

  WorldModel model_;
  SimParams params_;
  int64_t steps_ = 0;
  int lastContactCount_ = 0;
  std::unique_ptr<Impl> impl_;
};

/// True when ODE's random numbers come from the calling thread's own state
/// (set per world before each step), which makes parallel quick-stepping
/// worlds deterministic. See docs/architecture.md.
bool odeRandomIsPerThread();

}  // namespace sp
