#include "sim/rigid.h"

#include <algorithm>

#include "sim/kinematics.h"
#include "sim/params.h"

namespace sp {
namespace {

// The joint whose child is each link (-1 for a root link).
std::vector<int> jointAbove(const RobotModel& robot) {
  std::vector<int> above(robot.links.size(), -1);
  for (size_t j = 0; j < robot.joints.size(); ++j)
    if (robot.joints[j].child >= 0) above[static_cast<size_t>(robot.joints[j].child)] = static_cast<int>(j);
  return above;
}

}  // namespace

std::vector<int> subtreeJoints(const RobotModel& robot, std::string_view name) {
  const int top = robot.findJoint(name);
  if (top < 0) return {};
  std::vector<bool> inside(robot.links.size(), false);
  inside[static_cast<size_t>(robot.joints[static_cast<size_t>(top)].child)] = true;
  // Joints list parents before children (the loader's order), but do not rely on it.
  for (bool grew = true; grew;) {
    grew = false;
    for (const JointSpec& j : robot.joints)
      if (j.parent >= 0 && inside[static_cast<size_t>(j.parent)] && !inside[static_cast<size_t>(j.child)]) {
        inside[static_cast<size_t>(j.child)] = true;
        grew = true;
      }
  }
  std::vector<int> out;
  for (size_t j = 0; j < robot.joints.size(); ++j)
    if (static_cast<int>(j) == top || (robot.joints[j].parent >= 0 && inside[static_cast<size_t>(robot.joints[j].parent)]))
      out.push_back(static_cast<int>(j));
  return out;
}

std::vector<int> unmovedSubtrees(const RobotModel& robot, const std::vector<bool>& moved) {
  std::vector<int> held;
  std::vector<bool> taken(robot.joints.size(), false);
  for (size_t j = 0; j < robot.joints.size(); ++j) {
    if (taken[j]) continue;
    const std::vector<int> sub = subtreeJoints(robot, robot.joints[j].name);
    if (std::any_of(sub.begin(), sub.end(), [&](int k) { return moved[static_cast<size_t>(k)]; })) continue;
    for (int k : sub) {
      taken[static_cast<size_t>(k)] = true;
      held.push_back(k);
    }
  }
  std::sort(held.begin(), held.end());
  return held;
}

std::optional<std::vector<int>> holdableJoints(const RobotModel& robot, std::string_view names, std::string_view key,
                                               std::string& error) {
  std::vector<int> drive;  // the wheels and the articulation keep turning in a held subtree
  if (robot.drive) {
    drive.assign(robot.drive->wheels.begin(), robot.drive->wheels.end());
    drive.push_back(robot.drive->articulation);
  }
  std::vector<int> held;
  for (const std::string& name : splitNames(names)) {
    const std::vector<int> subtree = subtreeJoints(robot, name);
    if (subtree.empty()) {
      error = std::string(key) + ": the robot has no joint '" + name + "'";
      return std::nullopt;
    }
    if (std::find(drive.begin(), drive.end(), robot.findJoint(name)) != drive.end()) {
      error = std::string(key) + ": joint '" + name + "' drives the robot and cannot be held";
      return std::nullopt;
    }
    for (int j : subtree)
      if (std::find(drive.begin(), drive.end(), j) == drive.end() && std::find(held.begin(), held.end(), j) == held.end())
        held.push_back(j);
  }
  std::sort(held.begin(), held.end());
  return held;
}

std::optional<RigidRobot> holdRigid(const RobotModel& robot, std::span<const double> jointPositions,
                                    const std::vector<int>& held, std::string& error) {
  const size_t nj = robot.joints.size(), nl = robot.links.size();
  if (jointPositions.size() != nj) {
    error = "expected " + std::to_string(nj) + " joint positions, got " + std::to_string(jointPositions.size());
    return std::nullopt;
  }
  std::vector<bool> isHeld(nj, false);
  for (int j : held) {
    if (j < 0 || static_cast<size_t>(j) >= nj) {
      error = "no joint " + std::to_string(j);
      return std::nullopt;
    }
    isHeld[static_cast<size_t>(j)] = true;
  }
  const std::vector<int> above = jointAbove(robot);
  if (robot.drive) {
    std::vector<int> driveJoints(robot.drive->wheels.begin(), robot.drive->wheels.end());
    driveJoints.push_back(robot.drive->articulation);
    for (int j : driveJoints)
      if (j >= 0 && isHeld[static_cast<size_t>(j)]) {
        error = "joint '" + robot.joints[static_cast<size_t>(j)].name + "' drives the robot and cannot be held";
        return std::nullopt;
      }
  }

  // Each link's owner: itself, or (held joint above it) its parent's owner.
  std::vector<int> owner(nl, -1);
  const auto ownerOf = [&](auto& self, int link) -> int {
    int& o = owner[static_cast<size_t>(link)];
    if (o >= 0) return o;
    const int j = above[static_cast<size_t>(link)];
    o = j >= 0 && isHeld[static_cast<size_t>(j)] ? self(self, robot.joints[static_cast<size_t>(j)].parent) : link;
    return o;
  };
  for (size_t l = 0; l < nl; ++l) ownerOf(ownerOf, static_cast<int>(l));

  RigidRobot r;
  r.model.name = robot.name;
  r.model.file = robot.file;
  r.heldPositions.assign(jointPositions.begin(), jointPositions.end());
  std::vector<int> newLink(nl, -1), newJoint(nj, -1);
  for (size_t l = 0; l < nl; ++l)
    if (owner[l] == static_cast<int>(l)) {
      newLink[l] = static_cast<int>(r.model.links.size());
      r.model.links.push_back(robot.links[l]);
      r.linkOf.push_back(static_cast<int>(l));
    }
  for (size_t l = 0; l < nl; ++l) r.ownerOf.push_back(newLink[static_cast<size_t>(owner[l])]);

  // The rigid robot's zero pose is the full robot's with the held joints at
  // their held positions (the others at zero), so a joint that still moves
  // below held ones (a wheel below a held knee) keeps its meaning.
  std::vector<double> reposed(nj, 0.0);
  for (size_t j = 0; j < nj; ++j)
    if (isHeld[j]) reposed[j] = jointPositions[j];
  const std::vector<Pose> poses = linkPoses(robot, robot.links[0].pose, reposed);
  for (size_t l = 0; l < nl; ++l)
    if (newLink[l] >= 0) r.model.links[static_cast<size_t>(newLink[l])].pose = poses[l];
  // How each link moved from its zero pose into the reposed one.
  const auto moved = [&](int link) { return poses[static_cast<size_t>(link)] * inverse(robot.links[static_cast<size_t>(link)].pose); };

  // Gathered links: their geoms, each with its own mass, in the owner's
  // frame at the held pose. Owners' own geoms get their shares too.
  const auto shares = [](const LinkSpec& link) {
    double volume = 0;
    for (const GeomSpec& g : link.geoms) volume += geomVolume(g);
    std::vector<double> m;
    for (const GeomSpec& g : link.geoms) m.push_back(g.mass >= 0 ? g.mass : link.mass * geomVolume(g) / volume);
    return m;
  };
  for (size_t l = 0; l < nl; ++l) {
    if (owner[l] == static_cast<int>(l)) continue;
    const LinkSpec& link = robot.links[l];
    double volume = 0;
    for (const GeomSpec& g : link.geoms) volume += geomVolume(g);
    if (link.mass > 0 && (link.geoms.empty() || volume <= 0)) {
      error = "link '" + link.name + "' has mass but no geoms to carry it";
      return std::nullopt;
    }
    LinkSpec& target = r.model.links[static_cast<size_t>(newLink[static_cast<size_t>(owner[l])])];
    if (target.mass > 0 && target.geoms.empty()) {
      error = "link '" + target.name + "' has mass but no geoms to carry it";
      return std::nullopt;
    }
    if (!target.geoms.empty() && target.geoms.front().mass < 0) {
      const std::vector<double> own = shares(target);
      for (size_t g = 0; g < own.size(); ++g) target.geoms[g].mass = own[g];
    }
    const Pose rel = inverse(poses[static_cast<size_t>(owner[l])]) * poses[l];
    const std::vector<double> m = shares(link);
    for (size_t g = 0; g < link.geoms.size(); ++g) {
      GeomSpec geom = link.geoms[g];
      geom.pose = rel * geom.pose;
      geom.mass = m[g];
      target.geoms.push_back(geom);
    }
    target.mass += link.mass;
  }

  for (size_t j = 0; j < nj; ++j) {
    if (isHeld[j]) continue;
    JointSpec joint = robot.joints[j];
    const Pose m = moved(joint.parent >= 0 ? joint.parent : joint.child);
    joint.anchor = transformPoint(m, joint.anchor);
    joint.axis = rotate(m.q, joint.axis);
    joint.axis2 = rotate(m.q, joint.axis2);
    if (joint.parent >= 0) joint.parent = newLink[static_cast<size_t>(owner[static_cast<size_t>(joint.parent)])];
    joint.child = newLink[static_cast<size_t>(joint.child)];
    newJoint[j] = static_cast<int>(r.model.joints.size());
    r.model.joints.push_back(joint);
    r.jointOf.push_back(static_cast<int>(j));
  }
  for (ActuatorSpec a : robot.actuators) {
    if (isHeld[static_cast<size_t>(a.joint)]) continue;
    a.joint = newJoint[static_cast<size_t>(a.joint)];
    r.model.actuators.push_back(a);
  }
  for (SensorSpec s : robot.sensors) {
    if (s.joint >= 0) {
      if (isHeld[static_cast<size_t>(s.joint)]) continue;  // an encoder of a welded joint reads nothing
      s.joint = newJoint[static_cast<size_t>(s.joint)];
    }
    if (s.link >= 0) {
      const size_t l = static_cast<size_t>(s.link);
      s.pose = inverse(poses[static_cast<size_t>(owner[l])]) * poses[l] * s.pose;
      s.link = newLink[static_cast<size_t>(owner[l])];
    }
    r.model.sensors.push_back(s);
  }
  if (robot.drive) {
    DriveSpec d = *robot.drive;
    if (d.articulation >= 0) d.articulation = newJoint[static_cast<size_t>(d.articulation)];
    for (int& w : d.wheels)
      if (w >= 0) w = newJoint[static_cast<size_t>(w)];
    r.model.drive = d;
  }
  return r;
}

std::vector<double> fullJoints(const RigidRobot& rigid, std::span<const double> modelJoints, bool rates) {
  std::vector<double> out = rates ? std::vector<double>(rigid.heldPositions.size(), 0.0) : rigid.heldPositions;
  for (size_t j = 0; j < rigid.jointOf.size() && j < modelJoints.size(); ++j)
    out[static_cast<size_t>(rigid.jointOf[j])] = modelJoints[j];
  return out;
}

std::vector<double> rigidJoints(const RigidRobot& rigid, std::span<const double> full) {
  std::vector<double> out;
  for (int j : rigid.jointOf) out.push_back(static_cast<size_t>(j) < full.size() ? full[static_cast<size_t>(j)] : 0.0);
  return out;
}

}  // namespace sp
