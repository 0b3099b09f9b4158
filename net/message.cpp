#include "net/message.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <string_view>
#include <system_error>
#include <type_traits>

#include "sim/command_check.h"
#include "sim/command_file.h"
#include "sim/hash.h"
#include "sim/robot_model.h"

namespace sp::net {
namespace {

constexpr size_t kQuoteMax = 40;  // bytes of a value quoted in an error

// ---------------------------------------------------------------------------
// Names of enum values, in enum order.

constexpr const char* kTypeNames[] = {
    "HELLO",     "WELCOME", "LEASE_ACQUIRE", "LEASE_KEEPALIVE", "LEASE_RELEASE",
    "LEASE_STATE", "COMMAND", "REPLY",       "TELEMETRY",       "LASER",
    "HEARTBEAT", "ESTOP",   "REARM",         "EVENT",           "ERROR",
    "CHALLENGE", "LIMITS",  "SEQUENCE",      "SEQUENCE_STATE",  "ABORT"};
constexpr const char* kRoleNames[] = {"control", "monitor"};
constexpr const char* kStatusNames[] = {"ok",   "invalid", "out_of_limits", "not_owner",
                                        "busy", "failed",  "expired",       "duplicate"};
constexpr const char* kEventNames[] = {"failsafe", "divergence", "estop", "rearmed", "link"};
constexpr const char* kSequenceStateNames[] = {"accepted", "refused", "running", "done", "aborted"};
static_assert(std::size(kTypeNames) == kLastMessageType);

template <class E, size_t N>
const char* enumName(E value, const char* const (&names)[N]) {
  const auto i = static_cast<size_t>(value);
  return i < N ? names[i] : "?";
}

// "a, b or c"
template <size_t N>
std::string alternatives(const char* const (&names)[N]) {
  std::string out;
  for (size_t i = 0; i < N; ++i) {
    if (i > 0) out += i + 1 == N ? " or " : ", ";
    out += names[i];
  }
  return out;
}

// ---------------------------------------------------------------------------
// Text helpers.

// `'value'`, cut to kQuoteMax bytes at a character boundary, with control
// characters as \xNN, so that an error message stays one short line.
std::string quote(std::string_view value) {
  std::string out = "'";
  size_t n = value.size();
  bool cut = false;
  if (n > kQuoteMax) {
    n = kQuoteMax;
    while (n > 0 && (static_cast<unsigned char>(value[n]) & 0xC0u) == 0x80u) --n;
    cut = true;
  }
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(value[i]);
    if (c < 0x20 || c == 0x7F) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  out += cut ? "'..." : "'";
  return out;
}

// Offset of the first byte that is not part of well-formed UTF-8 (no
// overlong forms, no surrogates, nothing above U+10FFFF), or npos.
size_t invalidUtf8(std::string_view s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      ++i;
      continue;
    }
    size_t len = 0;
    unsigned char lo = 0x80, hi = 0xBF;  // range of the second byte
    if (c >= 0xC2 && c <= 0xDF) {
      len = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      len = 3;
      if (c == 0xE0) lo = 0xA0;
      if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      len = 4;
      if (c == 0xF0) lo = 0x90;
      if (c == 0xF4) hi = 0x8F;
    } else {
      return i;
    }
    if (i + len > s.size()) return i;
    const auto c1 = static_cast<unsigned char>(s[i + 1]);
    if (c1 < lo || c1 > hi) return i;
    for (size_t k = 2; k < len; ++k)
      if ((static_cast<unsigned char>(s[i + k]) & 0xC0u) != 0x80u) return i;
    i += len;
  }
  return std::string_view::npos;
}

std::vector<std::string_view> splitSpaces(std::string_view s) {
  std::vector<std::string_view> items;
  size_t i = 0;
  while (i < s.size()) {
    if (s[i] == ' ') {
      ++i;
      continue;
    }
    const size_t end = std::min(s.find(' ', i), s.size());
    items.push_back(s.substr(i, end - i));
    i = end;
  }
  return items;
}

void appendNumber(std::string& out, double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, ec == std::errc() ? end : buf);
}

void appendNumber(std::string& out, uint64_t v) {
  char buf[24];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, ec == std::errc() ? end : buf);
}

