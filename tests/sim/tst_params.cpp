// Tests of the simulation parameters (sim/params.h) and of
// config/defaults.params.

#include <QTest>

#include <QTemporaryDir>

#include <algorithm>
#include <fstream>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "tests/test_files.h"
#include "sim/calibration_table.h"
#include "sim/params.h"

using namespace sp;
using sp::test::writeFile;

namespace {

const std::string kDefaultsFile = std::string(SP_SOURCE_DIR) + "/config/defaults.params";

QString q(const std::string& s) { return QString::fromStdString(s); }

/// Every key's value as text, in table order. paramValue() prints numbers in
/// their shortest round-trip form, so equal text means bit-equal values.
QStringList values(const SimParams& params) {
  QStringList out;
  for (const ParamInfo& info : paramTable())
    out << q(info.key) + " = " + q(paramValue(params, info.key));
  return out;
}

/// A SimParams with every field away from its default.
SimParams allChanged() {
  SimParams p;
  p.step = 0.002;
  p.solver = Solver::Exact;
  p.iterations = 7;
  p.erp = 0.5;
  p.cfm = 0.01;
  p.surfaceLayer = 0.002;
  p.maxCorrectingVel = 3;
  p.maxContacts = 2;
  p.seed = 99;
  p.realTimeFactor = 0;
  p.telemetryRate = 1;
  p.laserRate = 2;
  p.logRate = 3;
  p.csvRate = 4;
  p.robotPort = 1234;
  p.linkDeadman = 0.5;
  p.linkKeepalive = 0.1;
  p.linkCommandExpiry = 2;
  p.linkLeaseConfirm = 20;
  p.linkMaxConnections = 500;
  p.linkHelloTimeout = 3;
  p.consoleStaleAfter = 4;
  p.maxLinearSpeed = 5;
  p.maxAngularSpeed = 6;
  p.maxJointError = 7;
  p.maxPenetration = 8;
  p.refineJointLimit = 5;
  p.refineYawRate = 9;
  p.ghostRegionInner = 0.4;
  p.ghostRegionOuter = 0.8;
  p.ghostRegionDeparture = 0.95;
  p.ghostRegionHold = 1;
  p.ghostRegionWindow = 30;
  p.ghostRegionGamma = 0.01;
  return p;
}

/// The keys assigned in a params file, in file order (comments stripped).
std::vector<std::string> keysInFile(const std::string& path) {
  std::vector<std::string> keys;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    line = line.substr(0, line.find('#'));
    const size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    std::string key = line.substr(0, eq);
    key.erase(0, key.find_first_not_of(" \t"));
    key.erase(key.find_last_not_of(" \t") + 1);
    keys.push_back(key);
  }
  return keys;
}


}  // namespace

class TestParams : public QObject {
  Q_OBJECT

 private slots:
  void defaultsFileLoadsToDefaults();
  void defaultsFileListsEveryKeyInTableOrder();
  void tableDefaultsAreSimParamsDefaults();
  void calibrationKeysComeFromTheirTable();
  void setParamAccepts_data();
  void setParamAccepts();
  void setParamStoresTypedValues();
  void setParamRejects_data();
  void setParamRejects();
  void loadParamsSyntax();
  void loadParamsErrors_data();
  void loadParamsErrors();
  void loadParamsMissingFile();
  void loadParamsDirectory();
  void applyOverrideAccepts();
  void applyOverrideRejects_data();
  void applyOverrideRejects();
  void paramValueOfUnknownKeyIsEmpty();
};

// Loading config/defaults.params over params that differ in every field
// gives exactly the default SimParams, with no diagnostics.
void TestParams::defaultsFileLoadsToDefaults() {
  SimParams params = allChanged();
  Diagnostics diag;
  QVERIFY2(loadParams(kDefaultsFile, params, diag), diag.format().c_str());
  QVERIFY2(diag.empty(), diag.format().c_str());
  QCOMPARE(values(params), values(SimParams{}));
}

