#include "sim/height_grid_ray.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace sp {

namespace {

// Minimum and maximum by value: std::min/max return references, which GCC
// turns into chains of loads and conditional moves of pointers; these become
// single minsd/maxsd instructions.
inline double minOf(double a, double b) { return b < a ? b : a; }
inline double maxOf(double a, double b) { return a < b ? b : a; }

bool isFinite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Narrows [tMin, tMax] to the parameters at which p + t*d lies in [0, hi]
// (one slab of the rectangle, in sample units); invD = 1/d. False when that
// is empty.
bool clipToSlab(double p, double d, double invD, double hi, double& tMin, double& tMax) {
  if (d == 0) return p >= 0 && p <= hi;
  double ta = (0 - p) * invD;
  double tb = (hi - p) * invD;
  if (ta > tb) std::swap(ta, tb);
  tMin = std::max(tMin, ta);
  tMax = std::min(tMax, tb);
  return tMin <= tMax;
}

// The ray in continuous sample coordinates, the frame HeightGrid::heightAt
// interpolates in: sample (i, j) at (i, j), heights unscaled. Along the ray,
// (sx, sy) = (px, py) + t*(dx, dy) and z = pz + t*dz, t in metres.
struct Ray {
  double px, py, pz;
  double dx, dy, dz;
};

// One cell (i, j) and its four corner heights.
struct Cell {
  int i, j;
  double h00, h10, h01, h11;