template <class T>
bool parseWhole(std::string_view s, T& value) {
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  return ec == std::errc() && end == s.data() + s.size();
}

// ---------------------------------------------------------------------------
// Fields. forEachField(message, f) calls f(key, member, need) for every key of
// a message in the order they are written; encoder and decoder share it, so
// a key's name, type and whether it is required are stated once.

enum class Need { Required, Optional };

template <class M, class F>
void forEachField(M& m, F& f) {
  using T = std::remove_const_t<M>;
  constexpr Need R = Need::Required;
  if constexpr (std::is_same_v<T, HelloMsg>) {
    f("name", m.name, R);
    f("role", m.role, R);
    f("proof", m.proof, Need::Optional);
    f("token", m.token, Need::Optional);
  } else if constexpr (std::is_same_v<T, WelcomeMsg>) {
    f("robot", m.robot, R);
    f("session", m.session, R);
    f("telemetry_rate", m.telemetryRate, R);
    f("deadman", m.deadman, Need::Optional);
    f("world_hash", m.worldHash, Need::Optional);
    f("robot_hash", m.robotHash, Need::Optional);
    f("capabilities", m.capabilities, Need::Optional);
  } else if constexpr (std::is_same_v<T, LeaseStateMsg>) {
    f("holder", m.holder, R);
    f("yours", m.yours, R);
  } else if constexpr (std::is_same_v<T, CommandMsg>) {
    f("seq", m.seq, R);
    f("expires_ms", m.expiresMs, R);
    f("command", m.command, R);
    f("sent_ms", m.sentMs, Need::Optional);
  } else if constexpr (std::is_same_v<T, ReplyMsg>) {
    f("seq", m.seq, R);
    f("status", m.status, R);
    f("reason", m.reason, Need::Optional);
  } else if constexpr (std::is_same_v<T, TelemetryMsg>) {
    f("seq", m.seq, R);
    f("time", m.time, R);
    f("pose", m.pose, R);
    f("base_velocity", m.baseVelocity, Need::Optional);
    f("joint_names", m.jointNames, R);
    f("joint_positions", m.jointPositions, R);
    f("joint_velocities", m.jointVelocities, R);
    f("wheel_normal", m.wheelNormal, R);
    f("wheel_tangential", m.wheelTangential, R);
    f("roll", m.roll, R);
    f("pitch", m.pitch, R);
    f("rtt_ms", m.rttMs, R);
    f("lost", m.lost, R);
    f("heard_ms", m.heardMs, Need::Optional);
    f("failsafe", m.failsafe, R);
    f("estop", m.estop, R);
    f("health", m.health, Need::Optional);
    f("objects", m.objects, Need::Optional);
  } else if constexpr (std::is_same_v<T, LaserMsg>) {
    f("seq", m.seq, R);
    f("time", m.time, R);
    f("angle_min", m.angleMin, R);
    f("angle_step", m.angleStep, R);
    f("ranges", m.ranges, R);
  } else if constexpr (std::is_same_v<T, HeartbeatMsg>) {
    f("seq", m.seq, R);
    f("time", m.time, R);
  } else if constexpr (std::is_same_v<T, EstopMsg>) {
    f("reason", m.reason, Need::Optional);
  } else if constexpr (std::is_same_v<T, EventMsg>) {
    f("kind", m.kind, R);
    f("text", m.text, Need::Optional);
  } else if constexpr (std::is_same_v<T, ErrorMsg>) {
    f("reason", m.reason, R);
  } else if constexpr (std::is_same_v<T, ChallengeMsg>) {
    f("nonce", m.nonce, R);
  } else if constexpr (std::is_same_v<T, LimitsMsg>) {
    f("joints", m.joints, R);
    f("lower", m.lower, R);
    f("upper", m.upper, R);
    f("max_velocity", m.maxVelocity, R);
    f("max_torque", m.maxTorque, R);
    f("drive_speed", m.driveSpeed, Need::Optional);
    f("wheel_speed", m.wheelSpeed, Need::Optional);
    f("articulation", m.articulation, Need::Optional);
  } else if constexpr (std::is_same_v<T, SequenceMsg>) {
    f("hash", m.hash, R);
    f("commands", m.commands, R);
    f("start", m.start, R);
    f("start_position", m.startPosition, R);
    f("start_heading", m.startHeading, R);
  } else if constexpr (std::is_same_v<T, SequenceStateMsg>) {
    f("hash", m.hash, R);
    f("state", m.state, R);
    f("index", m.index, Need::Optional);
    f("count", m.count, Need::Optional);
    f("start_time", m.startTime, Need::Optional);
    f("reason", m.reason, Need::Optional);
  } else if constexpr (std::is_same_v<T, AbortMsg>) {
    f("hash", m.hash, R);
    f("reason", m.reason, Need::Optional);
  } else {
    // LEASE_ACQUIRE, LEASE_KEEPALIVE, LEASE_RELEASE, REARM: no keys.
    static_assert(std::is_empty_v<T>);
  }
}

