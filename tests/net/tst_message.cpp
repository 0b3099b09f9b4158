// Tests of the typed messages and their payload encoding (net/message.h):
// every type round-trips, the text is as documented, and every decoding
// error names the type and the key in exact words.

#include <QTest>

#include <cmath>
#include <limits>
#include <string>
#include <tuple>

#include "net/message.h"
#include "sim/robot_model.h"
#include "sim/math.h"

using namespace sp;
using namespace sp::net;

Q_DECLARE_METATYPE(sp::net::Message)

namespace {

std::string s(const QByteArray& b) { return std::string(b.constData(), static_cast<size_t>(b.size())); }
QString q(const std::string& str) { return QString::fromStdString(str); }

const std::string kToken = "00112233445566778899aabbccddeeff";  // 128 bits

// The frame of `message`, through the frame decoder.
Frame roundTripFrame(const Message& message) {
  std::string error;
  const std::optional<std::string> bytes = encodeMessage(message, error);
  if (!bytes) qFatal("encode: %s", error.c_str());
  FrameDecoder decoder;
  decoder.feed(*bytes);
  std::optional<Frame> frame = decoder.next();
  if (!frame) qFatal("frame: %s", decoder.errorMessage().c_str());
  return *frame;
}

Frame frameOf(int type, const QByteArray& payload, int version = kProtocolVersion) {
  return Frame{static_cast<uint8_t>(type), static_cast<uint8_t>(version), s(payload)};
}

TelemetryMsg telemetry() {
  TelemetryMsg m;
  m.seq = 42;
  m.time = 12.5;
  m.pose = Pose{{1, 2, 0.5}, {1, 0, 0, 0}};
  m.jointNames = {"articulation", "knee_fl"};
  m.jointPositions = {0.1, -0.25};
  m.jointVelocities = {0, 1e-7};
  m.wheelNormal = {100, 200, 300, 400.5};
  m.wheelTangential = {1, 2, 3, 4};
  m.roll = 0.01;
  m.pitch = -0.02;
  m.rttMs = 12.3;
  m.lost = 3;
  m.estop = true;
  return m;
}

const char* kTelemetryText =
    "seq=42\n"
    "time=12.5\n"
    "pose=1 2 0.5 1 0 0 0\n"
    "joint_names=articulation knee_fl\n"
    "joint_positions=0.1 -0.25\n"
    "joint_velocities=0 1e-07\n"
    "wheel_normal=100 200 300 400.5\n"
    "wheel_tangential=1 2 3 4\n"
    "roll=0.01\n"
    "pitch=-0.02\n"
    "rtt_ms=12.3\n"
    "lost=3\n"
    "failsafe=0\n"
    "estop=1\n"
    "objects=\n";

// kTelemetryText with the line of `key` replaced by `line`.
QByteArray telemetryWith(const char* key, const char* line) {
  QByteArray text(kTelemetryText);
  const qsizetype start = text.indexOf(QByteArray("\n") + key + "=") + 1;
  const qsizetype end = text.indexOf('\n', start);
  return text.replace(start, end - start, line);
}

}  // namespace

class TestMessage : public QObject {
  Q_OBJECT

 private slots:
  void roundTrip_data();
  void roundTrip();
  void typeNames();
  void payloadText();
  void laserNoReturnAndInvalid();
  void numbersShortestRoundTrip();
  void decodeAccepts_data();
  void decodeAccepts();
  void decodeErrors_data();
  void decodeErrors();
  void encodeErrors_data();
  void encodeErrors();
  void oversizeMessage();
  void commandHelpers();
  void fanOutEqualsEncodeMessage();
};