  // Surface height at cell-local (u, v) in [0, 1]^2: the same two triangles
  // and formulas as HeightGrid::heightAt.
  double height(double u, double v) const {
    if (u >= v) return h00 + u * (h10 - h00) + v * (h11 - h10);  // (i,j) (i+1,j) (i+1,j+1)
    return h00 + v * (h01 - h00) + u * (h11 - h01);               // (i,j) (i,j+1) (i+1,j+1)
  }
};

// Which side of the surface the ray is on at a point: +1 above, -1 below.
int sideOf(double f) { return f > 0 ? 1 : -1; }

// Walk state shared by the cells of one ray: the side of the surface the ray
// was on at the end of the last cell (0 before the first), and whether the
// ray started inside the rectangle (so a first point below means "in the
// ground": distance 0).
struct Walk {
  int side = 0;
  bool originInside = false;
};

// Feeds the height of the ray above the surface, f, at parameter t to the
// walk. Returns the hit parameter when the ray touches or changes side at
// or before t; `tPrev`/`fPrev` are the previous sample of the same cell and
// plane, or NaN when the previous sample lies in another cell (the crossing
// is then put on the shared boundary, t).
std::optional<double> feed(Walk& w, double t, double f, double tPrev, double fPrev, const Ray& r,
                           const Cell& c) {
  if (f == 0) return t;  // touches the surface
  const int s = sideOf(f);
  if (w.side == 0) {
    if (s < 0 && w.originInside) return 0.0;  // origin in the ground
    w.side = s;
    return std::nullopt;
  }
  if (s == w.side) return std::nullopt;
  if (std::isnan(tPrev)) return t;  // changed side exactly at a cell boundary

  // Changed side inside [tPrev, t], which lies in one triangle, so f is linear
  // there. Prefer the triangle's own plane (exact for tiny intervals and for
  // vertical rays); fall back to interpolating f if rounding puts that root
  // outside the interval.
  double root = tPrev + (t - tPrev) * (fPrev / (fPrev - f));
  const double tm = 0.5 * (tPrev + t);
  const double um = r.px + tm * r.dx - c.i;
  const double vm = r.py + tm * r.dy - c.j;
  const bool lower = um >= vm;
  const double gx = lower ? c.h10 - c.h00 : c.h11 - c.h01;  // dh/du on that triangle
  const double gy = lower ? c.h11 - c.h10 : c.h01 - c.h00;  // dh/dv
  const double slope = r.dz - (gx * r.dx + gy * r.dy);      // df/dt
  if (slope != 0) {
    const double planeRoot = tPrev - fPrev / slope;
    if (planeRoot >= tPrev && planeRoot <= t) root = planeRoot;
  }
  return std::clamp(root, tPrev, t);
}

// Tests the ray against the two triangles of cell c over t in [t0, t1]: the
// ray's height above the surface is piecewise linear there, with one break
// where the ray's xy path crosses the diagonal u == v. Samples f at t0, at
// that crossing (if any) and at t1, and finds the first change of side.
std::optional<double> hitInCell(Walk& w, const Ray& r, const Cell& c, double t0, double t1) {
  const double u0 = r.px + t0 * r.dx - c.i, v0 = r.py + t0 * r.dy - c.j;
  const double u1 = r.px + t1 * r.dx - c.i, v1 = r.py + t1 * r.dy - c.j;
  auto f = [&](double t, double u, double v) {
    return (r.pz + t * r.dz) - c.height(std::clamp(u, 0.0, 1.0), std::clamp(v, 0.0, 1.0));
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();

  const double f0 = f(t0, u0, v0);
  if (auto hit = feed(w, t0, f0, nan, nan, r, c)) return hit;

  double tPrev = t0, fPrev = f0;
  const double g0 = u0 - v0, g1 = u1 - v1;
  if ((g0 > 0 && g1 < 0) || (g0 < 0 && g1 > 0)) {
    const double tDiag = std::clamp(t0 + (t1 - t0) * (g0 / (g0 - g1)), t0, t1);
    // On the diagonal both triangles give h00 + s*(h11 - h00), s = u = v.
    const double s = std::clamp(0.5 * ((r.px + tDiag * r.dx - c.i) + (r.py + tDiag * r.dy - c.j)), 0.0, 1.0);
    const double fDiag = (r.pz + tDiag * r.dz) - (c.h00 + s * (c.h11 - c.h00));
    if (auto hit = feed(w, tDiag, fDiag, tPrev, fPrev, r, c)) return hit;
    tPrev = tDiag;
    fPrev = fDiag;
  }
  return feed(w, t1, f(t1, u1, v1), tPrev, fPrev, r, c);
}

// One cell over [t0, t1]: rejected when the ray stays above (or below) all
// four corners, where only the side it is on is carried; else its two
// triangles are tested.
std::optional<double> visitCell(Walk& w, const Ray& r, const Cell& c, double t0, double t1) {
  const double z0 = r.pz + t0 * r.dz;
  const double z1 = r.pz + t1 * r.dz;
  const double cellMin = minOf(minOf(c.h00, c.h10), minOf(c.h01, c.h11));
  const double cellMax = maxOf(maxOf(c.h00, c.h10), maxOf(c.h01, c.h11));
  if (minOf(z0, z1) > cellMax) {
    if (w.side < 0) return t0;  // came up through the boundary with the last cell
    w.side = 1;
    return std::nullopt;
  }
  if (maxOf(z0, z1) < cellMin) {
    if (w.side > 0) return t0;  // went down through the boundary with the last cell
    if (w.side == 0 && w.originInside) return 0.0;  // origin in the ground
    w.side = -1;
    return std::nullopt;
  }
  return hitInCell(w, r, c, t0, t1);
}

// The 2-D DDA (Amanatides-Woo), stepped along the ray's major axis A (x when
// kXMajor, else y), along which it moves at least as fast as along the minor
// axis B. Each step covers one strip between two A lines, in which the ray
// crosses at most one B line: one or two cells. The strip's cells are first
// rejected together against the six samples around them (the ray usually
// passes well above the ground, and a strip costs no unpredictable branch);
// only when that fails is each cell visited on its own.
template <bool kXMajor>
std::optional<double> walkStrips(Walk& w, const Ray& r, const HeightGrid& g, int i, int j, double t0,
                                 double tExit) {
  const int cols = g.columns;
  const double pa = kXMajor ? r.px : r.py, da = kXMajor ? r.dx : r.dy;
  const double pb = kXMajor ? r.py : r.px, db = kXMajor ? r.dy : r.dx;
  const int lastA = (kXMajor ? g.columns : g.rows) - 2;  // last cell index along A
  const int lastB = (kXMajor ? g.rows : g.columns) - 2;
  const std::ptrdiff_t strideA = kXMajor ? 1 : cols;  // next sample along A
  const std::ptrdiff_t strideB = kXMajor ? cols : 1;
  const double invDa = 1 / da;  // da != 0: the ray is not vertical
  const double invDb = db != 0 ? 1 / db : 0;
  const int stepA = da > 0 ? 1 : -1;
  const int stepB = db > 0 ? 1 : -1;
  const double* samples = g.heights.data();
  auto cellAt = [&](int ca, int cb) {
    const int ci = kXMajor ? ca : cb, cj = kXMajor ? cb : ca;
    const double* s = samples + static_cast<std::ptrdiff_t>(cj) * cols + ci;
    return Cell{ci, cj, s[0], s[1], s[cols], s[cols + 1]};
  };

  int a = kXMajor ? i : j;
  int b = kXMajor ? j : i;
  double lineA = da > 0 ? a + 1 : a;  // the next A line the ray crosses
  double z0 = r.pz + t0 * r.dz;
  for (;;) {
    // This strip's part of the ray: [t0, t1], up to the next A line.
    const double tLine = (lineA - pa) * invDa;
    const bool last = tLine >= tExit;
    const double t1 = last ? tExit : std::max(t0, tLine);
    const double z1 = r.pz + t1 * r.dz;

    // Samples on A lines a, a+1 and B lines m..m+2 bound the strip's cells
    // (b and b + stepB, kept inside the grid).
    const int m = std::min(b, std::clamp(b + stepB, 0, lastB));
    const double* s = samples + a * strideA + m * strideB;
    const std::ptrdiff_t third = (m + 2 <= lastB + 1 ? 2 : 1) * strideB;
    const double stripMax = maxOf(maxOf(maxOf(s[0], s[strideA]), maxOf(s[strideB], s[strideA + strideB])),
                                  maxOf(s[third], s[strideA + third]));
    if (minOf(z0, z1) > stripMax) {
      if (w.side < 0) return t0;  // came up through the boundary with the last strip
      w.side = 1;
    } else {
      // Cell b up to the B line the ray crosses in this strip, if any, then
      // the cell beyond it.
      double tSplit = t1;
      if (db != 0) tSplit = std::clamp(((db > 0 ? b + 1 : b) - pb) * invDb, t0, t1);
      if (auto hit = visitCell(w, r, cellAt(a, b), t0, tSplit)) return hit;
      const int next = b + stepB;
      if (tSplit < t1 && next >= 0 && next <= lastB)
        if (auto hit = visitCell(w, r, cellAt(a, next), tSplit, t1)) return hit;
    }
    if (last) return std::nullopt;

    // Into the next strip, in the cell holding the ray where it enters it
    // (on a B line: the cell the ray heads into).
    a += stepA;
    lineA += stepA;
    if (a < 0 || a > lastA) return std::nullopt;  // left the rectangle
    const double q = pb + t1 * db;
    const int nb = std::clamp(static_cast<int>(q), 0, lastB);  // q >= 0 up to rounding
    b = db < 0 && nb > 0 && q == nb ? nb - 1 : nb;
    t0 = t1;
    z0 = z1;
  }
}

}  // namespace

std::optional<double> intersectRay(const HeightGrid& grid, Vec3 origin, Vec3 direction, double maxRange) {
  const int cols = grid.columns;
  const int rows = grid.rows;
  if (cols < 2 || rows < 2 || !(grid.width > 0) || !(grid.depth > 0) ||
      grid.heights.size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols))
    return std::nullopt;
  if (!isFinite(origin) || !isFinite(direction) || !(maxRange >= 0)) return std::nullopt;
  if (direction.x == 0 && direction.y == 0 && direction.z == 0) return std::nullopt;