// Rules beyond syntax, shared by encoder and decoder; "" when valid, else
// "key 'k': problem".
struct Validator {
  std::string operator()(const HelloMsg& m) const {
    if (m.name.empty()) return "key 'name': must not be empty";
    if (m.proof.empty() == m.token.empty())
      return m.proof.empty() ? "missing key 'proof' (or, on loopback, 'token')" : "keys 'proof' and 'token': send one, not both";
    if (!m.token.empty()) return hexDigits("token", m.token, 32, "at least 32 hex digits (128 bits)");
    if (m.proof.size() != 64) return "key 'proof': expected 64 hex digits (HMAC-SHA256), got " + std::to_string(m.proof.size());
    return hexDigits("proof", m.proof, 64, "64 hex digits (HMAC-SHA256)");
  }
  std::string operator()(const ChallengeMsg& m) const {
    return hexDigits("nonce", m.nonce, 32, "at least 32 hex digits (128 bits)");
  }
  std::string operator()(const LimitsMsg& m) const {
    for (size_t i = 0; i < m.joints.size(); ++i)
      if (m.joints[i].empty() || m.joints[i].find(' ') != std::string::npos)
        return "key 'joints': name " + std::to_string(i + 1) + " is empty or contains a space";
    const std::pair<const char*, size_t> lists[] = {{"lower", m.lower.size()},
                                                    {"upper", m.upper.size()},
                                                    {"max_velocity", m.maxVelocity.size()},
                                                    {"max_torque", m.maxTorque.size()}};
    for (const auto& [key, n] : lists)
      if (n != m.joints.size())
        return std::string("key '") + key + "': expected " + std::to_string(m.joints.size()) +
               " numbers (one per joint), got " + std::to_string(n);
    if (m.articulation.find(' ') != std::string::npos) return "key 'articulation': contains a space";
    return {};
  }
  // A run of at least `min` hex digits; never quotes the value (a token).
  static std::string hexDigits(const char* key, const std::string& value, size_t min, const char* expected) {
    const auto hex = [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'); };
    if (!std::all_of(value.begin(), value.end(), hex)) return std::string("key '") + key + "': expected hex digits only";
    if (value.size() < min)
      return std::string("key '") + key + "': expected " + expected + ", got " + std::to_string(value.size());
    return {};
  }
  std::string operator()(const WelcomeMsg& m) const {
    if (!(std::isfinite(m.telemetryRate) && m.telemetryRate > 0)) {
      std::string s = "key 'telemetry_rate': must be finite and > 0, got ";
      appendNumber(s, m.telemetryRate);
      return s;
    }
    for (const auto& [key, value] : {std::pair{"world_hash", &m.worldHash}, std::pair{"robot_hash", &m.robotHash}}) {
      if (value->empty()) continue;
      if (std::string e = hexDigits(key, *value, 16, "16 hex digits"); !e.empty()) return e;
      if (value->size() != 16) return std::string("key '") + key + "': expected 16 hex digits, got " + std::to_string(value->size());
    }
    for (char c : m.capabilities)
      if (!((c >= 'a' && c <= 'z') || c == '_' || c == ' '))
        return "key 'capabilities': expected words of a-z and _ separated by spaces";
    return {};
  }
  std::string operator()(const CommandMsg& m) const {
    if (m.expiresMs == 0) return "key 'expires_ms': must be > 0";
    if (m.command.empty()) return "key 'command': must not be empty";
    return {};
  }
  std::string operator()(const TelemetryMsg& m) const {
    for (size_t i = 0; i < m.jointNames.size(); ++i) {
      const std::string& name = m.jointNames[i];
      if (name.empty() || name.find(' ') != std::string::npos)
        return "key 'joint_names': name " + std::to_string(i + 1) + " is empty or contains a space";
    }
    const auto count = [&](const char* key, size_t n) -> std::string {
      if (n == m.jointNames.size()) return {};
      return std::string("key '") + key + "': expected " + std::to_string(m.jointNames.size()) +
             " numbers (one per joint name), got " + std::to_string(n);
    };
    if (std::string e = count("joint_positions", m.jointPositions.size()); !e.empty()) return e;
    if (std::string e = count("joint_velocities", m.jointVelocities.size()); !e.empty()) return e;
    if (!m.baseVelocity.empty() && m.baseVelocity.size() != 6)
      return "key 'base_velocity': expected 6 numbers (vx vy vz wx wy wz), got " + std::to_string(m.baseVelocity.size());
    for (size_t i = 0; i < m.objects.size(); ++i) {
      const std::string& name = m.objects[i].name;
      if (name.empty() || name.find(' ') != std::string::npos)
        return "key 'objects': name " + std::to_string(i + 1) + " is empty or contains a space";
    }
    return {};
  }
  std::string operator()(const SequenceMsg& m) const {
    if (std::string e = sequenceHashRule(m.hash); !e.empty()) return e;
    if (m.commands.empty()) return "key 'commands': must not be empty";
    if (!(std::isfinite(m.startPosition) && m.startPosition > 0)) return "key 'start_position': must be finite and > 0";
    if (!(std::isfinite(m.startHeading) && m.startHeading > 0)) return "key 'start_heading': must be finite and > 0";
    return {};
  }
  std::string operator()(const SequenceStateMsg& m) const { return m.hash.empty() ? "key 'hash': must not be empty" : ""; }
  std::string operator()(const AbortMsg& m) const { return sequenceHashRule(m.hash); }
  static std::string sequenceHashRule(const std::string& hash) {
    if (std::string e = hexDigits("hash", hash, 16, "16 hex digits"); !e.empty()) return e;
    if (hash.size() != 16) return "key 'hash': expected 16 hex digits, got " + std::to_string(hash.size());
    return {};
  }
  std::string operator()(const LaserMsg& m) const {
    if (!std::isfinite(m.angleMin)) return "key 'angle_min': must be finite";
    if (!std::isfinite(m.angleStep)) return "key 'angle_step': must be finite";
    return {};
  }
  std::string operator()(const auto&) const { return {}; }
};

std::string validate(const Message& message) { return std::visit(Validator{}, message); }

// ---------------------------------------------------------------------------
// Encoding.

struct Encoder {
  std::string out;
  std::string error;  // "key 'k': problem", first one only

