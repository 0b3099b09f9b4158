// Benchmark: 181-beam, 10 m laser scans against a terrain heightfield, cast
// with sp::intersectRay and with ODE's ray geom against a heightfield geom
// built as sim/world.cpp builds the terrain. Prints figures; asserts nothing.
//
// Usage: bench_height_grid_ray [path/to/bumpy.asc]
// (default: terrains/bumpy.asc of the source tree this was built from)

#include <ode/ode.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "sim/diagnostics.h"
#include "sim/height_grid.h"
#include "sim/height_grid_ray.h"
#include "sim/math.h"
#include "sim/terrain_loader.h"

namespace {

using Clock = std::chrono::steady_clock;
using sp::HeightGrid;
using sp::Vec3;

constexpr int kPositions = 100;
constexpr int kBeams = 181;         // 180 deg fan, 1 deg apart
constexpr double kRange = 10.0;     // [m]
constexpr double kMountHeight = 1.6;  // scanner above the ground [m]
constexpr double kOdeBudget = 4.0;  // wall time allowed to ODE per case [s]

struct Beam {
  Vec3 origin;
  Vec3 direction;
};
using Scan = std::array<Beam, kBeams>;

// Scans from kPositions random poses (fixed seed) at least 1 m inside the
// grid, scanner kMountHeight above the ground, pitched down by tiltDeg.
std::vector<Scan> makeScans(const HeightGrid& g, double tiltDeg, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(-g.width / 2 + 1, g.width / 2 - 1);
  std::uniform_real_distribution<double> uy(-g.depth / 2 + 1, g.depth / 2 - 1);
  std::uniform_real_distribution<double> uyaw(-sp::kPi, sp::kPi);
  const double tilt = sp::degToRad(tiltDeg);
  std::vector<Scan> scans(kPositions);
  for (Scan& scan : scans) {
    const double x = ux(rng), y = uy(rng), yaw = uyaw(rng);
    const Vec3 origin{x, y, g.heightAt(x, y) + kMountHeight};
    for (int k = 0; k < kBeams; ++k) {
      const double a = sp::degToRad(k - 90.0);
      // Beam in the scanner frame, pitched down about the scanner's y axis,
      // then turned by the heading.
      const Vec3 s{std::cos(a) * std::cos(tilt), std::sin(a), -std::cos(a) * std::sin(tilt)};
      scan[static_cast<std::size_t>(k)] = {
          origin, {s.x * std::cos(yaw) - s.y * std::sin(yaw), s.x * std::sin(yaw) + s.y * std::cos(yaw), s.z}};
    }
  }
  return scans;
}

// ODE's heightfield geom from a grid, as sim/world.cpp builds it, and a ray.
class OdeCaster {
 public:
  explicit OdeCaster(const HeightGrid& grid) : grid_(grid) {
    data_ = dGeomHeightfieldDataCreate();
    dGeomHeightfieldDataBuildCallback(data_, &grid_, &OdeCaster::heightAt, grid_.width, grid_.depth, grid_.columns,
                                      grid_.rows, 1.0, 0.0, 1.0, 0);
    dGeomHeightfieldDataSetBounds(data_, grid_.minHeight(), grid_.maxHeight());
    geom_ = dCreateHeightfield(nullptr, data_, 1);
    const sp::Quat q = sp::quatFromAxisAngle({1, 0, 0}, sp::kPi / 2);  // y-up to z-up
    const dQuaternion oq = {q.w, q.x, q.y, q.z};
    dGeomSetQuaternion(geom_, oq);
    ray_ = dCreateRay(nullptr, kRange);
    contacts_.resize(kMaxContacts);
  }
  ~OdeCaster() {
    dGeomDestroy(ray_);
    dGeomDestroy(geom_);
    dGeomHeightfieldDataDestroy(data_);
  }
  OdeCaster(const OdeCaster&) = delete;
  OdeCaster& operator=(const OdeCaster&) = delete;

  // Nearest contact; a ray contact's depth is its distance.
  std::optional<double> cast(const Beam& b) {
    dGeomRaySet(ray_, b.origin.x, b.origin.y, b.origin.z, b.direction.x, b.direction.y, b.direction.z);
    const int n = dCollide(geom_, ray_, kMaxContacts, contacts_.data(), sizeof(dContactGeom));
    std::optional<double> best;
    for (int k = 0; k < n; ++k) {
      const double depth = contacts_[static_cast<std::size_t>(k)].depth;
      if (!best || depth < *best) best = depth;
    }
    return best;
  }