// The robot's fan-out writes, per client, exactly the frame encodeMessage()
// writes for the same message.
void TestMessage::fanOutEqualsEncodeMessage() {
  std::string error;
  TelemetryMsg m = telemetry();
  m.objects = {{"pole", Pose{{2.5, 0, 0.94}, {0.5, 0.5, -0.5, 0.5}}}};
  m.health = "diverged";
  m.baseVelocity = {0.5, 0, 0, 0, 0, -0.1};
  const TelemetryFanOut telemetryOut(m);
  for (const auto& [seq, rtt, lost] : {std::tuple<uint64_t, double, uint64_t>{1, 0, 0}, {42, 12.3, 3},
                                       {18446744073709551615u, 1e-300, 7}, {5, std::nan(""), 0}}) {
    m.seq = seq;
    m.rttMs = rtt;
    m.lost = lost;
    QCOMPARE(telemetryOut.frame(seq, rtt, lost, error).value_or(error), encodeMessage(m, error).value_or("?"));
  }
  // The lease holder's frames add heard_ms (issue 30), and it reads back.
  m.heardMs = 48.5;
  const std::optional<std::string> holder = telemetryOut.frame(m.seq, m.rttMs, m.lost, error, m.heardMs);
  QCOMPARE(holder.value_or(error), encodeMessage(m, error).value_or("?"));
  FrameDecoder decoder;
  decoder.feed(holder->data(), holder->size());
  const std::optional<Message> back = decodeMessage(*decoder.next(), error);
  QVERIFY2(back, error.c_str());
  QCOMPARE(std::get<TelemetryMsg>(*back).heardMs, 48.5);
  m.heardMs = 0;
  LaserMsg laser{0, 1.25, -2.356194490192345, 0.004363323129985824, {1.5, 0.25, 30}};
  const LaserFanOut laserOut(laser);
  for (uint64_t seq : {1u, 2u, 1000000u}) {
    laser.seq = seq;
    QCOMPARE(laserOut.frame(seq, error).value_or(error), encodeMessage(laser, error).value_or("?"));
  }
  // A message that does not encode gives the encoder's error for every client.
  m.jointNames[0] = "bad name";
  QVERIFY(!TelemetryFanOut(m).frame(1, 0, 0, error));
  QCOMPARE(error, std::string("TELEMETRY: key 'joint_names': name 1 is empty or contains a space"));
}

