// Tests of command sequence files (sim/command_file.h) and of the command
// texts they share with sim/command.h (toText, toString).

#include <QTest>

#include <QTemporaryDir>

#include <fstream>

#include "tests/test_files.h"
#include "sim/command_check.h"
#include "sim/command_file.h"
#include "sim/math.h"
#include "sim/robot_model.h"

using namespace sp;
using sp::test::writeFile;

Q_DECLARE_METATYPE(sp::Command)

namespace {

QString q(const std::string& s) { return QString::fromStdString(s); }
QString q(const CommandCheck& c) { return QString::fromStdString(c.message); }

/// A small articulated robot, built by hand (no XML loader):
///   articulation  hinge [-35, 35] deg, PID, 30 deg/s, 5000 N m
///   knee_fl       hinge [0, 100] deg,   PID, 90 deg/s, 200 N m
///   hip_fl        hinge, no limits, no PID, 60 deg/s, 300 N m
///   wheel_fl..rr  hinges, no limits, no PID, 10 rad/s, 400 N m
///   lift          slider [0, 0.3] m, PID, 0.2 m/s, 1000 N
///   flap          hinge without actuator
/// and a <drive> over the articulation and the four wheels.
RobotModel testRobot() {
  RobotModel robot;
  robot.name = "tester";
  for (const char* link : {"front", "rear", "leg_fl", "wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr", "mast", "flap"}) {
    LinkSpec l;
    l.name = link;
    l.mass = 10;
    robot.links.push_back(l);
  }
  const auto joint = [&](const char* name, JointType type, int parent, int child, bool limited, double lower,
                         double upper) {
    JointSpec j;
    j.name = name;
    j.type = type;
    j.parent = parent;
    j.child = child;
    j.limited = limited;
    j.lower = lower;
    j.upper = upper;
    robot.joints.push_back(j);
    return static_cast<int>(robot.joints.size()) - 1;
  };
  const auto actuator = [&](int jointIndex, double maxTorque, double maxVelocity, bool pid) {
    ActuatorSpec a;
    a.name = robot.joints[jointIndex].name + "_motor";
    a.joint = jointIndex;
    a.maxTorque = maxTorque;
    a.maxVelocity = maxVelocity;
    a.hasPid = pid;
    a.kp = pid ? 10 : 0;
    a.mode = pid ? JointMode::Position : JointMode::Velocity;
    robot.actuators.push_back(a);
  };
  const int art = joint("articulation", JointType::Hinge, 0, 1, true, degToRad(-35), degToRad(35));
  actuator(art, 5000, degToRad(30), true);
  actuator(joint("knee_fl", JointType::Hinge, 0, 2, true, degToRad(0), degToRad(100)), 200, degToRad(90), true);
  actuator(joint("hip_fl", JointType::Hinge, 0, 2, false, 0, 0), 300, degToRad(60), false);
  DriveSpec drive;
  drive.articulation = art;
  drive.wheelRadius = 0.3;
  const char* wheels[4] = {"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"};
  for (int i = 0; i < 4; ++i) {
    drive.wheels[i] = joint(wheels[i], JointType::Hinge, i < 2 ? 0 : 1, 3 + i, false, 0, 0);
    actuator(drive.wheels[i], 400, 10, false);
  }
  robot.drive = drive;
  actuator(joint("lift", JointType::Slider, 0, 7, true, 0, 0.3), 1000, 0.2, true);
  joint("flap", JointType::Hinge, 1, 8, false, 0, 0);
  return robot;
}


}  // namespace

class TestCommandFile : public QObject {
  Q_OBJECT

 private slots:
  void jointModeNames();
  void parseCommand_data();
  void parseCommand();
  void parseCommandErrors_data();
  void parseCommandErrors();
  void toTextWritesFileSyntax_data();
  void toTextWritesFileSyntax();
  void parseSequence();
  void parseSequenceErrors_data();
  void parseSequenceErrors();
  void loadSequenceFile();
  void loadSequenceMissingFile();
  void loadSequenceDirectory();
  void checkCommands_data();
  void checkCommands();
  void checkCommandsWithoutDrive();
  void checkCommandsWheelWithoutActuator();
  void checkCommandTakesSliderValuesInMetres();
  void checkCommandsReportsEveryErrorAtItsLine();
};