// Every key of paramTable() is in config/defaults.params exactly once, the
// file has no other key, and the order is the same.
void TestParams::defaultsFileListsEveryKeyInTableOrder() {
  std::vector<std::string> tableKeys;
  for (const ParamInfo& info : paramTable()) tableKeys.push_back(info.key);
  const std::vector<std::string> fileKeys = keysInFile(kDefaultsFile);
  QStringList table, file;
  for (const std::string& k : tableKeys) table << q(k);
  for (const std::string& k : fileKeys) file << q(k);
  QCOMPARE(file, table);
}

// paramTable() reports SimParams' own defaults, unique dotted lower-case keys
// and a description for each.
void TestParams::tableDefaultsAreSimParamsDefaults() {
  const SimParams defaults;
  std::set<std::string> seen;
  const QRegularExpression keyPattern("^[a-z]+(\\.[a-z_]+)+$");
  const std::vector<ParamInfo> table = paramTable();
  QCOMPARE(table.size(), size_t(70));
  for (const ParamInfo& info : table) {
    QVERIFY2(seen.insert(info.key).second, info.key.c_str());
    QVERIFY2(keyPattern.match(q(info.key)).hasMatch(), info.key.c_str());
    QCOMPARE(q(info.defaultValue), q(paramValue(defaults, info.key)));
    QVERIFY2(!info.description.empty(), info.key.c_str());
  }
}

// The calibration.* keys are made from sim/calibration_table.h: each one's
// default is the table's files value, its bounds the table's (a value just
// past either is refused by the parser, the bound itself is taken), and a
// twin is calibrated() exactly when one of them differs from the files.
void TestParams::calibrationKeysComeFromTheirTable() {
  const SimParams defaults;
  QVERIFY(!defaults.calibrated());
  const std::vector<ParamInfo> table = paramTable();
  for (const CalParamInfo& c : calParams()) {
    QCOMPARE(defaults.*c.field, c.files);
    const auto row = std::find_if(table.begin(), table.end(), [&](const ParamInfo& i) { return i.key == c.key; });
    QVERIFY2(row != table.end(), c.key);
    QVERIFY2(row->description.find(c.description) == 0, c.key);
    for (const double bound : {c.lower, c.upper}) {
      SimParams p;
      Diagnostics diag;
      QVERIFY2(applyOverride(p, std::string(c.key) + "=" + std::to_string(bound), diag), c.key);
      QCOMPARE(p.*c.field, bound);
      QCOMPARE(p.calibrated(), bound != c.files);
    }
    for (const double outside : {c.lower - 0.01, c.upper + 0.01}) {
      SimParams p;
      Diagnostics diag;
      QVERIFY2(!applyOverride(p, std::string(c.key) + "=" + std::to_string(outside), diag), c.key);
      QVERIFY(!p.calibrated());
    }
  }
}

