// Closed-form support points and closest points against the independent Ipopt oracle.
#include "implicit_sim/core/geometry/support.h"

#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "test_models.h"

namespace implicit_sim {
namespace {

using test_models::MakePose;
using test_models::Rot;

std::vector<ConvexShape> Primitives() {
  std::vector<ConvexShape> shapes = {MakeSphere(0.3), MakeEllipsoid(Vec3(0.4, 0.25, 0.15)),
                                     MakeSuperellipsoid(Vec3(0.3, 0.2, 0.25), 4.0), MakeBox(Vec3(0.3, 0.2, 0.1)),
                                     MakeCylinder(0.2, 0.35), MakePrism(7, 0.3, 0.05)};
  shapes[2].X_BS = MakePose(Vec3(0.05, 0.0, -0.02), Rot(0.5, Vec3(1, 1, 0)));  // an offset shape frame too
  return shapes;
}

TEST(Support, ClosedFormSupportPointsMatchTheOracle) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss;
  const Pose X_WB = MakePose(Vec3(0.5, -0.2, 1.0), Rot(0.9, Vec3(1, -1, 2)));
  for (const ConvexShape& shape : Primitives()) {
    SCOPED_TRACE(shape.TypeName());
    for (int trial = 0; trial < 8; ++trial) {
      const Vec3 u = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
      Vec3 p;
      ASSERT_TRUE(SupportPoint(shape, X_WB, u, &p));
      EXPECT_NEAR(u.dot(p), SupportValue(shape, X_WB, u), 1e-7);
    }
  }
}

TEST(Support, ClosedFormClosestPointsMatchTheOracle) {
  const ConvexShape ground = MakeHalfSpace();
  const Pose X_ground = MakePose(Vec3(0, 0, -0.1), Rot(0.2, Vec3(1, 0.5, 0)));
  for (const ConvexShape& shape : Primitives()) {
    SCOPED_TRACE(shape.TypeName());
    const Pose X_WB = MakePose(Vec3(0.1, 0.2, 0.9), Rot(0.7, Vec3(0.3, 1, -0.4)));  // no face parallel to the plane
    for (bool plane_first : {false, true}) {
      ClosestPointsResult closed;
      const ConvexShape& s1 = plane_first ? ground : shape;
      const ConvexShape& s2 = plane_first ? shape : ground;
      const Pose& X1 = plane_first ? X_ground : X_WB;
      const Pose& X2 = plane_first ? X_WB : X_ground;
      ASSERT_TRUE(ClosedFormClosestPoints(s1, X1, s2, X2, &closed));
      const ClosestPointsResult oracle = ComputeClosestPoints(s1, X1, s2, X2);
      ASSERT_TRUE(oracle.solved);
      EXPECT_NEAR(closed.distance, oracle.distance, 1e-7);
      EXPECT_LT((closed.p_W1 - oracle.p_W1).norm(), 1e-5);
      EXPECT_LT((closed.p_W2 - oracle.p_W2).norm(), 1e-5);
    }
  }
  ClosestPointsResult spheres;
  ASSERT_TRUE(ClosedFormClosestPoints(MakeSphere(1.0), MakePose(Vec3(0, 0, 0)), MakeSphere(2.0),
                                      MakePose(Vec3(0, 2.5, 0)), &spheres));
  EXPECT_NEAR(spheres.distance, -0.5, 1e-15);  // signed: overlapping by 0.5 m
  EXPECT_TRUE(spheres.p_W1.isApprox(Vec3(0, 1, 0)));
  EXPECT_TRUE(spheres.p_W2.isApprox(Vec3(0, 0.5, 0)));
}

// A sphere or an ellipsoid and an ellipsoid apart: FindClosestPoints takes the support-function descent (no Ipopt), and its
// distance and points agree with the oracle's; the points lie on the shapes' surfaces and their difference is normal.
TEST(Support, SmoothPairsFindTheOraclesClosestPointsByDescent) {
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss;
  const std::vector<ConvexShape> shapes = Primitives();
  const std::vector<int> smooth = {0, 1};  // sphere, ellipsoid
  int pairs = 0;
  for (int i : smooth) {
    for (int j : smooth) {
      if (i == 0 && j == 0) continue;  // two spheres have a closed form
      SCOPED_TRACE(shapes[i].TypeName() + " / " + shapes[j].TypeName());
      for (int trial = 0; trial < 10; ++trial) {
        const Vec3 axis(gauss(rng), gauss(rng), gauss(rng));
        const Pose X1 = MakePose(0.9 * axis.normalized() + Vec3(0.1, 0.0, 0.2), Rot(gauss(rng), axis));
        const Pose X2 = MakePose(Vec3(0.1, 0.0, 0.2), Rot(gauss(rng), Vec3(gauss(rng), 1.0, gauss(rng))));
        const CrossingDescent d = DescendCrossing(shapes[i], X1, shapes[j], X2,
                                                  -std::numeric_limits<double>::infinity(), 1000);
        ASSERT_TRUE(d.stationary) << "value " << d.value << " trial " << trial;
        const ClosestPointsResult found = FindClosestPoints(shapes[i], X1, shapes[j], X2);
        const ClosestPointsResult oracle = ComputeClosestPoints(shapes[i], X1, shapes[j], X2);
        ASSERT_TRUE(found.solved && oracle.solved);
        ASSERT_GT(oracle.distance, 1e-3);  // apart
        EXPECT_NEAR(found.distance, oracle.distance, 1e-8);
        EXPECT_LT((found.p_W1 - oracle.p_W1).norm(), 1e-5);
        EXPECT_LT((found.p_W2 - oracle.p_W2).norm(), 1e-5);
        EXPECT_NEAR((found.p_W1 - found.p_W2).norm(), found.distance, 1e-12);
        ++pairs;
      }
    }
  }
  EXPECT_EQ(pairs, 30);
}

// The descent's value bounds the penetration depth of overlapping shapes from above (two spheres: exactly).
TEST(Support, CrossingDescentBoundsTheOverlap) {
  const ConvexShape a = MakeSphere(0.3), b = MakeEllipsoid(Vec3(0.4, 0.25, 0.15));
  const CrossingDescent spheres = DescendCrossing(a, MakePose(Vec3(0.5, 0.0, 0.0)), a, Pose::Identity(),
                                                  -std::numeric_limits<double>::infinity(), 1000);
  EXPECT_TRUE(spheres.stationary);
  EXPECT_NEAR(spheres.value, 0.1, 1e-12);  // 0.6 - 0.5 m of overlap
  // An ellipsoid resting 0.01 m deep in a sphere along z: the depth along z is 0.01, no direction does better.
  const CrossingDescent deep = DescendCrossing(a, MakePose(Vec3(0.0, 0.0, 0.44)), b, Pose::Identity(),
                                               -std::numeric_limits<double>::infinity(), 1000);
  EXPECT_TRUE(deep.stationary);
  EXPECT_NEAR(deep.value, 0.01, 1e-9);
  EXPECT_LT((deep.n_W - Vec3::UnitZ()).norm(), 1e-6);
  // Stopping early: once a separation below stop_below is certified.
  const CrossingDescent apart = DescendCrossing(a, MakePose(Vec3(2.0, 0.1, 0.0)), b, Pose::Identity(), -1e-6, 1000);
  EXPECT_LT(apart.value, -1e-6);
}

TEST(Support, NoClosedFormForGeneralIntersections) {
  ConvexShape lens;
  lens.type = ShapeType::kIntersection;
  lens.inequalities = {Inequality::Sphere(1.0), Inequality::HalfSpace(Vec3::UnitZ(), 0.2)};
  Vec3 p;
  EXPECT_FALSE(SupportPoint(lens, Pose::Identity(), Vec3::UnitZ(), &p));
  ClosestPointsResult r;
  EXPECT_FALSE(ClosedFormClosestPoints(lens, Pose::Identity(), MakeSphere(1.0), MakePose(Vec3(3, 0, 0)), &r));
  const ClosestPointsResult found = FindClosestPoints(lens, Pose::Identity(), MakeSphere(1.0), MakePose(Vec3(3, 0, 0)));
  EXPECT_TRUE(found.solved);  // through the oracle
  EXPECT_NEAR(found.distance, 1.0, 1e-7);
}

}  // namespace
}  // namespace implicit_sim