 private:
  static constexpr int kMaxContacts = 512;
  static dReal heightAt(void* data, int x, int z) {
    const HeightGrid& g = *static_cast<const HeightGrid*>(data);
    return g.at(x, g.rows - 1 - z);  // ODE row z is our row rows-1-z
  }
  HeightGrid grid_;
  dHeightfieldDataID data_ = nullptr;
  dGeomID geom_ = nullptr;
  dGeomID ray_ = nullptr;
  std::vector<dContactGeom> contacts_;
};

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void runCase(const char* terrain, const HeightGrid& g, const char* scanner, double tiltDeg) {
  const std::vector<Scan> scans = makeScans(g, tiltDeg, 42);

  // Ours: all scans, repeated for at least half a second; the median pass
  // (the machine is shared, so a mean would carry others' bursts).
  std::vector<double> passUs;
  int oursHits = 0;
  double checksum = 0;
  const Clock::time_point start = Clock::now();
  do {
    const Clock::time_point passStart = Clock::now();
    oursHits = 0;
    for (const Scan& scan : scans)
      for (const Beam& b : scan)
        if (const auto t = sp::intersectRay(g, b.origin, b.direction, kRange)) {
          ++oursHits;
          checksum += *t;
        }
    passUs.push_back(1e6 * secondsSince(passStart) / kPositions);
  } while (secondsSince(start) < 0.5 || passUs.size() < 5);
  std::sort(passUs.begin(), passUs.end());
  const double oursUs = passUs[passUs.size() / 2];

  // ODE: as many scans as fit in its time budget (at least one), compared
  // beam by beam with ours.
  OdeCaster ode(g);
  int odeScans = 0;
  int disagree = 0;
  double maxDiff = 0;
  double odeSeconds = 0;
  for (const Scan& scan : scans) {
    std::array<std::optional<double>, kBeams> theirs;
    const Clock::time_point odeStart = Clock::now();
    for (std::size_t k = 0; k < scan.size(); ++k) theirs[k] = ode.cast(scan[k]);
    odeSeconds += secondsSince(odeStart);
    ++odeScans;
    for (std::size_t k = 0; k < scan.size(); ++k) {
      const auto ours = sp::intersectRay(g, scan[k].origin, scan[k].direction, kRange);
      if (ours.has_value() != theirs[k].has_value())
        ++disagree;
      else if (ours)
        maxDiff = std::max(maxDiff, std::abs(*ours - *theirs[k]));
    }
    if (odeSeconds > kOdeBudget) break;
  }
  const double odeUs = 1e6 * odeSeconds / odeScans;

  std::printf("%-20s %-13s %9.1f %11.0f %6d %9.0fx %9.1f %10.2g %6d\n", terrain, scanner, oursUs, odeUs, odeScans,
              odeUs / oursUs, static_cast<double>(oursHits) / kPositions, maxDiff, disagree);
  if (checksum < 0) std::printf("(checksum %g)\n", checksum);  // keeps the loop from being optimised away
}

// Rolling bumps on a 128 x 128 grid at 0.25 m spacing.
HeightGrid bumps128() {
  HeightGrid g;
  g.columns = 128;
  g.rows = 128;
  g.width = 127 * 0.25;
  g.depth = 127 * 0.25;
  g.heights.resize(128 * 128);
  for (int j = 0; j < g.rows; ++j)
    for (int i = 0; i < g.columns; ++i) {
      const double x = -g.width / 2 + i * 0.25, y = -g.depth / 2 + j * 0.25;
      g.at(i, j) = 0.15 * std::sin(0.7 * x) * std::cos(0.5 * y) + 0.05 * std::sin(1.9 * x + 1.3 * y);
    }
  return g;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? std::string(argv[1])
                                    : (std::filesystem::path(__FILE__).parent_path().parent_path() / "terrains" /
                                       "bumpy.asc")
                                          .string();
  sp::Diagnostics diag;
  sp::TerrainSource source;
  source.path = path;
  const std::optional<HeightGrid> bumpy = sp::loadHeightGrid(source, diag);
  if (!bumpy) {
    std::fprintf(stderr, "%s", diag.format().c_str());
    return 1;
  }

  dInitODE2(0);
  dAllocateODEDataForThread(dAllocateMaskAll);

  std::printf("%d scans per case of %d beams, %.0f m, scanner %.1f m above the ground; ODE on as many scans as fit "
              "in %.0f s.\n",
              kPositions, kBeams, kRange, kMountHeight, kOdeBudget);
  std::printf("%-20s %-13s %9s %11s %6s %10s %9s %10s %6s\n", "terrain", "scanner", "ours us", "ODE us", "scans",
              "ODE/ours", "hits", "max diff", "beams");
  std::printf("%-20s %-13s %9s %11s %6s %10s %9s %10s %6s\n", "", "", "per scan", "per scan", "(ODE)", "",
              "per scan", "[m]", "differ");
  const HeightGrid big = bumps128();
  const std::string bumpyName = "bumpy.asc " + std::to_string(bumpy->columns) + "x" + std::to_string(bumpy->rows);
  runCase(bumpyName.c_str(), *bumpy, "tilted 5 deg", 5);
  runCase(bumpyName.c_str(), *bumpy, "level", 0);
  runCase(bumpyName.c_str(), *bumpy, "tilted 15 deg", 15);  // most beams hit, at about 6 m
  runCase("128x128 at 0.25 m", big, "tilted 5 deg", 5);
  runCase("128x128 at 0.25 m", big, "level", 0);
  runCase("128x128 at 0.25 m", big, "tilted 15 deg", 15);

  dCloseODE();
  return 0;
}
