// A triangle mesh of a shape's boundary, for drawing (rviz markers, the Python renderer): never used by the stepper.
#pragma once

#include <array>
#include <vector>

#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {

struct SurfaceMesh {
  std::vector<Vec3> vertices;                // in the shape frame S (m)
  std::vector<std::array<int, 3>> triangles;  // vertex indices, counter-clockwise seen from outside
};

// Bounded shapes: rays from the shape-frame origin (inside every shape the loader makes) on a latitude-longitude grid
// of `resolution` latitudes and 2 * resolution longitudes, each ending on the boundary (bisection to 2^-40 of the
// bounding radius). A half-space: the square of half size `plane_half_size` (m) in its plane z = 0. Unbounded
// intersections other than a half-space are cut at 10 m. Throws std::invalid_argument for resolution outside
// [2, 512] or plane_half_size outside (0, 1e6] m.
SurfaceMesh MakeSurfaceMesh(const ConvexShape& shape, int resolution, double plane_half_size = 1.0);

}  // namespace implicit_sim
