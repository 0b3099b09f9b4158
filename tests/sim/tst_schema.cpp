// Tests of the XML schemas sim/schema/robot.xsd and world.xsd: every shipped
// robot and world file validates, the examples in docs/formats.md validate,
// and deliberately bad documents fail with the expected complaint, so the
// schemas are known to be strict. Runs xmllint (package libxml2-utils).

#include <QProcess>
#include <QStandardPaths>
#include <QTest>

#include <QRegularExpression>

namespace {

const QString kSourceDir = QStringLiteral(SP_SOURCE_DIR);

QString schemaPath(const QString& kind) { return kSourceDir + "/sim/schema/" + kind + ".xsd"; }

/// What xmllint said about one file.
struct Validation {
  int exitCode = -1;  ///< 0 valid, 3 invalid, 5 schema does not compile, ...
  QString output;     ///< stderr and stdout
};

Validation validate(const QString& xmllint, const QString& schema, const QString& file) {
  QProcess p;
  p.setProcessChannelMode(QProcess::MergedChannels);
  p.start(xmllint, {"--noout", "--schema", schema, file});
  Validation v;
  if (!p.waitForFinished(60000) || p.exitStatus() != QProcess::NormalExit) {
    v.output = "xmllint did not finish: " + p.errorString();
    return v;
  }
  v.exitCode = p.exitCode();
  v.output = QString::fromLocal8Bit(p.readAll());
  return v;
}

QStringList filesIn(const QString& dir, const QString& pattern) {
  QStringList out;
  for (const QString& name : QDir(kSourceDir + "/" + dir).entryList({pattern}, QDir::Files, QDir::Name))
    out << dir + "/" + name;
  return out;
}

/// The ```xml blocks of docs/formats.md whose root is <robot> or <world>.
QList<QPair<QString, QString>> docExamples() {
  QFile f(kSourceDir + "/docs/formats.md");
  if (!f.open(QIODevice::ReadOnly)) return {};
  const QString doc = QString::fromUtf8(f.readAll());
  static const QRegularExpression block(QStringLiteral("```xml\\n(.*?)```"),
                                        QRegularExpression::DotMatchesEverythingOption);
  static const QRegularExpression comment(QStringLiteral("<!--.*?-->"),
                                          QRegularExpression::DotMatchesEverythingOption);
  QList<QPair<QString, QString>> out;
  for (auto it = block.globalMatch(doc); it.hasNext();) {
    const QString xml = it.next().captured(1);
    const QString start = QString(xml).remove(comment).trimmed();
    if (start.startsWith("<robot")) out.append({"robot", xml});
    else if (start.startsWith("<world")) out.append({"world", xml});
  }
  return out;
}

}  // namespace

class TestSchema : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase();
  void testShippedFilesExist();
  void testShippedFiles_data();
  void testShippedFiles();
  void testDocExamples_data();
  void testDocExamples();
  void testGoodDocuments_data();
  void testGoodDocuments();
  void testBadDocuments_data();
  void testBadDocuments();

 private:
  void writeAndValidate(const QString& kind, const QByteArray& xml, Validation& result);

  QString xmllint_;
  QTemporaryDir dir_;
  int fileCount_ = 0;
};

void TestSchema::initTestCase() {
  xmllint_ = QStandardPaths::findExecutable("xmllint");
  if (xmllint_.isEmpty()) QSKIP("xmllint is not installed (package libxml2-utils)");
  QVERIFY(dir_.isValid());
  QVERIFY(QFile::exists(schemaPath("robot")));
  QVERIFY(QFile::exists(schemaPath("world")));
}

void TestSchema::writeAndValidate(const QString& kind, const QByteArray& xml, Validation& result) {
  const QString path = dir_.filePath(QString("doc%1.xml").arg(++fileCount_));
  QFile f(path);
  QVERIFY(f.open(QIODevice::WriteOnly));
  QCOMPARE(f.write(xml), xml.size());
  f.close();
  result = validate(xmllint_, schemaPath(kind), path);
}

