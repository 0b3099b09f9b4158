#include "sim/model_loader.h"

#include <tinyxml2.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <sstream>

#include "sim/terrain_loader.h"
#include "sim/text.h"

namespace sp {
namespace {

namespace fs = std::filesystem;
using tinyxml2::XMLAttribute;
using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;

std::optional<double> parseDouble(std::string_view text) { return parseReal(trim(text)); }

std::string formatNumber(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

/// Reads the attributes of one element with type and range checks, records
/// which it consumed, and reports the rest as unknown in finish().
constexpr double kMaxFileValue = 1e6;

class ElementReader {
 public:
  ElementReader(const XMLElement* element, std::string_view file, Diagnostics& diag)
      : e_(element), file_(file), diag_(diag) {
    const char* name = e_->Attribute("name");
    context_ = name ? std::string(e_->Name()) + " '" + name + "'"
                    : "<" + std::string(e_->Name()) + ">";
  }

  int line() const { return e_->GetLineNum(); }
  const std::string& context() const { return context_; }
  bool has(const char* attr) const { return e_->FindAttribute(attr) != nullptr; }

  void error(int line, const std::string& message) { diag_.error(file_, line, context_ + ": " + message); }
  void error(const std::string& message) { error(line(), message); }

  /// The attribute's text, or nullopt if absent (an error when required).
  std::optional<std::string> text(const char* attr, bool required) {
    used_.push_back(attr);
    const XMLAttribute* a = e_->FindAttribute(attr);
    if (!a) {
      if (required) error("missing required attribute '" + std::string(attr) + "'");
      return std::nullopt;
    }
    return std::string(a->Value());
  }

  std::string name(const char* attr = "name") {
    std::optional<std::string> value = text(attr, true);
    if (!value) return {};
    if (!validName(*value)) {
      error(attrLine(attr), std::string(attr) + ": '" + *value +
                                "' is not a valid name (letters, digits, _ . -; not starting with a digit)");
    }
    return *value;
  }

  /// A number; `scale` converts file units (degrees) to internal ones.
  /// Range checks apply to the file value.
  double number(const char* attr, double fallback, bool required = false, double scale = 1.0) {
    lastValid_ = false;
    std::optional<std::string> t = text(attr, required);
    if (!t) return fallback;
    std::optional<double> v = parseDouble(*t);
    if (!v) {
      error(attrLine(attr), std::string(attr) + ": expected a number, got '" + *t + "'");
      return fallback;
    }
    if (!plausible(attr, *v)) return fallback;
    last_ = *v;
    lastValid_ = true;
    return *v * scale;
  }

  /// Every number of a robot or world file lies within +-kMaxFileValue
  /// (docs/formats.md): no mass, length, position, gain or limit of a robot
  /// is a million of its units, and ODE aborts on values like 1e300.
  bool plausible(const char* attr, double v) {
    if (std::abs(v) <= kMaxFileValue) return true;
    error(attrLine(attr), std::string(attr) + ": " + shortestText(v) + " is not a plausible value (beyond +-1e6)");
    return false;
  }

  /// Whether the last number() or vec3() call found a valid value.
  bool lastValid() const { return lastValid_; }

  // Range checks on the last number read, in file units; skipped when it was
  // absent or not a number (already reported).
  void positive(const char* attr) {
    if (lastValid_ && has(attr) && !(last_ > 0)) rangeError(attr, "> 0");
  }
  void nonNegative(const char* attr) {
    if (lastValid_ && has(attr) && !(last_ >= 0)) rangeError(attr, ">= 0");
  }
  void within(const char* attr, double lo, double hi) {
    if (lastValid_ && has(attr) && !(last_ >= lo && last_ <= hi))
      rangeError(attr, "in [" + formatNumber(lo) + ", " + formatNumber(hi) + "]");
  }

  int integer(const char* attr, int fallback, int lo, int hi) {
    std::optional<std::string> t = text(attr, false);
    if (!t) return fallback;
    int v = 0;
    const auto [end, ec] = std::from_chars(t->data(), t->data() + t->size(), v);
    if (t->empty() || ec != std::errc() || end != t->data() + t->size()) {
      error(attrLine(attr), std::string(attr) + ": expected an integer, got '" + *t + "'");
      return fallback;
    }
    if (v < lo || v > hi) {
      error(attrLine(attr), std::string(attr) + " must be in [" + std::to_string(lo) + ", " +
                                std::to_string(hi) + "], got " + *t);
      return fallback;
    }
    return v;
  }

  Vec3 vec3(const char* attr, Vec3 fallback, double scale = 1.0) {
    lastValid_ = false;
    std::optional<std::string> t = text(attr, false);
    if (!t) return fallback;
    std::istringstream in(*t);
    std::string parts[4];
    int count = 0;
    while (count < 4 && in >> parts[count]) ++count;
    std::optional<double> v[3];
    bool ok = count == 3;
    for (int i = 0; ok && i < 3; ++i) ok = (v[i] = parseDouble(parts[i])).has_value();
    if (!ok) {
      error(attrLine(attr), std::string(attr) + ": expected 3 numbers, got '" + *t + "'");
      return fallback;
    }
    for (const std::optional<double>& x : v)
      if (!plausible(attr, *x)) return fallback;
    lastValid_ = true;
    return {*v[0] * scale, *v[1] * scale, *v[2] * scale};
  }

  bool boolean(const char* attr, bool fallback) {
    std::optional<std::string> t = text(attr, false);
    if (!t) return fallback;
    if (*t == "true") return true;
    if (*t == "false") return false;
    error(attrLine(attr), std::string(attr) + ": expected true or false, got '" + *t + "'");
    return fallback;
  }

  /// One of `options`; returns its index, or `fallback` if absent or bad.
  int choice(const char* attr, std::initializer_list<const char*> options, int fallback,
             bool required = false) {
    std::optional<std::string> t = text(attr, required);
    if (!t) return fallback;
    int i = 0;
    std::string list;
    for (const char* option : options) {
      if (*t == option) return i;
      list += (i ? ", " : "") + std::string(option);
      ++i;
    }
    error(attrLine(attr), std::string(attr) + ": expected one of " + list + "; got '" + *t + "'");
    return fallback;
  }

  Pose pose() {
    const Vec3 xyz = vec3("xyz", {});
    const Vec3 rpy = vec3("rpy", {}, degToRad(1));
    return {xyz, quatFromRpy(rpy)};
  }

  Color color() {
    std::optional<std::string> t = text("color", false);
    if (!t) return {};
    std::istringstream in(*t);
    std::string parts[5];
    int count = 0;
    while (count < 5 && in >> parts[count]) ++count;
    double v[4] = {0, 0, 0, 1};
    bool ok = count == 3 || count == 4;
    for (int i = 0; ok && i < count; ++i) {
      std::optional<double> p = parseDouble(parts[i]);
      ok = p && *p >= 0 && *p <= 1;
      if (ok) v[i] = *p;
    }
    if (!ok) {
      error(attrLine("color"), "color: expected 3 or 4 numbers in [0, 1] (r g b [a]), got '" + *t + "'");
      return {};
    }
    return {v[0], v[1], v[2], v[3]};
  }

  /// Reports attributes that were never read.
  void finish() {
    for (const XMLAttribute* a = e_->FirstAttribute(); a; a = a->Next()) {
      bool known = false;
      for (const std::string& u : used_) known = known || u == a->Name();
      if (!known) error(a->GetLineNum(), "unknown attribute '" + std::string(a->Name()) + "'");
    }
  }

 private:
  static bool validName(const std::string& s) {
    if (s.empty() || (s[0] >= '0' && s[0] <= '9')) return false;
    for (char c : s) {
      const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '_' || c == '.' || c == '-';
      if (!ok) return false;
    }
    return true;
  }
  int attrLine(const char* attr) const {
    const XMLAttribute* a = e_->FindAttribute(attr);
    return a ? a->GetLineNum() : line();
  }
  void rangeError(const char* attr, const std::string& rule) {
    error(attrLine(attr), std::string(attr) + " must be " + rule + ", got " + formatNumber(last_));
  }

  const XMLElement* e_;
  std::string file_;
  Diagnostics& diag_;
  std::string context_;
  std::vector<std::string> used_;
  double last_ = 0;
  bool lastValid_ = false;
};

/// Tracks names of one kind for duplicate detection.
class NameSet {
 public:
  NameSet(const char* kind, std::string_view file, Diagnostics& diag)
      : kind_(kind), file_(file), diag_(diag) {}
  void add(const std::string& name, int line) {
    if (name.empty()) return;
    auto [it, inserted] = lines_.emplace(name, line);
    if (!inserted)
      diag_.error(file_, line, "duplicate " + kind_ + " name '" + name + "' (first defined on line " +
                                   std::to_string(it->second) + ")");
  }

 private:
  std::string kind_;
  std::string file_;
  Diagnostics& diag_;
  std::map<std::string, int> lines_;
};

void unknownElement(const XMLElement* child, const XMLElement* parent, std::string_view file,
                    Diagnostics& diag) {
  diag.error(file, child->GetLineNum(),
             "unknown element <" + std::string(child->Name()) + "> in <" + parent->Name() + ">");
}

/// Reports every child of an element that takes none.
void noChildren(const XMLElement* e, std::string_view file, Diagnostics& diag) {
  for (const XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement())
    unknownElement(c, e, file, diag);
}

/// Why a robot or world file was not read, for its error.
std::string unreadable(const std::string& path, const FileSet* files, const char* kind) {
  if (!sourceFileExists(path, files)) return std::string("cannot open ") + kind + " file: not found";
  const std::string why = sourceFileProblem(path, files);
  return std::string("cannot open ") + kind + " file: " + (why.empty() ? "cannot read it" : "it " + why);
}

/// Parses the document; reports a syntax error with its line.
bool parseXml(XMLDocument& doc, std::string_view xml, std::string_view file, Diagnostics& diag) {
  if (doc.Parse(xml.data(), xml.size()) == tinyxml2::XML_SUCCESS) return true;
  std::string what = doc.ErrorName();
  if (what.rfind("XML_ERROR_", 0) == 0) what = what.substr(10);
  for (char& c : what) c = c == '_' ? ' ' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // Line 1 at least (an empty file has none): editors jump to file:line.
  diag.error(file, std::max(1, doc.ErrorLineNum()), "XML syntax: " + what);
  return false;
}

const XMLElement* rootElement(const XMLDocument& doc, const char* expected, std::string_view file,
                              Diagnostics& diag) {
  const XMLElement* root = doc.RootElement();
  if (!root) {
    diag.error(file, 1, std::string("empty document, expected <") + expected + ">");
    return nullptr;
  }
  if (std::string_view(root->Name()) != expected) {
    diag.error(file, root->GetLineNum(),
               "root element is <" + std::string(root->Name()) + ">, expected <" + expected + ">");
    return nullptr;
  }
  return root;
}

void readVersion(ElementReader& r) {
  if (!r.has("version")) return;
  const int version = r.integer("version", 1, 1, 1);
  (void)version;
}

/// Parses `xml`, checks its root element is `<expected>` and reads the
/// root's name and version; nullptr (with diagnostics) if any of that fails.
const XMLElement* openRoot(XMLDocument& doc, std::string_view xml, std::string_view file, const char* expected,
                           std::string& name, Diagnostics& diag) {
  if (!parseXml(doc, xml, file, diag)) return nullptr;
  const XMLElement* root = rootElement(doc, expected, file, diag);
  if (!root) return nullptr;
  ElementReader r(root, file, diag);
  name = r.name();
  readVersion(r);
  r.finish();
  return root;
}

std::optional<GeomSpec> readGeom(const XMLElement* e, std::string_view file, Diagnostics& diag) {
  ElementReader r(e, file, diag);
  const int errorsBefore = diag.errorCount();
  GeomSpec g;
  g.line = r.line();
  const int type = r.choice("type", {"box", "cylinder", "sphere", "capsule"}, -1, true);
  g.type = static_cast<GeomType>(std::max(type, 0));
  if (type < 0) {
    // Type missing or unknown (reported): which shape attributes it needs is
    // unknown too, so do not report them as missing or unknown.
    for (const char* attr : {"size", "radius", "length"}) (void)r.text(attr, false);
  } else if (g.type == GeomType::Box) {
    if (!r.has("size")) r.error("missing required attribute 'size' (box)");
    g.size = r.vec3("size", {});
    if (r.has("size") && r.lastValid() && !(g.size.x > 0 && g.size.y > 0 && g.size.z > 0))
      r.error("size: every edge must be > 0");
  } else {
    g.radius = r.number("radius", 0, true);
    r.positive("radius");
    if (g.type != GeomType::Sphere) {
      g.length = r.number("length", 0, true);
      if (g.type == GeomType::Cylinder) r.positive("length");
      else r.nonNegative("length");
    }
  }
  g.pose = r.pose();
  if (std::optional<std::string> m = r.text("material", false)) g.material = *m;
  g.color = r.color();
  r.finish();
  noChildren(e, file, diag);
  if (diag.errorCount() != errorsBefore) return std::nullopt;
  return g;
}

std::vector<GeomSpec> readGeoms(const XMLElement* owner, std::string_view file, Diagnostics& diag) {
  std::vector<GeomSpec> geoms;
  for (const XMLElement* c = owner->FirstChildElement(); c; c = c->NextSiblingElement()) {
    if (std::string_view(c->Name()) == "geom") {
      if (std::optional<GeomSpec> g = readGeom(c, file, diag)) geoms.push_back(*g);
    } else {
      unknownElement(c, owner, file, diag);
    }
  }
  return geoms;
}

void readLink(const XMLElement* e, RobotModel& robot, NameSet& names, std::string_view file,
              Diagnostics& diag) {
  ElementReader r(e, file, diag);
  LinkSpec link;
  link.line = r.line();
  link.name = r.name();
  names.add(link.name, link.line);
  if (link.name == "world") r.error("name: 'world' is reserved for the ground in joint parents");
  link.mass = r.number("mass", 0, true);
  r.positive("mass");
  link.pose = r.pose();
  r.finish();
  link.geoms = readGeoms(e, file, diag);
  if (!e->FirstChildElement("geom"))
    diag.warning(file, link.line, r.context() + ": no <geom>, so the link has no collision shape");
  robot.links.push_back(std::move(link));
}

struct PendingJoint {
  JointSpec spec;
  std::string parent, child;
  int parentLine = 0, childLine = 0;
};

void readJoint(const XMLElement* e, std::vector<PendingJoint>& joints, NameSet& names,
               std::string_view file, Diagnostics& diag) {
  ElementReader r(e, file, diag);
  PendingJoint p;
  JointSpec& j = p.spec;
  j.line = r.line();
  j.name = r.name();
  names.add(j.name, j.line);
  j.type = static_cast<JointType>(
      r.choice("type", {"hinge", "slider", "universal", "ball", "fixed"}, 0, true));
  p.parent = r.text("parent", true).value_or("");
  p.child = r.text("child", true).value_or("");
  const XMLAttribute* pa = e->FindAttribute("parent");
  const XMLAttribute* ca = e->FindAttribute("child");
  p.parentLine = pa ? pa->GetLineNum() : j.line;
  p.childLine = ca ? ca->GetLineNum() : j.line;
  j.anchor = r.vec3("xyz", {});
  const bool hasAxis = j.type == JointType::Hinge || j.type == JointType::Slider ||
                       j.type == JointType::Universal;
  if (r.has("axis") && !hasAxis) r.error(std::string("axis: not used by a ") + toString(j.type) + " joint");
  if (r.has("axis2") && j.type != JointType::Universal) r.error("axis2: only universal joints have a second axis");
  j.axis = r.vec3("axis", {0, 0, 1});
  j.axis2 = r.vec3("axis2", {0, 1, 0});
  if (norm(j.axis) < 1e-9) r.error("axis must not be zero");
  if (norm(j.axis2) < 1e-9) r.error("axis2 must not be zero");
  j.axis = normalized(j.axis);
  j.axis2 = normalized(j.axis2);
  if (j.type == JointType::Universal && std::abs(dot(j.axis, j.axis2)) > 1e-6)
    r.error("axis and axis2 must be perpendicular");
  const bool angular = j.type != JointType::Slider;
  const double scale = angular ? degToRad(1) : 1.0;
  const char* unit = angular ? " deg" : " m";
  if (r.has("lower") != r.has("upper")) r.error("lower and upper limits come together");
  if (r.has("lower") && r.has("upper")) {
    if (!hasAxis) r.error(std::string("limits: a ") + toString(j.type) + " joint has no limits");
    j.limited = true;
    j.lower = r.number("lower", 0, false, scale);
    const double lowerFile = j.lower / scale;
    const bool lowerValid = r.lastValid();
    j.upper = r.number("upper", 0, false, scale);
    const double upperFile = j.upper / scale;
    if (lowerValid && r.lastValid() && lowerFile > upperFile)
      r.error("lower limit " + formatNumber(lowerFile) + unit + " is above upper limit " +
              formatNumber(upperFile) + unit);
  } else {
    (void)r.text("lower", false);
    (void)r.text("upper", false);
  }
  j.damping = r.number("damping", 0);
  r.nonNegative("damping");
  r.finish();
  noChildren(e, file, diag);
  joints.push_back(std::move(p));
}

struct PendingActuator {
  ActuatorSpec spec;
  std::string joint;
  int jointLine = 0;
  double targetFile = 0;
  bool hasTarget = false;
};

void readActuator(const XMLElement* e, std::vector<PendingActuator>& out, NameSet& names,
                  std::string_view file, Diagnostics& diag) {
  ElementReader r(e, file, diag);
  PendingActuator p;
  ActuatorSpec& a = p.spec;
  a.line = r.line();
  a.name = r.name();
  names.add(a.name, a.line);
  p.joint = r.text("joint", true).value_or("");
  const XMLAttribute* ja = e->FindAttribute("joint");
  p.jointLine = ja ? ja->GetLineNum() : a.line;
  a.mode = static_cast<JointMode>(r.choice("mode", {"velocity", "position", "torque", "free"}, 0));
  a.maxTorque = r.number("max_torque", 0, true);
  r.positive("max_torque");
  // Converted to radians once the joint type is known (resolveActuators).
  a.maxVelocity = r.number("max_velocity", 0, true);
  r.positive("max_velocity");
  a.hasPid = r.has("kp") || r.has("ki") || r.has("kd");
  a.kp = r.number("kp", 0);
  r.nonNegative("kp");
  a.ki = r.number("ki", 0);
  r.nonNegative("ki");
  a.kd = r.number("kd", 0);
  r.nonNegative("kd");
  a.integralLimit = r.number("integral_limit", 0);
  r.nonNegative("integral_limit");
  a.velocityScale = r.number("velocity_scale", 1);
  r.positive("velocity_scale");
  a.continuous = r.boolean("continuous", false);
  p.hasTarget = r.has("target");
  p.targetFile = r.number("target", 0);
  if (a.mode == JointMode::Position && !(a.hasPid && a.kp > 0))
    r.error("mode position needs PID gains (kp > 0)");
  r.finish();
  noChildren(e, file, diag);
  out.push_back(std::move(p));
}

struct PendingSensor {
  SensorSpec spec;
  std::string link, joint;
  int line = 0;
};

void readSensor(const XMLElement* e, std::vector<PendingSensor>& out, NameSet& names,
                std::string_view file, Diagnostics& diag) {
  ElementReader r(e, file, diag);
  PendingSensor p;
  SensorSpec& s = p.spec;
  s.line = p.line = r.line();
  s.name = r.name();
  names.add(s.name, s.line);
  s.type = static_cast<SensorType>(
      r.choice("type", {"pose", "laser", "encoder", "wheel_force", "joint_force", "imu"}, 0, true));
  const bool onJoint = s.type == SensorType::Encoder || s.type == SensorType::JointForce;
  if (onJoint) {
    p.joint = r.text("joint", true).value_or("");
    if (r.has("link")) r.error(std::string("link: ") + toString(s.type) + " sensors are on a joint");
    (void)r.text("link", false);  // reported above, not as unknown
  } else {
    p.link = r.text("link", true).value_or("");
    if (r.has("joint")) r.error(std::string("joint: ") + toString(s.type) + " sensors are on a link");
    (void)r.text("joint", false);
  }
  s.rate = r.number("rate", 0);
  r.nonNegative("rate");
  s.noise = r.number("noise", 0);
  r.nonNegative("noise");
  s.pose = r.pose();
  const bool laser = s.type == SensorType::Laser;
  for (const char* attr : {"fov", "beams", "min_range", "max_range", "exclude_self"})
    if (!laser && r.has(attr)) r.error(std::string(attr) + ": only laser sensors have it");
  s.fov = r.number("fov", degToRad(180), false, degToRad(1));  // fallback is not scaled
  if (r.has("fov")) r.within("fov", 1e-9, 360);
  s.beams = r.integer("beams", 181, 1, 100000);
  s.minRange = r.number("min_range", 0.05);
  r.nonNegative("min_range");
  s.maxRange = r.number("max_range", 10);
  r.positive("max_range");
  if (s.minRange >= s.maxRange)
    r.error("min_range " + formatNumber(s.minRange) + " m must be below max_range " +
            formatNumber(s.maxRange) + " m");
  s.excludeSelf = r.boolean("exclude_self", true);
  r.finish();
  noChildren(e, file, diag);
  out.push_back(std::move(p));
}

void readDrive(const XMLElement* e, RobotModel& robot, std::string_view file, Diagnostics& diag) {
  ElementReader r(e, file, diag);
  DriveSpec d;
  d.line = r.line();
  if (robot.drive) {
    r.error("only one <drive> per robot (first on line " + std::to_string(robot.drive->line) + ")");
    return;
  }
  const std::string art = r.text("articulation", true).value_or("");
  d.wheelRadius = r.number("wheel_radius", 0, true);
  r.positive("wheel_radius");
  d.tyreStiffness = r.number("tyre_stiffness", 0);
  d.tyreDamping = r.number("tyre_damping", 0);
  // As for a contact's stiffness and damping: a spring rings without its damper.
  if ((e->Attribute("tyre_stiffness") != nullptr) != (e->Attribute("tyre_damping") != nullptr))
    r.error("tyre_stiffness and tyre_damping go together: give both or neither");
  else if (e->Attribute("tyre_stiffness") && (d.tyreStiffness <= 0 || d.tyreDamping <= 0))
    r.error("tyre_stiffness and tyre_damping must both be > 0");
  r.finish();
  if (!art.empty()) {
    d.articulation = robot.findJoint(art);
    if (d.articulation < 0) r.error("unknown articulation joint '" + art + "'");
    else if (robot.joints[d.articulation].type != JointType::Hinge)
      r.error("articulation joint '" + art + "' must be a hinge");
  }
  int count = 0;
  for (const XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    if (std::string_view(c->Name()) != "wheel") {
      unknownElement(c, e, file, diag);
      continue;
    }
    ++count;
    ElementReader w(c, file, diag);
    const std::string joint = w.text("joint", true).value_or("");
    const int pos = w.choice("position", {"front_left", "front_right", "rear_left", "rear_right"}, -1, true);
    w.finish();
    noChildren(c, file, diag);
    const int index = robot.findJoint(joint);
    if (!joint.empty() && index < 0) w.error("unknown joint '" + joint + "'");
    else if (index >= 0 && robot.joints[index].type != JointType::Hinge)
      w.error("wheel joint '" + joint + "' must be a hinge");
    if (pos >= 0) {
      if (d.wheels[pos] >= 0) w.error("position already has a wheel");
      d.wheels[pos] = index;
    }
  }
  if (count != 4) r.error("needs exactly 4 <wheel> elements, got " + std::to_string(count));
  robot.drive = d;
}

}  // namespace

std::optional<RobotModel> parseRobot(std::string_view xml, std::string_view file, Diagnostics& diag) {
  const int errorsBefore = diag.errorCount();
  XMLDocument doc;
  RobotModel robot;
  robot.file = std::string(file);
  const XMLElement* root = openRoot(doc, xml, file, "robot", robot.name, diag);
  if (!root) return std::nullopt;
  NameSet links("link", file, diag), joints("joint", file, diag), actuators("actuator", file, diag),
      sensors("sensor", file, diag);
  std::vector<PendingJoint> pendingJoints;
  std::vector<PendingActuator> pendingActuators;
  std::vector<PendingSensor> pendingSensors;
  std::vector<const XMLElement*> drives;
  for (const XMLElement* e = root->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string_view tag = e->Name();
    if (tag == "link") readLink(e, robot, links, file, diag);
    else if (tag == "joint") readJoint(e, pendingJoints, joints, file, diag);
    else if (tag == "actuator") readActuator(e, pendingActuators, actuators, file, diag);
    else if (tag == "sensor") readSensor(e, pendingSensors, sensors, file, diag);
    else if (tag == "drive") drives.push_back(e);
    else unknownElement(e, root, file, diag);
  }
  if (robot.links.empty()) diag.error(file, root->GetLineNum(), "robot '" + robot.name + "': no <link>");

  // Resolve references once every name is known.
  std::vector<int> parentOf(robot.links.size(), -2);
  for (PendingJoint& p : pendingJoints) {
    JointSpec& j = p.spec;
    const std::string ctx = "joint '" + j.name + "': ";
    if (p.parent == "world") j.parent = -1;
    else if (!p.parent.empty() && (j.parent = robot.findLink(p.parent)) < 0)
      diag.error(file, p.parentLine, ctx + "unknown parent link '" + p.parent + "'");
    if (!p.child.empty() && (j.child = robot.findLink(p.child)) < 0)
      diag.error(file, p.childLine, ctx + "unknown child link '" + p.child + "'");
    if (!p.child.empty() && p.child == p.parent)
      diag.error(file, j.line, ctx + "parent and child are the same link");
    if (j.child >= 0) {
      if (parentOf[j.child] != -2)
        diag.error(file, j.line, ctx + "link '" + p.child + "' is already the child of another joint");
      parentOf[j.child] = j.parent;
    }
    robot.joints.push_back(j);
  }
  // Following parents never loops. Several roots are allowed: a link that is
  // no joint's child is a free body (docs/formats.md).
  for (size_t i = 0; i < robot.links.size(); ++i) {
    int at = static_cast<int>(i);
    for (size_t hops = 0; at >= 0 && parentOf[at] >= 0 && hops <= robot.links.size(); ++hops)
      at = parentOf[at];
    if (at >= 0 && parentOf[at] >= 0)
      diag.error(file, robot.links[i].line,
                 "link '" + robot.links[i].name + "': its joints form a loop");
  }

  for (PendingActuator& p : pendingActuators) {
    ActuatorSpec& a = p.spec;
    const std::string ctx = "actuator '" + a.name + "': ";
    if (!p.joint.empty()) {
      a.joint = robot.findJoint(p.joint);
      if (a.joint < 0) {
        diag.error(file, p.jointLine, ctx + "unknown joint '" + p.joint + "'");
      } else {
        const JointSpec& j = robot.joints[a.joint];
        if (j.type != JointType::Hinge && j.type != JointType::Slider)
          diag.error(file, p.jointLine,
                     ctx + "joint '" + p.joint + "' is a " + toString(j.type) +
                         " joint; actuators drive hinge and slider joints");
        for (const ActuatorSpec& other : robot.actuators)
          if (other.joint == a.joint)
            diag.error(file, a.line, ctx + "joint '" + p.joint + "' already has actuator '" + other.name +
                                         "' (line " + std::to_string(other.line) + ")");
        const bool angular = j.type != JointType::Slider;
        const double scale = angular ? degToRad(1) : 1.0;
        a.maxVelocity *= scale;
        a.integralLimit *= scale;
        a.initialTarget = p.targetFile * scale;
        if (p.hasTarget && j.limited && (a.initialTarget < j.lower || a.initialTarget > j.upper)) {
          const char* unit = angular ? " deg" : " m";
          diag.error(file, a.line,
                     ctx + "target " + formatNumber(p.targetFile) + unit + " is outside joint '" + j.name +
                         "' limits [" + formatNumber(j.lower / scale) + ", " +
                         formatNumber(j.upper / scale) + "]" + unit);
        }
        if (a.continuous && j.limited)
          diag.error(file, a.line, ctx + "continuous, but joint '" + j.name + "' has limits");
      }
    }
    robot.actuators.push_back(a);
  }

  for (PendingSensor& p : pendingSensors) {
    SensorSpec& s = p.spec;
    const std::string ctx = "sensor '" + s.name + "': ";
    if (!p.link.empty() && (s.link = robot.findLink(p.link)) < 0)
      diag.error(file, p.line, ctx + "unknown link '" + p.link + "'");
    if (!p.joint.empty() && (s.joint = robot.findJoint(p.joint)) < 0)
      diag.error(file, p.line, ctx + "unknown joint '" + p.joint + "'");
    robot.sensors.push_back(s);
  }
  for (const XMLElement* e : drives) readDrive(e, robot, file, diag);

  if (diag.errorCount() != errorsBefore) return std::nullopt;
  return robot;
}

std::optional<RobotModel> loadRobot(const std::string& path, Diagnostics& diag, const FileSet* files) {
  std::optional<std::string> text = readSourceFile(path, files);
  if (!text) {
    diag.error(path, 0, unreadable(path, files, "robot"));
    return std::nullopt;
  }
  return parseRobot(*text, path, diag);
}

namespace {

std::string resolvePath(std::string_view baseDir, const std::string& relative) {
  const fs::path p(relative);
  if (p.is_absolute() || baseDir.empty()) return p.lexically_normal().string();
  return (fs::path(baseDir) / p).lexically_normal().string();
}

void readContact(const XMLElement* e, WorldModel& world, std::string_view file, Diagnostics& diag,
                 std::vector<std::pair<std::string, int>>& materialRefs, bool& haveDefault) {
  ElementReader r(e, file, diag);
  ContactSpec c;
  c.line = r.line();
  const bool isDefault = r.boolean("default", false);
  const std::optional<std::string> a = r.text("a", false);
  const std::optional<std::string> b = r.text("b", false);
  if (isDefault && (a || b)) r.error("a default contact names no materials");
  if (!isDefault && (!a || !b)) r.error("needs both materials a and b, or default=\"true\"");
  c.a = a.value_or("");
  c.b = b.value_or("");
  c.mu = r.number("mu", 1.0);
  r.nonNegative("mu");
  c.bounce = r.number("bounce", 0);
  r.within("bounce", 0, 1);
  c.bounceVelocity = r.number("bounce_velocity", 0.1);
  r.nonNegative("bounce_velocity");
  c.softErp = r.number("soft_erp", -1);
  r.within("soft_erp", 0, 1);
  c.softCfm = r.number("soft_cfm", -1);
  r.nonNegative("soft_cfm");
  c.stiffness = r.number("stiffness", 0);
  r.nonNegative("stiffness");
  c.damping = r.number("damping", 0);
  r.nonNegative("damping");
  // A spring without its damper rings for ever, a damper alone holds nothing.
  if ((e->Attribute("stiffness") != nullptr) != (e->Attribute("damping") != nullptr))
    r.error("stiffness and damping go together: give both or neither");
  else if (e->Attribute("stiffness") && (c.stiffness <= 0 || c.damping <= 0))
    r.error("stiffness and damping must both be > 0");
  if (e->Attribute("stiffness") && (e->Attribute("soft_erp") || e->Attribute("soft_cfm")))
    r.error("stiffness and damping set soft_erp and soft_cfm: give one or the other");
  c.rollingResistance = r.number("rolling_resistance", 0);
  r.nonNegative("rolling_resistance");
  c.motionResistance = r.number("motion_resistance", 0);
  r.within("motion_resistance", 0, 1);
  c.motionResistanceSliding = r.boolean("motion_resistance_sliding", true);
  r.finish();
  noChildren(e, file, diag);
  if (isDefault) {
    if (haveDefault) r.error("a second default contact");
    haveDefault = true;
    world.defaultContact = c;
    return;
  }
  if (a) materialRefs.emplace_back(*a, c.line);
  if (b) materialRefs.emplace_back(*b, c.line);
  for (const ContactSpec& other : world.contacts)
    if ((other.a == c.a && other.b == c.b) || (other.a == c.b && other.b == c.a))
      r.error("materials '" + c.a + "' and '" + c.b + "' already have a contact (line " +
              std::to_string(other.line) + ")");
  world.contacts.push_back(c);
}

void readTerrain(const XMLElement* e, WorldModel& world, std::string_view file, std::string_view baseDir,
                 Diagnostics& diag, std::vector<std::pair<std::string, int>>& materialRefs, const FileSet* files) {
  ElementReader r(e, file, diag);
  const int errorsBefore = diag.errorCount();
  TerrainSpec& t = world.terrain;
  t.line = r.line();
  const int kind = r.choice("type", {"plane", "heightfield", "profile"}, 0, true);
  if (std::optional<std::string> m = r.text("material", false)) {
    t.material = *m;
    materialRefs.emplace_back(*m, t.line);
  }
  t.pose = r.pose();
  t.heightUncertainty = r.number("height_uncertainty", -1);
  r.nonNegative("height_uncertainty");
  if (t.heightUncertainty < 0) t.heightUncertainty = -1;  // refused above when stated
  const Vec3 rpy = rpyFromQuat(t.pose.q);
  if (std::abs(rpy.x) > 1e-9 || std::abs(rpy.y) > 1e-9) r.error("rpy: terrain may only be turned about z (yaw)");
  if (kind == 0) {
    t.kind = TerrainSpec::Kind::Plane;
    for (const char* attr : {"file", "format", "width", "depth", "min_height", "max_height", "resolution"})
      if (r.has(attr)) {
        r.error(std::string(attr) + ": not used by a plane");
        (void)r.text(attr, false);  // reported; not unknown as well
      }
    r.finish();
    noChildren(e, file, diag);
    return;
  }
  t.kind = TerrainSpec::Kind::Heightfield;
  TerrainSource src;
  const std::optional<std::string> f = r.text("file", true);
  if (kind == 2) {
    src.format = TerrainFormat::Profile;
    if (r.has("format")) r.error("format: a profile is always distance,height CSV");
    (void)r.text("format", false);  // reported; not unknown as well
    if (r.has("width")) r.error("width: a profile's length comes from its distances");
    if (!r.has("depth")) r.error("missing required attribute 'depth' (lateral width of the profile)");
  } else {
    src.format = static_cast<TerrainFormat>(r.choice("format", {"auto", "asc", "pgm", "csv"}, 0));
    if (r.has("resolution")) r.error("resolution: only profiles are resampled");
  }
  src.width = r.number("width", 0);
  r.positive("width");
  src.depth = r.number("depth", 0);
  r.positive("depth");
  src.minHeight = r.number("min_height", 0);
  src.maxHeight = r.number("max_height", 1);
  if (src.minHeight > src.maxHeight) r.error("min_height is above max_height");
  src.resolution = r.number("resolution", 0.05);
  r.positive("resolution");
  r.finish();
  noChildren(e, file, diag);
  if (!f) return;
  t.file = resolvePath(baseDir, *f);
  src.path = t.file;
  if (!sourceFileExists(t.file, files)) {
    r.error("terrain file '" + *f + "' not found (looked at " + t.file + ")");
    return;
  }
  if (diag.errorCount() != errorsBefore) return;  // do not load with bad scaling attributes
  if (std::optional<HeightGrid> grid = loadHeightGrid(src, diag, files)) t.grid = std::move(*grid);
}

void readObject(const XMLElement* e, WorldModel& world, NameSet& names, std::string_view file,
                Diagnostics& diag) {
  ElementReader r(e, file, diag);
  ObjectSpec o;
  o.line = r.line();
  o.name = r.name();
  names.add(o.name, o.line);
  o.isStatic = r.boolean("static", true);
  o.mass = r.number("mass", 0);
  if (o.isStatic && r.has("mass")) r.error("mass: a static object does not move; remove it or set static=\"false\"");
  if (!o.isStatic) {
    if (!r.has("mass")) r.error("missing required attribute 'mass' (dynamic object)");
    r.positive("mass");
  }
  o.pose = r.pose();
  r.finish();
  o.geoms = readGeoms(e, file, diag);
  if (o.geoms.empty() && !e->FirstChildElement()) r.error("needs at least one <geom>");
  world.objects.push_back(std::move(o));
}

}  // namespace

std::optional<WorldModel> parseWorld(std::string_view xml, std::string_view file, std::string_view baseDir,
                                     Diagnostics& diag, const FileSet* files) {
  const int errorsBefore = diag.errorCount();
  XMLDocument doc;
  WorldModel world;
  world.file = std::string(file);
  const XMLElement* root = openRoot(doc, xml, file, "world", world.name, diag);
  if (!root) return std::nullopt;
  NameSet materials("material", file, diag), objects("object", file, diag), robots("robot", file, diag);
  std::vector<std::pair<std::string, int>> materialRefs;
  bool haveDefault = false, haveGravity = false;
  int terrainLine = 0;
  for (const XMLElement* e = root->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string_view tag = e->Name();
    if (tag == "gravity") {
      ElementReader r(e, file, diag);
      if (haveGravity) r.error("a second <gravity>");
      haveGravity = true;
      world.gravity = r.vec3("xyz", world.gravity);
      r.finish();
      noChildren(e, file, diag);
    } else if (tag == "material") {
      ElementReader r(e, file, diag);
      const std::string name = r.name();
      r.finish();
      noChildren(e, file, diag);
      materials.add(name, r.line());
      world.materials.push_back(name);
    } else if (tag == "contact") {
      readContact(e, world, file, diag, materialRefs, haveDefault);
    } else if (tag == "terrain") {
      if (terrainLine) {
        diag.error(file, e->GetLineNum(),
                   "a second <terrain> (first on line " + std::to_string(terrainLine) + ")");
        continue;
      }
      terrainLine = e->GetLineNum();
      readTerrain(e, world, file, baseDir, diag, materialRefs, files);
    } else if (tag == "object") {
      readObject(e, world, objects, file, diag);
    } else if (tag == "robot") {
      ElementReader r(e, file, diag);
      RobotInstance inst;
      inst.line = r.line();
      inst.name = r.name();
      robots.add(inst.name, inst.line);
      const std::optional<std::string> f = r.text("file", true);
      inst.pose = r.pose();
      r.finish();
      noChildren(e, file, diag);
      if (f) {
        const std::string path = resolvePath(baseDir, *f);
        if (!sourceFileExists(path, files)) {
          r.error("robot file '" + *f + "' not found (looked at " + path + ")");
        } else if (const std::string why = sourceFileProblem(path, files); !why.empty()) {
          r.error("robot file '" + *f + "' " + why);
        } else if (std::optional<RobotModel> model = loadRobot(path, diag, files)) {
          inst.model = std::move(*model);
          for (const LinkSpec& link : inst.model.links)
            for (const GeomSpec& g : link.geoms)
              if (!g.material.empty()) materialRefs.emplace_back(g.material, -inst.line);
        }
      }
      world.robots.push_back(std::move(inst));
    } else {
      unknownElement(e, root, file, diag);
    }
  }
  if (!terrainLine) diag.error(file, root->GetLineNum(), "world '" + world.name + "': no <terrain>");
  for (const ObjectSpec& o : world.objects)
    for (const GeomSpec& g : o.geoms)
      if (!g.material.empty()) materialRefs.emplace_back(g.material, g.line);

  // Materials must be declared; robot geoms report at the <robot> line.
  std::vector<std::pair<std::string, int>> reported;
  for (const auto& [name, line] : materialRefs) {
    const std::pair<std::string, int> key{name, line};
    if (std::find(reported.begin(), reported.end(), key) != reported.end()) continue;
    reported.push_back(key);
    bool declared = false;
    for (const std::string& m : world.materials) declared = declared || m == name;
    if (!declared) {
      const bool fromRobot = line < 0;
      diag.error(file, fromRobot ? -line : line,
                 std::string(fromRobot ? "robot uses" : "uses") + " undeclared material '" + name +
                     "' (declare it with <material name=\"" + name + "\"/>)");
    }
  }
  if (diag.errorCount() != errorsBefore) return std::nullopt;
  return world;
}

std::optional<WorldModel> loadWorld(const std::string& path, Diagnostics& diag, const FileSet* files) {
  std::optional<std::string> text = readSourceFile(path, files);
  if (!text) {
    diag.error(path, 0, unreadable(path, files, "world"));
    return std::nullopt;
  }
  return parseWorld(*text, path, fs::path(path).parent_path().string(), diag, files);
}

std::string xmlRootName(const std::string& path) {
  XMLDocument doc;
  std::optional<std::string> text = readSourceFile(path, nullptr);
  if (!text || doc.Parse(text->data(), text->size()) != tinyxml2::XML_SUCCESS || !doc.RootElement())
    return {};
  return doc.RootElement()->Name();
}

}  // namespace sp
