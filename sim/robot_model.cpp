#include "sim/robot_model.h"

#include <algorithm>
#include <cmath>

namespace sp {

const char* toString(GeomType type) {
  switch (type) {
    case GeomType::Box: return "box";
    case GeomType::Cylinder: return "cylinder";
    case GeomType::Sphere: return "sphere";
    case GeomType::Capsule: return "capsule";
  }
  return "?";
}

const char* toString(JointType type) {
  switch (type) {
    case JointType::Hinge: return "hinge";
    case JointType::Slider: return "slider";
    case JointType::Universal: return "universal";
    case JointType::Ball: return "ball";
    case JointType::Fixed: return "fixed";
  }
  return "?";
}

const char* toString(SensorType type) {
  switch (type) {
    case SensorType::Pose: return "pose";
    case SensorType::Laser: return "laser";
    case SensorType::Encoder: return "encoder";
    case SensorType::WheelForce: return "wheel_force";
    case SensorType::JointForce: return "joint_force";
    case SensorType::Imu: return "imu";
  }
  return "?";
}

namespace {
template <typename T>
int findByName(const std::vector<T>& items, std::string_view name) {
  const auto it = std::find_if(items.begin(), items.end(),
                               [&](const T& item) { return item.name == name; });
  return it == items.end() ? -1 : static_cast<int>(it - items.begin());
}
}  // namespace

int RobotModel::findLink(std::string_view n) const { return findByName(links, n); }
int RobotModel::findJoint(std::string_view n) const { return findByName(joints, n); }
int RobotModel::findSensor(std::string_view n) const { return findByName(sensors, n); }

int RobotModel::findActuator(std::string_view jointName) const {
  const int joint = findJoint(jointName);
  if (joint < 0) return -1;
  for (size_t i = 0; i < actuators.size(); ++i)
    if (actuators[i].joint == joint) return static_cast<int>(i);
  return -1;
}

double geomVolume(const GeomSpec& g) {
  const double r = g.radius;
  switch (g.type) {
    case GeomType::Box: return g.size.x * g.size.y * g.size.z;
    case GeomType::Cylinder: return kPi * r * r * g.length;
    case GeomType::Capsule: return kPi * r * r * g.length + 4.0 / 3.0 * kPi * r * r * r;
    case GeomType::Sphere: return 4.0 / 3.0 * kPi * r * r * r;
  }
  return 0;
}

double RobotModel::totalMass() const {
  double sum = 0;
  for (const LinkSpec& link : links) sum += link.mass;
  return sum;
}

const ContactSpec& WorldModel::contactFor(std::string_view a, std::string_view b) const {
  for (const ContactSpec& c : contacts)
    if ((c.a == a && c.b == b) || (c.a == b && c.b == a)) return c;
  return defaultContact;
}

double groundHeight(const TerrainSpec& t, double x, double y) {
  if (t.kind == TerrainSpec::Kind::Plane || t.grid.columns < 2 || t.grid.rows < 2) return t.pose.p.z;
  const Vec3 local = transformPoint(inverse(t.pose), {x, y, 0});
  return t.grid.heightAt(local.x, local.y) + t.pose.p.z;
}

bool onTerrain(const TerrainSpec& t, double x, double y) {
  if (t.kind == TerrainSpec::Kind::Plane) return true;
  const Vec3 local = transformPoint(inverse(t.pose), {x, y, 0});
  return std::abs(local.x) <= t.grid.width / 2 && std::abs(local.y) <= t.grid.depth / 2;
}

double terrainUncertainty(const TerrainSpec& terrain) {
  if (terrain.heightUncertainty >= 0) return terrain.heightUncertainty;
  if (terrain.kind == TerrainSpec::Kind::Plane) return 0;
  const HeightGrid& g = terrain.grid;
  double sum = 0;
  size_t n = 0;
  // Bilinear interpolation of a smooth surface misses by up to an eighth of
  // its second difference over a cell: the grid's own curvature bounds how
  // well it can know the ground between its samples.
  for (int j = 1; j + 1 < g.rows; ++j)
    for (int i = 1; i + 1 < g.columns; ++i) {
      const double dx = (g.at(i - 1, j) + g.at(i + 1, j) - 2 * g.at(i, j)) / 8;
      const double dy = (g.at(i, j - 1) + g.at(i, j + 1) - 2 * g.at(i, j)) / 8;
      sum += dx * dx + dy * dy;
      n += 2;
    }
  return n ? std::sqrt(sum / static_cast<double>(n)) : 0;
}

}  // namespace sp