// toString(JointMode) gives the words that `mode` commands and robot files use.
void TestCommandFile::jointModeNames() {
  QCOMPARE(toString(JointMode::Velocity), "velocity");
  QCOMPARE(toString(JointMode::Position), "position");
  QCOMPARE(toString(JointMode::Torque), "torque");
  QCOMPARE(toString(JointMode::Free), "free");
}

void TestCommandFile::parseCommand_data() {
  QTest::addColumn<QString>("text");
  QTest::addColumn<Command>("expected");
  QTest::addColumn<QString>("canonical");  // toText() of the result
  QTest::newRow("drive") << "drive 0.5 10" << Command(DriveCmd{0.5, degToRad(10)}) << "drive 0.5 10";
  QTest::newRow("gait") << "gait caterpillar" << Command(GaitCmd{Gait::Caterpillar}) << "gait caterpillar";
  QTest::newRow("gait off") << "gait off" << Command(GaitCmd{Gait::Off}) << "gait off";
  QTest::newRow("turn by rate") << "turn 0.5 -12" << Command(TurnCmd{0.5, degToRad(-12)}) << "turn 0.5 -12";
  QTest::newRow("drive spacing") << "  drive\t0.50   -10 " << Command(DriveCmd{0.5, degToRad(-10)})
                                 << "drive 0.5 -10";
  QTest::newRow("wheels in rad/s") << "wheels 1 2 -3 4.5" << Command(WheelsCmd{{1, 2, -3, 4.5}})
                                   << "wheels 1 2 -3 4.5";
  QTest::newRow("target in deg") << "target knee_fl 45" << Command(JointTargetCmd{"knee_fl", degToRad(45)})
                                 << "target knee_fl 45";
  QTest::newRow("target exponent") << "target knee_fl 1.5e1" << Command(JointTargetCmd{"knee_fl", degToRad(15)})
                                   << "target knee_fl 15";
  QTest::newRow("velocity in deg/s") << "velocity hip_fl -30" << Command(JointVelocityCmd{"hip_fl", degToRad(-30)})
                                     << "velocity hip_fl -30";
  QTest::newRow("torque in N m") << "torque knee_fl 12.5" << Command(JointTorqueCmd{"knee_fl", 12.5})
                                 << "torque knee_fl 12.5";
  QTest::newRow("mode velocity") << "mode knee_fl velocity"
                                 << Command(JointModeCmd{"knee_fl", JointMode::Velocity}) << "mode knee_fl velocity";
  QTest::newRow("mode position") << "mode knee_fl position"
                                 << Command(JointModeCmd{"knee_fl", JointMode::Position}) << "mode knee_fl position";
  QTest::newRow("mode torque") << "mode knee_fl torque" << Command(JointModeCmd{"knee_fl", JointMode::Torque})
                               << "mode knee_fl torque";
  QTest::newRow("mode free") << "mode knee_fl free" << Command(JointModeCmd{"knee_fl", JointMode::Free})
                             << "mode knee_fl free";
  QTest::newRow("stop") << "stop" << Command(StopCmd{}) << "stop";
}

// Each command parses into its typed value, degrees converted to radians
// (wheel speeds, torques and drive speed unconverted), and toText() writes
// it back in canonical form.
void TestCommandFile::parseCommand() {
  QFETCH(QString, text);
  QFETCH(Command, expected);
  QFETCH(QString, canonical);
  std::string error;
  const std::optional<Command> command = sp::parseCommand(text.toStdString(), error);
  QVERIFY2(command, error.c_str());
  QVERIFY2(*command == expected, toText(*command).c_str());
  QCOMPARE(q(toText(*command)), canonical);
}