void TestParams::setParamAccepts_data() {
  QTest::addColumn<QString>("key");
  QTest::addColumn<QString>("value");
  QTest::addColumn<QString>("stored");  // paramValue() afterwards
  QTest::newRow("step") << "physics.step" << "0.002" << "0.002";
  QTest::newRow("step upper bound") << "physics.step" << "0.1" << "0.1";
  QTest::newRow("step exponent") << "physics.step" << "5e-4" << "5e-04";
  QTest::newRow("solver exact") << "physics.solver" << "exact" << "exact";
  QTest::newRow("solver quick") << "physics.solver" << "quick" << "quick";
  QTest::newRow("iterations min") << "physics.iterations" << "1" << "1";
  QTest::newRow("iterations max") << "physics.iterations" << "1000" << "1000";
  QTest::newRow("erp 0") << "physics.erp" << "0" << "0";
  QTest::newRow("erp 1") << "physics.erp" << "1" << "1";
  QTest::newRow("cfm 0") << "physics.cfm" << "0" << "0";
  QTest::newRow("cfm 0.999") << "physics.cfm" << "0.999" << "0.999";
  QTest::newRow("surface layer 0") << "contact.surface_layer" << "0" << "0";
  QTest::newRow("correcting velocity") << "contact.max_correcting_velocity" << "2.5" << "2.5";
  QTest::newRow("contacts 64") << "contact.max_per_pair" << "64" << "64";
  QTest::newRow("seed 0") << "random.seed" << "0" << "0";
  QTest::newRow("seed max") << "random.seed" << "18446744073709551615" << "18446744073709551615";
  QTest::newRow("factor") << "realtime.factor" << "0.25" << "0.25";
  QTest::newRow("factor max") << "realtime.factor" << "max" << "max";
  QTest::newRow("telemetry") << "rate.telemetry" << "10000" << "10000";
  QTest::newRow("laser") << "rate.laser" << "0.5" << "0.5";
  QTest::newRow("log") << "rate.log" << "1000" << "1000";
  QTest::newRow("csv") << "rate.csv" << "25" << "25";
  QTest::newRow("port min") << "port.robot" << "1" << "1";
  QTest::newRow("port max") << "port.robot" << "65535" << "65535";
  QTest::newRow("linear speed") << "health.max_linear_speed" << "12.5" << "12.5";
  QTest::newRow("angular speed") << "health.max_angular_speed" << "1e3" << "1000";
  QTest::newRow("acceleration") << "health.max_linear_acceleration" << "2500" << "2500";
  QTest::newRow("caterpillar swing") << "gait.caterpillar.hip_swing" << "20" << "20";
  QTest::newRow("rolking body time") << "gait.rolking.body_time" << "2.5" << "2.5";
  QTest::newRow("angular acceleration") << "health.max_angular_acceleration" << "5e4" << "50000";
  QTest::newRow("joint error") << "health.max_joint_error" << "0.01" << "0.01";
  QTest::newRow("penetration") << "health.max_penetration" << "0.2" << "0.2";
  QTest::newRow("refine band 0") << "rehearsal.refine.joint_limit" << "0" << "0";
}

// Valid values within each key's range are stored and read back.
void TestParams::setParamAccepts() {
  QFETCH(QString, key);
  QFETCH(QString, value);
  QFETCH(QString, stored);
  SimParams params;
  Diagnostics diag;
  QVERIFY2(setParam(params, key.toStdString(), value.toStdString(), "test.params", 4, diag),
           diag.format().c_str());
  QVERIFY(diag.empty());
  QCOMPARE(q(paramValue(params, key.toStdString())), stored);
}

// Values land in the matching typed fields; `max` stores factor 0 (unpaced).
void TestParams::setParamStoresTypedValues() {
  SimParams params;
  Diagnostics diag;
  QVERIFY(setParam(params, "physics.solver", "exact", "t", 1, diag));
  QCOMPARE(params.solver, Solver::Exact);
  QVERIFY(setParam(params, "realtime.factor", "max", "t", 1, diag));
  QCOMPARE(params.realTimeFactor, 0.0);
  QVERIFY(setParam(params, "random.seed", "18446744073709551615", "t", 1, diag));
  QCOMPARE(params.seed, std::numeric_limits<uint64_t>::max());
  QVERIFY(setParam(params, "physics.step", "0.0025", "t", 1, diag));
  QCOMPARE(params.step, 0.0025);
  QVERIFY(setParam(params, "contact.max_per_pair", "16", "t", 1, diag));
  QCOMPARE(params.maxContacts, 16);
  QVERIFY(setParam(params, "port.robot", "5000", "t", 1, diag));
  QCOMPARE(params.robotPort, 5000);
  QVERIFY(setParam(params, "contact.max_correcting_velocity", "2", "t", 1, diag));
  QCOMPARE(params.maxCorrectingVel, 2.0);
  QVERIFY(diag.empty());
}

