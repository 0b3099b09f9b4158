// The robot as URDF (sim/urdf.h): read back with its own rules (a joint's
// origin, then a rotation about its axis), the URDF puts every shape where
// the twin's kinematics puts it, at zero and at random joint angles; the
// inertia is the textbook one; check_urdf (urdfdom, Debian's
// liburdfdom-tools) parses the WorkPartner's with every joint; what URDF
// cannot say is refused with the reason.

#include <QProcess>
#include <QTest>

#include <tinyxml2.h>

#include <cmath>
#include <map>
#include <random>

#include "sim/kinematics.h"
#include "sim/model_loader.h"
#include "sim/urdf.h"

using namespace sp;

namespace {

Vec3 parseVec(const char* text) {
  Vec3 v;
  if (text) std::sscanf(text, "%lf %lf %lf", &v.x, &v.y, &v.z);
  return v;
}

Pose originOf(const tinyxml2::XMLElement* e) {
  const tinyxml2::XMLElement* o = e->FirstChildElement("origin");
  if (!o) return {};
  return {parseVec(o->Attribute("xyz")), quatFromRpy(parseVec(o->Attribute("rpy")))};
}

double angleBetween(const Quat& a, const Quat& b) {
  const Quat d = conjugate(a) * b;
  return 2 * std::atan2(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z), std::abs(d.w));
}

/// Forward kinematics of a URDF document as URDF defines it: each joint's
/// child frame = parent frame * origin * rotation (or shift) by its value
/// along its axis. Returns every link's frame, the root at `root`.
std::map<std::string, Pose> urdfFrames(const tinyxml2::XMLDocument& doc, const std::map<std::string, double>& q,
                                       const Pose& root) {
  struct Joint {
    std::string parent, type;
    Pose origin;
    Vec3 axis;
    double value;
  };
  std::map<std::string, Joint> byChild;
  std::vector<std::string> links;
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  for (auto* l = robot->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) links.push_back(l->Attribute("name"));
  for (auto* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const auto it = q.find(j->Attribute("name"));
    const tinyxml2::XMLElement* axis = j->FirstChildElement("axis");
    byChild[j->FirstChildElement("child")->Attribute("link")] = {
        j->FirstChildElement("parent")->Attribute("link"), j->Attribute("type"), originOf(j),
        axis ? parseVec(axis->Attribute("xyz")) : Vec3{1, 0, 0}, it == q.end() ? 0 : it->second};
  }
  std::map<std::string, Pose> frames;
  std::function<Pose(const std::string&)> frameOf = [&](const std::string& link) -> Pose {
    if (auto f = frames.find(link); f != frames.end()) return f->second;
    const auto j = byChild.find(link);
    Pose pose = root;
    if (j != byChild.end()) {
      const Joint& joint = j->second;
      Pose motion;
      if (joint.type == "prismatic") motion.p = joint.value * joint.axis;
      else if (joint.type != "fixed") motion.q = quatFromAxisAngle(joint.axis, joint.value);
      pose = frameOf(joint.parent) * joint.origin * motion;
    }
    return frames[link] = pose;
  };
  for (const std::string& l : links) frameOf(l);
  return frames;
}

RobotModel workPartner() {
  Diagnostics diag;
  std::optional<RobotModel> robot = loadRobot(SP_SOURCE_DIR "/robots/workpartner.xml", diag);
  if (!robot) qFatal("%s", diag.format().c_str());
  return *robot;
}

}  // namespace

class TestUrdf : public QObject {
  Q_OBJECT