  void fail(const char* key, const std::string& problem) {
    if (error.empty()) error = std::string("key '") + key + "': " + problem;
  }
  void text(const char* key, const std::string& value) {
    if (value.find('\n') != std::string::npos) fail(key, "contains a line feed");
    else if (invalidUtf8(value) != std::string::npos) fail(key, "is not valid UTF-8");
    out += value;
  }
  template <size_t N>
  void name(const char* key, size_t value, const char* const (&names)[N]) {
    if (value >= N) fail(key, "bad enum value " + std::to_string(value));
    else out += names[value];
  }

  void operator()(const char* key, const std::string& v, Need need) {
    if (need == Need::Optional && v.empty()) return;
    line(key, [&] { text(key, v); });
  }
  // An optional number at its default (0) is left out: older peers never
  // see keys they do not know unless the value means something.
  void operator()(const char* key, uint64_t v, Need need) {
    if (need == Need::Optional && v == 0) return;
    line(key, [&] { appendNumber(out, v); });
  }
  void operator()(const char* key, double v, Need need) {
    if (need == Need::Optional && v == 0) return;
    line(key, [&] { appendNumber(out, v); });
  }
  void operator()(const char* key, bool v, Need) { line(key, [&] { out += v ? '1' : '0'; }); }
  void operator()(const char* key, Role v, Need) {
    line(key, [&] { name(key, static_cast<size_t>(v), kRoleNames); });
  }
  void operator()(const char* key, ReplyStatus v, Need) {
    line(key, [&] { name(key, static_cast<size_t>(v), kStatusNames); });
  }
  void operator()(const char* key, EventKind v, Need) {
    line(key, [&] { name(key, static_cast<size_t>(v), kEventNames); });
  }
  void operator()(const char* key, SequenceStateKind v, Need) {
    line(key, [&] { name(key, static_cast<size_t>(v), kSequenceStateNames); });
  }
  void operator()(const char* key, const Pose& v, Need) {
    const double xs[7] = {v.p.x, v.p.y, v.p.z, v.q.w, v.q.x, v.q.y, v.q.z};
    line(key, [&] { numbers(xs, xs + 7); });
  }
  void operator()(const char* key, const std::array<double, 4>& v, Need) {
    line(key, [&] { numbers(v.begin(), v.end()); });
  }
  void operator()(const char* key, const std::vector<double>& v, Need need) {
    if (need == Need::Optional && v.empty()) return;
    line(key, [&] { numbers(v.begin(), v.end()); });
  }
  void operator()(const char* key, const std::vector<std::string>& v, Need) {
    line(key, [&] {
      for (size_t i = 0; i < v.size(); ++i) {
        if (i > 0) out += ' ';
        text(key, v[i]);
      }
    });
  }