// There is something to validate: at least one robot and one world ships.
void TestSchema::testShippedFilesExist() {
  QVERIFY2(!filesIn("robots", "*.xml").isEmpty(), "no robots/*.xml found");
  QVERIFY2(!filesIn("terrains", "*.world.xml").isEmpty(), "no terrains/*.world.xml found");
}

// Every shipped robot and world file is valid against its schema.
void TestSchema::testShippedFiles_data() {
  QTest::addColumn<QString>("kind");
  QTest::addColumn<QString>("file");
  for (const QString& file : filesIn("robots", "*.xml"))
    QTest::newRow(qPrintable(file)) << "robot" << file;
  for (const QString& file : filesIn("terrains", "*.world.xml"))
    QTest::newRow(qPrintable(file)) << "world" << file;
  // An empty table would run the test without data; testShippedFilesExist
  // reports the missing files.
  if (filesIn("robots", "*.xml").isEmpty() &&
      filesIn("terrains", "*.world.xml").isEmpty())
    QTest::newRow("no shipped files") << QString() << QString();
}

void TestSchema::testShippedFiles() {
  QFETCH(QString, kind);
  QFETCH(QString, file);
  if (file.isEmpty()) QSKIP("nothing shipped yet (see testShippedFilesExist)");
  const Validation v = validate(xmllint_, schemaPath(kind), kSourceDir + "/" + file);
  QVERIFY2(v.exitCode == 0, qPrintable(v.output));
}

// The robot and world examples of docs/formats.md are valid.
void TestSchema::testDocExamples_data() {
  QTest::addColumn<QString>("kind");
  QTest::addColumn<QByteArray>("xml");
  int n = 0;
  bool robot = false, world = false;
  for (const auto& [kind, xml] : docExamples()) {
    QTest::newRow(qPrintable(QString("%1 example %2").arg(kind).arg(++n))) << kind << xml.toUtf8();
    robot = robot || kind == "robot";
    world = world || kind == "world";
  }
  // A missing example fails (an empty table would not run the test at all).
  if (!robot) QTest::newRow("no robot example") << QString() << QByteArray();
  if (!world) QTest::newRow("no world example") << QString() << QByteArray();
}

void TestSchema::testDocExamples() {
  QFETCH(QString, kind);
  QFETCH(QByteArray, xml);
  QVERIFY2(!kind.isEmpty(), "docs/formats.md has no ```xml example with a <robot> or <world> root");
  Validation v;
  writeAndValidate(kind, xml, v);
  QVERIFY2(v.exitCode == 0, qPrintable(v.output));
}

