#include "sim/urdf.h"

#include <tinyxml2.h>

#include <cstdio>
#include <functional>
#include <vector>

namespace sp {
namespace {

std::string num(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v == 0 ? 0.0 : v);  // no "-0"
  return text;
}
std::string vec(Vec3 v) { return num(v.x) + " " + num(v.y) + " " + num(v.z); }

void origin(tinyxml2::XMLPrinter& out, const Pose& pose) {
  out.OpenElement("origin");
  out.PushAttribute("xyz", vec(pose.p).c_str());
  out.PushAttribute("rpy", vec(rpyFromQuat(pose.q)).c_str());
  out.CloseElement();
}

/// One visual or collision element per primitive (a capsule is three).
void shapes(tinyxml2::XMLPrinter& out, const char* element, const GeomSpec& g, const Pose& inFrame) {
  struct Part {
    Pose pose;
    std::string tag;
    std::vector<std::pair<const char*, std::string>> attributes;
  };
  std::vector<Part> parts;
  switch (g.type) {
    case GeomType::Box: parts.push_back({inFrame, "box", {{"size", vec(g.size)}}}); break;
    case GeomType::Sphere: parts.push_back({inFrame, "sphere", {{"radius", num(g.radius)}}}); break;
    case GeomType::Cylinder:
      parts.push_back({inFrame, "cylinder", {{"radius", num(g.radius)}, {"length", num(g.length)}}});
      break;
    case GeomType::Capsule:
      parts.push_back({inFrame, "cylinder", {{"radius", num(g.radius)}, {"length", num(g.length)}}});
      for (double end : {-0.5, 0.5})
        parts.push_back({inFrame * Pose{{0, 0, end * g.length}, {}}, "sphere", {{"radius", num(g.radius)}}});
      break;
  }
  for (const Part& part : parts) {
    out.OpenElement(element);
    origin(out, part.pose);
    out.OpenElement("geometry");
    out.OpenElement(part.tag.c_str());
    for (const auto& [name, value] : part.attributes) out.PushAttribute(name, value.c_str());
    out.CloseElement();
    out.CloseElement();
    if (std::string(element) == "visual") {
      const Color& c = g.color;
      const std::string rgba = num(c.r) + " " + num(c.g) + " " + num(c.b) + " " + num(c.a);
      out.OpenElement("material");
      // Named by its colour: one name, one colour, however many links share it.
      std::string name = "rgba";
      for (double v : {c.r, c.g, c.b, c.a}) name += "_" + std::to_string(static_cast<int>(v * 1000 + 0.5));
      out.PushAttribute("name", name.c_str());
      out.OpenElement("color");
      out.PushAttribute("rgba", rgba.c_str());
      out.CloseElement();
      out.CloseElement();
    }
    out.CloseElement();
  }
}

void massless(tinyxml2::XMLPrinter& out, const std::string& name) {
  out.OpenElement("link");
  out.PushAttribute("name", name.c_str());
  out.CloseElement();
}

}  // namespace