  // `name x y z qw qx qy qz` per object, all items space-separated.
  void operator()(const char* key, const std::vector<ObjectPose>& v, Need) {
    line(key, [&] {
      for (size_t i = 0; i < v.size(); ++i) {
        if (i > 0) out += ' ';
        text(key, v[i].name);
        const Pose& p = v[i].pose;
        const double xs[7] = {p.p.x, p.p.y, p.p.z, p.q.w, p.q.x, p.q.y, p.q.z};
        out += ' ';
        numbers(xs, xs + 7);
      }
    });
  }

  template <class It>
  void numbers(It begin, It end) {
    for (It it = begin; it != end; ++it) {
      if (it != begin) out += ' ';
      appendNumber(out, *it);
    }
  }
  template <class W>
  void line(const char* key, W write) {
    out += key;
    out += '=';
    write();
    out += '\n';
  }
};

// ---------------------------------------------------------------------------
// Decoding.

struct Entry {
  std::string_view key, value;
  int line = 0;
};

struct Decoder {
  const std::vector<Entry>& entries;  // sorted by key
  std::string error;                  // "key 'k': problem" or "missing key 'k'", first one only

  template <class T>
  void operator()(const char* key, T& member, Need need) {
    if (!error.empty()) return;
    const auto it = std::lower_bound(entries.begin(), entries.end(), std::string_view(key),
                                     [](const Entry& e, std::string_view k) { return e.key < k; });
    if (it == entries.end() || it->key != key) {
      if (need == Need::Required) error = std::string("missing key '") + key + "'";
      return;
    }
    std::string problem = parse(it->value, member);
    if (!problem.empty()) error = std::string("key '") + key + "': " + problem;
  }

  static std::string parse(std::string_view s, std::string& v) {
    v.assign(s);
    return {};
  }
  static std::string parse(std::string_view s, uint64_t& v) {
    return parseWhole(s, v) ? std::string() : "expected an unsigned integer, got " + quote(s);
  }
  static std::string parse(std::string_view s, double& v) {
    return parseWhole(s, v) ? std::string() : "expected a number, got " + quote(s);
  }
  static std::string parse(std::string_view s, bool& v) {
    if (s != "0" && s != "1") return "expected 0 or 1, got " + quote(s);
    v = s == "1";
    return {};
  }
  template <class E, size_t N>
  static std::string parseName(std::string_view s, E& v, const char* const (&names)[N]) {
    for (size_t i = 0; i < N; ++i)
      if (s == names[i]) {
        v = static_cast<E>(i);
        return {};
      }
    return "expected " + alternatives(names) + ", got " + quote(s);
  }
  static std::string parse(std::string_view s, Role& v) { return parseName(s, v, kRoleNames); }
  static std::string parse(std::string_view s, ReplyStatus& v) { return parseName(s, v, kStatusNames); }
  static std::string parse(std::string_view s, EventKind& v) { return parseName(s, v, kEventNames); }
  static std::string parse(std::string_view s, SequenceStateKind& v) { return parseName(s, v, kSequenceStateNames); }

