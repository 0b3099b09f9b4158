// Benchmark of how sure the ghost is (issue 61, app/ghost/ghost_region.h):
// the coverage and sharpness of its regions and its departures, against a
// stand-in over a 1 s each-way link. Prints a table, asserts nothing.
//
//   build/bench/bench_region [--seeds A-B] [--worlds rough,bumpy,track] [--seconds S]
//                            [--departures A-B] [--matched] [--control]
//
// Each case: the console's session (app/console/console_session.h) with its
// ghost and calibrator, a stand-in on loopback with the link's delay, a
// client driving as the console does, 60 s of driving and turning drawn
// from the seed (left turns and straights that stay on the world's
// terrain; on the test track, gentle steering along it). Seed 0 is the
// matched robot (the files); others are perturbed (sim/perturbation.h).
//
// Judged, after the first 20 s (the layer has learnt): every telemetry
// frame against what the ghost showed for its time: inside the inner
// (50 %) and outer (90 %) regions as they stood then; the outer radius's
// median against the ghost's median error (sharpness); departures
// announced on mapped ground (false alarms).
//
// --departures A-B: the rough field's robot stands on rough_unmapped's
// ground (a 9 cm ridge at x = -2 m, a 7 cm hollow at x = 2 m) while the
// console's map is rough.asc; for each crossing of either the time from
// the front wheels meeting it to the departure's announcement (telemetry's
// robot time: the departure is dated by the frame that announced it).
//
// --control: the conformal layer off (its Gaussian multipliers on the
// scale alone), to show that the coverage figures can fail.
//
// --change T: the stand-in changes at robot time T (friction x 0.7,
// delay + 100 ms: sim/perturbation.h SuddenChange; the drive starts some
// 4 s into robot time, and the line says where in the drive it fell); the 90 % region's
// coverage is printed for each 10 s after 20 s, and whether every window
// from 20 s after the change on holds 85-95 % (back within 30 s).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "app/console/console_session.h"
#include "app/console/session_drive.h"
#include "sim/math.h"

using namespace sp;
using namespace sp::net;

