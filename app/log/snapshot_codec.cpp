#include "app/log/snapshot_codec.h"

#include <cstring>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "sim/height_grid.h"
#include "sim/state_fields.h"

namespace sp {
namespace {

// Appends values little-endian.
class Writer {
 public:
  void u8(uint8_t v) { out_.push_back(v); }
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) out_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) out_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void i64(int64_t v) { u64(static_cast<uint64_t>(v)); }
  void i32(int v) { i64(v); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void f64(double v) {
    uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void str(const std::string& s) {
    u64(s.size());
    out_.insert(out_.end(), s.begin(), s.end());
  }
  void vec3(const Vec3& v) { f64(v.x); f64(v.y); f64(v.z); }
  void pose(const Pose& p) {
    vec3(p.p);
    f64(p.q.w); f64(p.q.x); f64(p.q.y); f64(p.q.z);
  }
  std::vector<uint8_t> take() { return std::move(out_); }

 private:
  std::vector<uint8_t> out_;
};

struct Truncated : std::runtime_error {
  Truncated() : std::runtime_error("truncated snapshot data") {}
};

// Reads what Writer wrote; throws Truncated past the end (caught in decodeSnapshot).
class Reader {
 public:
  explicit Reader(const std::vector<uint8_t>& in) : in_(in) {}
  uint8_t u8() {
    need(1);
    return in_[pos_++];
  }
  uint32_t u32() {
    need(4);
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(in_[pos_++]) << (8 * i);
    return v;
  }
  uint64_t u64() {
    need(8);
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(in_[pos_++]) << (8 * i);
    return v;
  }
  int64_t i64() { return static_cast<int64_t>(u64()); }
  int i32() { return static_cast<int>(i64()); }
  bool boolean() { return u8() != 0; }
  double f64() {
    uint64_t bits = u64();
    double v = 0;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  std::size_t count(std::size_t minElementSize) {
    uint64_t n = u64();
    if (minElementSize > 0 && n > (in_.size() - pos_) / minElementSize) throw Truncated();
    return static_cast<std::size_t>(n);
  }
  std::string str() {
    std::size_t n = count(1);
    std::string s(in_.begin() + static_cast<std::ptrdiff_t>(pos_),
                  in_.begin() + static_cast<std::ptrdiff_t>(pos_ + n));
    pos_ += n;
    return s;
  }
  Vec3 vec3() {
    Vec3 v;
    v.x = f64(); v.y = f64(); v.z = f64();
    return v;
  }
  Pose pose() {
    Pose p;
    p.p = vec3();
    p.q.w = f64(); p.q.x = f64(); p.q.y = f64(); p.q.z = f64();
    return p;
  }
  bool atEnd() const { return pos_ == in_.size(); }

 private:
  void need(std::size_t n) const {
    if (in_.size() - pos_ < n) throw Truncated();
  }
  const std::vector<uint8_t>& in_;
  std::size_t pos_ = 0;
};

struct BadData : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void writeSensorValue(Writer& w, const SensorValue& value) {
  w.u8(static_cast<uint8_t>(value.index()));
  std::visit(
      [&w](const auto& r) {
        using T = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<T, PoseReading>) {
          w.pose(r.pose);
        } else if constexpr (std::is_same_v<T, LaserReading>) {
          w.pose(r.sensorPose);
          w.f64(r.angleMin); w.f64(r.angleStep); w.f64(r.minRange); w.f64(r.maxRange);
          w.u64(r.ranges.size());
          for (double d : r.ranges) w.f64(d);
        } else if constexpr (std::is_same_v<T, EncoderReading>) {
          w.f64(r.position); w.f64(r.velocity);
        } else if constexpr (std::is_same_v<T, WheelForceReading>) {
          w.vec3(r.force); w.f64(r.normal); w.f64(r.tangential); w.i32(r.contacts);
        } else if constexpr (std::is_same_v<T, JointForceReading>) {
          w.vec3(r.force); w.vec3(r.torque);
        } else {
          static_assert(std::is_same_v<T, ImuReading>);
          w.f64(r.roll); w.f64(r.pitch); w.vec3(r.angularRate); w.vec3(r.acceleration);
        }
      },
      value);
}

SensorValue readSensorValue(Reader& r) {
  switch (r.u8()) {
    case 0: return PoseReading{r.pose()};
    case 1: {
      LaserReading l;
      l.sensorPose = r.pose();
      l.angleMin = r.f64(); l.angleStep = r.f64(); l.minRange = r.f64(); l.maxRange = r.f64();
      l.ranges.resize(r.count(8));
      for (double& d : l.ranges) d = r.f64();
      return l;
    }
    case 2: {
      EncoderReading e;
      e.position = r.f64(); e.velocity = r.f64();
      return e;
    }
    case 3: {
      WheelForceReading f;
      f.force = r.vec3(); f.normal = r.f64(); f.tangential = r.f64(); f.contacts = r.i32();
      return f;
    }
    case 4: {
      JointForceReading f;
      f.force = r.vec3(); f.torque = r.vec3();
      return f;
    }
    case 5: {
      ImuReading m;
      m.roll = r.f64(); m.pitch = r.f64(); m.angularRate = r.vec3(); m.acceleration = r.vec3();
      return m;
    }
    default: throw BadData("unknown sensor reading type");
  }
}

void writeCommand(Writer& w, const Command& command) {
  w.u8(static_cast<uint8_t>(command.index()));
  std::visit(
      [&w](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, JointVelocityCmd>) {
          w.str(c.joint); w.f64(c.velocity);
        } else if constexpr (std::is_same_v<T, JointTargetCmd>) {
          w.str(c.joint); w.f64(c.position);
        } else if constexpr (std::is_same_v<T, JointTorqueCmd>) {
          w.str(c.joint); w.f64(c.torque);
        } else if constexpr (std::is_same_v<T, JointModeCmd>) {
          w.str(c.joint); w.u8(static_cast<uint8_t>(c.mode));
        } else if constexpr (std::is_same_v<T, WheelsCmd>) {
          for (double o : c.omega) w.f64(o);
        } else if constexpr (std::is_same_v<T, DriveCmd>) {
          w.f64(c.speed); w.f64(c.articulation);
        } else if constexpr (std::is_same_v<T, StopCmd>) {
        } else if constexpr (std::is_same_v<T, GaitCmd>) {
          w.u8(static_cast<uint8_t>(c.gait));
        } else if constexpr (std::is_same_v<T, TurnCmd>) {
          w.f64(c.speed); w.f64(c.yawRate);
        } else {
          static_assert(std::is_same_v<T, TerrainPatchCmd>);
          w.i32(c.column); w.i32(c.row); w.i32(c.columns); w.i32(c.rows);
          w.u64(c.heights.size());
          for (double h : c.heights) w.f64(h);
        }
      },
      command);
}

Command readCommand(Reader& r) {
  switch (r.u8()) {
    case 0: { JointVelocityCmd c; c.joint = r.str(); c.velocity = r.f64(); return c; }
    case 1: { JointTargetCmd c; c.joint = r.str(); c.position = r.f64(); return c; }
    case 2: { JointTorqueCmd c; c.joint = r.str(); c.torque = r.f64(); return c; }
    case 3: {
      JointModeCmd c;
      c.joint = r.str();
      uint8_t m = r.u8();
      if (m > static_cast<uint8_t>(JointMode::Free)) throw BadData("unknown joint mode");
      c.mode = static_cast<JointMode>(m);
      return c;
    }
    case 4: { WheelsCmd c; for (double& o : c.omega) o = r.f64(); return c; }
    case 5: { DriveCmd c; c.speed = r.f64(); c.articulation = r.f64(); return c; }
    case 6: return StopCmd{};
    case 7: {
      uint8_t g = r.u8();
      if (g > static_cast<uint8_t>(Gait::Rolking)) throw BadData("unknown gait");
      return GaitCmd{static_cast<Gait>(g)};
    }
    case 8: { TurnCmd c; c.speed = r.f64(); c.yawRate = r.f64(); return c; }
    case 9: {
      TerrainPatchCmd c;
      c.column = r.i32(); c.row = r.i32(); c.columns = r.i32(); c.rows = r.i32();
      c.heights.resize(r.count(8));
      for (double& h : c.heights) h = r.f64();
      return c;
    }
    default: throw BadData("unknown command type");
  }
}

// Writes the fields sim/state_fields.h lists, in its order.
struct Encode {
  Writer& w;
  void operator()(double v, auto) { w.f64(v); }
  void operator()(uint64_t v, auto) { w.u64(v); }
  void operator()(bool v, auto) { w.boolean(v); }
  void operator()(int v, auto) { w.i32(v); }
  void operator()(int64_t v, auto) { w.i64(v); }
  void operator()(JointMode m, auto) { w.u8(static_cast<uint8_t>(m)); }
  void operator()(const Vec3& v, auto) { w.vec3(v); }
  template <size_t N>
  void operator()(const std::array<double, N>& a, auto) {
    for (double v : a) w.f64(v);
  }
  template <size_t N>
  void operator()(const std::array<uint64_t, N>& a, auto) {
    for (uint64_t v : a) w.u64(v);
  }
  void operator()(const GaitState& g, auto) {
    w.u8(static_cast<uint8_t>(g.gait));
    w.i32(g.phase);
    w.i64(g.phaseStart);
  }
  void operator()(const SensorSample& s, auto) {
    w.i32(s.robot);
    w.i32(s.sensor);
    w.i64(s.step);
    w.f64(s.time);
    writeSensorValue(w, s.value);
  }
  template <StateOf T>
  void operator()(const std::vector<T>& items, auto) {
    w.u64(items.size());
    for (const T& item : items) visitState(item, *this);
  }
  void robots(const std::vector<RobotControlState>& controls, const std::vector<std::vector<SensorState>>& sensors) {
    (*this)(controls, kHashed);
    w.u64(sensors.size());
    for (const std::vector<SensorState>& robotSensors : sensors) (*this)(robotSensors, kHashed);
  }
  void terrain(const std::shared_ptr<const HeightGrid>& grid) {
    w.boolean(grid != nullptr);
    if (!grid) return;
    w.i32(grid->columns);
    w.i32(grid->rows);
    w.f64(grid->width);
    w.f64(grid->depth);
    w.u64(grid->heights.size());
    for (double h : grid->heights) w.f64(h);
  }
  void operator()(const std::vector<std::pair<int, Command>>& pending, auto) {
    w.u64(pending.size());
    for (const auto& [robot, command] : pending) {
      w.i32(robot);
      writeCommand(w, command);
    }
  }
  void resistance(const std::vector<double>& forces, const std::vector<double>& shares,
                  const std::vector<double>& holds) {
    w.u64(forces.size());
    for (size_t l = 0; l < forces.size(); ++l) {
      w.f64(forces[l]);
      w.f64(l < shares.size() ? shares[l] : 1.0);
      w.f64(l < holds.size() ? holds[l] : 0.0);
    }
  }
};

// The fewest bytes a T takes encoded (its vectors empty): a count of Ts
// beyond what is left of the data is a truncated snapshot, not an allocation.
template <StateOf T>
size_t minEncodedSize() {
  static const size_t size = [] {
    Writer w;
    Encode encode{w};
    const T empty{};
    visitState(empty, encode);
    return w.take().size();
  }();
  return size;
}

// Reads what Encode wrote; `version` is the snapshot's (1 has no motion resistance, 2 no hold).
struct Decode {
  Reader& r;
  uint32_t version;
  void operator()(double& v, auto) { v = r.f64(); }
  void operator()(uint64_t& v, auto) { v = r.u64(); }
  void operator()(bool& v, auto) { v = r.boolean(); }
  void operator()(int& v, auto) { v = r.i32(); }
  void operator()(int64_t& v, auto) { v = r.i64(); }
  void operator()(JointMode& m, auto) {
    const uint8_t v = r.u8();
    if (v > static_cast<uint8_t>(JointMode::Free)) throw BadData("unknown joint mode");
    m = static_cast<JointMode>(v);
  }
  void operator()(Vec3& v, auto) { v = r.vec3(); }
  template <size_t N>
  void operator()(std::array<double, N>& a, auto) {
    for (double& v : a) v = r.f64();
  }
  template <size_t N>
  void operator()(std::array<uint64_t, N>& a, auto) {
    for (uint64_t& v : a) v = r.u64();
  }
  void operator()(GaitState& g, auto) {
    const uint8_t v = r.u8();
    if (v > static_cast<uint8_t>(Gait::Rolking)) throw BadData("unknown gait");
    g.gait = static_cast<Gait>(v);
    g.phase = r.i32();
    g.phaseStart = r.i64();
  }
  void operator()(SensorSample& s, auto) {
    s.robot = r.i32();
    s.sensor = r.i32();
    s.step = r.i64();
    s.time = r.f64();
    s.value = readSensorValue(r);
  }
  template <StateOf T>
  void operator()(std::vector<T>& items, auto) {
    items.resize(r.count(minEncodedSize<T>()));
    for (T& item : items) visitState(item, *this);
  }
  void robots(std::vector<RobotControlState>& controls, std::vector<std::vector<SensorState>>& sensors) {
    (*this)(controls, kHashed);
    sensors.resize(r.count(8));
    for (std::vector<SensorState>& robotSensors : sensors) (*this)(robotSensors, kHashed);
  }
  void terrain(std::shared_ptr<const HeightGrid>& terrain) {
    if (!r.boolean()) return;
    auto grid = std::make_shared<HeightGrid>();
    grid->columns = r.i32();
    grid->rows = r.i32();
    grid->width = r.f64();
    grid->depth = r.f64();
    grid->heights.resize(r.count(8));
    for (double& h : grid->heights) h = r.f64();
    terrain = std::move(grid);
  }
  void operator()(std::vector<std::pair<int, Command>>& pending, auto) {
    pending.resize(r.count(9));
    for (auto& [robot, command] : pending) {
      robot = r.i32();
      command = readCommand(r);
    }
  }
  void resistance(std::vector<double>& forces, std::vector<double>& shares, std::vector<double>& holds) {
    if (version < 2) return;
    forces.resize(r.count(version < 3 ? 16 : 24));
    shares.resize(forces.size());
    holds.assign(forces.size(), 0.0);  // version 2: a hold not yet given way
    for (size_t l = 0; l < forces.size(); ++l) {
      forces[l] = r.f64();
      shares[l] = r.f64();
      if (version >= 3) holds[l] = r.f64();
    }
  }
};

}  // namespace

