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
#include "sim/gait.h"
#include "sim/kinematics.h"
#include "sim/params.h"
#include "sim/robot_model.h"
#include "sim/sensors.h"

namespace sp {

/// The state of one rigid body, exactly as ODE holds it.
struct BodyState {
  std::array<double, 3> position{};
  /// w, x, y, z. In a Snapshot: the quaternion that, given to ODE (which
  /// normalises it), yields the body's orientation bit for bit; it may
  /// differ from that orientation in the last bit.
  std::array<double, 4> quaternion{};
  std::array<double, 3> linearVelocity{};
  std::array<double, 3> angularVelocity{};
  friend bool operator==(const BodyState&, const BodyState&) = default;
};

/// Controller state of one robot: actuators and the drive mode.
struct RobotControlState {
  std::vector<ActuatorState> actuators;
  bool driveActive = false;
  double driveSpeed = 0;
  double driveArticulation = 0;
  bool driveByYawRate = false;  ///< TurnCmd: the articulation follows driveYawRate
  double driveYawRate = 0;
  bool gaitActive = false;
  GaitState gait;
  /// Motion resistance (a surface's motion_resistance) per link: the
  /// force [N] the last step's contacts set for the next, C x normal force,
  /// and the share of it a rolling-only surface leaves (1 when sliding
  /// wheels meet it too). State: it carries a step's forces into the next.
  std::vector<double> resistance, resistanceShare;
  /// [m] per link: how far the snow holding a wheel has given way along
  /// its travel since the wheel last slipped through it (the resistance's
  /// hold, World::applyMotionResistance).
  std::vector<double> resistanceHold;
  friend bool operator==(const RobotControlState&, const RobotControlState&) = default;
};

/// Sampling state of one sensor.
struct SensorState {
  int64_t nextStep = 0;  ///< step count at which it samples next
  Vec3 lastVelocity;     ///< imu: velocity at the last sample (for acceleration)
  // wheel_force: sums over the steps since the last sample (the reading is
  // their mean, as a force sensor's low-pass output would be).
  Vec3 forceSum;         ///< contact force on the wheel [N s/step]
  Vec3 normalSum;        ///< normal force times contact normal
  int contactSum = 0;
  int stepsSummed = 0;
  SensorSample latest;
};

/// The whole dynamic state of a World at a step boundary: a plain value.
/// Restoring it into the same World, or into a fresh one built from the same
/// files and parameters, continues bit for bit as the original would.
struct Snapshot {
  uint64_t modelKey = 0;  ///< identifies the model layout it fits
  int64_t step = 0;
  double stepSize = 0;    ///< [s] of the world it was taken from
  std::vector<BodyState> bodies;  ///< robot links in order, then dynamic objects
  std::vector<RobotControlState> robots;
  std::vector<std::vector<SensorState>> sensors;  ///< per robot, per sensor
  unsigned long odeRandom = 0;        ///< the quick stepper's random state
  std::array<uint64_t, 4> random{};   ///< the noise engine's state
  std::shared_ptr<const HeightGrid> terrain;  ///< heightfield heights (shared, immutable)
  std::vector<std::pair<int, Command>> pending;  ///< commands queued for the next step
};

/// What went wrong when the twin diverged, where and when.
struct HealthReport {
  enum class Kind { Healthy, NotFinite, Speed, AngularSpeed, Acceleration, AngularAcceleration,
                    JointSeparation, Penetration, EngineFailure };
  Kind kind = Kind::Healthy;
  std::string where;  ///< "link 'wheel_fl'", "joint 'knee_fl'", ...; for EngineFailure ODE's message
  int64_t step = 0;   ///< the step that produced it
  double time = 0;    ///< [s], after that step
  double value = 0;   ///< the offending value
  double limit = 0;   ///< the limit it broke (its parameter names it in message())
  bool healthy() const { return kind == Kind::Healthy; }
  /// One line, e.g. "step 1204 (t = 1.204 s): body 'wheel_fl' angular speed
  /// 512 rad/s exceeds health.max_angular_speed = 200".
  std::string message() const;
};

/// What a World computes besides the physics (the benchmark turns both off
/// to measure the bare ODE world).
struct WorldOptions {
  bool sensors = true;      ///< sample the robot's sensors
  bool controllers = true;  ///< run actuators, drive kinematics and damping
  /// With sensors off, still sample the wheel_force sensors (the contacts'
  /// feedback; no laser, no IMU): what a calibration compares of the forces.
  bool wheelForces = false;
};

/// One contact point of the last step that involves a robot's link.
struct LinkContact {
  int robot = -1, link = -1;            ///< the robot link touching
  int otherRobot = -1, otherLink = -1;  ///< when it touches a robot link (its own robot's too)
  int object = -1;                      ///< when it touches a world object
  bool terrain = false;                 ///< when it touches the ground
  Vec3 position;                        ///< [m] world frame
  double depth = 0;                     ///< [m] penetration
};

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

/// The articulation angle [rad] at which the hinge runs at `speed` [m/s]
/// with yaw rate `yawRate` [rad/s] (the inverse of the kinematics above),
/// limited to +-`maxAngle`; 0 for a zero yaw rate.
double articulationForTurn(const DriveGeometry& g, double speed, double yawRate, double maxAngle);

class World {
 public:
  /// Builds the ODE world. Returns nullptr with diagnostics if the model
  /// cannot be built (it was checked by the loader, so this is rare).
  static std::unique_ptr<World> create(const WorldModel& model, const SimParams& params,
                                       Diagnostics& diag, WorldOptions options = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// Checks a command against robot `robot` and queues it for the next step
  /// boundary. Returns "" when accepted, else why it was rejected (nothing
  /// is queued then).
  std::string submit(const Command& command, int robot = 0);

  /// Multiplies every contact's friction coefficient (each pair of
  /// materials', and the model's) by `factor` (> 0, finite): the ground
  /// turned wet under a robot. Takes effect at the next collision. Not a
  /// command and not in snapshots: a stand-in's sudden change (issue 61),
  /// which its log records as a note. Returns "" or why not (unchanged).
  std::string scaleFriction(double factor);

  /// Advances one fixed step: applies queued commands, runs the actuators,
  /// collides, steps ODE, checks health, samples the sensors that are due.
  /// Returns false, and does nothing, once the twin has diverged (health()).
  bool step();

  /// Healthy until a step breaks a limit; then stepping stops until a
  /// snapshot is restored.
  const HealthReport& health() const { return health_; }
  /// Messages ODE printed during the last step (solver trouble, say).
  const std::vector<std::string>& odeMessages() const { return odeMessages_; }

  /// The dynamic state now. Cheap: bodies, controllers, sensor phases.
  Snapshot snapshot() const;
  /// Restores a snapshot of this world or of one built from the same files.
  /// Returns "" on success, else why not (nothing is changed then): another
  /// model, a non-finite state, a time off this world's step grid, or a world
  /// whose physics engine failed (EngineFailure: build a new one).
  std::string restore(const Snapshot& snapshot);
  /// Puts robot `robot`'s links where `links` says (robot.links order: each
  /// frame's pose and its origin's velocities, e.g. from linkMotions()) and
  /// the dynamic objects named in `objects` at those poses, at rest: the
  /// state a robot reports, rebuilt into this twin (the predictive ghost
  /// re-anchors so). Time, controllers and sensors are left as they are.
  /// Returns "" or why not (a size that does not fit, a value not finite);
  /// nothing is changed then.
  std::string setRobotMotion(int robot, const std::vector<LinkMotion>& links,
                             const std::vector<std::pair<std::string, Pose>>& objects = {});
  /// A 64-bit hash of the dynamic state (bodies bit for bit, controllers,
  /// random states, step), to compare runs.
  uint64_t stateHash() const;
  /// Which of ODE's broad phases finds this world's contact pairs: "simple"
  /// for few geoms, "hash" for many (world_build.cpp). Either gives the
  /// same contacts in the same order, so the same run.
  const char* broadPhase() const;

  /// Latest sample of each sensor of a robot (step -1 until first sampled).
  const SensorSample& sensorSample(int robot, int sensor) const;
  /// (robot, sensor) pairs sampled by the last step.
  const std::vector<std::pair<int, int>>& sampledLastStep() const { return sampledLastStep_; }
  /// Casts one ray through the world (terrain, objects, robots) [m];
  /// +infinity if nothing is hit within maxRange, 0 from inside the ground.
  /// With `excludeRobot` >= 0 the ray passes through that robot's link
  /// `excludeLink`, or through all its links when excludeLink < 0.
  double castRay(Vec3 origin, Vec3 direction, double maxRange, int excludeRobot = -1,
                 int excludeLink = -1) const;
  /// A fan of rays in the xy plane of `pose`, beam b at angleMin + b *
  /// angleStep about its z axis; fills `ranges` (sized by the caller) as
  /// castRay would, gathering the candidate geoms once for the whole fan.
  void castFan(const Pose& pose, double angleMin, double angleStep, double maxRange, int excludeRobot,
               int excludeLink, std::vector<double>& ranges) const;

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
  /// The contact points of the last step that involve a robot link, in
  /// the canonical contact order. Built on each call (flight rules read it).
  std::vector<LinkContact> linkContacts() const;
  /// Number of contact points in the last step.
  int contactCount() const { return lastContactCount_; }

  // Terrain. Edits are commands (TerrainPatchCmd, through submit()): they
  // apply at a step boundary, are logged and re-simulated like any other,
  // and snapshots carry the heights. They reach the physics at the next
  // collision: ODE reads the heights through a callback, no geom is rebuilt.
  const HeightGrid* terrainGrid() const;
  /// Terrain height at world (x, y): the plane's or the heightfield's.
  double terrainHeight(double x, double y) const;

 private:
  struct Impl;
  World(const WorldModel& model, const SimParams& params, WorldOptions options);
  bool build(Diagnostics& diag);
  void applyCommand(const Command& command, int robot);
  // "" if the patch fits this world's heightfield, else why not.
  std::string checkTerrainPatch(const TerrainPatchCmd& patch) const;
  void applyTerrainPatch(const TerrainPatchCmd& patch);
  void runActuators();
  void collide();
  void canonicalizeQuaternions();
  void checkHealth();
  void accumulateWheelForces();
  /// Motion resistance: the force each wheel meets this step, from the last
  /// step's normal forces (applyMotionResistance), and those of this step
  /// (updateMotionResistance, while the contact feedback is valid).
  void applyMotionResistance();
  void updateMotionResistance();
  void sampleSensors();
  void prepareRayTargets(int excludeRobot, int excludeLink) const;
  double castPrepared(Vec3 origin, Vec3 direction, double maxRange) const;
  uint64_t modelKey() const;

  WorldModel model_;
  SimParams params_;
  WorldOptions options_;
  int64_t steps_ = 0;
  int lastContactCount_ = 0;
  HealthReport health_;
  std::vector<std::string> odeMessages_;
  std::vector<std::pair<int, int>> sampledLastStep_;
  std::unique_ptr<Impl> impl_;
};

/// True when ODE's random numbers come from the calling thread's own state
/// (set per world before each step), which makes parallel quick-stepping
/// worlds deterministic. See docs/architecture.md.
bool odeRandomIsPerThread();

}  // namespace sp