void TestCommandFile::parseCommandErrors_data() {
  QTest::addColumn<QString>("text");
  QTest::addColumn<QString>("message");
  QTest::newRow("empty") << "  " << "empty command";
  QTest::newRow("unknown") << "drvie 1 2" << "unknown command 'drvie'";
  QTest::newRow("case matters") << "Drive 1 2" << "unknown command 'Drive'";
  QTest::newRow("drive 1 arg") << "drive 1" << "drive: expected 2 arguments (speed m/s, articulation deg), got 1";
  QTest::newRow("drive 3 args") << "drive 1 2 3"
                                << "drive: expected 2 arguments (speed m/s, articulation deg), got 3";
  QTest::newRow("drive bad number") << "drive 1 x" << "drive: bad number 'x'";
  QTest::newRow("drive first bad number") << "drive y x" << "drive: bad number 'y'";
  QTest::newRow("drive leading plus") << "drive +1 0" << "drive: bad number '+1'";
  QTest::newRow("drive unit suffix") << "drive 1m/s 0" << "drive: bad number '1m/s'";
  QTest::newRow("terrain too short") << "terrain 0 0 1"
      << "terrain: expected column, row, columns, rows and columns x rows heights in m, got 3 arguments";
  QTest::newRow("terrain count") << "terrain 0 0 2 2 0.1 0.2 0.3"
      << "terrain: 2 x 2 patch needs 4 heights, got 3";
  QTest::newRow("terrain negative column") << "terrain -1 0 1 1 0.1"
      << "terrain: bad column '-1' (expected a whole number >= 0)";
  QTest::newRow("terrain zero rows") << "terrain 0 0 1 0 0.1"
      << "terrain: bad rows '0' (expected a whole number > 0)";
  QTest::newRow("terrain bad height") << "terrain 0 0 1 2 0.1 up" << "terrain: bad height 'up'";
  QTest::newRow("terrain inf height") << "terrain 0 0 1 1 inf" << "terrain: bad height 'inf'";
  QTest::newRow("wheels 3 args") << "wheels 1 2 3"
                                 << "wheels: expected 4 arguments (front-left, front-right, rear-left, "
                                    "rear-right rad/s), got 3";
  QTest::newRow("wheels nan") << "wheels 1 nan 3 4" << "wheels: bad number 'nan'";
  QTest::newRow("target no value") << "target knee_fl" << "target: expected 2 arguments (joint, angle deg or position m), got 1";
  QTest::newRow("target degree suffix") << "target knee_fl 10deg" << "target: bad number '10deg'";
  QTest::newRow("velocity no args") << "velocity" << "velocity: expected 2 arguments (joint, velocity deg/s or m/s), got 0";
  QTest::newRow("velocity inf") << "velocity knee_fl inf" << "velocity: bad number 'inf'";
  QTest::newRow("torque decimal comma") << "torque knee_fl 1,5" << "torque: bad number '1,5'";
  QTest::newRow("torque 3 args") << "torque knee_fl 1 2" << "torque: expected 2 arguments (joint, torque N m), got 3";
  QTest::newRow("mode no mode") << "mode knee_fl"
                                << "mode: expected 2 arguments (joint, velocity|position|torque|free), got 1";
  QTest::newRow("mode unknown") << "mode knee_fl fast"
                                << "mode: unknown mode 'fast' (expected velocity, position, torque or free)";
  QTest::newRow("stop with args") << "stop now" << "stop: expected no arguments, got 1";
}

// Malformed commands give nullopt and the exact message, without location.
void TestCommandFile::parseCommandErrors() {
  QFETCH(QString, text);
  QFETCH(QString, message);
  std::string error;
  QVERIFY(!sp::parseCommand(text.toStdString(), error));
  QCOMPARE(q(error), message);
}

void TestCommandFile::toTextWritesFileSyntax_data() {
  QTest::addColumn<Command>("command");
  QTest::addColumn<QString>("text");
  QTest::newRow("drive") << Command(DriveCmd{-0.25, degToRad(12.5)}) << "drive -0.25 12.5";
  QTest::newRow("wheels") << Command(WheelsCmd{{0, 0.5, -1, 1e-3}}) << "wheels 0 0.5 -1 0.001";
  QTest::newRow("target") << Command(JointTargetCmd{"knee_fl", degToRad(90)}) << "target knee_fl 90";
  QTest::newRow("target 1 rad") << Command(JointTargetCmd{"knee_fl", 1.0}) << "target knee_fl 57.29577951308232";
  QTest::newRow("velocity") << Command(JointVelocityCmd{"hip_fl", degToRad(-45)}) << "velocity hip_fl -45";
  QTest::newRow("torque") << Command(JointTorqueCmd{"hip_fl", -300}) << "torque hip_fl -300";
  QTest::newRow("mode") << Command(JointModeCmd{"hip_fl", JointMode::Torque}) << "mode hip_fl torque";
  QTest::newRow("stop") << Command(StopCmd{}) << "stop";
  // Heights in their shortest exact form: 0.1 + 0.2 reads back bit for bit.
  QTest::newRow("terrain") << Command(TerrainPatchCmd{3, 4, 2, 1, {0.1 + 0.2, -1.5}})
                           << "terrain 3 4 2 1 0.30000000000000004 -1.5";
}

