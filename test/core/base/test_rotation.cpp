// SO(3) helpers: ExpSO3 is a rotation and matches Eigen::AngleAxis (also on its small-angle branch), LeftJacobianSO3
// matches finite differences of Log(Exp(phi + d) Exp(phi)^-1) (also on its series branch), Skew(a) b = a x b.
#include "implicit_sim/core/base/rotation.h"

#include <vector>

#include <gtest/gtest.h>

namespace implicit_sim {
namespace {

// Rotation vectors: large, moderate, near pi, and on both sides of the series thresholds (1e-6 and 1e-12).
const std::vector<Vec3> kAngles = {Vec3(0.3, -1.2, 0.7), Vec3(2.0, 1.0, -0.5), Vec3(0.0, 0.0, 3.1),
                                   Vec3(1e-3, 2e-3, -1e-3), Vec3(3e-7, -4e-7, 0.0), Vec3(2e-6, 0.0, 0.0),
                                   Vec3(5e-13, 0.0, -2e-13), Vec3::Zero()};

// Log of a rotation, accurate for small angles (through the quaternion).
Vec3 LogSO3(const Mat3& R) {
  const Eigen::AngleAxisd aa{Eigen::Quaterniond(R)};
  return aa.angle() * aa.axis();
}

double MaxAbs(const Mat3& M) { return M.cwiseAbs().maxCoeff(); }

TEST(RotationSo3, ExpIsARotation) {
  for (const Vec3& phi : kAngles) {
    const Mat3 R = ExpSO3(phi);
    EXPECT_LT(MaxAbs(R.transpose() * R - Mat3::Identity()), 1e-15) << phi.transpose();
    EXPECT_NEAR(R.determinant(), 1.0, 1e-15) << phi.transpose();
  }
}

TEST(RotationSo3, ExpMatchesAngleAxis) {
  for (const Vec3& phi : kAngles) {
    const double angle = phi.norm();
    const Mat3 expected = angle > 0 ? Mat3(Eigen::AngleAxisd(angle, phi / angle)) : Mat3::Identity();
    EXPECT_LT(MaxAbs(ExpSO3(phi) - expected), 1e-15) << phi.transpose();
    EXPECT_LT((ExpSO3(phi) * Vec3(1, 2, 3) - expected * Vec3(1, 2, 3)).norm(), 1e-14);
  }
  // A quarter turn about z takes x to y.
  EXPECT_LT((ExpSO3(Vec3(0, 0, M_PI / 2)) * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-15);
}

TEST(RotationSo3, ExpOfTheOppositeVectorIsTheInverse) {
  for (const Vec3& phi : kAngles) {
    EXPECT_LT(MaxAbs(ExpSO3(-phi) * ExpSO3(phi) - Mat3::Identity()), 1e-15) << phi.transpose();
  }
}

// Column k of J_l(phi) by central differences: Log(Exp(phi +- h e_k) Exp(phi)^T) / (2 h).
Mat3 LeftJacobianByDifferences(const Vec3& phi, double h) {
  const Mat3 R_inverse = ExpSO3(phi).transpose();
  Mat3 J;
  for (int k = 0; k < 3; ++k) {
    const Vec3 d = h * Vec3::Unit(k);
    J.col(k) = (LogSO3(ExpSO3(phi + d) * R_inverse) - LogSO3(ExpSO3(phi - d) * R_inverse)) / (2 * h);
  }
  return J;
}

TEST(RotationSo3, LeftJacobianMatchesFiniteDifferences) {
  for (const Vec3& phi : kAngles) {
    SCOPED_TRACE(::testing::Message() << "phi " << phi.transpose());
    EXPECT_LT(MaxAbs(LeftJacobianSO3(phi) - LeftJacobianByDifferences(phi, 1e-5)), 1e-9);
  }
}

TEST(RotationSo3, LeftJacobianSeriesBranchKeepsItsFirstOrderTerm) {
  // |phi| = 5e-7 < 1e-6: J_l = I + S/2 + O(|phi|^2); the S/2 part (2.5e-7) is well above the difference error.
  const Vec3 phi(3e-7, -4e-7, 0.0);
  const Mat3 J = LeftJacobianSO3(phi);
  EXPECT_LT(MaxAbs(J - LeftJacobianByDifferences(phi, 1e-4)), 1e-11);
  EXPECT_LT(MaxAbs(J - Mat3::Identity() - 0.5 * Skew(phi)), 1e-13);
  EXPECT_GT(MaxAbs(J - Mat3::Identity()), 1e-7);
  EXPECT_EQ(LeftJacobianSO3(Vec3::Zero()), Mat3::Identity());
}

TEST(RotationSo3, LeftJacobianIsContinuousAcrossItsSeriesThreshold) {
  const Vec3 axis = Vec3(1, -2, 2) / 3.0;
  const Mat3 below = LeftJacobianSO3(0.999e-6 * axis);  // series
  const Mat3 above = LeftJacobianSO3(1.001e-6 * axis);  // closed form
  EXPECT_LT(MaxAbs(below - above), 1e-9);
}

TEST(RotationSo3, LeftJacobianMapsTheAngularRateOfTheExponential) {
  // J_l(phi) phi = phi: moving along the axis only changes the angle.
  for (const Vec3& phi : kAngles) EXPECT_LT((LeftJacobianSO3(phi) * phi - phi).norm(), 1e-15) << phi.transpose();
}

TEST(RotationSo3, SkewIsTheCrossProduct) {
  const std::vector<Vec3> vectors = {Vec3(1, 2, 3), Vec3(-0.5, 4, 0.25), Vec3::UnitZ(), Vec3::Zero()};
  for (const Vec3& a : vectors) {
    EXPECT_EQ(Skew(a).transpose(), -Skew(a));
    for (const Vec3& b : vectors) EXPECT_EQ(Skew(a) * b, a.cross(b)) << a.transpose() << " x " << b.transpose();
  }
}

}  // namespace
}  // namespace implicit_sim