void TestMessage::roundTrip_data() {
  QTest::addColumn<Message>("message");
  QTest::newRow("HELLO") << Message(HelloMsg{"console é", kToken + "ABCDEF", Role::Control, {}});
  QTest::newRow("HELLO with proof") << Message(HelloMsg{"console", "", Role::Monitor, std::string(64, 'a')});
  QTest::newRow("CHALLENGE") << Message(ChallengeMsg{kToken});
  LimitsMsg limits{{"hip_fl", "lift"}, {-1.5, -0.1}, {1.5, 0.2}, {2, 0.05}, {120, 800}, 0.9, 3.6, "steer"};
  QTest::newRow("LIMITS") << Message(limits);
  limits.lower[0] = -std::numeric_limits<double>::infinity();
  limits.upper[0] = std::numeric_limits<double>::infinity();
  QTest::newRow("LIMITS unlimited joint") << Message(limits);
  QTest::newRow("SEQUENCE") << Message(SequenceMsg{"0123456789abcdef", "0 drive 0.5 10;2.5 stop",
                                                   Pose{{1, 2, 0.8}, {1, 0, 0, 0}}, 0.1, 0.0873});
  QTest::newRow("SEQUENCE_STATE") << Message(SequenceStateMsg{"0123456789abcdef", SequenceStateKind::Running, 1, 2, 12.5, ""});
  QTest::newRow("SEQUENCE_STATE refused")
      << Message(SequenceStateMsg{"0123456789abcdef", SequenceStateKind::Refused, 0, 0, 0, "stale rehearsal"});
  QTest::newRow("ABORT") << Message(AbortMsg{"0123456789abcdef", "guard: position 0.31 m"});
  QTest::newRow("LIMITS without drive") << Message(LimitsMsg{{"arm"}, {0}, {1}, {2}, {3}, 0, 0, ""});
  QTest::newRow("WELCOME") << Message(WelcomeMsg{"workpartner", 18446744073709551615u, 50, 0, "", "", ""});
  QTest::newRow("WELCOME with files") << Message(WelcomeMsg{"workpartner", 3, 50, 0.5, "0123456789abcdef", "fedcba9876543210", ""});
  QTest::newRow("WELCOME with capabilities") << Message(WelcomeMsg{"workpartner", 4, 50, 0.5, "", "", "terrain_edit"});
  QTest::newRow("LEASE_ACQUIRE") << Message(LeaseAcquireMsg{});
  QTest::newRow("LEASE_KEEPALIVE") << Message(LeaseKeepaliveMsg{});
  QTest::newRow("LEASE_RELEASE") << Message(LeaseReleaseMsg{});
  QTest::newRow("LEASE_STATE") << Message(LeaseStateMsg{"console", true});
  QTest::newRow("LEASE_STATE free") << Message(LeaseStateMsg{"", false});
  QTest::newRow("COMMAND") << Message(CommandMsg{7, 250, "drive 0.5 10"});
  QTest::newRow("REPLY") << Message(ReplyMsg{7, ReplyStatus::OutOfLimits, "target 120 deg is outside joint limits"});
  QTest::newRow("REPLY ok") << Message(ReplyMsg{8, ReplyStatus::Ok, ""});
  QTest::newRow("TELEMETRY") << Message(telemetry());
  TelemetryMsg empty;
  empty.health = "angular speed 512 rad/s exceeds 200";
  empty.failsafe = true;
  QTest::newRow("TELEMETRY no joints") << Message(empty);
  TelemetryMsg withObjects = telemetry();
  withObjects.objects = {{"pole", Pose{{2.5, 0, 0.94}, {0.7071067811865476, 0.7071067811865475, 0, 0}}},
                         {"crate.2", Pose{{-1e-300, 1.5, -0.25}, {1, 0, 0, 0}}}};
  QTest::newRow("TELEMETRY with objects") << Message(withObjects);
  TelemetryMsg withTwist = telemetry();
  withTwist.baseVelocity = {0.5, -0.01, 1e-9, 0, 0, 0.25};
  QTest::newRow("TELEMETRY with base velocity") << Message(withTwist);
  QTest::newRow("LASER") << Message(LaserMsg{3, 1.25, -2.356194490192345, 0.004363323129985824, {1.5, 0.25, 30}});
  QTest::newRow("HEARTBEAT") << Message(HeartbeatMsg{9, 1234.000001});
  QTest::newRow("ESTOP") << Message(EstopMsg{"operator pressed e-stop"});
  QTest::newRow("REARM") << Message(RearmMsg{});
  QTest::newRow("EVENT") << Message(EventMsg{EventKind::Divergence, "twin diverged at t=3.2 s"});
  QTest::newRow("ERROR") << Message(ErrorMsg{"COMMAND: missing key 'seq'"});
}

// Every message type encodes to a frame of its type code and decodes back
// to an equal message.
void TestMessage::roundTrip() {
  QFETCH(Message, message);
  const Frame frame = roundTripFrame(message);
  QCOMPARE(int(frame.type), int(message.index()) + 1);
  QCOMPARE(QString(messageTypeName(frame.type)), QString(QTest::currentDataTag()).section(' ', 0, 0));
  std::string error;
  const std::optional<Message> decoded = decodeMessage(frame, error);
  QVERIFY2(decoded, error.c_str());
  QVERIFY(*decoded == message);
}

// Type codes and names are those of docs/protocol.md; other bytes are
// "unknown".
void TestMessage::typeNames() {
  const char* names[] = {"HELLO",     "WELCOME", "LEASE_ACQUIRE", "LEASE_KEEPALIVE", "LEASE_RELEASE",
                         "LEASE_STATE", "COMMAND", "REPLY",        "TELEMETRY",       "LASER",
                         "HEARTBEAT", "ESTOP",   "REARM",         "EVENT",           "ERROR",
                         "CHALLENGE", "LIMITS",  "SEQUENCE",      "SEQUENCE_STATE",  "ABORT"};
  for (int code = 1; code <= 20; ++code) {
    QCOMPARE(messageTypeName(static_cast<uint8_t>(code)), names[code - 1]);
    QCOMPARE(toString(static_cast<MessageType>(code)), names[code - 1]);
  }
  QCOMPARE(messageTypeName(0), "unknown");
  QCOMPARE(messageTypeName(21), "unknown");
  QCOMPARE(toString(SequenceStateKind::Aborted), "aborted");
  QCOMPARE(toString(ReplyStatus::NotOwner), "not_owner");
  QCOMPARE(toString(EventKind::Rearmed), "rearmed");
  QCOMPARE(toString(Role::Monitor), "monitor");
}