std::optional<std::string> robotUrdf(const RobotModel& robot, std::string& error) {
  const size_t n = robot.links.size();
  // Each link's URDF frame: at its parent joint's anchor (the root: its own
  // pose), in its own orientation; robot frame, every joint at zero.
  std::vector<int> parentJoint(n, -1);
  for (size_t j = 0; j < robot.joints.size(); ++j) {
    const JointSpec& joint = robot.joints[j];
    if (joint.child < 0) continue;
    if (parentJoint[static_cast<size_t>(joint.child)] >= 0) {
      error = "link '" + robot.links[static_cast<size_t>(joint.child)].name + "' is the child of joints '" +
              robot.joints[static_cast<size_t>(parentJoint[static_cast<size_t>(joint.child)])].name + "' and '" +
              joint.name + "': a closed loop, which URDF cannot describe";
      return std::nullopt;
    }
    parentJoint[static_cast<size_t>(joint.child)] = static_cast<int>(j);
  }
  std::vector<int> roots;
  bool toWorld = false;
  for (size_t i = 0; i < n; ++i) {
    if (parentJoint[i] < 0) roots.push_back(static_cast<int>(i));
    else toWorld |= robot.joints[static_cast<size_t>(parentJoint[i])].parent < 0;
  }
  if (roots.size() + (toWorld ? 1 : 0) != 1) {
    std::string names;
    for (int r : roots) names += (names.empty() ? "'" : ", '") + robot.links[static_cast<size_t>(r)].name + "'";
    error = "URDF needs one root link; " + (roots.empty() ? std::string("every link hangs off the world and others")
                                                           : "these have no parent joint: " + names);
    return std::nullopt;
  }
  std::vector<Pose> frame(n);
  for (size_t i = 0; i < n; ++i) {
    frame[i] = robot.links[i].pose;
    if (parentJoint[i] >= 0) frame[i].p = robot.joints[static_cast<size_t>(parentJoint[i])].anchor;
  }
  const auto frameOf = [&](int link) { return link < 0 ? Pose{} : frame[static_cast<size_t>(link)]; };

  tinyxml2::XMLPrinter out;
  out.PushHeader(false, true);
  out.PushComment((" " + robot.name + ", written by simpartner-sim urdf from " + robot.file + " ").c_str());
  out.OpenElement("robot");
  out.PushAttribute("name", robot.name.c_str());
  if (toWorld) massless(out, "world");
  for (size_t i = 0; i < n; ++i) {
    const LinkSpec& link = robot.links[i];
    const Pose toLink = inverse(frame[i]) * link.pose;  // the link's own frame in its URDF frame
    out.OpenElement("link");
    out.PushAttribute("name", link.name.c_str());
    const MassProperties m = massProperties(link);
    out.OpenElement("inertial");
    // The inertia is about the centre in the link's axes; toLink turns those.
    origin(out, toLink * Pose{m.centre, {}});
    out.OpenElement("mass");
    out.PushAttribute("value", num(m.mass).c_str());
    out.CloseElement();
    out.OpenElement("inertia");
    const std::pair<const char*, double> inertia[] = {{"ixx", m.ixx}, {"ixy", m.ixy}, {"ixz", m.ixz},
                                                      {"iyy", m.iyy}, {"iyz", m.iyz}, {"izz", m.izz}};
    for (const auto& [name, value] : inertia) out.PushAttribute(name, num(value).c_str());
    out.CloseElement();
    out.CloseElement();
    for (const GeomSpec& g : link.geoms) shapes(out, "visual", g, toLink * g.pose);
    for (const GeomSpec& g : link.geoms) shapes(out, "collision", g, toLink * g.pose);
    out.CloseElement();
  }
  for (const JointSpec& joint : robot.joints) {
    if (joint.child < 0) continue;
    const int a = robot.findActuator(joint.name);
    const ActuatorSpec* actuator = a >= 0 ? &robot.actuators[static_cast<size_t>(a)] : nullptr;
    const Pose childFrame = frameOf(joint.child);
    // One URDF joint per axis: a universal joint two, a ball three, through
    // massless links between them.
    std::vector<Vec3> axes;
    switch (joint.type) {
      case JointType::Hinge:
      case JointType::Slider: axes = {joint.axis}; break;
      case JointType::Universal: axes = {joint.axis, joint.axis2}; break;
      case JointType::Ball: axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}; break;
      case JointType::Fixed: axes = {}; break;
    }
    const std::string parentName =
        joint.parent < 0 ? "world" : robot.links[static_cast<size_t>(joint.parent)].name;
    std::string from = parentName;
    Pose fromFrame = frameOf(joint.parent);
    const size_t stages = std::max<size_t>(axes.size(), 1);
    for (size_t k = 0; k < stages; ++k) {
      const bool last = k + 1 == stages;
      const std::string name = stages == 1 ? joint.name : joint.name + "_" + std::to_string(k + 1);
      const std::string to = last ? robot.links[static_cast<size_t>(joint.child)].name : name + "_link";
      if (!last) massless(out, to);
      const char* type = "fixed";
      if (!axes.empty()) {
        if (joint.type == JointType::Slider) type = "prismatic";
        else type = joint.limited && axes.size() == 1 ? "revolute" : "continuous";
      }
      out.OpenElement("joint");
      out.PushAttribute("name", name.c_str());
      out.PushAttribute("type", type);
      origin(out, inverse(fromFrame) * childFrame);
      out.OpenElement("parent");
      out.PushAttribute("link", from.c_str());
      out.CloseElement();
      out.OpenElement("child");
      out.PushAttribute("link", to.c_str());
      out.CloseElement();
      if (!axes.empty()) {
        out.OpenElement("axis");
        out.PushAttribute("xyz", vec(normalized(rotate(conjugate(childFrame.q), axes[k]))).c_str());
        out.CloseElement();
        const bool limitTag = std::string(type) != "continuous" || actuator;
        if (limitTag) {
          out.OpenElement("limit");
          if (std::string(type) != "continuous") {
            out.PushAttribute("lower", num(joint.limited ? joint.lower : -1e3).c_str());
            out.PushAttribute("upper", num(joint.limited ? joint.upper : 1e3).c_str());
          }
          out.PushAttribute("effort", num(actuator ? actuator->maxTorque : 0).c_str());
          out.PushAttribute("velocity", num(actuator ? actuator->maxVelocity : 0).c_str());
          out.CloseElement();
        }
        if (joint.damping > 0) {
          out.OpenElement("dynamics");
          out.PushAttribute("damping", num(joint.damping).c_str());
          out.CloseElement();
        }
      }
      out.CloseElement();
      from = to;
      fromFrame = childFrame;  // the stages share the child's frame: zero offsets after the first
    }
  }
  out.CloseElement();
  return std::string(out.CStr());
}

}  // namespace sp