// toText() writes sequence-file syntax in degrees with the fewest digits
// that parse back to the same command.
void TestCommandFile::toTextWritesFileSyntax() {
  QFETCH(Command, command);
  QFETCH(QString, text);
  QCOMPARE(q(toText(command)), text);
  std::string error;
  const std::optional<Command> back = sp::parseCommand(text.toStdString(), error);
  QVERIFY2(back, error.c_str());
  QVERIFY2(*back == command, toText(*back).c_str());
}

// A valid sequence: comments, blank lines, CRLF, equal times, no final
// newline; every command keeps its time and 1-based line.
void TestCommandFile::parseSequence() {
  const std::string text =
      "# warm-up\n"
      "\n"
      "0     mode knee_fl position   # hold\n"
      "0.0   target knee_fl 30\r\n"
      "  1.5 drive 0.5 -10\n"
      "\t# comment only\n"
      "1.5   wheels 1 1 1 1\n"
      "10    stop";
  Diagnostics diag;
  const auto commands = parseCommandSequence(text, "walk.seq", diag);
  QVERIFY2(commands, diag.format().c_str());
  QVERIFY(diag.empty());
  QCOMPARE(commands->size(), size_t(5));
  const double times[] = {0, 0, 1.5, 1.5, 10};
  const int lines[] = {3, 4, 5, 7, 8};
  const char* texts[] = {"mode knee_fl position", "target knee_fl 30", "drive 0.5 -10", "wheels 1 1 1 1", "stop"};
  for (size_t i = 0; i < commands->size(); ++i) {
    const TimedCommand& c = (*commands)[i];
    QCOMPARE(c.time, times[i]);
    QCOMPARE(c.line, lines[i]);
    QCOMPARE(q(toText(c.command)), QString(texts[i]));
  }
}

void TestCommandFile::parseSequenceErrors_data() {
  QTest::addColumn<QString>("text");
  QTest::addColumn<QString>("expected");
  QTest::newRow("unknown command") << "1.0 drvie 1 2" << "walk.seq:1: error: unknown command 'drvie'\n";
  QTest::newRow("unknown gait") << "1.0 gait trot"
                                << "walk.seq:1: error: gait: unknown gait 'trot' (expected off, caterpillar or rolking)\n";
  QTest::newRow("bad time") << "x drive 1 2" << "walk.seq:1: error: bad time 'x'\n";
  QTest::newRow("time with unit") << "1s stop" << "walk.seq:1: error: bad time '1s'\n";
  QTest::newRow("negative time") << "-1 stop" << "walk.seq:1: error: time must be >= 0\n";
  QTest::newRow("time going back") << "2 stop\n1.5 stop"
                                   << "walk.seq:2: error: time 1.5 is before the previous command's time 2\n";
  QTest::newRow("time only") << "# c\n3   # nothing\n" << "walk.seq:2: error: expected a command after the time\n";
  QTest::newRow("arity after comments")
      << "# header\n\n0 stop\n1 drive 1 # too few\n"
      << "walk.seq:4: error: drive: expected 2 arguments (speed m/s, articulation deg), got 1\n";
  QTest::newRow("bad number") << "0 target knee_fl ten" << "walk.seq:1: error: target: bad number 'ten'\n";
  QTest::newRow("every error in one pass")
      << "0 stop\n"
         "1 drvie 1 2\n"
         "0.5 stop\n"
         "2 wheels 1 2 3\n"
         "x stop\n"
         "3 mode knee_fl fast\n"
         "3 stop\n"
      << "walk.seq:2: error: unknown command 'drvie'\n"
         "walk.seq:3: error: time 0.5 is before the previous command's time 1\n"
         "walk.seq:4: error: wheels: expected 4 arguments (front-left, front-right, rear-left, rear-right "
         "rad/s), got 3\n"
         "walk.seq:5: error: bad time 'x'\n"
         "walk.seq:6: error: mode: unknown mode 'fast' (expected velocity, position, torque or free)\n";
}