  static std::string parse(std::string_view s, std::vector<double>& v) {
    const std::vector<std::string_view> items = splitSpaces(s);
    v.assign(items.size(), 0.0);
    for (size_t i = 0; i < items.size(); ++i)
      if (!parseWhole(items[i], v[i]))
        return "number " + std::to_string(i + 1) + ": expected a number, got " + quote(items[i]);
    return {};
  }
  static std::string parseFixed(std::string_view s, double* out, size_t n, const char* what) {
    std::vector<double> v;
    if (std::string e = parse(s, v); !e.empty()) return e;
    if (v.size() != n)
      return "expected " + std::to_string(n) + " numbers (" + what + "), got " + std::to_string(v.size());
    std::copy(v.begin(), v.end(), out);
    return {};
  }
  static std::string parse(std::string_view s, Pose& v) {
    double xs[7];
    if (std::string e = parseFixed(s, xs, 7, "x y z qw qx qy qz"); !e.empty()) return e;
    v.p = {xs[0], xs[1], xs[2]};
    v.q = {xs[3], xs[4], xs[5], xs[6]};
    return {};
  }
  static std::string parse(std::string_view s, std::array<double, 4>& v) {
    return parseFixed(s, v.data(), 4, "FL FR RL RR");
  }
  static std::string parse(std::string_view s, std::vector<std::string>& v) {
    v.clear();
    for (std::string_view item : splitSpaces(s)) v.emplace_back(item);
    return {};
  }
  static std::string parse(std::string_view s, std::vector<ObjectPose>& v) {
    constexpr size_t kItems = 8;  // name x y z qw qx qy qz
    const std::vector<std::string_view> items = splitSpaces(s);
    if (items.size() % kItems != 0)
      return "expected groups of 8 items (name x y z qw qx qy qz), got " + std::to_string(items.size()) +
             " items";
    v.assign(items.size() / kItems, ObjectPose{});
    for (size_t i = 0; i < v.size(); ++i) {
      const std::string_view* item = &items[i * kItems];
      double xs[7];
      for (size_t k = 0; k < 7; ++k)
        if (!parseWhole(item[k + 1], xs[k]))
          return "object " + std::to_string(i + 1) + " " + quote(item[0]) + ": number " + std::to_string(k + 1) +
                 ": expected a number, got " + quote(item[k + 1]);
      v[i].name.assign(item[0]);
      v[i].pose.p = {xs[0], xs[1], xs[2]};
      v[i].pose.q = {xs[3], xs[4], xs[5], xs[6]};
    }
    return {};
  }
};

bool isKey(std::string_view key) {
  return !key.empty() && std::all_of(key.begin(), key.end(), [](char c) { return (c >= 'a' && c <= 'z') || c == '_'; });
}

// The alternative of Message with index i, default-constructed.
template <size_t I = 0>
Message messageOfIndex(size_t i) {
  if constexpr (I + 1 < std::variant_size_v<Message>) {
    if (i != I) return messageOfIndex<I + 1>(i);
  }
  return Message(std::in_place_index<I>);
}

// The frame of `type` with `payload`, or nullopt and the error encodeMessage() gives.
std::optional<std::string> frameOf(MessageType type, const std::string& payload, std::string& error) {
  std::optional<std::string> frame = encodeFrame(static_cast<uint8_t>(type), payload);
  if (!frame)
    error = std::string(toString(type)) + ": payload of " + std::to_string(payload.size()) +
            " bytes exceeds the maximum " + std::to_string(kMaxPayloadSize);
  return frame;
}

// Where the line of `key` starts in a payload (keys start lines; values
// hold no line feed, so "\nkey=" cannot occur inside a value).
size_t lineOf(const std::string& payload, const char* key) {
  const std::string prefix = key + std::string("=");
  if (payload.compare(0, prefix.size(), prefix) == 0) return 0;
  const size_t at = payload.find("\n" + prefix);
  return at == std::string::npos ? at : at + 1;
}
size_t endOfLine(const std::string& payload, size_t start) { return payload.find('\n', start) + 1; }


}  // namespace

static_assert(std::variant_size_v<Message> == kLastMessageType);

const char* toString(MessageType type) { return messageTypeName(static_cast<uint8_t>(type)); }

