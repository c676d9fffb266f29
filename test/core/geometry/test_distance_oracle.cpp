// Distance oracle against closed forms: closest points (paper eq. 7), support values and penetration bounds.
#include "implicit_sim/core/geometry/distance_oracle.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include <gtest/gtest.h>

#include "test_models.h"

namespace implicit_sim {
namespace {

constexpr double kTol = 1e-7;

using test_models::MakePose;
using test_models::Rot;

void ExpectNear(const Vec3& a, const Vec3& b, double tol) {
  EXPECT_LT((a - b).norm(), tol) << "got " << a.transpose() << ", expected " << b.transpose();
}

TEST(DistanceOracle, SphereAboveGround) {
  const ClosestPointsResult r = ComputeClosestPoints(MakeSphere(1.0), MakePose(Vec3(0, 0, 2)), MakeHalfSpace(),
                                                     Pose::Identity());
  ASSERT_TRUE(r.solved);
  EXPECT_NEAR(r.distance, 1.0, kTol);
  ExpectNear(r.p_W1, Vec3(0, 0, 1), kTol);
  ExpectNear(r.p_W2, Vec3(0, 0, 0), kTol);
}

TEST(DistanceOracle, GroundFirstTiltedGround) {
  // Ground tilted by 20 deg about x, sphere centre 3 m along its normal from a point on it: distance 2.
  const Mat3 R = Rot(20.0 * kPi / 180.0, Vec3::UnitX());
  const Vec3 n_W = R * Vec3::UnitZ(), q_W(0.5, -1.0, 0.2);
  const ClosestPointsResult r =
      ComputeClosestPoints(MakeHalfSpace(), MakePose(q_W, R), MakeSphere(1.0), MakePose(q_W + 3.0 * n_W));
  ASSERT_TRUE(r.solved);
  EXPECT_NEAR(r.distance, 2.0, kTol);
  ExpectNear(r.p_W1, q_W, kTol);
  ExpectNear(r.p_W2, q_W + 2.0 * n_W, kTol);
}

TEST(DistanceOracle, TwoSpheresRotatedBodyAndShapeOffset) {
  // Body 2 is rotated arbitrarily and its sphere sits at an offset X_BS in the body, centred at (5, 0, 0) in W.
  ConvexShape sphere2 = MakeSphere(2.0);
  sphere2.X_BS = MakePose(Vec3(0.3, -0.2, 0.1), Rot(0.7, Vec3(1, 2, 3)));
  const Mat3 R_WB2 = Rot(1.1, Vec3(-2, 1, 0.5));
  const Pose X_WB2 = MakePose(Vec3(5, 0, 0) - R_WB2 * sphere2.X_BS.translation(), R_WB2);
  ASSERT_LT(((X_WB2 * sphere2.X_BS).translation() - Vec3(5, 0, 0)).norm(), 1e-12);

  const ClosestPointsResult r = ComputeClosestPoints(MakeSphere(1.0), Pose::Identity(), sphere2, X_WB2);
  ASSERT_TRUE(r.solved);
  EXPECT_NEAR(r.distance, 2.0, kTol);
  ExpectNear(r.p_W1, Vec3(1, 0, 0), kTol);
  ExpectNear(r.p_W2, Vec3(3, 0, 0), kTol);
}

TEST(DistanceOracle, SphereVersusRotatedBox) {
  const Vec3 half(1, 2, 3);
  const Pose X_WB = MakePose(Vec3(0.5, -1.0, 2.0), Rot(kPi / 6.0, Vec3::UnitZ()));
  const double radius = 0.5;
  // Centres near a face, an edge and a corner of the box (in box coordinates).
  for (const Vec3& c_B : {Vec3(2.5, 0.3, -1.0), Vec3(2.0, 3.0, 0.5), Vec3(-2.2, 3.1, 4.0)}) {
    const Vec3 c_W = X_WB * c_B;
    const Vec3 clamped_B = c_B.cwiseMax(-half).cwiseMin(half);
    const Vec3 box_W = X_WB * clamped_B;
    const double expected = (c_W - box_W).norm() - radius;
    const Vec3 sphere_W = c_W + radius * (box_W - c_W).normalized();

    const ClosestPointsResult r = ComputeClosestPoints(MakeSphere(radius), MakePose(c_W), MakeBox(half), X_WB);
    ASSERT_TRUE(r.solved) << c_B.transpose();
    EXPECT_NEAR(r.distance, expected, kTol) << c_B.transpose();
    ExpectNear(r.p_W1, sphere_W, 1e-6);
    ExpectNear(r.p_W2, box_W, 1e-6);
  }
}

TEST(DistanceOracle, EllipsoidOnGround) {
  const ConvexShape ellipsoid = MakeEllipsoid(Vec3(3, 2, 1));
  // Rotated 90 deg about x: the 2 m semi-axis is vertical, the bottom at 1.5 - 2 = -0.5: overlapping, distance 0.
  const ClosestPointsResult overlap = ComputeClosestPoints(
      ellipsoid, MakePose(Vec3(0, 0, 1.5), Rot(kPi / 2.0, Vec3::UnitX())), MakeHalfSpace(), Pose::Identity());
  ASSERT_TRUE(overlap.solved);
  EXPECT_LT(overlap.distance, 1e-6);

  // Upright at z = 2: the 1 m semi-axis is vertical, distance 1.
  const ClosestPointsResult above =
      ComputeClosestPoints(ellipsoid, MakePose(Vec3(0, 0, 2)), MakeHalfSpace(), Pose::Identity());
  ASSERT_TRUE(above.solved);
  EXPECT_NEAR(above.distance, 1.0, kTol);
  ExpectNear(above.p_W1, Vec3(0, 0, 1), 1e-6);
  EXPECT_NEAR(above.p_W2.z(), 0.0, kTol);
}

TEST(DistanceOracle, TouchingSpheres) {
  const Vec3 dir = Vec3(1, -2, 0.5).normalized();
  const ClosestPointsResult r =
      ComputeClosestPoints(MakeSphere(1.0), MakePose(Vec3(1, 1, 1)), MakeSphere(0.5), MakePose(Vec3(1, 1, 1) + 1.5 * dir));
  ASSERT_TRUE(r.solved);
  EXPECT_LT(r.distance, 1e-6);
  ExpectNear(r.p_W1, Vec3(1, 1, 1) + dir, 1e-5);
}

TEST(DistanceOracle, SupportSphere) {
  const Vec3 c(1, -2, 3), u = Vec3(1, 1, -2).normalized();
  EXPECT_NEAR(SupportValue(MakeSphere(0.7), MakePose(c, Rot(0.4, Vec3(1, 0, 1))), u), c.dot(u) + 0.7, kTol);
}

TEST(DistanceOracle, SupportRotatedBox) {
  const Vec3 half(1, 2, 3), c(0.5, 0.2, -1.0);
  const Mat3 R = Rot(0.9, Vec3(1, 2, -1));
  for (const Vec3& u : {Vec3(1, 0, 0), Vec3(0.3, -0.5, 0.8).normalized(), Vec3(-1, -1, 1).normalized()}) {
    // max over vertices: u.c + sum_i a_i |(R^T u)_i|
    const double expected = u.dot(c) + half.dot((R.transpose() * u).cwiseAbs());
    EXPECT_NEAR(SupportValue(MakeBox(half), MakePose(c, R), u), expected, kTol) << u.transpose();
  }
}

TEST(DistanceOracle, SupportCylinder) {
  const double radius = 0.4, half_length = 1.5;
  const Vec3 c(-1, 2, 0.5);
  const Mat3 R = Rot(0.6, Vec3(0, 1, 1));
  const Vec3 axis = R * Vec3::UnitZ();
  for (const Vec3& u : {Vec3(0, 0, 1), Vec3(1, 0.2, -0.3).normalized(), axis, Vec3(axis.y(), -axis.x(), 0).normalized()}) {
    const double a = u.dot(axis);
    const double expected = u.dot(c) + radius * std::sqrt(std::max(0.0, 1.0 - a * a)) + half_length * std::abs(a);
    EXPECT_NEAR(SupportValue(MakeCylinder(radius, half_length), MakePose(c, R), u), expected, kTol) << u.transpose();
  }
}

TEST(DistanceOracle, SupportPrism) {
  const ConvexShape prism = MakePrism(10, 1.0, 0.1);
  EXPECT_NEAR(SupportValue(prism, Pose::Identity(), Vec3::UnitX()), 1.0, kTol);  // a vertex on +x
  const Vec3 face(std::cos(kPi / 10.0), std::sin(kPi / 10.0), 0.0);
  EXPECT_NEAR(SupportValue(prism, Pose::Identity(), face), std::cos(kPi / 10.0), kTol);  // apothem
  EXPECT_NEAR(SupportValue(prism, Pose::Identity(), Vec3::UnitZ()), 0.1, kTol);
}

TEST(DistanceOracle, SupportHalfSpace) {
  const ConvexShape ground = MakeHalfSpace();
  EXPECT_NEAR(SupportValue(ground, Pose::Identity(), Vec3::UnitZ()), 0.0, 1e-12);
  EXPECT_NEAR(SupportValue(ground, MakePose(Vec3(3, 4, -0.25)), Vec3::UnitZ()), -0.25, 1e-12);
  EXPECT_TRUE(std::isinf(SupportValue(ground, Pose::Identity(), Vec3(0.01, 0, 1).normalized())));
  EXPECT_TRUE(std::isinf(SupportValue(ground, Pose::Identity(), -Vec3::UnitZ())));
  // Tilted plane through (0, 0, 1): the support along its normal is n . (0, 0, 1).
  const Mat3 R = Rot(0.3, Vec3::UnitY());
  EXPECT_NEAR(SupportValue(ground, MakePose(Vec3(0, 0, 1), R), R * Vec3::UnitZ()), (R * Vec3::UnitZ()).z(), 1e-12);
}

TEST(DistanceOracle, SupportUnboundedIntersectionIsClipped) {
  // An uncapped infinite cylinder along z: clipped by the 1e4 m box around its origin.
  ConvexShape tube;
  tube.inequalities = {Inequality::InfiniteCylinder(0.5)};
  EXPECT_NEAR(SupportValue(tube, Pose::Identity(), Vec3::UnitX()), 0.5, kTol);
  EXPECT_NEAR(SupportValue(tube, Pose::Identity(), Vec3::UnitZ()), 1e4, 1e-4);
}

TEST(DistanceOracle, PenetrationBoundSphereOnGround) {
  const ConvexShape sphere = MakeSphere(1.0), ground = MakeHalfSpace();
  EXPECT_LT(PenetrationBound(sphere, MakePose(Vec3(0, 0, 1)), ground, Pose::Identity(), Vec3::Zero(), Vec3::UnitZ()),
            1e-8);
  EXPECT_NEAR(PenetrationBound(sphere, MakePose(Vec3(0, 0, 0.9)), ground, Pose::Identity(), Vec3::Zero(),
                               Vec3::UnitZ()),
              0.1, kTol);
  // A non-unit normal is normalised.
  EXPECT_NEAR(PenetrationBound(sphere, MakePose(Vec3(0, 0, 0.9)), ground, Pose::Identity(), Vec3::Zero(),
                               3.0 * Vec3::UnitZ()),
              0.1, kTol);
  // A normal that is not the ground's cannot certify anything: +inf.
  EXPECT_TRUE(std::isinf(PenetrationBound(sphere, MakePose(Vec3(0, 0, 0.9)), ground, Pose::Identity(), Vec3::Zero(),
                                          Vec3(0.1, 0, 1))));
}

TEST(DistanceOracle, PenetrationBoundTwoSpheres) {
  // Body 2 at the origin, body 1 at x = 1.95 (overlap [0.95, 1]); plane at the midpoint, normal from 2 towards 1.
  const ConvexShape sphere = MakeSphere(1.0);
  EXPECT_NEAR(PenetrationBound(sphere, MakePose(Vec3(1.95, 0, 0)), sphere, Pose::Identity(), Vec3(0.975, 0, 0),
                               Vec3::UnitX()),
              0.05, kTol);
}

TEST(DistanceOracle, NeverCrashesOnDegenerateInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const ClosestPointsResult r =
      ComputeClosestPoints(MakeSphere(1.0), MakePose(Vec3(nan, 0, 0)), MakeHalfSpace(), Pose::Identity());
  EXPECT_FALSE(r.solved);
  EXPECT_FALSE(ComputeClosestPoints(ConvexShape(), Pose::Identity(), MakeSphere(1.0), Pose::Identity()).solved);
  EXPECT_TRUE(std::isinf(SupportValue(MakeSphere(1.0), MakePose(Vec3(nan, 0, 0)), Vec3::UnitX())));
}

TEST(DistanceOracle, SphereGroundHeightSweep) {
  for (int i = 0; i < 50; ++i) {
    const double height = 1.0 + 0.02 * i;  // from touching to 0.98 m above the ground
    const ClosestPointsResult r =
        ComputeClosestPoints(MakeSphere(1.0), MakePose(Vec3(0.3, -0.1, height)), MakeHalfSpace(), Pose::Identity());
    ASSERT_TRUE(r.solved);
    // Minimizing the squared distance makes the distance accurate to about sqrt(tolerance) ~ 1e-6 m at contact.
    EXPECT_NEAR(r.distance, height - 1.0, i == 0 ? 2e-6 : kTol) << "height " << height;
  }
}

}  // namespace
}  // namespace implicit_sim