// The payload is key=value lines in the documented order, numbers in
// shortest form, lists space-separated, flags 0/1.
void TestMessage::payloadText() {
  std::string error;
  QCOMPARE(encodePayload(telemetry(), error).value_or(error), std::string(kTelemetryText));
  QCOMPARE(encodePayload(CommandMsg{1, 500, "stop"}, error).value_or(error),
           std::string("seq=1\nexpires_ms=500\ncommand=stop\n"));
  QCOMPARE(encodePayload(LeaseAcquireMsg{}, error).value_or(error), std::string());
}

// Laser ranges carry `inf` (no return) and `nan` (invalid) through.
void TestMessage::laserNoReturnAndInvalid() {
  const double inf = std::numeric_limits<double>::infinity();
  const LaserMsg laser{1, 0.5, 0, 0.01, {1.5, inf, std::nan("")}};
  std::string error;
  const std::optional<std::string> text = encodePayload(laser, error);
  QCOMPARE(text.value_or(error), std::string("seq=1\ntime=0.5\nangle_min=0\nangle_step=0.01\nranges=1.5 inf nan\n"));
  const std::optional<Message> back = decodeMessage(roundTripFrame(laser), error);
  QVERIFY2(back, error.c_str());
  const auto& ranges = std::get<LaserMsg>(*back).ranges;
  QCOMPARE(ranges.size(), size_t{3});
  QCOMPARE(ranges[0], 1.5);
  QVERIFY(std::isinf(ranges[1]) && ranges[1] > 0);
  QVERIFY(std::isnan(ranges[2]));
}

// Doubles are written in their shortest form and read back bit-exactly.
void TestMessage::numbersShortestRoundTrip() {
  const double values[] = {0.1, 1.0 / 3, -2.5e-300, 1e300, 5e-324, std::numeric_limits<double>::max(), 123456789.125};
  const char* texts[] = {"0.1", "0.3333333333333333", "-2.5e-300", "1e+300", "5e-324", "1.7976931348623157e+308",
                         "123456789.125"};
  for (size_t i = 0; i < std::size(values); ++i) {
    std::string error;
    const HeartbeatMsg hb{1, values[i]};
    QCOMPARE(encodePayload(hb, error).value_or(error), "seq=1\ntime=" + std::string(texts[i]) + "\n");
    const std::optional<Message> back = decodeMessage(roundTripFrame(hb), error);
    QVERIFY2(back, error.c_str());
    QCOMPARE(std::get<HeartbeatMsg>(*back).time, values[i]);
  }
}

void TestMessage::decodeAccepts_data() {
  QTest::addColumn<int>("type");
  QTest::addColumn<QByteArray>("payload");
  QTest::addColumn<Message>("message");
  QTest::newRow("unknown keys ignored") << 15 << QByteArray("future_key=1\nreason=x\n") << Message(ErrorMsg{"x"});
  QTest::newRow("any order, blank lines, no final newline")
      << 11 << QByteArray("\ntime=2\n\nseq=5") << Message(HeartbeatMsg{5, 2});
  QTest::newRow("optional key absent") << 8 << QByteArray("seq=3\nstatus=busy\n")
                                       << Message(ReplyMsg{3, ReplyStatus::Busy, ""});
  QTest::newRow("value keeps '=', spaces and CR")
      << 15 << QByteArray("reason= a=b \r\n") << Message(ErrorMsg{" a=b \r"});
  QTest::newRow("list with extra spaces") << 10 << QByteArray("seq=1\ntime=0\nangle_min=0\nangle_step=1\nranges= 1  2 \n")
                                          << Message(LaserMsg{1, 0, 0, 1, {1, 2}});
  QTest::newRow("leading zeros, exponent") << 11 << QByteArray("seq=007\ntime=1e3\n") << Message(HeartbeatMsg{7, 1000});
  QTest::newRow("upper-case token")
      << 1 << QByteArray("name=c\ntoken=00112233445566778899AABBCCDDEEFF\nrole=monitor\n")
      << Message(HelloMsg{"c", "00112233445566778899AABBCCDDEEFF", Role::Monitor, {}});
  QTest::newRow("keys on a message without keys") << 3 << QByteArray("later=1\n") << Message(LeaseAcquireMsg{});
  QTest::newRow("objects absent") << 9 << telemetryWith("objects", "") << Message(telemetry());
  TelemetryMsg withPole = telemetry();
  withPole.objects = {{"pole", Pose{{2.5, 0, 0.94}, {0.5, 0.5, -0.5, 0.5}}}, {"box", Pose{}}};
  QTest::newRow("objects, 8 items each, extra spaces")
      << 9 << telemetryWith("objects", "objects=pole 2.5 0 0.94 0.5 0.5 -0.5 0.5  box 0 0 0 1 0 0 0 ")
      << Message(withPole);
}

