// Shapes: every inequality's gradient and Hessian against finite differences, and the closed-form volumes and
// inertias against exact identities and a numerical integration of the shape's indicator.
#include "implicit_sim/core/geometry/shapes.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace implicit_sim {
namespace {


Pose SomePose() {
  Pose X = Pose::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  X.translation() = Vec3(0.1, -0.3, 0.2);
  return X;
}

void ExpectDerivativesMatchFiniteDifferences(Inequality q) {
  q.X_SP = SomePose();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 x(u(rng), u(rng), u(rng));
    double f;
    Vec3 g;
    Mat3 H;
    q.Evaluate(x, &f, &g, &H);
    EXPECT_NEAR(f, q.Value(x), 1e-12 * std::max(1.0, std::abs(f)));
    const double eps = 1e-6;
    for (int i = 0; i < 3; ++i) {
      const Vec3 e = eps * Vec3::Unit(i);
      const double dfdx = (q.Value(x + e) - q.Value(x - e)) / (2 * eps);
      EXPECT_NEAR(g[i], dfdx, 1e-6 * std::max(1.0, std::abs(dfdx))) << "gradient " << i << " at " << x.transpose();
      double fp, fm;
      Vec3 gp, gm;
      q.Evaluate(x + e, &fp, &gp, nullptr);
      q.Evaluate(x - e, &fm, &gm, nullptr);
      const Vec3 column = (gp - gm) / (2 * eps);
      EXPECT_LT((H.col(i) - column).norm(), 1e-5 * std::max(1.0, column.norm())) << "Hessian column " << i;
    }
  }
}

TEST(Inequality, HalfSpaceDerivatives) { ExpectDerivativesMatchFiniteDifferences(Inequality::HalfSpace(Vec3(1, 2, 2), 0.3)); }
TEST(Inequality, SphereDerivatives) { ExpectDerivativesMatchFiniteDifferences(Inequality::Sphere(0.8)); }
TEST(Inequality, EllipsoidDerivatives) {
  ExpectDerivativesMatchFiniteDifferences(Inequality::Ellipsoid(Vec3(0.9, 0.5, 0.3)));
}
TEST(Inequality, SuperellipsoidDerivatives) {
  for (double p : {2.0, 2.5, 4.0, 10.0}) {
    SCOPED_TRACE(p);
    ExpectDerivativesMatchFiniteDifferences(Inequality::Superellipsoid(Vec3(0.9, 0.5, 0.3), p));
  }
}
TEST(Inequality, InfiniteCylinderDerivatives) { ExpectDerivativesMatchFiniteDifferences(Inequality::InfiniteCylinder(0.4)); }

TEST(Inequality, ScaledSoThatTheGradientIsUnitOnASphereSurface) {
  const Inequality q = Inequality::Sphere(2.0);
  double f;
  Vec3 g;
  q.Evaluate(Vec3(0, 2, 0), &f, &g, nullptr);
  EXPECT_NEAR(f, 0.0, 1e-15);
  EXPECT_NEAR(g.norm(), 1.0, 1e-15);
  EXPECT_NEAR(q.Value(Vec3(0, 2.001, 0)), 0.001, 1e-6);  // about the signed distance near the surface
}

bool Inside(const ConvexShape& s, const Vec3& x) {
  for (const Inequality& q : s.inequalities) {
    if (q.Value(x) > 0.0) return false;
  }
  return true;
}

// Midpoint-rule integration of the indicator over a grid of the bounding box.
void IntegrateNumerically(const ConvexShape& s, const Vec3& half_box, int n, double* volume, Mat3* inertia) {
  const Vec3 cell = 2.0 * half_box / n;
  const double dV = cell.prod();
  *volume = 0.0;
  inertia->setZero();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) {
        const Vec3 x = -half_box + cell.cwiseProduct(Vec3(i + 0.5, j + 0.5, k + 0.5));
        if (!Inside(s, x)) continue;
        *volume += dV;
        *inertia += dV * (x.squaredNorm() * Mat3::Identity() - x * x.transpose());
      }
    }
  }
}

void ExpectMassPropertiesMatchIntegration(const ConvexShape& s, const Vec3& half_box) {
  double V, V_num;
  Mat3 I, I_num;
  s.UnitDensityMassProperties(&V, &I);
  IntegrateNumerically(s, half_box, 90, &V_num, &I_num);
  EXPECT_NEAR(V, V_num, 0.01 * V) << s.TypeName();
  EXPECT_LT((I - I_num).norm(), 0.02 * I.norm()) << s.TypeName() << "\n" << I << "\nnumerical\n" << I_num;
}

