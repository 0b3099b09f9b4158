// What the wheels' load cells and rolling tell without a twin
// (app/calibration/calibration.h): the mass, the centre of mass, the tyres'
// radii from rolling without slip.
#include "app/calibration/calibration.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <tuple>

#include "app/state/parallel_for.h"
#include "app/state/robot_shapes.h"
#include "app/ghost/hold_policy.h"
#include "app/log/resimulation.h"
#include "app/log/session_log.h"
#include "sim/command_file.h"
#include "sim/kinematics.h"
#include "sim/perturbation.h"
#include "sim/rigid.h"
#include "sim/runner.h"
#include "sim/text.h"
#include "sim/world.h"

#include "app/calibration/usable_frames.h"

namespace sp {

using calibration_detail::usableFrames;

namespace {

// Each link's mass properties, and the robot's total mass.
std::vector<MassProperties> linkMasses(const RobotModel& robot, double& total) {
  std::vector<MassProperties> mass;
  total = 0;
  for (const LinkSpec& l : robot.links) total += mass.emplace_back(massProperties(l)).mass;
  return mass;
}

// The centre of mass of `robot` at a pose (its links' motions `m`).
Vec3 centreAt(const std::vector<MassProperties>& mass, double total, const std::vector<LinkMotion>& m) {
  Vec3 centre{};
  for (size_t i = 0; i < mass.size(); ++i) centre = centre + (mass[i].mass / total) * transformPoint(m[i].pose, mass[i].centre);
  return centre;
}

// Least squares of (com_x, com_y) over frames. The parameter moves each
// link's centre in its own frame at zero pose, so at a frame's pose the
// robot's centre moves by A (com_x, com_y), A the mass-weighted mean of the
// links' turns since zero pose (a bent leg turns its part of a forward shift
// downward): the twin's own meaning of calibration.com_x. Each row: A (2 x 2,
// by rows) and the centre's observed move d, in the robot's heading.
class CentreFit {
 public:
  CentreFit(const RobotModel& robot, const std::vector<MassProperties>& mass, double total)
      : robot_(robot), mass_(mass), total_(total) {}
  void add(const std::vector<LinkMotion>& m, const Quat& base, Vec3 moved) {
    Vec3 ux{}, uy{};
    for (size_t i = 0; i < mass_.size(); ++i) {
      const double share = mass_[i].mass / total_;
      const Quat turned = m[i].pose.q * conjugate(robot_.links[i].pose.q);
      ux = ux + share * rotate(turned, Vec3{1, 0, 0});
      uy = uy + share * rotate(turned, Vec3{0, 1, 0});
    }
    const double c = std::cos(heading(base)), s = std::sin(heading(base));
    const auto fwd = [&](Vec3 v) { return c * v.x + s * v.y; };
    const auto lft = [&](Vec3 v) { return -s * v.x + c * v.y; };
    rows_.push_back({fwd(ux), fwd(uy), lft(ux), lft(uy), fwd(moved), lft(moved)});
  }
  std::optional<LoadCentre> solve() const {
    double n11 = 0, n12 = 0, n22 = 0, b1 = 0, b2 = 0;
    for (const auto& r : rows_) {
      n11 += r[0] * r[0] + r[2] * r[2];
      n12 += r[0] * r[1] + r[2] * r[3];
      n22 += r[1] * r[1] + r[3] * r[3];
      b1 += r[0] * r[4] + r[2] * r[5];
      b2 += r[1] * r[4] + r[3] * r[5];
    }
    const double det = n11 * n22 - n12 * n12;
    if (rows_.size() < 50 || !(det > 0)) return std::nullopt;
    LoadCentre out;
    out.forward = (n22 * b1 - n12 * b2) / det;
    out.left = (n11 * b2 - n12 * b1) / det;
    double ss = 0;
    for (const auto& r : rows_) {
      const double ef = r[4] - r[0] * out.forward - r[1] * out.left, el = r[5] - r[2] * out.forward - r[3] * out.left;
      ss += ef * ef + el * el;
    }
    // Neighbouring frames are not independent (the body rocks over ~0.2 s):
    // one sample per 10 frames.
    const double s2 = ss / static_cast<double>(2 * rows_.size() - 2) * 10;
    out.sigmaForward = std::sqrt(s2 * n22 / det);
    out.sigmaLeft = std::sqrt(s2 * n11 / det);
    out.frames = static_cast<int>(rows_.size());
    return out;
  }