namespace {

const std::string kToken = "00112233445566778899aabbccddeeff";

// The drive of `seed` on `world` ("rough", "bumpy", "track") over `seconds`.
std::vector<DrivePhase> driveOf(const std::string& world, uint64_t seed, double seconds) {
  std::mt19937_64 rng(seed * 7919 + 17);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<DrivePhase> out;
  const auto add = [&out](double at, const Command& c) {
    DrivePhase& p = out.emplace_back();
    p.at = at;
    p.command = c;
  };
  double t = 0;
  if (world == "track") {
    // Along the 22 m track, 4 m wide: slow, steering a little either way.
    double side = u(rng) < 0.5 ? 1 : -1;
    while (t < seconds) {
      const double speed = 0.22 + 0.1 * u(rng);
      const double steer = degToRad(1 + 2.5 * u(rng)) * side;
      add(t, DriveCmd{speed, steer});
      t += 3 + 3 * u(rng);
      side = -side;
      if (u(rng) < 0.15) {
        add(t, StopCmd{});
        t += 1.5;
      }
    }
    return out;
  }
  // Left turns and straights: loops of radius about 3-3.5 m about a centre
  // left of the start that each straight moves on, inside the 20 m fields
  // (articulation 20-25 deg: an axle's radius is 0.55 m / tan(angle / 2) by
  // the kinematics, more with the tyres' slip). Wider loops, of 15-20 deg
  // with straights of up to 3 s, took a perturbed robot to the field's edge
  // (bumpy, seed 24: y = 9.8 m at 31 s), where the ghost's prediction left
  // the map.
  while (t < seconds) {
    const double speed = 0.35 + 0.2 * u(rng);
    add(t, DriveCmd{speed, degToRad(20 + 5 * u(rng))});
    t += 5 + 4 * u(rng);
    add(t, DriveCmd{speed, 0});
    t += 1 + 1 * u(rng);
    if (u(rng) < 0.2) {
      add(t, StopCmd{});
      t += 1.5;
    }
  }
  while (!out.empty() && out.back().at >= seconds) out.pop_back();  // phases are sent in order: none after the stop
  add(seconds, StopCmd{});
  return out;
}

struct Result {
  int judged = 0, inner = 0, outer = 0;
  std::vector<std::pair<int, int>> windows;  // (judged, in 90 %) per 10 s of the drive
  double changeIntoDrive = -1;               // [s] the sudden change, from the drive's start
  std::vector<double> errors, radii;
  int falseAlarms = 0;  // departures on mapped ground
  std::vector<double> latencies;  // [s] feature met to departure announced (departure runs)
  int crossings = 0, announced = 0;
  double anchorsPerSecond = 0;
  std::string error;
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// The axles' x: the base is the rear body, whose frame is 0.45 m behind
// the robot's; the front wheels 1.0 m ahead of it, the rear 0.1 m behind
// (robots/workpartner.xml), the articulation taken straight.
std::pair<double, double> axlesX(const TelemetryMsg& t) {
  const double c = std::cos(heading(t.pose.q));
  return {t.pose.p.x + 1.0 * c, t.pose.p.x - 0.1 * c};
}

Result runCase(const std::string& world, uint64_t seed, double seconds, bool unmapped, bool control,
               double changeAt = -1) {
  Result r;
  ConsoleSessionOptions o;
  const std::string file = world == "track" ? "test_track" : world;
  o.world = std::string(SP_SOURCE_DIR) + "/terrains/" + file + ".world.xml";
  if (unmapped) o.ground = std::string(SP_SOURCE_DIR) + "/terrains/rough_unmapped.world.xml";
  o.token = kToken;
  o.log = false;
  o.delay = 1.0;
  o.overrides = {"link.deadman=0.5"};
  if (seed != 0) o.perturbSeed = seed;
  if (control) o.ghostOptions.conformal = false;
  if (changeAt >= 0) o.change = SuddenChange{changeAt, 0.7, 0.1};  // robot time, not the drive's
  ConsoleSession session(o);
  if (std::string e = session.start(); !e.empty()) {
    r.error = e;
    return r;
  }
  double driveStart = -1;     // robot time of the first frame after the drive began
  double met = -1;            // robot time the front wheels met a feature not yet announced
  // The ridge's and the hollow's extents along x (terrains/README.md):
  // the robot meets one when an axle reaches its edge (where a cosine
  // ridge starts from nothing, a tyre's front touches it no earlier).
  const std::pair<double, double> features[] = {{-2.3, -1.7}, {1.6, 2.4}};
  bool on = false;  // an axle was on a feature in the last frame
  const int64_t anchors0 = session.ghost() ? session.ghost()->stats().anchors : 0;
  const auto wall0 = std::chrono::steady_clock::now();
  // Until the last command has come back in telemetry.
  const bool trace = std::getenv("SP_BENCH_TRACE") != nullptr;
  const std::vector<DrivePhase> drive = driveOf(world, seed, seconds);
  if (trace)
    for (const DrivePhase& p : drive) {
      if (const auto* d = std::get_if<DriveCmd>(&p.command))
        std::fprintf(stderr, "phase %.2f drive %.3f m/s %.1f deg\n", p.at, d->speed, radToDeg(d->articulation));
      else
        std::fprintf(stderr, "phase %.2f stop\n", p.at);
    }
  const std::string why = driveSession(session, kToken, drive, seconds + 2.5,
                                       [&](const TelemetryMsg& t, const std::optional<GhostError>& e) {
      if (driveStart < 0) {
        driveStart = t.time;
        r.changeIntoDrive = changeAt - driveStart;
      }
      const bool judged = t.time - driveStart >= 20 + 1.0 && e && e->scale > 0;
      if (judged) {
        ++r.judged;
        r.inner += e->position <= e->inner;
        r.outer += e->position <= e->outer;
        r.errors.push_back(e->position);
        r.radii.push_back(e->outer);
        const auto w = static_cast<size_t>((t.time - driveStart) / 10);
        if (r.windows.size() <= w) r.windows.resize(w + 1);
        ++r.windows[w].first;
        r.windows[w].second += e->position <= e->outer;
      }
      if (trace && e)
        std::fprintf(stderr,
                     "%.2f x %.2f y %.2f z %.3f err %.1f lim %.1f vert %.1f vlim %.1f scale %.1f dep %d sus %d\n",
                     t.time, axlesX(t).first, t.pose.p.y, t.pose.p.z, e->position * 1000, e->limit * 1000,
                     e->vertical * 1000, e->verticalLimit * 1000, e->scale * 1000, e->departure, e->suspect);
      if (unmapped) {
        // An axle coming onto a feature: the robot meets it (once per
        // crossing: the next needs both axles off first).
        const auto [front, rear] = axlesX(t);
        bool now = false;
        for (const auto& [lo, hi] : features)
          for (double x : {front, rear}) now |= x >= lo && x <= hi;
        if (now && !on && met < 0 && t.time - driveStart > 2) {
          ++r.crossings;
          if (session.ghost() && !session.ghost()->departures().empty() &&
              session.ghost()->departures().back().ended < 0) {
            r.latencies.push_back(0);  // a departure on already
            ++r.announced;
          } else {
            met = t.time;
          }
        }
        on = now;
        if (e && e->departure == 1 && met >= 0) {
          r.latencies.push_back(t.time - met);
          ++r.announced;
          met = -1;
        } else if (met >= 0 && t.time - met > 4) {
          met = -1;  // not announced within 4 s: missed
        }
      } else if (e && e->departure == 1 && t.time - driveStart >= 20) {
        ++r.falseAlarms;
      }
  });
  r.error = why;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (session.ghost()) {
    r.anchorsPerSecond = static_cast<double>(session.ghost()->stats().anchors - anchors0) / wall;
    if (trace) {
      std::fprintf(stderr, "end: ghost problem '%s', view time %.2f\n", session.ghost()->view().problem.c_str(),
                   session.ghost()->view().time);
      if (const LiveCalibrator* c = session.calibrator()) {
        const CalibrationState st = c->state();
        std::fprintf(stderr, "calibration: %d fits, %d refused ('%s')\n", st.fits, st.refusals, st.lastRefusal.c_str());
        for (size_t i = 0; i < kCalParams; ++i)
          if (st.observed[i])
            std::fprintf(stderr, "  %s = %.4f +- %.4f\n", calParams()[i].key, st.applied[i], st.sigma[i]);
      }
    }
  }
  return r;
}

std::pair<uint64_t, uint64_t> range(const char* text) {
  unsigned long long a = 0, b = 0;
  if (std::sscanf(text, "%llu-%llu", &a, &b) == 2) return {a, b};
  if (std::sscanf(text, "%llu", &a) == 1) return {a, a};
  std::fprintf(stderr, "bench_region: expected A-B, got '%s'\n", text);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  std::pair<uint64_t, uint64_t> seeds{1, 20}, departures{0, 0};
  bool runDepartures = false, matched = false, control = false;
  double changeAt = -1;
  std::string worlds = "rough,bumpy,track";
  double seconds = 60;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seeds" && i + 1 < argc) seeds = range(argv[++i]);
    else if (a == "--worlds" && i + 1 < argc) worlds = argv[++i];
    else if (a == "--seconds" && i + 1 < argc) seconds = std::atof(argv[++i]);
    else if (a == "--departures" && i + 1 < argc) {
      departures = range(argv[++i]);
      runDepartures = true;
    } else if (a == "--change" && i + 1 < argc) changeAt = std::atof(argv[++i]);
    else if (a == "--matched") matched = true;
    else if (a == "--control") control = true;
    else {
      std::fprintf(stderr,
                   "usage: bench_region [--seeds A-B] [--worlds rough,bumpy,track] [--seconds S] [--departures A-B] "
                   "[--matched] [--control] [--change T]\n");
      return 2;
    }
  }
  if (runDepartures) {
    std::printf("departures: rough field's map, rough_unmapped's ground, 1 s each way, %.0f s each\n", seconds);
    std::printf("%6s %9s %9s %s\n", "seed", "crossings", "announced", "latencies [s]");
    int within = 0, crossings = 0;
    for (uint64_t s = departures.first; s <= departures.second; ++s) {
      const Result r = runCase("rough", s, seconds, true, control);
      if (!r.error.empty()) {
        std::printf("%6llu error: %s\n", static_cast<unsigned long long>(s), r.error.c_str());
        continue;
      }
      std::string lat;
      for (double l : r.latencies) {
        char b[16];
        std::snprintf(b, sizeof b, " %.2f", l);
        lat += b;
        within += l <= 1.0;
      }
      crossings += r.crossings;
      std::printf("%6llu %9d %9d%s\n", static_cast<unsigned long long>(s), r.crossings, r.announced, lat.c_str());
      std::fflush(stdout);
    }
    std::printf("announced within 1 s: %d of %d crossings\n", within, crossings);
    return 0;
  }
  std::printf("coverage: 1 s each way, %.0f s each, judged after 20 s%s\n", seconds,
              control ? " (control: the conformal layer off)" : "");
  std::printf("%-6s %6s %7s %7s %7s %9s %9s %6s %6s %8s\n", "world", "seed", "judged", "in 50", "in 90", "err med",
              "r90 med", "ratio", "false", "anchor/s");
  size_t from = 0;
  while (from <= worlds.size()) {
    const size_t comma = worlds.find(',', from);
    const std::string w = worlds.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
    from = comma == std::string::npos ? worlds.size() + 1 : comma + 1;
    int judged = 0, inner = 0, outer = 0, alarms = 0;
    std::vector<double> ratios;
    std::vector<uint64_t> list;
    if (matched) list.push_back(0);
    for (uint64_t s = seeds.first; s <= seeds.second && s > 0; ++s) list.push_back(s);
    for (uint64_t s : list) {
      const Result r = runCase(w, s, seconds, false, control, changeAt);
      if (!r.error.empty()) {
        std::printf("%-6s %6llu error: %s\n", w.c_str(), static_cast<unsigned long long>(s), r.error.c_str());
        continue;
      }
      const double em = median(r.errors), rm = median(r.radii);
      std::printf("%-6s %6llu %7d %7.3f %7.3f %8.1fmm %8.1fmm %6.2f %6d %8.1f\n", w.c_str(),
                  static_cast<unsigned long long>(s), r.judged, r.judged ? double(r.inner) / r.judged : NAN,
                  r.judged ? double(r.outer) / r.judged : NAN, em * 1000, rm * 1000, rm / em, r.falseAlarms,
                  r.anchorsPerSecond);
      std::fflush(stdout);
      if (changeAt >= 0) {
        // Each 10 s window's coverage; back when every window that starts
        // 20 s or more after the change holds 85-95 %.
        std::string line;
        bool back = true;
        int after = 0;
        for (size_t k = 2; k < r.windows.size() && 10.0 * static_cast<double>(k + 1) <= seconds + 1e-9; ++k) {
          if (r.windows[k].first == 0) continue;  // (the last, past the drive's end, holds the stop)
          const double c = double(r.windows[k].second) / r.windows[k].first;
          char b[40];
          std::snprintf(b, sizeof b, " %zu-%zus %.3f", 10 * k, 10 * k + 10, c);
          line += b;
          if (10.0 * static_cast<double>(k) >= r.changeIntoDrive + 20 - 1e-9) {
            ++after;
            back = back && c >= 0.85 && c <= 0.95;
          }
        }
        std::printf("       change at %.1f s of the drive; 90 %% coverage per 10 s:%s; back within 30 s: %s\n",
                    r.changeIntoDrive, line.c_str(), after == 0 ? "not judged (drive too short)" : back ? "yes" : "no");
      }
      judged += r.judged;
      inner += r.inner;
      outer += r.outer;
      alarms += r.falseAlarms;
      ratios.push_back(rm / em);
    }
    if (judged)
      std::printf("%-6s %6s %7d %7.3f %7.3f %9s %9s %6.2f %6d\n", w.c_str(), "all", judged, double(inner) / judged,
                  double(outer) / judged, "", "", median(ratios), alarms);
  }
  return 0;
}
