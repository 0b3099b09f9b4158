#pragma once
// Ray casting against a HeightGrid: the distance along a ray to the first
// point of the grid's triangulated surface, for range sensors. A 181-beam,
// 10 m laser scan costs tens of microseconds; ODE's ray-vs-heightfield geom
// costs from a few microseconds per beam that passes high over the ground to
// milliseconds per beam that hits it.

#include <optional>

#include "sim/height_grid.h"
#include "sim/math.h"

namespace sp {

/// Distance along a ray to the first point where it meets the grid's surface:
/// the two triangles of each cell split by the diagonal (i, j)-(i+1, j+1),
/// exactly the surface HeightGrid::heightAt describes and ODE's heightfield
/// geom collides with (tests/sim/tst_height_grid_ray.cpp compares the two).
///
/// - `origin` [m] and `direction` are in the grid frame: grid centred on the
///   origin, x along columns, y along rows, heights along z.
/// - `direction` must be a unit vector; the result is the ray parameter t of
///   the hit point origin + t*direction, a distance in metres only then.
/// - `maxRange` [m]: hits farther than this are not reported; a hit exactly
///   at maxRange is. May be +infinity.
///
/// Returns nullopt when the ray meets no surface within maxRange, including
/// when it leaves the grid's width x depth rectangle first (the surface ends
/// at the rectangle; there are no side walls), and for invalid input: a grid
/// with fewer than 2x2 samples or a heights vector of the wrong size, a zero
/// or non-finite direction, a non-finite origin, a negative or NaN maxRange.
///
/// Rays from below: a ray whose origin lies inside the rectangle on or below
/// the surface reports 0 (the origin is already in the ground), whatever its
/// direction. A ray whose origin lies outside the rectangle and that enters
/// it below the surface reports where it first comes up through the surface,
/// as ODE does (ODE's ray-vs-triangle test is two-sided).
///
/// The surface is watertight: a ray through a shared edge, a shared vertex or
/// along a cell diagonal hits (the walk carries which side of the surface the
/// ray is on from cell to cell, so rounding at a boundary cannot open a gap).
/// ODE's own ray test is not: it misses some rays that run exactly along a
/// grid line or through a vertex.
///
/// Cost: proportional to the number of cells the ray's xy projection crosses
/// (a 2-D DDA stepped along the ray's faster axis, one or two cells a step),
/// most of them rejected by comparing the ray's height range over them with
/// the sample heights around them; only cells the ray comes near have their
/// triangles tested. No allocation; about 0.2-0.3 us per 10 m beam on 0.25 m
/// cells (bench/bench_height_grid_ray.cpp).
///
/// Thread-safety: a pure function; it only reads `grid`. Any number of threads
/// may call it at once on the same grid as long as none writes that grid.
std::optional<double> intersectRay(const HeightGrid& grid, Vec3 origin, Vec3 direction, double maxRange);

}  // namespace sp