  // The ray in sample coordinates, computed as heightAt computes them.
  const double sx = grid.spacingX();
  const double sy = grid.spacingY();
  Ray r{(origin.x + grid.width / 2) / sx, (origin.y + grid.depth / 2) / sy, origin.z,
        direction.x / sx,                 direction.y / sy,                 direction.z};
  // Components too small to invert (below about 1e-308) count as 0.
  if (std::isinf(1 / r.dx)) r.dx = 0;
  if (std::isinf(1 / r.dy)) r.dy = 0;
  const double invDx = r.dx != 0 ? 1 / r.dx : 0;
  const double invDy = r.dy != 0 ? 1 / r.dy : 0;

  // Clip to the rectangle: the part of the ray over the surface.
  double tEnter = 0;
  double tExit = maxRange;
  if (!clipToSlab(r.px, r.dx, invDx, cols - 1, tEnter, tExit) ||
      !clipToSlab(r.py, r.dy, invDy, rows - 1, tEnter, tExit))
    return std::nullopt;

  // First cell: the one holding the entry point, or, when that point lies on
  // a grid line, the one on the side the ray heads to.
  const double qx = std::clamp(r.px + tEnter * r.dx, 0.0, double(cols - 1));
  const double qy = std::clamp(r.py + tEnter * r.dy, 0.0, double(rows - 1));
  int i = std::min(static_cast<int>(qx), cols - 2);
  int j = std::min(static_cast<int>(qy), rows - 2);
  if (r.dx < 0 && i > 0 && qx == i) --i;
  if (r.dy < 0 && j > 0 && qy == j) --j;

  Walk walk;
  walk.originInside = tEnter == 0;
  if (r.dx == 0 && r.dy == 0) {  // vertical: one cell
    const double* h = grid.heights.data() + static_cast<std::ptrdiff_t>(j) * cols + i;
    const Cell cell{i, j, h[0], h[1], h[cols], h[cols + 1]};
    if (std::isinf(tExit)) {  // maxRange = inf: no farther than the cell's lowest corner
      const double lowest = minOf(minOf(cell.h00, cell.h10), minOf(cell.h01, cell.h11));
      tExit = r.dz < 0 ? maxOf(0.0, (r.pz - lowest) / -r.dz) : 0.0;
    }
    return visitCell(walk, r, cell, tEnter, tExit);
  }
  return std::abs(r.dx) >= std::abs(r.dy) ? walkStrips<true>(walk, r, grid, i, j, tEnter, tExit)
                                          : walkStrips<false>(walk, r, grid, i, j, tEnter, tExit);
}

}  // namespace sp