 private slots:
  // Every link's first shape lies where the twin's kinematics puts that
  // geom: at zero, and at random angles of every hinge within its limits.
  void shapesWhereTheKinematicsPutThem_data() {
    QTest::addColumn<int>("seed");  // 0 = every joint at zero
    for (int seed : {0, 1, 2, 3}) QTest::newRow(qPrintable(QString("seed %1").arg(seed))) << seed;
  }
  void shapesWhereTheKinematicsPutThem() {
    QFETCH(int, seed);
    const RobotModel robot = workPartner();
    std::string error;
    const std::optional<std::string> urdf = robotUrdf(robot, error);
    QVERIFY2(urdf, error.c_str());
    tinyxml2::XMLDocument doc;
    QCOMPARE(doc.Parse(urdf->c_str()), tinyxml2::XML_SUCCESS);

    std::mt19937 rng(static_cast<unsigned>(seed));
    std::vector<double> positions(robot.joints.size(), 0.0);
    std::map<std::string, double> byName;
    for (size_t j = 0; j < robot.joints.size() && seed; ++j) {
      const JointSpec& joint = robot.joints[j];
      const double lo = joint.limited ? joint.lower : -kPi, hi = joint.limited ? joint.upper : kPi;
      positions[j] = std::uniform_real_distribution<double>(lo, hi)(rng);
      byName[joint.name] = positions[j];
    }
    const Pose base{{0.3, -0.2, 0.9}, quatFromRpy({0.1, -0.05, 0.7})};
    const std::vector<Pose> expected = linkPoses(robot, base, positions);
    const std::map<std::string, Pose> frames = urdfFrames(doc, byName, base);  // the root keeps its own frame
    int checked = 0;
    for (auto* l = doc.FirstChildElement("robot")->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) {
      const int li = robot.findLink(l->Attribute("name"));
      const tinyxml2::XMLElement* visual = l->FirstChildElement("visual");
      if (li < 0 || !visual) continue;
      const Pose fromUrdf = frames.at(l->Attribute("name")) * originOf(visual);
      const Pose fromTwin = expected[static_cast<size_t>(li)] * robot.links[static_cast<size_t>(li)].geoms[0].pose;
      QVERIFY2(norm(fromUrdf.p - fromTwin.p) < 1e-6,
               qPrintable(QString("%1: %2 m apart").arg(l->Attribute("name")).arg(norm(fromUrdf.p - fromTwin.p))));
      QVERIFY2(angleBetween(fromUrdf.q, fromTwin.q) < 1e-6, l->Attribute("name"));
      ++checked;
    }
    QCOMPARE(checked, static_cast<int>(robot.links.size()));
  }

  // Mass and inertia as the textbook has them: a wheel (a 9 kg cylinder of
  // radius 0.2 m and width 0.1 m, its axis along y) has I = m r^2 / 2 about
  // its axle and m (3 r^2 + w^2) / 12 across; the masses sum to the robot's.
  void inertiaOfAWheel() {
    const RobotModel robot = workPartner();
    std::string error;
    tinyxml2::XMLDocument doc;
    doc.Parse(robotUrdf(robot, error)->c_str());
    double total = 0;
    for (auto* l = doc.FirstChildElement("robot")->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) {
      const tinyxml2::XMLElement* inertial = l->FirstChildElement("inertial");
      if (!inertial) continue;
      total += inertial->FirstChildElement("mass")->DoubleAttribute("value");
      if (std::string(l->Attribute("name")) != "wheel_fl") continue;
      const tinyxml2::XMLElement* i = inertial->FirstChildElement("inertia");
      const double m = 9, r = 0.2, w = 0.1;
      QVERIFY(std::abs(i->DoubleAttribute("iyy") - m * r * r / 2) < 1e-9);
      QVERIFY(std::abs(i->DoubleAttribute("ixx") - m * (3 * r * r + w * w) / 12) < 1e-9);
      QVERIFY(std::abs(i->DoubleAttribute("izz") - m * (3 * r * r + w * w) / 12) < 1e-9);
      QVERIFY(std::abs(i->DoubleAttribute("ixy")) < 1e-12);
      QVERIFY(norm(originOf(inertial).p) < 1e-12);  // the centre on the axle, where the joint is
    }
    QVERIFY(std::abs(total - robot.totalMass()) < 1e-9);
  }

  // check_urdf (urdfdom) parses it: the root, and every joint of the robot.
  void checkUrdfPassesIt() {
    const RobotModel robot = workPartner();
    QTemporaryDir dir;
    const QString path = dir.filePath("workpartner.urdf");
    std::string error;
    QFile file(path);
    QVERIFY(file.open(QIODevice::WriteOnly));
    file.write(robotUrdf(robot, error)->c_str());
    file.close();
    QProcess check;
    check.start(QStringLiteral("check_urdf"), {path});
    if (!check.waitForStarted()) QSKIP("check_urdf is not installed (Debian: liburdfdom-tools; scripts/install-deps.sh)");
    QVERIFY(check.waitForFinished(20000));
    const QString out = QString::fromUtf8(check.readAllStandardOutput());
    QVERIFY2(check.exitCode() == 0, qPrintable(out + check.readAllStandardError()));
    QVERIFY(out.contains(QLatin1String("root Link: rear_body")));
    // Every link is listed once as a child of its joint; the root is not a child.
    QCOMPARE(static_cast<int>(out.count(QRegularExpression(QStringLiteral("child\\(\\d+\\):")))),
             static_cast<int>(robot.joints.size()));
    // The control: a broken document fails it.
    QVERIFY(file.open(QIODevice::WriteOnly));
    file.write("<robot name=\"x\"><joint name=\"j\" type=\"revolute\"/></robot>");
    file.close();
    check.start(QStringLiteral("check_urdf"), {path});
    QVERIFY(check.waitForFinished(20000));
    QVERIFY(check.exitCode() != 0);
  }