const char* messageTypeName(uint8_t type) {
  return type >= kFirstMessageType && type <= kLastMessageType ? kTypeNames[type - kFirstMessageType] : "unknown";
}

const char* toString(Role role) { return enumName(role, kRoleNames); }
const char* toString(ReplyStatus status) { return enumName(status, kStatusNames); }
const char* toString(EventKind kind) { return enumName(kind, kEventNames); }
const char* toString(SequenceStateKind state) { return enumName(state, kSequenceStateNames); }

MessageType typeOf(const Message& message) {
  return static_cast<MessageType>(message.index() + kFirstMessageType);
}

std::optional<std::string> encodePayload(const Message& message, std::string& error) {
  const char* type = toString(typeOf(message));
  if (std::string problem = validate(message); !problem.empty()) {
    error = std::string(type) + ": " + problem;
    return std::nullopt;
  }
  Encoder encoder;
  std::visit([&](const auto& m) { forEachField(m, encoder); }, message);
  if (!encoder.error.empty()) {
    error = std::string(type) + ": " + encoder.error;
    return std::nullopt;
  }
  return std::move(encoder.out);
}

std::optional<std::string> encodeMessage(const Message& message, std::string& error) {
  std::optional<std::string> payload = encodePayload(message, error);
  if (!payload) return std::nullopt;
  return frameOf(typeOf(message), *payload, error);
}

std::optional<Message> decodeMessage(const Frame& frame, std::string& error) {
  if (frame.type < kFirstMessageType || frame.type > kLastMessageType) {
    error = "unknown message type " + std::to_string(frame.type);
    return std::nullopt;
  }
  const std::string type = messageTypeName(frame.type);
  const auto fail = [&](const std::string& problem) {
    error = type + ": " + problem;
    return std::nullopt;
  };
  if (frame.version != kProtocolVersion)
    return fail("unsupported protocol version " + std::to_string(frame.version) + ", expected " +
                std::to_string(kProtocolVersion));
  const std::string_view payload = frame.payload;
  if (const size_t bad = invalidUtf8(payload); bad != std::string_view::npos)
    return fail("payload is not valid UTF-8 at byte " + std::to_string(bad));

  // Lines to entries.
  std::vector<Entry> entries;
  int lineNo = 0;
  for (size_t pos = 0; pos < payload.size();) {
    const size_t end = std::min(payload.find('\n', pos), payload.size());
    const std::string_view line = payload.substr(pos, end - pos);
    pos = end + 1;
    ++lineNo;
    if (line.empty()) continue;
    const size_t eq = line.find('=');
    if (eq == std::string_view::npos)
      return fail("line " + std::to_string(lineNo) + ": expected key=value, got " + quote(line));
    const std::string_view key = line.substr(0, eq);
    if (!isKey(key)) return fail("line " + std::to_string(lineNo) + ": bad key " + quote(key) + ", expected [a-z_]+");
    entries.push_back({key, line.substr(eq + 1), lineNo});
  }
  std::stable_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.key < b.key; });
  const Entry* repeat = nullptr;  // the repeat with the lowest line
  for (size_t i = 1; i < entries.size(); ++i)
    if (entries[i].key == entries[i - 1].key && (!repeat || entries[i].line < repeat->line)) repeat = &entries[i];
  if (repeat) {
    const auto first = std::lower_bound(entries.begin(), entries.end(), repeat->key,
                                        [](const Entry& e, std::string_view k) { return e.key < k; });
    return fail("line " + std::to_string(repeat->line) + ": key '" + std::string(repeat->key) + "' repeats line " +
                std::to_string(first->line));
  }

  Message message = messageOfIndex(frame.type - kFirstMessageType);
  Decoder decoder{entries, {}};
  std::visit([&](auto& m) { forEachField(m, decoder); }, message);
  if (!decoder.error.empty()) return fail(decoder.error);
  if (std::string problem = validate(message); !problem.empty()) return fail(problem);
  return message;
}

TelemetryFanOut::TelemetryFanOut(const TelemetryMsg& common) {
  std::optional<std::string> payload = encodePayload(common, error_);
  if (!payload) return;
  // Laid out as seq, ..., rtt_ms, lost, ... (forEachField's order).
  const size_t afterSeq = endOfLine(*payload, lineOf(*payload, "seq"));
  const size_t rtt = lineOf(*payload, "rtt_ms");
  const size_t afterLost = endOfLine(*payload, lineOf(*payload, "lost"));
  middle_ = payload->substr(afterSeq, rtt - afterSeq);
  tail_ = payload->substr(afterLost);
}