// Documents using every element and attribute are valid: the schemas accept
// what the loader accepts, in any child order.
void TestSchema::testGoodDocuments_data() {
  QTest::addColumn<QString>("kind");
  QTest::addColumn<QByteArray>("xml");

  QTest::newRow("robot, every attribute") << "robot" << QByteArray(R"(<robot name="r-1.x" version="1">
  <sensor name="gps" type="pose" link="body" rate="10" noise="0.01"/>
  <drive articulation="waist" wheel_radius="0.3">
    <wheel joint="waist" position="rear_right"/>
    <wheel joint="waist" position="front_left"/>
    <wheel joint="waist" position="rear_left"/>
    <wheel joint="waist" position="front_right"/>
  </drive>
  <link name="body" mass="4" xyz="0 0 0.15" rpy="0 0 90">
    <geom type="box" size="0.4 0.3 0.1" material="steel" color="1 0 0"/>
    <geom type="cylinder" radius="0.1" length="0.04" xyz="0 0 1" rpy="90 0 0" color="0 0 1 0.5"/>
    <geom type="capsule" radius=".02" length="0"/>
    <geom type="sphere" radius="5e-2"/>
  </link>
  <link name="_rear" mass="1.5"/>
  <joint name="waist" type="hinge" parent="body" child="_rear" xyz="-0.5 0 0" axis="0 0 1"
         lower="-30" upper="30." damping="0.5"/>
  <joint name="u" type="universal" parent="world" child="body" axis="1 0 0" axis2="0 1 0"/>
  <actuator name="m" joint="waist" mode="position" max_torque="20" max_velocity="45" kp="2"
            ki="0.1" kd="0" integral_limit="5" continuous="false" target="-10"/>
  <sensor name="scan" type="laser" link="body" xyz="0.2 0 0.1" rpy="0 0 180" fov="360" beams="720"
          min_range="0" max_range="8" exclude_self="true"/>
  <sensor name="enc" type="encoder" joint="waist"/>
</robot>)");
  QTest::newRow("world, every attribute") << "world" << QByteArray(R"(<world name="yard" version="1">
  <robot name="wp" file="../robots/workpartner.xml" xyz="0 0 0.5" rpy="0 0 90"/>
  <contact a="rubber" b="ground" mu="1.1" bounce="1" bounce_velocity="0.5" soft_erp="0.3"
           soft_cfm="1e-5" rolling_resistance="0.01"/>
  <contact default="true" mu="0.6"/>
  <terrain type="heightfield" material="ground" file="bumpy.asc" format="asc" width="20" depth="20"
           min_height="-1" max_height="2" xyz="0 0 -0.5" rpy="0 0 45"/>
  <material name="ground"/>
  <material name="rubber"/>
  <gravity xyz="0 0 -9.81"/>
  <object name="crate" static="false" mass="3" xyz="2 0 0.25" rpy="0 0 45">
    <geom type="box" size="0.5 0.5 0.5" material="rubber"/>
  </object>
  <object name="wall" static="true"><geom type="box" size="0.1 4 1"/></object>
</world>)");
  QTest::newRow("world, profile terrain") << "world" << QByteArray(R"(<world name="track">
  <terrain type="profile" file="test_track.csv" depth="3" resolution="0.05"/>
</world>)");
}

void TestSchema::testGoodDocuments() {
  QFETCH(QString, kind);
  QFETCH(QByteArray, xml);
  Validation v;
  writeAndValidate(kind, xml, v);
  QVERIFY2(v.exitCode == 0, qPrintable(v.output));
}