void TestParams::setParamRejects_data() {
  QTest::addColumn<QString>("key");
  QTest::addColumn<QString>("value");
  QTest::addColumn<QString>("message");
  QTest::newRow("unknown key") << "physics.stpe" << "1" << "unknown key 'physics.stpe'";
  QTest::newRow("key case") << "Physics.Step" << "1" << "unknown key 'Physics.Step'";
  QTest::newRow("not a number") << "physics.step" << "abc" << "physics.step: expected a number, got 'abc'";
  QTest::newRow("empty") << "physics.step" << "" << "physics.step: expected a number, got ''";
  QTest::newRow("trailing junk") << "physics.step" << "0.001s" << "physics.step: expected a number, got '0.001s'";
  QTest::newRow("leading plus") << "physics.step" << "+0.004" << "physics.step: expected a number, got '+0.004'";
  QTest::newRow("decimal comma") << "physics.step" << "0,001" << "physics.step: expected a number, got '0,001'";
  QTest::newRow("nan") << "physics.step" << "nan" << "physics.step: expected a number, got 'nan'";
  QTest::newRow("inf") << "health.max_linear_speed" << "inf"
                       << "health.max_linear_speed: expected a number, got 'inf'";
  QTest::newRow("step negative") << "physics.step" << "-1" << "physics.step: must be >= 1e-05, got -1";
  QTest::newRow("step zero") << "physics.step" << "0" << "physics.step: must be >= 1e-05, got 0";
  QTest::newRow("step vanishing") << "physics.step" << "1e-300" << "physics.step: must be >= 1e-05, got 1e-300";
  QTest::newRow("step too big") << "physics.step" << "0.2" << "physics.step: must be <= 0.1, got 0.2";
  QTest::newRow("refine band negative") << "rehearsal.refine.speed" << "-0.1"
                                        << "rehearsal.refine.speed: must be >= 0, got -0.1";
  QTest::newRow("solver") << "physics.solver" << "fast" << "physics.solver: expected 'quick' or 'exact', got 'fast'";
  QTest::newRow("solver case") << "physics.solver" << "Quick"
                               << "physics.solver: expected 'quick' or 'exact', got 'Quick'";
  QTest::newRow("iterations fraction") << "physics.iterations" << "1.5"
                                       << "physics.iterations: expected an integer, got '1.5'";
  QTest::newRow("iterations zero") << "physics.iterations" << "0" << "physics.iterations: must be >= 1, got 0";
  QTest::newRow("iterations big") << "physics.iterations" << "1001" << "physics.iterations: must be <= 1000, got 1001";
  QTest::newRow("iterations huge") << "physics.iterations" << "99999999999999999999"
                                   << "physics.iterations: must be <= 1000, got 99999999999999999999";
  QTest::newRow("iterations hugely negative") << "physics.iterations" << "-99999999999999999999"
                                              << "physics.iterations: must be >= 1, got -99999999999999999999";
  QTest::newRow("erp negative") << "physics.erp" << "-0.1" << "physics.erp: must be >= 0, got -0.1";
  QTest::newRow("erp above 1") << "physics.erp" << "1.5" << "physics.erp: must be <= 1, got 1.5";
  QTest::newRow("cfm 1") << "physics.cfm" << "1" << "physics.cfm: must be < 1, got 1";
  QTest::newRow("cfm negative") << "physics.cfm" << "-1e-9" << "physics.cfm: must be >= 0, got -1e-9";
  QTest::newRow("surface layer") << "contact.surface_layer" << "-0.001"
                                 << "contact.surface_layer: must be >= 0, got -0.001";
  QTest::newRow("correcting velocity") << "contact.max_correcting_velocity" << "0"
                                       << "contact.max_correcting_velocity: must be > 0, got 0";
  QTest::newRow("contacts zero") << "contact.max_per_pair" << "0" << "contact.max_per_pair: must be >= 1, got 0";
  QTest::newRow("contacts 65") << "contact.max_per_pair" << "65" << "contact.max_per_pair: must be <= 64, got 65";
  QTest::newRow("seed negative") << "random.seed" << "-1"
                                 << "random.seed: expected a non-negative integer, got '-1'";
  QTest::newRow("seed 2^64") << "random.seed" << "18446744073709551616"
                             << "random.seed: must be <= 18446744073709551615, got 18446744073709551616";
  QTest::newRow("seed fraction") << "random.seed" << "1.5"
                                 << "random.seed: expected a non-negative integer, got '1.5'";
  QTest::newRow("factor zero") << "realtime.factor" << "0" << "realtime.factor: must be > 0, got 0";
  QTest::newRow("factor negative") << "realtime.factor" << "-2" << "realtime.factor: must be > 0, got -2";
  QTest::newRow("factor word") << "realtime.factor" << "fast"
                               << "realtime.factor: expected a number or 'max', got 'fast'";
  QTest::newRow("telemetry zero") << "rate.telemetry" << "0" << "rate.telemetry: must be > 0, got 0";
  QTest::newRow("laser big") << "rate.laser" << "20000" << "rate.laser: must be <= 10000, got 20000";
  QTest::newRow("log negative") << "rate.log" << "-5" << "rate.log: must be > 0, got -5";
  QTest::newRow("csv big") << "rate.csv" << "10000.5" << "rate.csv: must be <= 10000, got 10000.5";
  QTest::newRow("port zero") << "port.robot" << "0" << "port.robot: must be >= 1, got 0";
  QTest::newRow("port big") << "port.robot" << "65536" << "port.robot: must be <= 65535, got 65536";
  QTest::newRow("port word") << "port.robot" << "http" << "port.robot: expected an integer, got 'http'";
  QTest::newRow("linear speed") << "health.max_linear_speed" << "0"
                                << "health.max_linear_speed: must be > 0, got 0";
  QTest::newRow("angular speed") << "health.max_angular_speed" << "-1"
                                 << "health.max_angular_speed: must be > 0, got -1";
  QTest::newRow("swing too wide") << "gait.rolking.hip_swing" << "50"
                                  << "gait.rolking.hip_swing: must be <= 45, got 50";
  QTest::newRow("acceleration") << "health.max_linear_acceleration" << "0"
                                << "health.max_linear_acceleration: must be > 0, got 0";
  QTest::newRow("joint error") << "health.max_joint_error" << "0" << "health.max_joint_error: must be > 0, got 0";
  QTest::newRow("penetration") << "health.max_penetration" << "-0.5"
                               << "health.max_penetration: must be > 0, got -0.5";
}