std::vector<uint8_t> encodeSnapshot(const Snapshot& s) {
  static_assert(std::variant_size_v<Command> == 10, "update the snapshot codec");
  static_assert(std::variant_size_v<SensorValue> == 6, "update the snapshot codec");
  Writer w;
  for (char c : std::string("SPSN")) w.u8(static_cast<uint8_t>(c));
  w.u32(kSnapshotCodecVersion);
  static_assert(std::is_same_v<unsigned long, uint64_t>, "odeRandom is written as a u64");
  Encode encode{w};
  visitState(s, encode);
  return w.take();
}

std::optional<Snapshot> decodeSnapshot(const std::vector<uint8_t>& data, std::string* error) {
  auto fail = [error](const std::string& message) -> std::optional<Snapshot> {
    if (error) *error = message;
    return std::nullopt;
  };
  if (data.size() < 8 || std::memcmp(data.data(), "SPSN", 4) != 0) return fail("not a snapshot (bad magic)");
  Reader r(data);
  try {
    for (int i = 0; i < 4; ++i) r.u8();
    uint32_t version = r.u32();
    if (version < 1 || version > kSnapshotCodecVersion)
      return fail("snapshot format version " + std::to_string(version) + " is not supported (expected " +
                  std::to_string(kSnapshotCodecVersion) + ")");
    Snapshot s;
    Decode decode{r, version};
    visitState(s, decode);
    if (!r.atEnd()) return fail("trailing bytes after the snapshot");
    return s;
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}

}  // namespace sp
