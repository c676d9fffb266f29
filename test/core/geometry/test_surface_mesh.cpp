// MakeSurfaceMesh: every vertex lies on the shape's boundary (its largest inequality is 0 to the bisection's
// precision), triangles face outwards, the mesh closes (its volume approaches the shape's), and bad arguments are
// refused.
#include "implicit_sim/core/geometry/surface_mesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace implicit_sim {
namespace {

double LargestInequality(const ConvexShape& shape, const Vec3& x_S) {
  double largest = -INFINITY;
  for (const Inequality& inequality : shape.inequalities) largest = std::max(largest, inequality.Value(x_S));
  return largest;
}

// Signed volume of the closed mesh (divergence theorem): positive when triangles face outwards.
double Volume(const SurfaceMesh& mesh) {
  double six_volume = 0.0;
  for (const auto& t : mesh.triangles) {
    six_volume += mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]]));
  }
  return six_volume / 6.0;
}

TEST(SurfaceMesh, VerticesLieOnTheBoundaryAndTheVolumeConverges) {
  const ConvexShape shapes[] = {MakeSphere(0.3), MakeEllipsoid(Vec3(0.3, 0.2, 0.1)), MakeBox(Vec3(0.1, 0.2, 0.3)),
                                MakeSuperellipsoid(Vec3(0.1, 0.1, 0.2), 6.0), MakeCylinder(0.2, 0.4)};
  for (const ConvexShape& shape : shapes) {
    const SurfaceMesh mesh = MakeSurfaceMesh(shape, 64);
    ASSERT_EQ(mesh.vertices.size(), 65u * 129u);
    ASSERT_EQ(mesh.triangles.size(), 2u * 64u * 128u);
    for (const Vec3& p : mesh.vertices) {
      EXPECT_NEAR(LargestInequality(shape, p), 0.0, 1e-9) << shape.TypeName();
    }
    double volume = 0.0;
    Mat3 inertia;
    shape.UnitDensityMassProperties(&volume, &inertia);
    EXPECT_NEAR(Volume(mesh) / volume, 1.0, 0.02) << shape.TypeName();  // inscribed: slightly smaller
    EXPECT_LT(Volume(mesh), volume) << shape.TypeName();
  }
}

TEST(SurfaceMesh, AHalfSpaceIsASquareInItsPlaneFacingOutwards) {
  const SurfaceMesh mesh = MakeSurfaceMesh(MakeHalfSpace(), 8, 2.5);
  ASSERT_EQ(mesh.vertices.size(), 4u);
  for (const Vec3& p : mesh.vertices) {
    EXPECT_EQ(p.z(), 0.0);
    EXPECT_EQ(p.head<2>().cwiseAbs().maxCoeff(), 2.5);
  }
  for (const auto& t : mesh.triangles) {
    const Vec3 normal = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    EXPECT_GT(normal.z(), 0.0);  // the outward normal of z <= 0
  }
}

TEST(SurfaceMesh, RefusesAResolutionOrPlaneSizeOutOfRange) {
  EXPECT_THROW(MakeSurfaceMesh(MakeSphere(1.0), 1), std::invalid_argument);
  EXPECT_THROW(MakeSurfaceMesh(MakeSphere(1.0), 513), std::invalid_argument);
  EXPECT_THROW(MakeSurfaceMesh(MakeHalfSpace(), 8, 0.0), std::invalid_argument);
  try {
    MakeSurfaceMesh(MakeSphere(1.0), 1);
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "surface mesh resolution must be in [2, 512], got 1");
  }
}

}  // namespace
}  // namespace implicit_sim