// Bad keys and values give one exact diagnostic at the given origin, return
// false and leave every parameter unchanged.
void TestParams::setParamRejects() {
  QFETCH(QString, key);
  QFETCH(QString, value);
  QFETCH(QString, message);
  SimParams params = allChanged();
  Diagnostics diag;
  QVERIFY(!setParam(params, key.toStdString(), value.toStdString(), "test.params", 7, diag));
  QCOMPARE(q(diag.format()), "test.params:7: error: " + message + "\n");
  QCOMPARE(values(params), values(allChanged()));
}

// Comments (whole-line and after a value), blank lines, surrounding spaces
// and tabs, no spaces around '=', and CRLF line ends are all accepted; keys
// the file leaves out keep their values.
void TestParams::loadParamsSyntax() {
  QTemporaryDir dir;
  QVERIFY(dir.isValid());
  const std::string path = writeFile(dir, "ok.params",
                                     "# header comment\n"
                                     "\n"
                                     "   \t\n"
                                     "physics.step = 0.002   # faster\n"
                                     "\tphysics.solver\t=\texact\t\n"
                                     "physics.iterations=20\r\n"
                                     "realtime.factor = max#unpaced\n"
                                     "   # indented comment\n"
                                     "port.robot = 5000");
  SimParams params;
  Diagnostics diag;
  QVERIFY2(loadParams(path, params, diag), diag.format().c_str());
  QVERIFY(diag.empty());
  SimParams expected;
  expected.step = 0.002;
  expected.solver = Solver::Exact;
  expected.iterations = 20;
  expected.realTimeFactor = 0;
  expected.robotPort = 5000;
  QCOMPARE(values(params), values(expected));
}