// Receivers accept what a later or looser sender may write: unknown keys,
// keys in any order, blank lines, a missing final newline, extra spaces in
// lists, absent optional keys.
void TestMessage::decodeAccepts() {
  QFETCH(int, type);
  QFETCH(QByteArray, payload);
  QFETCH(Message, message);
  std::string error;
  const std::optional<Message> decoded = decodeMessage(frameOf(type, payload), error);
  QVERIFY2(decoded, error.c_str());
  QVERIFY(*decoded == message);
}

void TestMessage::decodeErrors_data() {
  QTest::addColumn<int>("type");
  QTest::addColumn<int>("version");
  QTest::addColumn<QByteArray>("payload");
  QTest::addColumn<QString>("error");
  const QByteArray hello = "name=c\nrole=control\ntoken=";
  const auto row = [](const char* tag, int type, const QByteArray& payload, const char* error) {
    QTest::newRow(tag) << type << 1 << payload << QString::fromUtf8(error);
  };
  row("missing key", 7, "seq=1\ncommand=stop\n", "COMMAND: missing key 'expires_ms'");
  row("missing key, empty payload", 6, "", "LEASE_STATE: missing key 'holder'");
  row("missing reason", 15, "", "ERROR: missing key 'reason'");
  row("negative integer", 7, "seq=-1\nexpires_ms=5\ncommand=stop\n",
      "COMMAND: key 'seq': expected an unsigned integer, got '-1'");
  // An optional number sent empty is refused (an optional text sent empty
  // counts as absent: docs/protocol.md, Errors).
  row("empty optional number", 7, "seq=1\nexpires_ms=5\nsent_ms=\ncommand=stop\n",
      "COMMAND: key 'sent_ms': expected an unsigned integer, got ''");
  row("integer with plus", 7, "seq=+1\nexpires_ms=5\ncommand=stop\n",
      "COMMAND: key 'seq': expected an unsigned integer, got '+1'");
  row("integer overflow", 7, "seq=18446744073709551616\nexpires_ms=5\ncommand=stop\n",
      "COMMAND: key 'seq': expected an unsigned integer, got '18446744073709551616'");
  row("fractional integer", 9, telemetryWith("lost", "lost=1.5"),
      "TELEMETRY: key 'lost': expected an unsigned integer, got '1.5'");
  row("bad number", 11, "seq=1\ntime=abc\n", "HEARTBEAT: key 'time': expected a number, got 'abc'");
  row("number with trailing space", 11, "seq=1\ntime=1.5 \n",
      "HEARTBEAT: key 'time': expected a number, got '1.5 '");
  row("empty number", 11, "seq=1\ntime=\n", "HEARTBEAT: key 'time': expected a number, got ''");
  row("hex number", 11, "seq=1\ntime=0x10\n", "HEARTBEAT: key 'time': expected a number, got '0x10'");
  row("flag", 6, "holder=\nyours=2\n", "LEASE_STATE: key 'yours': expected 0 or 1, got '2'");
  row("status", 8, "seq=1\nstatus=maybe\n",
      "REPLY: key 'status': expected ok, invalid, out_of_limits, not_owner, busy, failed, expired or duplicate, "
      "got 'maybe'");
  row("role", 1, QByteArray(hello).replace("control", "admin") + QByteArray::fromStdString(kToken),
      "HELLO: key 'role': expected control or monitor, got 'admin'");
  row("event kind", 14, "kind=oops\n",
      "EVENT: key 'kind': expected failsafe, divergence, estop, rearmed or link, got 'oops'");
  row("pose count", 9, telemetryWith("pose", "pose=1 2 3 1 0 0"),
      "TELEMETRY: key 'pose': expected 7 numbers (x y z qw qx qy qz), got 6");
  row("pose item", 9, telemetryWith("pose", "pose=1 2 x 1 0 0 0"),
      "TELEMETRY: key 'pose': number 3: expected a number, got 'x'");
  row("wheel count", 9, telemetryWith("wheel_normal", "wheel_normal=1 2 3"),
      "TELEMETRY: key 'wheel_normal': expected 4 numbers (FL FR RL RR), got 3");
  row("joint count", 9, telemetryWith("joint_velocities", "joint_velocities=1"),
      "TELEMETRY: key 'joint_velocities': expected 2 numbers (one per joint name), got 1");
  row("object count", 9, telemetryWith("objects", "objects=pole 2.5 0 0.94 1 0 0"),
      "TELEMETRY: key 'objects': expected groups of 8 items (name x y z qw qx qy qz), got 7 items");
  row("object without a name", 9, telemetryWith("objects", "objects=2.5 0 0.94 1 0 0 0"),
      "TELEMETRY: key 'objects': expected groups of 8 items (name x y z qw qx qy qz), got 7 items");
  row("object item", 9, telemetryWith("objects", "objects=box 0 0 0 1 0 0 0 pole 2.5 0 0.94 1 0 0 +0"),
      "TELEMETRY: key 'objects': object 2 'pole': number 7: expected a number, got '+0'");
  row("short token", 1, hello + QByteArray::fromStdString(kToken.substr(1)),
      "HELLO: key 'token': expected at least 32 hex digits (128 bits), got 31");
  row("non-hex token", 1, hello + QByteArray::fromStdString(kToken + "g"),
      "HELLO: key 'token': expected hex digits only");
  row("empty name", 1, "name=\nrole=control\ntoken=" + QByteArray::fromStdString(kToken),
      "HELLO: key 'name': must not be empty");
  row("zero expiry", 7, "seq=1\nexpires_ms=0\ncommand=stop\n", "COMMAND: key 'expires_ms': must be > 0");
  row("empty command", 7, "seq=1\nexpires_ms=10\ncommand=\n", "COMMAND: key 'command': must not be empty");
  row("short world hash", 2, "robot=r\nsession=1\ntelemetry_rate=50\nworld_hash=abc\n",
      "WELCOME: key 'world_hash': expected 16 hex digits, got 3");
  row("robot hash not hex", 2, "robot=r\nsession=1\ntelemetry_rate=50\nrobot_hash=0123456789abcdeg\n",
      "WELCOME: key 'robot_hash': expected hex digits only");
  row("bad capability", 2, "robot=r\nsession=1\ntelemetry_rate=50\ncapabilities=terrain-edit\n",
      "WELCOME: key 'capabilities': expected words of a-z and _ separated by spaces");
  row("zero rate", 2, "robot=r\nsession=1\ntelemetry_rate=0\n",
      "WELCOME: key 'telemetry_rate': must be finite and > 0, got 0");
  row("nan rate", 2, "robot=r\nsession=1\ntelemetry_rate=nan\n",
      "WELCOME: key 'telemetry_rate': must be finite and > 0, got nan");
  row("infinite angle", 10, "seq=1\ntime=0\nangle_min=-inf\nangle_step=0.1\nranges=\n",
      "LASER: key 'angle_min': must be finite");
  row("bad range", 10, "seq=1\ntime=0\nangle_min=0\nangle_step=0.1\nranges=1 2 zz\n",
      "LASER: key 'ranges': number 3: expected a number, got 'zz'");
  row("no '='", 15, "reason=x\noops\n", "ERROR: line 2: expected key=value, got 'oops'");
  row("upper-case key", 15, "Reason=x\n", "ERROR: line 1: bad key 'Reason', expected [a-z_]+");
  row("empty key", 15, "=x\n", "ERROR: line 1: bad key '', expected [a-z_]+");
  row("key with space", 15, "reason =x\n", "ERROR: line 1: bad key 'reason ', expected [a-z_]+");
  row("repeated key", 15, "reason=a\n\nreason=b\n", "ERROR: line 3: key 'reason' repeats line 1");
  row("first repeat reported", 11, "time=1\nseq=1\nseq=2\ntime=2\n", "HEARTBEAT: line 3: key 'seq' repeats line 2");
  row("truncated UTF-8", 15, "reason=caf\xc3", "ERROR: payload is not valid UTF-8 at byte 10");
  row("overlong UTF-8", 15, "reason=\xc0\xaf", "ERROR: payload is not valid UTF-8 at byte 7");
  row("UTF-16 surrogate", 15, "reason=\xed\xa0\x80", "ERROR: payload is not valid UTF-8 at byte 7");
  row("long value cut", 11, "seq=1\ntime=" + QByteArray(100, 'x'),
      "HEARTBEAT: key 'time': expected a number, got 'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx'...");
  row("cut at a character boundary", 11, "seq=1\ntime=" + QByteArray(39, 'a') + "\xc3\xa9",
      "HEARTBEAT: key 'time': expected a number, got 'aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa'...");
  row("control characters escaped", 11, "seq=1\ntime=1\r\x1b\n",
      "HEARTBEAT: key 'time': expected a number, got '1\\x0d\\x1b'");
  row("unknown type", 200, "reason=x\n", "unknown message type 200");
  row("type 0", 0, "", "unknown message type 0");
  QTest::newRow("version 2") << 1 << 2 << QByteArray() << "HELLO: unsupported protocol version 2, expected 1";
}