  // A capsule is a cylinder and two spheres; universal and ball joints are
  // chains of revolute ones through massless links; a loop is refused.
  void whatUrdfCannotSay() {
    RobotModel robot;
    robot.name = "r";
    robot.links.resize(3);
    robot.links[0].name = "a";
    robot.links[1].name = "b";
    robot.links[2].name = "c";
    for (LinkSpec& l : robot.links) l.mass = 1;
    GeomSpec capsule;
    capsule.type = GeomType::Capsule;
    capsule.radius = 0.1;
    capsule.length = 0.4;
    robot.links[1].geoms.push_back(capsule);
    JointSpec u;
    u.name = "u";
    u.type = JointType::Universal;
    u.parent = 0;
    u.child = 1;
    JointSpec ball;
    ball.name = "s";
    ball.type = JointType::Ball;
    ball.parent = 1;
    ball.child = 2;
    robot.joints = {u, ball};
    std::string error;
    const std::optional<std::string> urdf = robotUrdf(robot, error);
    QVERIFY2(urdf, error.c_str());
    tinyxml2::XMLDocument doc;
    QCOMPARE(doc.Parse(urdf->c_str()), tinyxml2::XML_SUCCESS);
    int joints = 0, links = 0, cylinders = 0, spheres = 0;
    const tinyxml2::XMLElement* r = doc.FirstChildElement("robot");
    for (auto* j = r->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) ++joints;
    for (auto* l = r->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) {
      ++links;
      for (auto* v = l->FirstChildElement("visual"); v; v = v->NextSiblingElement("visual")) {
        cylinders += v->FirstChildElement("geometry")->FirstChildElement("cylinder") != nullptr;
        spheres += v->FirstChildElement("geometry")->FirstChildElement("sphere") != nullptr;
      }
    }
    QCOMPARE(joints, 5);  // 2 + 3 revolute
    QCOMPARE(links, 3 + 1 + 2);
    QCOMPARE(cylinders, 1);
    QCOMPARE(spheres, 2);

    JointSpec loop = u;
    loop.name = "closing";
    loop.type = JointType::Hinge;
    loop.parent = 0;
    loop.child = 2;
    robot.joints.push_back(loop);
    QVERIFY(!robotUrdf(robot, error));
    QCOMPARE(QString::fromStdString(error),
             QString("link 'c' is the child of joints 's' and 'closing': a closed loop, which URDF cannot describe"));
  }

  // simpartner-sim urdf: a file it cannot write is an error, and nothing is
  // left half-written; a good one is written whole.
  void commandWritesWholeOrNothing() {
    QTemporaryDir dir;
    QProcess sim;
    const QString exe = QStringLiteral(SP_BINARY_DIR "/app/simpartner-sim");
    sim.start(exe, {QStringLiteral("urdf"), QStringLiteral(SP_SOURCE_DIR "/robots/workpartner.xml"), QStringLiteral("--out"),
                    dir.filePath("no/such/folder/w.urdf")});
    QVERIFY(sim.waitForFinished(20000));
    QCOMPARE(sim.exitCode(), 1);
    QVERIFY2(sim.readAllStandardError().contains("no/such/folder/w.urdf: cannot write the file"), "the error names the file");
    QVERIFY(!QFileInfo::exists(dir.filePath("no/such/folder")));
    sim.start(exe, {QStringLiteral("urdf"), QStringLiteral(SP_SOURCE_DIR "/terrains/flat.world.xml"), QStringLiteral("--out"),
                    dir.filePath("w.urdf")});
    QVERIFY(sim.waitForFinished(20000));
    QCOMPARE(sim.exitCode(), 0);
    QCOMPARE(QString::fromUtf8(sim.readAllStandardOutput()).trimmed(),
             "wrote " + dir.filePath("w.urdf") + " (28 links, 27 joints)");
    QCOMPARE(QDir(dir.path()).entryList(QDir::Files), QStringList{"w.urdf"});  // no temporary left
  }
};

QTEST_GUILESS_MAIN(TestUrdf)
#include "tst_urdf.moc"