void TestParams::loadParamsErrors_data() {
  QTest::addColumn<QByteArray>("content");
  QTest::addColumn<QString>("expected");  // "{file}" stands for the file's path
  QTest::newRow("unknown key") << QByteArray("physics.step = 0.002\nphysics.stpe = 1\n")
                               << "{file}:2: error: unknown key 'physics.stpe'\n";
  QTest::newRow("bad number") << QByteArray("physics.step = abc\n")
                              << "{file}:1: error: physics.step: expected a number, got 'abc'\n";
  QTest::newRow("out of range after comments")
      << QByteArray("# comment\n\nphysics.step = -1   # negative\n")
      << "{file}:3: error: physics.step: must be >= 1e-05, got -1\n";
  QTest::newRow("no equals sign") << QByteArray("physics.step 0.002\n") << "{file}:1: error: expected 'key = value'\n";
  QTest::newRow("no key") << QByteArray("  = 3\n") << "{file}:1: error: expected 'key = value'\n";
  QTest::newRow("no value") << QByteArray("physics.step =   # later\n")
                            << "{file}:1: error: expected 'key = value'\n";
  QTest::newRow("junk after value") << QByteArray("physics.iterations = 20 iterations\n")
                                    << "{file}:1: error: physics.iterations: expected an integer, "
                                       "got '20 iterations'\n";
  QTest::newRow("second equals sign") << QByteArray("physics.solver = quick = exact\n")
                                      << "{file}:1: error: physics.solver: expected 'quick' or 'exact', "
                                         "got 'quick = exact'\n";
  QTest::newRow("duplicate") << QByteArray("physics.erp = 0.3\n\nphysics.step = 0.002\nphysics.cfm = 0\n"
                                           "physics.step = 0.004\n")
                             << "{file}:5: error: duplicate key 'physics.step' (first set on line 3)\n";
  QTest::newRow("duplicate of a bad value")
      << QByteArray("physics.step = x\nphysics.step = 0.002\n")
      << "{file}:1: error: physics.step: expected a number, got 'x'\n"
         "{file}:2: error: duplicate key 'physics.step' (first set on line 1)\n";
  QTest::newRow("CRLF line numbers") << QByteArray("physics.step = 0.002\r\nfoo = 1\r\n")
                                     << "{file}:2: error: unknown key 'foo'\n";
  QTest::newRow("every error in one pass")
      << QByteArray("# tuned for the test rig\n"
                    "physics.step = 0.002\n"
                    "physics.stpe = 0.002\n"
                    "physics.iterations = lots\n"
                    "physics.erp = 0.4\n"
                    "rate.laser\n"
                    "port.robot = 99999\n"
                    "physics.erp = 0.5\n")
      << "{file}:3: error: unknown key 'physics.stpe'\n"
         "{file}:4: error: physics.iterations: expected an integer, got 'lots'\n"
         "{file}:6: error: expected 'key = value'\n"
         "{file}:7: error: port.robot: must be <= 65535, got 99999\n"
         "{file}:8: error: duplicate key 'physics.erp' (first set on line 5)\n";
}

// A file with errors reports every one with its 1-based line, returns false
// and leaves the params exactly as they were, valid lines included.
void TestParams::loadParamsErrors() {
  QFETCH(QByteArray, content);
  QFETCH(QString, expected);
  QTemporaryDir dir;
  QVERIFY(dir.isValid());
  const std::string path = writeFile(dir, "bad.params", content);
  SimParams params = allChanged();
  Diagnostics diag;
  QVERIFY(!loadParams(path, params, diag));
  QCOMPARE(q(diag.format()), expected.replace("{file}", q(path)));
  QCOMPARE(values(params), values(allChanged()));
}

