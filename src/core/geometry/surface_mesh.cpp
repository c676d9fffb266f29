#include "implicit_sim/core/geometry/surface_mesh.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {
namespace {


bool Inside(const ConvexShape& shape, const Vec3& x_S) {
  for (const Inequality& inequality : shape.inequalities) {
    if (inequality.Value(x_S) > 0.0) return false;
  }
  return true;
}

// Distance (m) from the shape-frame origin to the boundary along the unit direction u, by bisection (the shape is
// convex and contains its origin).
double RayToBoundary(const ConvexShape& shape, const Vec3& u, double max_length) {
  double inside = 0.0, outside = max_length;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (inside + outside);
    (Inside(shape, mid * u) ? inside : outside) = mid;
  }
  return inside;
}

SurfaceMesh PlanePatch(double half_size) {
  SurfaceMesh mesh;
  const double s = half_size;
  mesh.vertices = {Vec3(-s, -s, 0.0), Vec3(s, -s, 0.0), Vec3(s, s, 0.0), Vec3(-s, s, 0.0)};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};  // normal +z: the outward normal of z <= 0
  return mesh;
}

}  // namespace

SurfaceMesh MakeSurfaceMesh(const ConvexShape& shape, int resolution, double plane_half_size) {
  if (resolution < 2 || resolution > 512) {
    throw std::invalid_argument("surface mesh resolution must be in [2, 512], got " + std::to_string(resolution));
  }
  if (!(plane_half_size > 0.0 && plane_half_size <= 1e6)) {
    throw std::invalid_argument("surface mesh plane_half_size must be in (0, 1e6] m, got " +
                                FormatNumber(plane_half_size));
  }
  if (shape.type == ShapeType::kHalfSpace) return PlanePatch(plane_half_size);
  SurfaceMesh mesh;
  if (shape.inequalities.empty()) return mesh;
  const int n_lat = resolution, n_lon = 2 * resolution;
  const double max_length = std::isfinite(shape.BoundingRadius()) ? 1.01 * shape.BoundingRadius() : 10.0;
  mesh.vertices.reserve((n_lat + 1) * (n_lon + 1));
  for (int i = 0; i <= n_lat; ++i) {  // vertex (i, j) at index i (n_lon + 1) + j; column n_lon closes the seam
    for (int j = 0; j <= n_lon; ++j) {
      const double theta = kPi * i / n_lat, phi = 2.0 * kPi * j / n_lon;
      const Vec3 u(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      mesh.vertices.push_back(RayToBoundary(shape, u, max_length) * u);
    }
  }
  mesh.triangles.reserve(2 * n_lat * n_lon);
  for (int i = 0; i < n_lat; ++i) {
    for (int j = 0; j < n_lon; ++j) {
      const int a = i * (n_lon + 1) + j, b = a + n_lon + 1, c = b + 1, d = a + 1;
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, d});
    }
  }
  return mesh;
}

}  // namespace implicit_sim
