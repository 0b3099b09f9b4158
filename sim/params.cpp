#include "sim/params.h"

#include "sim/calibration_table.h"
#include "sim/file_set.h"
#include "sim/properties.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <system_error>

#include "sim/text.h"

namespace sp {
namespace {

/// Result of reading an integer: the value, or why not.
template <typename Int>
struct IntRead {
  std::optional<Int> value;
  bool tooLarge = false;  // a well-formed integer beyond the type's range
  bool tooSmall = false;
};

template <typename Int>
IntRead<Int> parseInt(std::string_view text) {
  Int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  IntRead<Int> out;
  if (text.empty() || end != text.data() + text.size()) return out;
  if (ec == std::errc::result_out_of_range) {
    (text.front() == '-' ? out.tooSmall : out.tooLarge) = true;
    return out;
  }
  if (ec == std::errc()) out.value = value;
  return out;
}

/// Bounds of a numeric key; a bound may be open (strict) or absent.
struct Range {
  std::optional<double> lo, hi;
  bool loOpen = false, hiOpen = false;
};
Range atLeast(double lo) { return {lo, std::nullopt, false, false}; }
Range above(double lo) { return {lo, std::nullopt, true, false}; }
Range closed(double lo, double hi) { return {lo, hi, false, false}; }
Range openClosed(double lo, double hi) { return {lo, hi, true, false}; }
Range closedOpen(double lo, double hi) { return {lo, hi, false, true}; }
Range open(double lo, double hi) { return {lo, hi, true, true}; }

/// The violated bound as "must be > 0", or "" when `value` is in range.
std::string rangeError(const Range& range, double value) {
  if (range.lo && (range.loOpen ? !(value > *range.lo) : !(value >= *range.lo)))
    return std::string("must be ") + (range.loOpen ? "> " : ">= ") + shortestText(*range.lo);
  if (range.hi && (range.hiOpen ? !(value < *range.hi) : !(value <= *range.hi)))
    return std::string("must be ") + (range.hiOpen ? "< " : "<= ") + shortestText(*range.hi);
  return {};
}

/// Parses `text` into `params` and returns "", or leaves `params` alone and
/// returns the problem (without the key, which the caller prefixes).
using Setter = std::function<std::string(SimParams& params, std::string_view text)>;
using Getter = std::function<std::string(const SimParams& params)>;

struct Entry {
  const char* key;
  std::string description;
  Setter set;
  Getter get;
};

struct Accessors {
  Setter set;
  Getter get;
};

Accessors real(double SimParams::*field, Range range) {
  return {[field, range](SimParams& p, std::string_view text) -> std::string {
            const std::optional<double> v = parseReal(text);
            if (!v) return "expected a number, got '" + std::string(text) + "'";
            if (std::string e = rangeError(range, *v); !e.empty()) return e + ", got " + std::string(text);
            p.*field = *v;
            return {};
          },
          [field](const SimParams& p) { return shortestText(p.*field); }};
}

Accessors integer(int SimParams::*field, int lo, int hi) {
  return {[field, lo, hi](SimParams& p, std::string_view text) -> std::string {
            const IntRead<int64_t> v = parseInt<int64_t>(text);
            const std::string got = ", got " + std::string(text);
            if (v.tooSmall || (v.value && *v.value < lo)) return "must be >= " + std::to_string(lo) + got;
            if (v.tooLarge || (v.value && *v.value > hi)) return "must be <= " + std::to_string(hi) + got;
            if (!v.value) return "expected an integer, got '" + std::string(text) + "'";
            p.*field = static_cast<int>(*v.value);
            return {};
          },
          [field](const SimParams& p) { return std::to_string(p.*field); }};
}

Accessors unsigned64(uint64_t SimParams::*field) {
  return {[field](SimParams& p, std::string_view text) -> std::string {
            const IntRead<uint64_t> v = parseInt<uint64_t>(text);
            if (v.tooLarge)
              return "must be <= " + std::to_string(std::numeric_limits<uint64_t>::max()) + ", got " +
                     std::string(text);
            if (!v.value) return "expected a non-negative integer, got '" + std::string(text) + "'";
            p.*field = *v.value;
            return {};
          },
          [field](const SimParams& p) { return std::to_string(p.*field); }};
}

Accessors solver() {
  return {[](SimParams& p, std::string_view text) -> std::string {
            if (text == "quick") p.solver = Solver::Quick;
            else if (text == "exact") p.solver = Solver::Exact;
            else return "expected 'quick' or 'exact', got '" + std::string(text) + "'";
            return {};
          },
          [](const SimParams& p) -> std::string { return p.solver == Solver::Exact ? "exact" : "quick"; }};
}

// A factor > 0, or `max` (stored as 0): run as fast as possible.
Accessors realTimeFactor() {
  return {[](SimParams& p, std::string_view text) -> std::string {
            if (text == "max") {
              p.realTimeFactor = 0;
              return {};
            }
            const std::optional<double> v = parseReal(text);
            if (!v) return "expected a number or 'max', got '" + std::string(text) + "'";
            if (!(*v > 0)) return "must be > 0, got " + std::string(text);
            p.realTimeFactor = *v;
            return {};
          },
          [](const SimParams& p) { return p.realTimeFactor > 0 ? shortestText(p.realTimeFactor) : "max"; }};
}

// Comma-separated joint names, or `none`.
Accessors jointNames(std::string SimParams::*field) {
  return {[field](SimParams& p, std::string_view text) -> std::string {
            if (text != "none")
              for (const std::string& name : splitNames(text))
                if (name.empty() || !std::all_of(name.begin(), name.end(), [](char c) {
                      return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
                    }))
                  return "expected joint names separated by commas, or 'none', got '" + std::string(text) + "'";
            p.*field = std::string(text);
            return {};
          },
          [field](const SimParams& p) { return p.*field; }};
}

Entry entry(const char* key, std::string description, Accessors a) {
  return {key, std::move(description), std::move(a.set), std::move(a.get)};
}

// The calibration.* keys, from their one table.
std::vector<Entry> calibrationEntries() {
  std::vector<Entry> out;
  for (const CalParamInfo& c : calParams())
    out.push_back(entry(c.key,
                        std::string(c.description) + ", [" + shortestText(c.lower) + ", " + shortestText(c.upper) + "]",
                        real(c.field, closed(c.lower, c.upper))));
  return out;
}

// The one list of keys, in the order of config/defaults.params. Defaults are
// not repeated here: they are SimParams' in-class initializers.
const std::vector<Entry>& table() {
  constexpr double kMaxRate = 10000;
  static const std::vector<Entry> entries = [] {
    std::vector<Entry> all = {
      // At least 10 us: a finer step simulates nothing in any useful time
      // (1e-300 ran "1 s" as zero steps and exited 0).
      entry("physics.step", "fixed integration step [s], [1e-05, 0.1]",
            real(&SimParams::step, closed(1e-5, 0.1))),
      entry("physics.solver", "quick (dWorldQuickStep, iterative) or exact (dWorldStep)", solver()),
      entry("physics.iterations", "quick solver iterations per step, 1..1000",
            integer(&SimParams::iterations, 1, 1000)),
      entry("physics.erp", "error reduction parameter, [0, 1]", real(&SimParams::erp, closed(0, 1))),
      entry("physics.cfm", "constraint force mixing, [0, 1)", real(&SimParams::cfm, closedOpen(0, 1))),
      entry("contact.surface_layer", "contact depth allowed before correction [m], >= 0",
            real(&SimParams::surfaceLayer, atLeast(0))),
      entry("contact.max_correcting_velocity", "max speed of penetration correction [m/s], > 0",
            real(&SimParams::maxCorrectingVel, above(0))),
      entry("contact.max_per_pair", "contact points per colliding geom pair, 1..64",
            integer(&SimParams::maxContacts, 1, 64)),
      entry("random.seed", "seed of the world's random engine (sensor noise), 0..2^64-1",
            unsigned64(&SimParams::seed)),
      entry("realtime.factor", "sim seconds per wall second, > 0, or max (unpaced)", realTimeFactor()),
      entry("rate.telemetry", "telemetry messages to the console [Hz], (0, 10000]",
            real(&SimParams::telemetryRate, openClosed(0, kMaxRate))),
      entry("rate.laser", "laser scans published [Hz], (0, 10000]",
            real(&SimParams::laserRate, openClosed(0, kMaxRate))),
      entry("rate.log", "state rows recorded in the session log [Hz], (0, 10000]",
            real(&SimParams::logRate, openClosed(0, kMaxRate))),
      entry("rate.csv", "rows per sim second written by run --csv [Hz], (0, 10000]",
            real(&SimParams::csvRate, openClosed(0, kMaxRate))),
      entry("log.keep", "console: session logs kept in its log folder, the newest; older ones are deleted when a session starts; 0 = all, 0..100000",
            integer(&SimParams::logKeep, 0, 100000)),
      entry("port.robot", "TCP port of the robot link, 1..65535", integer(&SimParams::robotPort, 1, 65535)),
      entry("link.deadman", "robot: longest gap between arrivals of the controller's keep-alives [s], [0.02, 60]",
            real(&SimParams::linkDeadman, closed(0.02, 60))),
      entry("link.keepalive", "console: keep-alive period [s], [0.005, 15] (shortened to a quarter of the robot's deadman)",
            real(&SimParams::linkKeepalive, closed(0.005, 15))),
      entry("link.command_expiry", "console: a command arriving later than the link's usual delay by more is refused [s], [0.001, 600]",
            real(&SimParams::linkCommandExpiry, closed(0.001, 600))),
      entry("link.lease_confirm", "robot: wait for a new controller's first keep-alive before taking the lease back [s], [0.1, 600]",
            real(&SimParams::linkLeaseConfirm, closed(0.1, 600))),
      entry("link.max_connections", "robot: connections open at once (more are closed at once), 1..10000",
            integer(&SimParams::linkMaxConnections, 1, 10000)),
      entry("link.hello_timeout", "robot: a connection without a good HELLO by then is closed [s], [0.1, 600]",
            real(&SimParams::linkHelloTimeout, closed(0.1, 600))),
      entry("console.stale_after", "console: no telemetry this long greys the robot and says 'no data' [s], [0.05, 60]",
            real(&SimParams::consoleStaleAfter, closed(0.05, 60))),
      entry("rehearsal.fast_step", "rehearsals' fast profile (robustness samples, first verdicts): physics step [s], [1e-05, 0.02]",
            real(&SimParams::rehearsalFastStep, closed(1e-5, 0.02))),
      entry("rehearsal.fast_iterations", "rehearsals' fast profile: quick solver iterations per step, 1..1000",
            integer(&SimParams::rehearsalFastIterations, 1, 1000)),
      entry("rehearsal.fast_hold",
            "rehearsals' fast profile: joints whose subtrees it also welds while no command or gait moves them (the drive's joints turn), comma-separated, or none",
            jointNames(&SimParams::rehearsalFastHold)),
      entry("rehearsal.refine.stability", "fast profile: a support margin this close to its limit is judged again at full fidelity [m], [0, 1]",
            real(&SimParams::refineStability, closed(0, 1))),
      entry("rehearsal.refine.roll", "fast profile: a roll this close to its limit, judged again [deg], [0, 90]",
            real(&SimParams::refineRoll, closed(0, 90))),
      entry("rehearsal.refine.pitch", "fast profile: a pitch this close to its limit, judged again [deg], [0, 90]",
            real(&SimParams::refinePitch, closed(0, 90))),
      entry("rehearsal.refine.joint_limit", "fast profile: a joint this close to its stop's margin, judged again [deg; cm for a sliding joint], [0, 180]",
            real(&SimParams::refineJointLimit, closed(0, 180))),
      entry("rehearsal.refine.wheel_liftoff", "fast profile: a wheel off the ground this close to its limit, judged again [s], [0, 60]",
            real(&SimParams::refineLiftoff, closed(0, 60))),
      entry("rehearsal.refine.wheel_force", "fast profile: a wheel force this close to its limit, judged again [N], [0, 100000]",
            real(&SimParams::refineWheelForce, closed(0, 1e5))),
      entry("rehearsal.refine.speed", "fast profile: a speed this close to its limit, judged again [m/s], [0, 10]",
            real(&SimParams::refineSpeed, closed(0, 10))),
      entry("rehearsal.refine.yaw_rate", "fast profile: a yaw rate this close to its limit, judged again [deg/s], [0, 360]",
            real(&SimParams::refineYawRate, closed(0, 360))),
      entry("ghost.step", "console's predictive ghost: physics step [s], [1e-05, 0.02]",
            real(&SimParams::ghostStep, closed(1e-5, 0.02))),
      entry("ghost.iterations", "ghost: quick solver iterations per step, 1..1000",
            integer(&SimParams::ghostIterations, 1, 1000)),
      entry("ghost.horizon", "ghost: seconds of predicted path drawn ahead of the ghost [s], [0, 60]",
            real(&SimParams::ghostHorizon, closed(0, 60))),
      entry("ghost.anchor_rate", "ghost: re-anchorings on telemetry per second at most [Hz], [1, 1000]",
            real(&SimParams::ghostAnchorRate, closed(1, 1000))),
      entry("ghost.hold", "ghost: joints whose subtrees it holds rigid while still (the drive's joints turn), comma-separated, or none",
            jointNames(&SimParams::ghostHold)),
      entry("ghost.region.inner", "ghost: the inner region's level, the share of predictions it holds, (0, 1)",
            real(&SimParams::ghostRegionInner, open(0, 1))),
      entry("ghost.region.outer", "ghost: the outer region's level (the trail's band, the status bar's radius), (0, 1)",
            real(&SimParams::ghostRegionOuter, open(0, 1))),
      entry("ghost.region.departure", "ghost: telemetry outside the region of this level for ghost.region.hold s is a departure, (0, 1)",
            real(&SimParams::ghostRegionDeparture, open(0, 1))),
      entry("ghost.region.hold", "ghost: how long telemetry stays outside before a departure is said [s], [0.02, 60]",
            real(&SimParams::ghostRegionHold, closed(0.02, 60))),
      entry("ghost.region.window", "ghost: robot time the conformal quantiles are over [s], [1, 600]",
            real(&SimParams::ghostRegionWindow, closed(1, 600))),
      entry("ghost.region.gamma", "ghost: adaptive conformal inference's step per judged prediction (0: off), [0, 0.1]",
            real(&SimParams::ghostRegionGamma, closed(0, 0.1))),
    };
    // In place: the keys keep the order of config/defaults.params.
    for (Entry& e : calibrationEntries()) all.push_back(std::move(e));
    all.insert(all.end(), {
      entry("gait.caterpillar.hip_swing", "caterpillar: hip swing about the stance pose [deg], (0, 45]",
            real(&SimParams::caterpillarHipSwing, openClosed(0, 45))),
      entry("gait.caterpillar.phase_time", "caterpillar: duration of each half cycle [s], (0, 60]",
            real(&SimParams::caterpillarPhaseTime, openClosed(0, 60))),
      entry("gait.rolking.hip_swing", "rolking: hip swing about the stance pose [deg], (0, 45]",
            real(&SimParams::rolkingHipSwing, openClosed(0, 45))),
      entry("gait.rolking.leg_time", "rolking: time for one leg to reach forward [s], (0, 60]",
            real(&SimParams::rolkingLegTime, openClosed(0, 60))),
      entry("gait.rolking.body_time", "rolking: time to bring the body over the feet [s], (0, 60]",
            real(&SimParams::rolkingBodyTime, openClosed(0, 60))),
      entry("health.max_linear_speed", "any body faster than this diverged [m/s], > 0",
            real(&SimParams::maxLinearSpeed, above(0))),
      entry("health.max_angular_speed", "any body spinning faster than this diverged [rad/s], > 0",
            real(&SimParams::maxAngularSpeed, above(0))),
      entry("health.max_linear_acceleration", "any body accelerating faster than this diverged [m/s^2], > 0",
            real(&SimParams::maxLinearAcceleration, above(0))),
      entry("health.max_angular_acceleration", "the same for angular acceleration [rad/s^2], > 0",
            real(&SimParams::maxAngularAcceleration, above(0))),
      entry("health.max_joint_error", "joint anchors pulled apart by more than this [m], > 0",
            real(&SimParams::maxJointError, above(0))),
      entry("health.max_penetration", "body below the ground by more than this [m], > 0",
            real(&SimParams::maxPenetration, above(0))),
    });
    return all;
  }();
  return entries;
}

const Entry* findEntry(std::string_view key) {
  for (const Entry& e : table())
    if (key == e.key) return &e;
  return nullptr;
}

constexpr const char* kCommandLine = "<command line>";

}  // namespace

std::vector<std::string> splitNames(std::string_view text) {
  std::vector<std::string> out;
  if (text == "none") return out;
  size_t start = 0;
  for (;;) {
    const size_t comma = text.find(',', start);
    out.emplace_back(text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

bool setParam(SimParams& params, std::string_view key, std::string_view value, std::string_view where,
              int line, Diagnostics& diag) {
  const Entry* e = findEntry(key);
  if (!e) {
    diag.error(where, line, "unknown key '" + std::string(key) + "'");
    return false;
  }
  if (std::string problem = e->set(params, value); !problem.empty()) {
    diag.error(where, line, std::string(key) + ": " + problem);
    return false;
  }
  return true;
}

bool loadParams(const std::string& path, SimParams& params, Diagnostics& diag) {
  const std::optional<std::string> contents = readSourceFile(path, nullptr);
  if (!contents) {
    // There but not readable as a file: a directory, say.
    diag.error(path, 0, sourceFileExists(path, nullptr) ? "cannot read parameters file" : "cannot open parameters file");
    return false;
  }
  return parseParams(*contents, path, params, diag);
}

bool parseParams(std::string_view contents, std::string_view path, SimParams& params, Diagnostics& diag) {
  // Applied to a copy, committed only if the whole file is valid.
  SimParams staged = params;
  const bool ok = readProperties(
      contents, path, diag, [](std::string_view key) { return findEntry(key) != nullptr; },
      [&](std::string_view key, std::string_view value, int line) {
        return setParam(staged, key, value, path, line, diag);
      });
  if (ok) params = staged;
  return ok;
}

bool applyOverride(SimParams& params, std::string_view assignment, Diagnostics& diag) {
  const size_t eq = assignment.find('=');
  const std::string_view key = eq == std::string_view::npos ? std::string_view() : trim(assignment.substr(0, eq));
  if (key.empty()) {
    diag.error(kCommandLine, 0, "expected key=value, got '" + std::string(assignment) + "'");
    return false;
  }
  return setParam(params, key, trim(assignment.substr(eq + 1)), kCommandLine, 0, diag);
}

std::vector<ParamInfo> paramTable() {
  const SimParams defaults;
  std::vector<ParamInfo> out;
  out.reserve(table().size());
  for (const Entry& e : table()) out.push_back({e.key, e.get(defaults), e.description});
  return out;
}

std::string paramValue(const SimParams& params, std::string_view key) {
  const Entry* e = findEntry(key);
  return e ? e->get(params) : std::string();
}

bool SimParams::calibrated() const {
  for (const CalParamInfo& c : calParams())
    if (this->*c.field != c.files) return true;
  return false;
}

}  // namespace sp
