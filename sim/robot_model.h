#pragma once
// The description of a robot and of a world, as read from their XML files
// (docs/formats.md). Immutable after loading: the ODE world (world.h) is built
// from it, and any number of worlds may be built from one model.
// All values SI, angles in radians (files use degrees).

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sim/height_grid.h"
#include "sim/joint_mode.h"
#include "sim/math.h"

namespace sp {

struct Color {
  double r = 0.7, g = 0.7, b = 0.7, a = 1.0;
  friend bool operator==(const Color&, const Color&) = default;
};

enum class GeomType { Box, Cylinder, Sphere, Capsule };
const char* toString(GeomType type);

/// A collision and visual shape. Cylinders and capsules lie along local z.
struct GeomSpec {
  GeomType type = GeomType::Box;
  Vec3 size;           ///< box: full edge lengths [m]
  double radius = 0;   ///< cylinder, capsule, sphere [m]
  double length = 0;   ///< cylinder, capsule: length of the straight part [m]
  Pose pose;           ///< in the owning link's (or object's) frame
  std::string material;  ///< contact material name, "" = default
  Color color;
  /// [kg] this geom's own share of its link's mass; < 0 (as loaded): the
  /// link's mass is spread over its geoms by volume. Set by holdRigid(),
  /// which gathers geoms of several links onto one.
  double mass = -1;
  int line = 0;
};

/// The volume of a geom [m^3] (how a link's mass is spread over its geoms).
double geomVolume(const GeomSpec& g);

/// A rigid body. `pose` is the link frame in the robot frame with every
/// joint at zero.
struct LinkSpec {
  std::string name;
  double mass = 0;  ///< [kg], distributed over the geoms by volume
  Pose pose;
  std::vector<GeomSpec> geoms;
  /// [m] the centre of mass moved off where the geoms put it, link frame
  /// (not in files: a perturbed robot's, sim/perturbation.h).
  Vec3 centreOfMassShift;
  int line = 0;
};

/// A link's mass properties as the twin builds its body (sim/world_build.cpp,
/// with ODE's own mass functions): the mass, its centre in the link frame,
/// and the inertia tensor about that centre in the link's axes [kg m^2].
struct MassProperties {
  double mass = 0;
  Vec3 centre;
  double ixx = 0, iyy = 0, izz = 0, ixy = 0, ixz = 0, iyz = 0;
};
MassProperties massProperties(const LinkSpec& link);

enum class JointType { Hinge, Slider, Universal, Ball, Fixed };
const char* toString(JointType type);

struct JointSpec {
  std::string name;
  JointType type = JointType::Hinge;
  int parent = -1;  ///< link index; -1 = the world (fixed to the ground)
  int child = -1;   ///< link index
  Vec3 anchor;      ///< in the robot frame at zero pose [m]
  Vec3 axis{0, 0, 1};   ///< hinge, slider, universal (first axis); unit
  Vec3 axis2{0, 1, 0};  ///< universal second axis; unit
  bool limited = false;
  double lower = 0, upper = 0;  ///< [rad] or [m] for sliders
  double damping = 0;           ///< viscous [N m s/rad] or [N s/m]
  int line = 0;
};

/// A drive on a hinge or slider joint; all modes of JointMode are available,
/// Position only when PID gains are given.
struct ActuatorSpec {
  std::string name;
  int joint = -1;
  JointMode mode = JointMode::Velocity;  ///< initial mode
  double maxTorque = 0;     ///< torque (force) limit [N m or N], > 0
  double maxVelocity = 0;   ///< speed limit [rad/s or m/s], > 0
  bool hasPid = false;
  double kp = 0, ki = 0, kd = 0;  ///< PID gains: velocity per unit of error
  double integralLimit = 0;       ///< clamp of the integral term [rad s]
  bool continuous = false;        ///< wrap angle errors to (-pi, pi]
  double initialTarget = 0;       ///< initial set-point of Position mode [rad]
  /// The motor reaches this times the commanded speed in Velocity mode: a
  /// calibrated robot file's measured speed loop (`velocity_scale`), or a
  /// perturbed robot's mis-calibrated one (sim/perturbation.h).
  double velocityScale = 1;
  int line = 0;
};

enum class SensorType { Pose, Laser, Encoder, WheelForce, JointForce, Imu };
const char* toString(SensorType type);

struct SensorSpec {
  std::string name;
  SensorType type = SensorType::Pose;
  int link = -1;    ///< pose, laser, imu, wheel_force (the wheel link)
  int joint = -1;   ///< encoder, joint_force
  double rate = 0;  ///< [Hz]; 0 = every step
  double noise = 0; ///< standard deviation, in the reading's unit
  Pose pose;        ///< mounting pose on the link (laser, imu)
  // Laser only
  double fov = degToRad(180);  ///< [rad]
  int beams = 181;
  double minRange = 0.05, maxRange = 10;  ///< [m]
  bool excludeSelf = true;  ///< beams pass through the robot's own bodies
  int line = 0;
};

/// Which joints drive and steer the robot, for DriveCmd and WheelsCmd.
struct DriveSpec {
  int articulation = -1;            ///< hinge joint between front and rear body
  std::array<int, 4> wheels{-1, -1, -1, -1};  ///< FL, FR, RL, RR wheel joints
  double wheelRadius = 0;           ///< [m]
  /// The tyres' vertical compliance [N/m, N s/m], per wheel; 0 = rigid.
  /// A world's contact with its own stiffness or softness overrides it.
  double tyreStiffness = 0, tyreDamping = 0;
  int line = 0;
};

struct RobotModel {
  std::string name;
  std::string file;  ///< path it was loaded from
  std::vector<LinkSpec> links;
  std::vector<JointSpec> joints;
  std::vector<ActuatorSpec> actuators;
  std::vector<SensorSpec> sensors;
  std::optional<DriveSpec> drive;