std::optional<std::string> TelemetryFanOut::frame(uint64_t seq, double rttMs, uint64_t lost, std::string& error,
                                                  double heardMs) const {
  if (!error_.empty()) {
    error = error_;
    return std::nullopt;
  }
  std::string payload = "seq=";
  payload.reserve(middle_.size() + tail_.size() + 64);
  appendNumber(payload, seq);
  payload += '\n';
  payload += middle_;
  payload += "rtt_ms=";
  appendNumber(payload, rttMs);
  payload += "\nlost=";
  appendNumber(payload, lost);
  payload += '\n';
  if (heardMs > 0) {
    payload += "heard_ms=";
    appendNumber(payload, heardMs);
    payload += '\n';
  }
  payload += tail_;
  return frameOf(MessageType::Telemetry, payload, error);
}

LaserFanOut::LaserFanOut(const LaserMsg& common) {
  std::optional<std::string> payload = encodePayload(common, error_);
  if (payload) tail_ = payload->substr(endOfLine(*payload, lineOf(*payload, "seq")));
}

std::optional<std::string> LaserFanOut::frame(uint64_t seq, std::string& error) const {
  if (!error_.empty()) {
    error = error_;
    return std::nullopt;
  }
  std::string payload = "seq=";
  payload.reserve(tail_.size() + 32);
  appendNumber(payload, seq);
  payload += '\n';
  payload += tail_;
  return frameOf(MessageType::Laser, payload, error);
}

LimitsMsg limitsOf(const RobotModel& robot) {
  LimitsMsg out;
  constexpr double inf = std::numeric_limits<double>::infinity();
  for (const ActuatorSpec& a : robot.actuators) {
    if (a.joint < 0 || static_cast<size_t>(a.joint) >= robot.joints.size()) continue;
    const JointSpec& joint = robot.joints[a.joint];
    out.joints.push_back(joint.name);
    out.lower.push_back(joint.limited ? joint.lower : -inf);
    out.upper.push_back(joint.limited ? joint.upper : inf);
    out.maxVelocity.push_back(a.maxVelocity);
    out.maxTorque.push_back(a.maxTorque);
  }
  if (robot.drive) {
    out.driveSpeed = driveSpeedLimit(robot);
    out.wheelSpeed = slowestWheelSpeed(robot);
    out.articulation = robot.joints[robot.drive->articulation].name;
  }
  return out;
}

CommandMsg makeCommandMsg(uint64_t seq, uint64_t expiresMs, const Command& command, const RobotModel* robot) {
  return CommandMsg{seq, expiresMs, toText(command, robot)};
}

std::optional<std::vector<TimedCommand>> parseSequenceMsg(const SequenceMsg& message, const RobotModel* robot,
                                                          std::string& error) {
  std::string text;
  for (size_t start = 0; start <= message.commands.size();) {
    const size_t end = std::min(message.commands.find(';', start), message.commands.size());
    text.append(message.commands, start, end - start);
    text += '\n';
    start = end + 1;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(text)));
  std::string lower = message.hash;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](char c) { return static_cast<char>(std::tolower(c)); });
  if (lower != hex) {
    error = "SEQUENCE: key 'hash': " + quote(message.hash) + " is not the hash of the commands (" + hex + ")";
    return std::nullopt;
  }
  Diagnostics diag;
  std::optional<std::vector<TimedCommand>> commands = parseCommandSequence(text, "SEQUENCE", diag, robot);
  if (!commands) {
    const Diagnostic& d = diag.items().front();
    error = "SEQUENCE: key 'commands': command " + std::to_string(d.line) + ": " + d.message;
  } else if (commands->empty()) {
    error = "SEQUENCE: key 'commands': no command";
    commands.reset();
  }
  return commands;
}

std::optional<Command> parseCommandMsg(const CommandMsg& message, const RobotModel* robot, std::string& error) {
  std::string problem;
  std::optional<Command> command = parseCommand(message.command, problem, robot);
  if (!command) error = "COMMAND: key 'command': " + problem;
  return command;
}

}  // namespace sp::net