// Each malformed payload is refused with a one-line message that names the
// message type and the key (or line), quoting the bad value briefly and
// never the token.
void TestMessage::decodeErrors() {
  QFETCH(int, type);
  QFETCH(int, version);
  QFETCH(QByteArray, payload);
  QFETCH(QString, error);
  std::string actual;
  QVERIFY(!decodeMessage(frameOf(type, payload, version), actual));
  QCOMPARE(q(actual), error);
}

void TestMessage::encodeErrors_data() {
  QTest::addColumn<Message>("message");
  QTest::addColumn<QString>("error");
  QTest::newRow("line feed") << Message(HelloMsg{"a\nb", kToken, Role::Control, {}})
                             << "HELLO: key 'name': contains a line feed";
  QTest::newRow("not UTF-8") << Message(ErrorMsg{"\xff"}) << "ERROR: key 'reason': is not valid UTF-8";
  TelemetryMsg t = telemetry();
  t.jointNames[1] = "knee fl";
  QTest::newRow("joint name with space") << Message(t)
                                         << "TELEMETRY: key 'joint_names': name 2 is empty or contains a space";
  t = telemetry();
  t.objects = {{"pole", Pose{}}, {"the box", Pose{}}};
  QTest::newRow("object name with space") << Message(t)
                                          << "TELEMETRY: key 'objects': name 2 is empty or contains a space";
  t.objects = {{"", Pose{}}};
  QTest::newRow("empty object name") << Message(t)
                                     << "TELEMETRY: key 'objects': name 1 is empty or contains a space";
  t.objects = {{"pole\n", Pose{}}};
  QTest::newRow("object name with line feed") << Message(t) << "TELEMETRY: key 'objects': contains a line feed";
  QTest::newRow("short token") << Message(HelloMsg{"c", "abc", Role::Monitor, {}})
                               << "HELLO: key 'token': expected at least 32 hex digits (128 bits), got 3";
  QTest::newRow("token and proof") << Message(HelloMsg{"c", kToken, Role::Monitor, std::string(64, 'a')})
                                   << "HELLO: keys 'proof' and 'token': send one, not both";
  QTest::newRow("neither token nor proof") << Message(HelloMsg{"c", "", Role::Monitor, ""})
                                           << "HELLO: missing key 'proof' (or, on loopback, 'token')";
  QTest::newRow("short proof") << Message(HelloMsg{"c", "", Role::Monitor, std::string(63, 'a')})
                               << "HELLO: key 'proof': expected 64 hex digits (HMAC-SHA256), got 63";
  QTest::newRow("proof not hex") << Message(HelloMsg{"c", "", Role::Monitor, std::string(63, 'a') + "g"})
                                 << "HELLO: key 'proof': expected hex digits only";
  QTest::newRow("short nonce") << Message(ChallengeMsg{"abcd"})
                               << "CHALLENGE: key 'nonce': expected at least 32 hex digits (128 bits), got 4";
  QTest::newRow("limits list too short") << Message(LimitsMsg{{"a", "b"}, {0, 0}, {1, 1}, {1}, {1, 1}, 0, 0, ""})
                                         << "LIMITS: key 'max_velocity': expected 2 numbers (one per joint), got 1";
  TelemetryMsg shortTwist = telemetry();
  shortTwist.baseVelocity = {1, 2, 3, 4, 5};
  QTest::newRow("base velocity of 5") << Message(shortTwist)
                                      << "TELEMETRY: key 'base_velocity': expected 6 numbers (vx vy vz wx wy wz), got 5";
  QTest::newRow("zero expiry") << Message(CommandMsg{1, 0, "stop"}) << "COMMAND: key 'expires_ms': must be > 0";
  QTest::newRow("bad enum") << Message(ReplyMsg{1, static_cast<ReplyStatus>(99), ""})
                            << "REPLY: key 'status': bad enum value 99";
}