// Every problem of a sequence is reported with file and line, and any error
// makes the result nullopt.
void TestCommandFile::parseSequenceErrors() {
  QFETCH(QString, text);
  QFETCH(QString, expected);
  Diagnostics diag;
  QVERIFY(!parseCommandSequence(text.toStdString(), "walk.seq", diag));
  QCOMPARE(q(diag.format()), expected);
}

// loadCommandSequence() reads a file and names it in diagnostics.
void TestCommandFile::loadSequenceFile() {
  QTemporaryDir dir;
  QVERIFY(dir.isValid());
  const std::string good = writeFile(dir, "good.seq", "0 drive 1 0\n5 stop\n");
  Diagnostics diag;
  const auto commands = loadCommandSequence(good, diag);
  QVERIFY2(commands, diag.format().c_str());
  QCOMPARE(commands->size(), size_t(2));
  QCOMPARE(commands->back().line, 2);

  const std::string bad = writeFile(dir, "bad.seq", "0 drive 1 0\n5 stpo\n");
  QVERIFY(!loadCommandSequence(bad, diag));
  QCOMPARE(q(diag.format()), q(bad) + ":2: error: unknown command 'stpo'\n");
}

// A missing file is one error on the file as a whole.
void TestCommandFile::loadSequenceMissingFile() {
  Diagnostics diag;
  QVERIFY(!loadCommandSequence("no/such/walk.seq", diag));
  QCOMPARE(q(diag.format()), QString("no/such/walk.seq: error: cannot open command sequence file\n"));
}

// A path that opens but cannot be read (a directory) is an error, not an
// empty sequence.
void TestCommandFile::loadSequenceDirectory() {
  QTemporaryDir dir;
  QVERIFY(dir.isValid());
  Diagnostics diag;
  QVERIFY(!loadCommandSequence(dir.path().toStdString(), diag));
  QCOMPARE(q(diag.format()), dir.path() + ": error: cannot read command sequence file\n");
}