TEST(MassProperties, ClosedFormsOfTheScenarios) {
  double V;
  Mat3 I;
  MakeSphere(1.0).UnitDensityMassProperties(&V, &I);
  EXPECT_NEAR(I(0, 0) / V, 0.4, 1e-14);                     // solid sphere: 0.4 m r^2
  MakeCylinder(1.0, 0.05).UnitDensityMassProperties(&V, &I);
  EXPECT_NEAR(I(2, 2) / V, 0.5, 1e-14);                     // disc about its axis: 0.5 m r^2
  MakeEllipsoid(Vec3(0.06, 0.05, 0.04)).UnitDensityMassProperties(&V, &I);
  EXPECT_NEAR(I(0, 0) / V, (0.05 * 0.05 + 0.04 * 0.04) / 5.0, 1e-14);  // m (b^2 + c^2) / 5
  EXPECT_NEAR(V, 4.0 / 3.0 * kPi * 0.06 * 0.05 * 0.04, 1e-16);
}

TEST(MassProperties, PrimitivesAgreeWhereTheyCoincide) {
  double V1, V2;
  Mat3 I1, I2;
  // A superellipsoid with exponent 2 is the ellipsoid (different code paths: Gamma functions vs the closed form).
  MakeSuperellipsoid(Vec3(0.3, 0.2, 0.1), 2.0).UnitDensityMassProperties(&V1, &I1);
  MakeEllipsoid(Vec3(0.3, 0.2, 0.1)).UnitDensityMassProperties(&V2, &I2);
  EXPECT_NEAR(V1, V2, 1e-12);
  EXPECT_LT((I1 - I2).norm(), 1e-12);
  // A square prism (N = 4, circumradius R, rotated 45 deg about z) is a box of half side R / sqrt(2).
  MakePrism(4, 1.0, 0.3).UnitDensityMassProperties(&V1, &I1);
  MakeBox(Vec3(std::sqrt(0.5), std::sqrt(0.5), 0.3)).UnitDensityMassProperties(&V2, &I2);
  EXPECT_NEAR(V1, V2, 1e-12);
  EXPECT_LT((I1 - I2).norm(), 1e-12);
  // A 1000-gon prism is nearly the cylinder.
  MakePrism(1000, 1.0, 0.3).UnitDensityMassProperties(&V1, &I1);
  MakeCylinder(1.0, 0.3).UnitDensityMassProperties(&V2, &I2);
  EXPECT_NEAR(V1 / V2, 1.0, 1e-4);
  EXPECT_LT((I1 - I2).norm() / I2.norm(), 1e-4);
}

TEST(MassProperties, ClosedFormsMatchNumericalIntegration) {
  ExpectMassPropertiesMatchIntegration(MakeSuperellipsoid(Vec3(0.3, 0.2, 0.15), 4.0), Vec3(0.3, 0.2, 0.15));
  ExpectMassPropertiesMatchIntegration(MakePrism(6, 0.25, 0.1), Vec3(0.25, 0.25, 0.1));
  ExpectMassPropertiesMatchIntegration(MakeCylinder(0.2, 0.3), Vec3(0.2, 0.2, 0.3));
  ExpectMassPropertiesMatchIntegration(MakeBox(Vec3(0.3, 0.2, 0.1)), Vec3(0.3, 0.2, 0.1));
}

TEST(MassProperties, RefusesShapesWithoutAClosedForm) {
  double V;
  Mat3 I;
  EXPECT_THROW(MakeHalfSpace().UnitDensityMassProperties(&V, &I), std::invalid_argument);
}

TEST(Shapes, PrismHasAVertexOnPlusXAndItsApothemOnTheFaceNormals) {
  const ConvexShape prism = MakePrism(10, 1.0, 0.05);
  EXPECT_EQ(prism.inequalities.size(), 12u);
  EXPECT_TRUE(Inside(prism, Vec3(1.0 - 1e-9, 0, 0)));
  EXPECT_FALSE(Inside(prism, Vec3(1.0 + 1e-9, 0, 0)));
  const double apothem = std::cos(kPi / 10);
  const Vec3 face_normal(std::cos(kPi / 10), std::sin(kPi / 10), 0);
  EXPECT_TRUE(Inside(prism, (apothem - 1e-9) * face_normal));
  EXPECT_FALSE(Inside(prism, (apothem + 1e-9) * face_normal));
}

}  // namespace
}  // namespace implicit_sim