// Each bad document fails validation (exit code 3, not a schema compile
// error) and xmllint names the problem.
void TestSchema::testBadDocuments_data() {
  QTest::addColumn<QString>("kind");
  QTest::addColumn<QByteArray>("xml");
  QTest::addColumn<QString>("complaint");

  const auto robot = [](const char* body) {
    return QByteArray(R"(<robot name="r">
  <link name="a" mass="1"><geom type="sphere" radius="0.1"/></link>
  <link name="b" mass="1"><geom type="sphere" radius="0.1"/></link>
  <joint name="j" type="hinge" parent="a" child="b"/>
)") + body + "</robot>\n";
  };
  const auto world = [](const char* body) {
    return QByteArray(R"(<world name="w">
  <material name="ground"/>
  <terrain type="plane" material="ground"/>
)") + body + "</world>\n";
  };

  QTest::newRow("unknown attribute") << "robot" << robot(R"(<sensor name="s" type="pose" link="a" colour="red"/>)")
                                     << "The attribute 'colour' is not allowed.";
  QTest::newRow("bad enum") << "robot" << robot(R"(<joint name="k" type="revolute" parent="world" child="a"/>)")
                            << "[facet 'enumeration'] The value 'revolute' is not an element of the set";
  QTest::newRow("negative mass") << "robot" << robot(R"(<link name="c" mass="-1"/>)")
                                 << "[facet 'minExclusive'] The value '-1' must be greater than '0'.";
  QTest::newRow("zero box edge") << "robot" << robot(R"(<link name="c" mass="1"><geom type="box" size="1 0 1"/></link>)")
                                 << "[facet 'minExclusive'] The value '0' must be greater than '0'.";
  QTest::newRow("not a number") << "robot" << robot(R"(<link name="c" mass="heavy"/>)")
                                << "'heavy' is not a valid value of the atomic type 'positive'.";
  QTest::newRow("plus sign") << "robot" << robot(R"(<link name="c" mass="+1"/>)")
                             << "[facet 'pattern'] The value '+1' is not accepted by the pattern";
  QTest::newRow("infinity") << "robot" << robot(R"(<joint name="k" type="hinge" parent="a" child="b" upper="INF" lower="0"/>)")
                            << "[facet 'pattern'] The value 'INF' is not accepted by the pattern";
  QTest::newRow("vec3 of two numbers") << "robot" << robot(R"(<link name="c" mass="1" xyz="0 1"/>)")
                                       << "[facet 'length'] The value '0 1' has a length of '2'";
  QTest::newRow("color of five numbers") << "robot"
                                         << robot(R"(<link name="c" mass="1"><geom type="sphere" radius="1" color="1 1 1 1 1"/></link>)")
                                         << "[facet 'maxLength'] The value '1 1 1 1 1' has a length of '5'";
  QTest::newRow("color above 1") << "robot" << robot(R"(<link name="c" mass="1"><geom type="sphere" radius="1" color="1 2 1"/></link>)")
                                 << "[facet 'maxInclusive'] The value '2' is greater than the maximum value allowed ('1').";
  QTest::newRow("invalid name") << "robot" << robot(R"(<link name="2nd" mass="1"/>)")
                                << "[facet 'pattern'] The value '2nd' is not accepted by the pattern";
  QTest::newRow("boolean as 1") << "robot" << robot(R"(<sensor name="s" type="laser" link="a" exclude_self="1"/>)")
                                << "[facet 'enumeration'] The value '1' is not an element of the set {'true', 'false'}.";
  QTest::newRow("missing required attribute") << "robot" << robot(R"(<actuator name="m" joint="j" max_torque="1"/>)")
                                              << "The attribute 'max_velocity' is required but missing.";
  QTest::newRow("unknown element") << "robot" << robot(R"(<body name="c"/>)")
                                   << "Element 'body': This element is not expected.";
  QTest::newRow("child of a geom") << "robot" << robot(R"(<link name="c" mass="1"><geom type="sphere" radius="1"><color/></geom></link>)")
                                   << "Element 'geom': Element content is not allowed, because the content type is empty.";
  QTest::newRow("duplicate link") << "robot" << robot(R"(<link name="a" mass="1"/>)")
                                  << "Duplicate key-sequence ['a'] in key identity-constraint 'linkName'.";
  QTest::newRow("duplicate sensor") << "robot" << robot(R"(<sensor name="s" type="pose" link="a"/><sensor name="s" type="imu" link="a"/>)")
                                    << "Duplicate key-sequence ['s'] in unique identity-constraint 'sensorName'.";
  QTest::newRow("dangling child link") << "robot" << robot(R"(<joint name="k" type="hinge" parent="world" child="c"/>)")
                                       << "No match found for key-sequence ['c'] of keyref 'jointChildRef'.";
  QTest::newRow("dangling actuator joint") << "robot" << robot(R"(<actuator name="m" joint="k" max_torque="1" max_velocity="1"/>)")
                                           << "No match found for key-sequence ['k'] of keyref 'actuatorJointRef'.";
  QTest::newRow("dangling sensor link") << "robot" << robot(R"(<sensor name="s" type="imu" link="c"/>)")
                                        << "No match found for key-sequence ['c'] of keyref 'sensorLinkRef'.";
  QTest::newRow("two actuators on one joint") << "robot" << robot(R"(<actuator name="m1" joint="j" max_torque="1" max_velocity="1"/>
  <actuator name="m2" joint="j" max_torque="1" max_velocity="1"/>)")
                                              << "Duplicate key-sequence ['j'] in unique identity-constraint 'actuatorJointUnique'.";
  QTest::newRow("link child of two joints") << "robot" << robot(R"(<joint name="k" type="fixed" parent="world" child="b"/>)")
                                            << "Duplicate key-sequence ['b'] in unique identity-constraint 'jointChildUnique'.";
  QTest::newRow("drive with three wheels") << "robot" << robot(R"(<drive articulation="j" wheel_radius="0.3">
    <wheel joint="j" position="front_left"/><wheel joint="j" position="front_right"/><wheel joint="j" position="rear_left"/>
  </drive>)") << "Missing child element(s). Expected is ( wheel ).";
  QTest::newRow("wheel position twice") << "robot" << robot(R"(<drive articulation="j" wheel_radius="0.3">
    <wheel joint="j" position="front_left"/><wheel joint="j" position="front_left"/>
    <wheel joint="j" position="rear_left"/><wheel joint="j" position="rear_right"/>
  </drive>)") << "Duplicate key-sequence ['front_left'] in unique identity-constraint 'wheelPositionUnique'.";
  QTest::newRow("laser fov 0") << "robot" << robot(R"(<sensor name="s" type="laser" link="a" fov="0"/>)")
                               << "[facet 'minExclusive'] The value '0' must be greater than '0'.";
  QTest::newRow("robot version 2") << "robot" << QByteArray(R"(<robot name="r" version="2"/>)")
                                   << "[facet 'enumeration'] The value '2' is not an element of the set {'1'}.";
  QTest::newRow("world against the robot schema") << "robot" << world("")
                                                  << "No matching global declaration available for the validation root.";

  QTest::newRow("bounce above 1") << "world" << world(R"(<contact default="true" bounce="1.5"/>)")
                                  << "[facet 'maxInclusive'] The value '1.5' is greater than the maximum value allowed ('1').";
  QTest::newRow("bad terrain type") << "world" << world(R"(<terrain type="mesh"/>)")
                                    << "[facet 'enumeration'] The value 'mesh' is not an element of the set";
  QTest::newRow("undeclared contact material") << "world" << world(R"(<contact a="ground" b="ice"/>)")
                                               << "No match found for key-sequence ['ice'] of keyref 'contactBRef'.";
  QTest::newRow("undeclared object material") << "world" << world(R"(<object name="o"><geom type="sphere" radius="1" material="wood"/></object>)")
                                              << "No match found for key-sequence ['wood'] of keyref 'objectGeomMaterialRef'.";
  QTest::newRow("duplicate material") << "world" << world(R"(<material name="ground"/>)")
                                      << "Duplicate key-sequence ['ground'] in key identity-constraint 'materialName'.";
  QTest::newRow("object without geom") << "world" << world(R"(<object name="o" static="false" mass="1"/>)")
                                       << "Missing child element(s). Expected is ( geom ).";
  QTest::newRow("robot without file") << "world" << world(R"(<robot name="wp"/>)")
                                      << "The attribute 'file' is required but missing.";
  QTest::newRow("negative heightfield width") << "world" << world(R"(<terrain type="heightfield" file="h.csv" width="-2" depth="2"/>)")
                                              << "[facet 'minExclusive'] The value '-2' must be greater than '0'.";
  QTest::newRow("robot against the world schema") << "world" << robot("")
                                                  << "No matching global declaration available for the validation root.";
}

void TestSchema::testBadDocuments() {
  QFETCH(QString, kind);
  QFETCH(QByteArray, xml);
  QFETCH(QString, complaint);
  Validation v;
  writeAndValidate(kind, xml, v);
  QVERIFY2(v.exitCode == 3, qPrintable(QString("exit code %1: %2").arg(v.exitCode).arg(v.output)));
  QVERIFY2(v.output.contains(complaint), qPrintable(v.output));
}

QTEST_GUILESS_MAIN(TestSchema)
#include "tst_schema.moc"