  int findLink(std::string_view name) const;      ///< -1 if absent
  int findJoint(std::string_view name) const;     ///< -1 if absent
  int findActuator(std::string_view jointName) const;  ///< by joint; -1 if absent
  int findSensor(std::string_view name) const;
  double totalMass() const;
};

/// Contact parameters between two materials (ODE dSurfaceParameters).
struct ContactSpec {
  std::string a, b;       ///< material names; order does not matter
  double mu = 1.0;        ///< Coulomb friction (friction pyramid)
  double bounce = 0;      ///< restitution 0..1
  double bounceVelocity = 0.1;  ///< minimum speed for a bounce [m/s]
  double softErp = -1;    ///< < 0: the world's ERP
  double softCfm = -1;    ///< < 0: the world's CFM
  /// A compliant contact, per contact point: a spring [N/m] and damper
  /// [N s/m] (a tyre's), set as ODE's soft ERP and CFM for the step; 0:
  /// none (soft_erp, soft_cfm or the world's). Both or neither.
  double stiffness = 0, damping = 0;
  double rollingResistance = 0;  ///< [m], resisting torque = this x normal force
  /// Motion resistance of a wheel on the surface (snow, sand): a force C x
  /// normal force against the wheel's travel. On a robot's cylinder or
  /// sphere it resists rolling as a torque C x N x radius; with
  /// `motionResistanceSliding` a sliding (braced) wheel meets it too, as
  /// friction mu + C.
  double motionResistance = 0;
  bool motionResistanceSliding = true;
  int line = 0;
};

struct TerrainSpec {
  enum class Kind { Plane, Heightfield };
  Kind kind = Kind::Plane;
  std::string material;
  std::string file;    ///< heightfield source file ("" for a plane)
  Pose pose;           ///< grid centre (x, y, z offset added to heights); yaw only
  HeightGrid grid;     ///< heightfield only
  /// [m] one deviation of the real ground's height about these heights,
  /// as the world file states it (height_uncertainty); < 0: not stated,
  /// terrainUncertainty() derives it.
  double heightUncertainty = -1;
  int line = 0;
};

/// [m] how well `terrain` is known: what its world file states, else what
/// its grid implies (a plane: 0; a grid: the root mean square of what
/// interpolating between its samples misses, an eighth of its second
/// differences, along both axes).
double terrainUncertainty(const TerrainSpec& terrain);

/// Ground height at world (x, y): the plane's height, or the heightfield's
/// (its edge value outside it, as HeightGrid::heightAt does).
double groundHeight(const TerrainSpec& terrain, double x, double y);

/// Whether world (x, y) lies on `terrain`: always on a plane; inside its
/// extent on a heightfield (beyond it the physics has no ground: a robot
/// there falls).
bool onTerrain(const TerrainSpec& terrain, double x, double y);

/// A static or dynamic object of the world.
struct ObjectSpec {
  std::string name;
  bool isStatic = true;
  double mass = 0;  ///< dynamic only [kg]
  Pose pose;        ///< in the world frame
  std::vector<GeomSpec> geoms;
  int line = 0;
};

struct RobotInstance {
  std::string name;  ///< instance name (unique in the world)
  RobotModel model;
  Pose pose;         ///< robot frame in the world frame
  int line = 0;
};

struct WorldModel {
  std::string name;
  std::string file;
  Vec3 gravity{0, 0, -9.81};
  TerrainSpec terrain;
  std::vector<std::string> materials;
  ContactSpec defaultContact;  ///< for pairs without their own <contact>
  std::vector<ContactSpec> contacts;
  std::vector<ObjectSpec> objects;
  std::vector<RobotInstance> robots;

  /// Parameters for a pair of materials: the pair's own, else the default.
  const ContactSpec& contactFor(std::string_view a, std::string_view b) const;
};

}  // namespace sp
