#pragma once
// A sphere against a HeightGrid's triangulated surface: the contacts of a
// tyre (collided as a sphere of its rolling radius) with a heightfield.
//
// Why not ODE's own sphere-vs-heightfield: it collides the sphere with each
// nearby triangle's plane and keeps a contact only where the plane's contact
// point lies inside that triangle; for a sphere smaller than 1.5 cells it
// runs no vertex or edge pass. Over a ridge (a convex crease between two
// triangles) each plane's point falls inside the other triangle, so the
// sphere touches nothing and sinks: a wheel standing in a gait on a field of
// 3 cm bumps (0.5 m cells) went 11 cm into the ground at 2 ms / 100 and
// 5.7 cm at 1 ms / 60, and the twin was stopped as diverged
// (tests/sim/tst_height_grid_sphere.cpp reproduces the ridge).

#include "sim/height_grid.h"
#include "sim/math.h"

namespace sp {

/// One point where a sphere meets the surface, in the grid frame.
struct SurfaceContact {
  Vec3 position;  ///< the sphere's deepest point, centre - radius * normal [m]
  Vec3 normal;    ///< unit, from the surface towards the sphere's centre
  double depth;   ///< [m], > 0
};

/// The contacts of a sphere (centre `centre`, radius `radius`, grid frame:
/// grid centred on the origin, x along columns, y along rows, heights along
/// z) with the grid's triangles (the two of each cell split by the diagonal
/// (i, j)-(i+1, j+1), the surface HeightGrid::heightAt describes): one for
/// each triangle whose plane's point nearest the centre lies inside it and
/// within the radius (ODE's plane contacts, valleys included), along the
/// plane's normal; and, where an edge or a vertex is nearer the centre than
/// every such face (over a ridge or a peak), one from that nearest point.
/// A centre below a triangle's plane and over the triangle gets the
/// plane's normal. At most `max` contacts, the deepest, ties in the grid's
/// order. Nothing outside the grid's rectangle (there is no ground there).
/// Returns the count written to `out`.
int sphereContacts(const HeightGrid& grid, Vec3 centre, double radius, SurfaceContact* out, int max);

}  // namespace sp