// A message that could not be read back is refused when encoded, with the
// same kind of message.
void TestMessage::encodeErrors() {
  QFETCH(Message, message);
  QFETCH(QString, error);
  std::string actual;
  QVERIFY(!encodePayload(message, actual));
  QCOMPARE(q(actual), error);
  actual.clear();
  QVERIFY(!encodeMessage(message, actual));
  QCOMPARE(q(actual), error);
}

// A payload beyond 65524 bytes (a laser scan of 40000 beams) is refused
// with its size, not cut.
void TestMessage::oversizeMessage() {
  const LaserMsg laser{1, 0, 0, 0.001, std::vector<double>(40000, 1.0)};
  std::string error;
  const std::optional<std::string> payload = encodePayload(laser, error);
  QVERIFY(payload);
  QCOMPARE(payload->size(), size_t{80049});
  QVERIFY(!encodeMessage(laser, error));
  QCOMPARE(q(error), QString("LASER: payload of 80049 bytes exceeds the maximum 65524"));
}

// A COMMAND carries a twin command as sequence-file text (degrees), and
// parses back to the same command; bad text is refused with the parser's
// reason.
void TestMessage::commandHelpers() {
  const Command drive = DriveCmd{0.5, degToRad(10)};
  const CommandMsg message = makeCommandMsg(12, 300, drive);
  QCOMPARE(message, (CommandMsg{12, 300, "drive 0.5 10"}));
  std::string error;
  const std::optional<Command> back = parseCommandMsg(message, nullptr, error);
  QVERIFY2(back, error.c_str());
  QVERIFY(*back == drive);

  const Command wheels = WheelsCmd{{1, 2, 3, 4.5}};
  QVERIFY(parseCommandMsg(makeCommandMsg(1, 1, wheels), nullptr, error) == wheels);
  QVERIFY(parseCommandMsg(makeCommandMsg(1, 1, StopCmd{}), nullptr, error) == Command(StopCmd{}));
  // A slider's target travels in metres when both ends know the robot.
  RobotModel robot;
  robot.links = {LinkSpec{"base", 1, {}, {}, 0}, LinkSpec{"finger", 0.1, {}, {}, 0}};
  JointSpec slider;
  slider.name = "finger";
  slider.type = JointType::Slider;
  slider.parent = 0;
  slider.child = 1;
  robot.joints = {slider};
  const Command grip = JointTargetCmd{"finger", 0.03};
  QCOMPARE(makeCommandMsg(1, 1, grip, &robot).command, std::string("target finger 0.03"));
  QVERIFY(parseCommandMsg(makeCommandMsg(1, 1, grip, &robot), &robot, error) == grip);

  QVERIFY(!parseCommandMsg(CommandMsg{1, 10, "drvie 1 0"}, nullptr, error));
  QCOMPARE(q(error), QString("COMMAND: key 'command': unknown command 'drvie'"));
}

QTEST_GUILESS_MAIN(TestMessage)
#include "tst_message.moc"