 private:
  const RobotModel& robot_;
  const std::vector<MassProperties>& mass_;
  double total_;
  std::vector<std::array<double, 6>> rows_;
};

}  // namespace

std::optional<LoadCentre> comFromLoads(const WorldModel& files, const std::vector<RobotFrame>& f) {
  if (files.robots.empty() || !files.robots[0].model.drive) return std::nullopt;
  const RobotModel& robot = files.robots[0].model;
  const DriveSpec& drive = *robot.drive;
  const double g = norm(files.gravity);
  if (!(g > 0)) return std::nullopt;
  double total = 0;
  const std::vector<MassProperties> mass = linkMasses(robot, total);
  std::array<Vec3, 4> hub{};  // each hub in its wheel link's frame
  for (size_t w = 0; w < 4; ++w) {
    if (drive.wheels[w] < 0) return std::nullopt;
    const JointSpec& j = robot.joints[static_cast<size_t>(drive.wheels[w])];
    hub[w] = transformPoint(inverse(robot.links[static_cast<size_t>(j.child)].pose), j.anchor);
  }
  const TerrainSpec& terrain = files.terrain;
  const auto groundNormal = [&](Vec3 at) {
    if (terrain.kind != TerrainSpec::Kind::Heightfield) return Vec3{0, 0, 1};
    // Over a tyre's half width of ground either way: the contact spreads.
    const Vec3 l = transformPoint(inverse(terrain.pose), at);
    const double e = drive.wheelRadius / 2;
    const double gx = (terrain.grid.heightAt(l.x + e, l.y) - terrain.grid.heightAt(l.x - e, l.y)) / (2 * e);
    const double gy = (terrain.grid.heightAt(l.x, l.y + e) - terrain.grid.heightAt(l.x, l.y - e)) / (2 * e);
    return rotate(terrain.pose.q, normalized(Vec3{-gx, -gy, 1}));
  };
  CentreFit fit(robot, mass, total);
  for (size_t k = 1; k + 1 < f.size(); ++k) {
    const RobotFrame& r = f[k];
    const double dt = f[k + 1].time - f[k - 1].time;
    if (!r.hasBaseVelocity || !(dt > 0) || dt > 0.1 || r.jointPositions.size() != robot.joints.size()) continue;
    const std::vector<LinkMotion> m =
        linkMotions(robot, r.base, r.baseLinearVelocity, r.baseAngularVelocity, r.jointPositions, r.jointRates);
    const Vec3 centre = centreAt(mass, total, m);
    Vec3 balance{};
    double load = 0, ground = 0;
    for (size_t w = 0; w < 4; ++w) {
      const Vec3 at = transformPoint(m[static_cast<size_t>(robot.joints[static_cast<size_t>(drive.wheels[w])].child)].pose, hub[w]);
      const Vec3 n = groundNormal(at);
      const double vertical = r.wheelNormal[w] * n.z;
      const Vec3 contact = at - drive.wheelRadius * n;
      balance = balance + vertical * contact;
      load += vertical;
      ground += contact.z / 4;
    }
    if (!(load > 0)) continue;
    balance = (1 / load) * balance;
    // Accelerating, the ground's push below the centre loads the rear: the
    // balance point lies h a / g behind the centre.
    const Vec3 a = (1 / dt) * (f[k + 1].baseLinearVelocity - f[k - 1].baseLinearVelocity);
    fit.add(m, r.base.q, balance + ((centre.z - ground) / g) * a - centre);
  }
  return fit.solve();
}

std::optional<LoadCentre> centreShift(const RobotModel& files, const RobotModel& robot, const std::vector<RobotFrame>& f) {
  if (robot.links.size() != files.links.size()) return std::nullopt;
  double total = 0, robotTotal = 0;
  const std::vector<MassProperties> mass = linkMasses(files, total), robotMass = linkMasses(robot, robotTotal);
  CentreFit fit(files, mass, total);
  for (const RobotFrame& r : f) {
    if (r.jointPositions.size() != files.joints.size()) continue;
    const std::vector<LinkMotion> m =
        linkMotions(files, r.base, r.baseLinearVelocity, r.baseAngularVelocity, r.jointPositions, r.jointRates);
    fit.add(m, r.base.q, centreAt(robotMass, robotTotal, m) - centreAt(mass, total, m));
  }
  return fit.solve();
}

RollingRadii radiiFromRolling(const WorldModel& files, const std::vector<RobotFrame>& in) {
  RollingRadii out;
  if (files.robots.empty() || !files.robots[0].model.drive) return out;
  const RobotModel& robot = files.robots[0].model;
  const DriveSpec& drive = *robot.drive;
  const std::vector<RobotFrame> frames = usableFrames(in, 0);
  std::array<std::vector<std::pair<double, double>>, 4> samples;  // (spin [rad/s], speed across the axle [m/s])
  for (const RobotFrame& f : frames) {
    if (f.jointPositions.size() != robot.joints.size() || f.jointRates.size() != robot.joints.size()) continue;
    const std::vector<LinkMotion> m =
        linkMotions(robot, f.base, f.baseLinearVelocity, f.baseAngularVelocity, f.jointPositions, f.jointRates);
    for (size_t w = 0; w < 4; ++w) {
      if (drive.wheels[w] < 0) continue;
      const JointSpec& joint = robot.joints[static_cast<size_t>(drive.wheels[w])];
      const WheelRolling roll = wheelRolling(robot, joint, m[static_cast<size_t>(joint.child)]);
      if (std::abs(roll.spin) < 0.5) continue;
      // Signed: the hub moves the way the spin rolls it on level ground.
      const double sign = dot(roll.across, cross(roll.axle, Vec3{0, 0, 1})) * roll.spin > 0 ? 1.0 : -1.0;
      samples[w].push_back({std::abs(roll.spin), sign * norm(roll.across)});
    }
  }
  for (size_t w = 0; w < 4; ++w) {
    std::vector<std::pair<double, double>>& s = samples[w];
    if (s.size() < 50) continue;
    std::vector<double> ratio;
    for (const auto& [spin, speed] : s) ratio.push_back(speed / spin);
    std::vector<double> sorted = ratio;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
    const double med = sorted[sorted.size() / 2];
    double ss = 0, sv = 0;
    std::vector<std::pair<double, double>> kept;
    for (size_t i = 0; i < s.size(); ++i)
      if (std::abs(ratio[i] - med) < 0.05 * std::abs(med)) kept.push_back(s[i]);
    for (const auto& [spin, speed] : kept) {
      ss += spin * spin;
      sv += spin * speed;
    }
    out.slipping[w] = 1 - static_cast<double>(kept.size()) / static_cast<double>(s.size());
    if (kept.size() < 50 || ss <= 0) continue;
    const double r = sv / ss;
    double e2 = 0;
    for (const auto& [spin, speed] : kept) e2 += (speed - r * spin) * (speed - r * spin);
    // Neighbouring frames are not independent: one sample per 10.
    const double n = static_cast<double>(kept.size());
    out.factor[w] = r / drive.wheelRadius;
    out.sigma[w] = std::sqrt(e2 / (n - 1) / ss * 10) / drive.wheelRadius;
    out.frames[w] = static_cast<int>(kept.size());
  }
  return out;
}

std::array<double, 4> radiusValues(const std::array<double, 4>& w) {
  const double sum = w[0] + w[1] + w[2] + w[3];
  return {sum / 4, 2 * ((w[0] + w[1]) - (w[2] + w[3])) / sum, 2 * ((w[0] + w[2]) - (w[1] + w[3])) / sum,
          2 * ((w[0] + w[3]) - (w[1] + w[2])) / sum};
}

}  // namespace sp