void TestCommandFile::checkCommands_data() {
  QTest::addColumn<QString>("command");  // file syntax
  QTest::addColumn<QString>("message");  // "" = valid
  // Valid, limits included.
  QTest::newRow("drive") << "drive 1 20" << "";
  QTest::newRow("drive at limit") << "drive -1 -35" << "";
  QTest::newRow("wheels at limit") << "wheels 10 -10 0 5" << "";
  QTest::newRow("target at upper limit") << "target knee_fl 100" << "";
  QTest::newRow("target at lower limit") << "target knee_fl 0" << "";
  QTest::newRow("target on articulation") << "target articulation 10" << "";
  QTest::newRow("velocity at limit") << "velocity knee_fl -90" << "";
  QTest::newRow("velocity without PID") << "velocity hip_fl 60" << "";
  QTest::newRow("torque at limit") << "torque knee_fl -200" << "";
  QTest::newRow("torque on slider") << "torque lift 1000" << "";
  QTest::newRow("mode torque") << "mode hip_fl torque" << "";
  QTest::newRow("mode free") << "mode hip_fl free" << "";
  QTest::newRow("mode position with PID") << "mode knee_fl position" << "";
  QTest::newRow("mode position on slider") << "mode lift position" << "";
  QTest::newRow("stop") << "stop" << "";
  // Joints.
  QTest::newRow("unknown joint") << "target kne_fl 10" << "unknown joint 'kne_fl'";
  QTest::newRow("unknown joint torque") << "torque nothing 1" << "unknown joint 'nothing'";
  QTest::newRow("no actuator velocity") << "velocity flap 10" << "joint 'flap' has no actuator";
  QTest::newRow("no actuator mode") << "mode flap free" << "joint 'flap' has no actuator";
  QTest::newRow("no actuator target") << "target flap 0" << "joint 'flap' has no actuator";
  QTest::newRow("target without PID") << "target hip_fl 10"
                                      << "joint 'hip_fl': position mode needs PID gains on its actuator";
  QTest::newRow("mode position without PID") << "mode hip_fl position"
                                             << "joint 'hip_fl': position mode needs PID gains on its actuator";
  QTest::newRow("target above limit") << "target knee_fl 120"
                                      << "target 120 deg is outside joint 'knee_fl' limits [0, 100] deg";
  QTest::newRow("target below limit") << "target knee_fl -0.5"
                                      << "target -0.5 deg is outside joint 'knee_fl' limits [0, 100] deg";
  QTest::newRow("velocity too fast") << "velocity knee_fl 91"
                                     << "velocity 91 deg/s exceeds joint 'knee_fl' max_velocity 90 deg/s";
  QTest::newRow("velocity too fast backwards") << "velocity knee_fl -100"
                                               << "velocity -100 deg/s exceeds joint 'knee_fl' max_velocity 90 deg/s";
  QTest::newRow("torque too strong") << "torque knee_fl 250"
                                     << "torque 250 N m exceeds joint 'knee_fl' max_torque 200 N m";
  QTest::newRow("force too strong") << "torque lift -1500" << "torque -1500 N exceeds joint 'lift' max_torque 1000 N";
  QTest::newRow("slider target in metres") << "target lift 0.25" << "";
  QTest::newRow("slider target beyond limit") << "target lift 10"
                                              << "target 10 m is outside joint 'lift' limits [0, 0.3] m";
  QTest::newRow("slider velocity in m/s") << "velocity lift 0.1" << "";
  QTest::newRow("slider velocity too fast") << "velocity lift 0.5"
                                            << "velocity 0.5 m/s exceeds joint 'lift' max_velocity 0.2 m/s";
  // Drive.
  QTest::newRow("wheel too fast") << "wheels 10 10 10 12"
                                  << "rear-right wheel speed 12 rad/s exceeds joint 'wheel_rr' max_velocity "
                                     "10 rad/s (572.958 deg/s)";
  QTest::newRow("wheel too fast backwards") << "wheels -11 0 0 0"
                                            << "front-left wheel speed -11 rad/s exceeds joint 'wheel_fl' "
                                               "max_velocity 10 rad/s (572.958 deg/s)";
  QTest::newRow("articulation beyond limit") << "drive 1 40"
                                             << "articulation 40 deg is outside joint 'articulation' limits "
                                                "[-35, 35] deg";
  QTest::newRow("articulation below limit") << "drive 1 -35.5"
                                            << "articulation -35.5 deg is outside joint 'articulation' limits "
                                               "[-35, 35] deg";
}

// Each command is checked against the robot; an invalid one gives one
// diagnostic with the file and the command's line.
void TestCommandFile::checkCommands() {
  QFETCH(QString, command);
  QFETCH(QString, message);
  std::string error;
  const RobotModel robot = testRobot();
  const std::optional<Command> parsed = sp::parseCommand(command.toStdString(), error, &robot);
  QVERIFY2(parsed, error.c_str());
  Diagnostics diag;
  const bool ok = sp::checkCommands({TimedCommand{2.0, *parsed, 7}}, robot, "moves.seq", diag);
  QCOMPARE(ok, message.isEmpty());
  QCOMPARE(q(diag.format()), message.isEmpty() ? QString() : "moves.seq:7: error: " + message + "\n");
}

// Wheel and drive commands need the robot's <drive>.
void TestCommandFile::checkCommandsWithoutDrive() {
  RobotModel robot = testRobot();
  robot.name = "bare";
  robot.drive.reset();
  QCOMPARE(q(checkCommand(DriveCmd{1, 0}, robot)), QString("robot 'bare' has no <drive>"));
  QCOMPARE(q(checkCommand(WheelsCmd{{0, 0, 0, 0}}, robot)), QString("robot 'bare' has no <drive>"));
  QCOMPARE(q(checkCommand(JointTargetCmd{"knee_fl", 0.5}, robot)), QString());
  // Not a limit: the robot link answers `invalid`, not `out_of_limits`.
  QVERIFY(checkCommand(DriveCmd{1, 0}, robot).kind == CommandCheck::Kind::Invalid);
  QVERIFY(checkCommand(JointTargetCmd{"knee_fl", 0.5}, robot).ok());
}