// A missing file is one error on the file as a whole (no line).
void TestParams::loadParamsMissingFile() {
  SimParams params = allChanged();
  Diagnostics diag;
  QVERIFY(!loadParams("no/such/dir/sim.params", params, diag));
  QCOMPARE(q(diag.format()), QString("no/such/dir/sim.params: error: cannot open parameters file\n"));
  QCOMPARE(values(params), values(allChanged()));
}

// A path that opens but cannot be read (a directory) is an error too, not an
// empty file.
void TestParams::loadParamsDirectory() {
  QTemporaryDir dir;
  QVERIFY(dir.isValid());
  SimParams params = allChanged();
  Diagnostics diag;
  QVERIFY(!loadParams(dir.path().toStdString(), params, diag));
  QCOMPARE(q(diag.format()), dir.path() + ": error: cannot read parameters file\n");
  QCOMPARE(values(params), values(allChanged()));
}

// `key=value` overrides set the key, with or without spaces around '='.
void TestParams::applyOverrideAccepts() {
  SimParams params;
  Diagnostics diag;
  QVERIFY(applyOverride(params, "physics.step=0.002", diag));
  QVERIFY(applyOverride(params, " realtime.factor = max ", diag));
  QVERIFY(applyOverride(params, "physics.solver=exact", diag));
  QVERIFY2(diag.empty(), diag.format().c_str());
  QCOMPARE(params.step, 0.002);
  QCOMPARE(params.realTimeFactor, 0.0);
  QCOMPARE(params.solver, Solver::Exact);
}

void TestParams::applyOverrideRejects_data() {
  QTest::addColumn<QString>("assignment");
  QTest::addColumn<QString>("expected");
  QTest::newRow("no equals sign") << "physics.step" << "<command line>: error: expected key=value, got 'physics.step'\n";
  QTest::newRow("no key") << "=0.002" << "<command line>: error: expected key=value, got '=0.002'\n";
  QTest::newRow("empty") << "" << "<command line>: error: expected key=value, got ''\n";
  QTest::newRow("unknown key") << "physics.stpe=1" << "<command line>: error: unknown key 'physics.stpe'\n";
  QTest::newRow("bad value") << "physics.step=abc"
                             << "<command line>: error: physics.step: expected a number, got 'abc'\n";
  QTest::newRow("no value") << "physics.step=" << "<command line>: error: physics.step: expected a number, got ''\n";
  QTest::newRow("out of range") << "port.robot=0" << "<command line>: error: port.robot: must be >= 1, got 0\n";
  // Issue 61: a region's level is a share, inside (0, 1).
  QTest::newRow("a level of 1") << "ghost.region.outer=1"
                                << "<command line>: error: ghost.region.outer: must be < 1, got 1\n";
  QTest::newRow("a level of 0") << "ghost.region.inner=0"
                                << "<command line>: error: ghost.region.inner: must be > 0, got 0\n";
}

// Bad overrides are reported against "<command line>" (no line number) and
// change nothing.
void TestParams::applyOverrideRejects() {
  QFETCH(QString, assignment);
  QFETCH(QString, expected);
  SimParams params = allChanged();
  Diagnostics diag;
  QVERIFY(!applyOverride(params, assignment.toStdString(), diag));
  QCOMPARE(q(diag.format()), expected);
  QCOMPARE(values(params), values(allChanged()));
}

// paramValue() of a key that does not exist is empty, not an exception.
void TestParams::paramValueOfUnknownKeyIsEmpty() {
  QCOMPARE(q(paramValue(SimParams{}, "physics.stpe")), QString());
}

QTEST_GUILESS_MAIN(TestParams)
#include "tst_params.moc"