// A wheel joint of the <drive> without an actuator cannot take wheel speeds.
void TestCommandFile::checkCommandsWheelWithoutActuator() {
  RobotModel robot = testRobot();
  const int wheel = robot.findActuator("wheel_rl");
  QVERIFY(wheel >= 0);
  robot.actuators.erase(robot.actuators.begin() + wheel);
  QCOMPARE(q(checkCommand(WheelsCmd{{1, 1, 1, 1}}, robot)), QString("wheel joint 'wheel_rl' has no actuator"));
}

// checkCommand() on typed commands (from the GUI or the robot link, not from
// a file) accepts sliders and checks them in metres.
void TestCommandFile::checkCommandTakesSliderValuesInMetres() {
  const RobotModel robot = testRobot();
  QCOMPARE(q(checkCommand(JointTargetCmd{"lift", 0.2}, robot)), QString());
  QCOMPARE(q(checkCommand(JointTargetCmd{"lift", 0.5}, robot)),
           QString("target 0.5 m is outside joint 'lift' limits [0, 0.3] m"));
  QCOMPARE(q(checkCommand(JointVelocityCmd{"lift", -0.2}, robot)), QString());
  QCOMPARE(q(checkCommand(JointVelocityCmd{"lift", 0.3}, robot)),
           QString("velocity 0.3 m/s exceeds joint 'lift' max_velocity 0.2 m/s"));
  // Drive and turn speeds are checked too, never clipped (the slowest wheel
  // motor's top speed times the wheel radius).
  QVERIFY(checkCommand(DriveCmd{1e300, 0}, robot).kind == CommandCheck::Kind::OutOfLimits);
  QVERIFY(checkCommand(TurnCmd{-1e300, 0}, robot).kind == CommandCheck::Kind::OutOfLimits);
  QVERIFY(checkCommand(DriveCmd{std::nan(""), 0}, robot).kind == CommandCheck::Kind::OutOfLimits);
  QVERIFY(checkCommand(TurnCmd{0.5, std::numeric_limits<double>::infinity()}, robot).kind ==
          CommandCheck::Kind::OutOfLimits);
  QVERIFY(checkCommand(DriveCmd{0.5, 0}, robot).ok());
  QCOMPARE(q(checkCommand(DriveCmd{-3.5, 0}, robot)),
           QString("speed -3.5 m/s exceeds the drive's 3 m/s (wheel max_velocity x wheel radius)"));
  // Limits are a kind of their own (the link refuses them as out_of_limits).
  QVERIFY(checkCommand(JointTargetCmd{"lift", 0.5}, robot).kind == CommandCheck::Kind::OutOfLimits);
  QVERIFY(checkCommand(JointVelocityCmd{"lift", 0.3}, robot).kind == CommandCheck::Kind::OutOfLimits);
  QVERIFY(checkCommand(JointTargetCmd{"nope", 0.1}, robot).kind == CommandCheck::Kind::Invalid);
}

// A parsed file with several bad commands: checkCommands() reports every
// one, each at its own line, and returns false.
void TestCommandFile::checkCommandsReportsEveryErrorAtItsLine() {
  const std::string text =
      "# test run\n"
      "0    mode knee_fl position\n"
      "0    target knee_fl 120\n"
      "\n"
      "1    drive 0.5 10\n"
      "2    velocity kne_fl 10\n"
      "3    torque knee_fl 100\n"
      "4    wheels 20 0 0 0\n"
      "5    stop\n";
  Diagnostics diag;
  const auto commands = parseCommandSequence(text, "run.seq", diag);
  QVERIFY2(commands, diag.format().c_str());
  QVERIFY(!sp::checkCommands(*commands, testRobot(), "run.seq", diag));
  QCOMPARE(q(diag.format()),
           QString("run.seq:3: error: target 120 deg is outside joint 'knee_fl' limits [0, 100] deg\n"
                   "run.seq:6: error: unknown joint 'kne_fl'\n"
                   "run.seq:8: error: front-left wheel speed 20 rad/s exceeds joint 'wheel_fl' max_velocity "
                   "10 rad/s (572.958 deg/s)\n"));
}

QTEST_GUILESS_MAIN(TestCommandFile)
#include "tst_command_file.moc"
