// The contact kinematics the step shares between its rows, seeds and results (src/core/step/contact_frame.h), and the
// plane-crossing bound shared by the distance oracle and the cold-start overlap check: each against a closed form or
// finite differences.
#include <cmath>

#include <gtest/gtest.h>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/geometry/support.h"
#include "step/contact_frame.h"

namespace implicit_sim {
namespace {

TEST(ContactFrame, RelativeVelocityIsTheRateOfTheGapBetweenMaterialPoints) {
  const Vec3 v1(0.3, -0.2, 0.1), w1(1.0, 2.0, -0.5), r1(0.1, 0.05, -0.2);
  const Vec3 v2(-0.1, 0.4, 0.0), w2(-0.3, 0.2, 0.9), r2(-0.2, 0.1, 0.3);
  // Material points c + Exp(t w) r of two bodies whose centres c move with v: central differences of their gap.
  const auto gap = [&](double t) {
    const Vec3 x1 = t * v1 + ExpSO3(t * w1) * r1, x2 = t * v2 + ExpSO3(t * w2) * r2;
    return Vec3(x1 - x2);
  };
  const double dt = 1e-6;
  const Vec3 rate = (gap(dt) - gap(-dt)) / (2.0 * dt);
  EXPECT_LT((RelativeVelocity(v1, w1, r1, v2, w2, r2) - rate).norm(), 1e-9);
}

TEST(ContactFrame, EndOfStepPoseIsTheKinematicMapOfPaperEq2) {
  const Vec3 p0(1.0, 2.0, 3.0), v(0.5, -1.0, 2.0), w(0.0, 0.0, 3.0);
  const Mat3 R0 = Eigen::AngleAxisd(0.4, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  Vec3 p;
  Mat3 R;
  EndOfStepPose(p0, R0, v, w, 0.1, &p, &R);
  EXPECT_LT((p - Vec3(1.05, 1.9, 3.2)).norm(), 1e-15);
  const Mat3 expected = Eigen::AngleAxisd(0.3, Vec3::UnitZ()).toRotationMatrix() * R0;  // a turn of h |w| about z
  EXPECT_LT((R - expected).norm(), 1e-15);
}

TEST(ContactFrame, TangentBasisIsRightHandedOrthonormalWithExactDerivatives) {
  const Vec3 n = Vec3(0.2, -0.3, 0.9).normalized(), e = Vec3::UnitX();
  Vec3 t, o;
  Mat3 dt_dn, do_dn;
  TangentBasis(n, e, &t, &o, &dt_dn, &do_dn);
  EXPECT_NEAR(t.norm(), 1.0, 1e-15);
  EXPECT_NEAR(t.dot(n), 0.0, 1e-15);
  EXPECT_LT((o - n.cross(t)).norm(), 1e-15);
  EXPECT_EQ(LeastAlignedAxis(n), Vec3::UnitX());
  const double d = 1e-6;
  for (int j = 0; j < 3; ++j) {  // n is an unknown of the step: its derivative is taken off the unit sphere too
    Vec3 tp, op, tm, om;
    Mat3 unused1, unused2;
    TangentBasis(n + d * Vec3::Unit(j), e, &tp, &op, &unused1, &unused2);
    TangentBasis(n - d * Vec3::Unit(j), e, &tm, &om, &unused1, &unused2);
    EXPECT_LT((dt_dn.col(j) - (tp - tm) / (2 * d)).norm(), 1e-8) << "dt/dn column " << j;
    EXPECT_LT((do_dn.col(j) - (op - om) / (2 * d)).norm(), 1e-8) << "do/dn column " << j;
  }
}

TEST(PlaneCrossingBound, TwoOverlappingSpheresCrossTheirContactPlaneByTheOverlap) {
  const ConvexShape sphere = MakeSphere(0.5);
  Pose X_WB1 = Pose::Identity(), X_WB2 = Pose::Identity();
  X_WB1.translation() = Vec3(0.0, 0.0, 0.9);  // 0.1 m overlap along z
  const auto closed_form = [&](const Pose& X_WB) {
    return [&sphere, X_WB](const Vec3& u_W) {
      Vec3 p_W;
      EXPECT_TRUE(SupportPoint(sphere, X_WB, u_W, &p_W));
      return u_W.dot(p_W);
    };
  };
  const Vec3 p_W(0.0, 0.0, 0.5), n_W = Vec3::UnitZ();  // the top of sphere 2, its outward normal
  EXPECT_NEAR(PlaneCrossingBound(closed_form(X_WB1), closed_form(X_WB2), p_W, n_W), 0.1, 1e-15);
  // The oracle's bound is the same function of its own support values.
  EXPECT_NEAR(PenetrationBound(sphere, X_WB1, sphere, X_WB2, p_W, n_W), 0.1, 1e-6);
  X_WB1.translation() = Vec3(0.0, 0.0, 1.2);  // apart: nothing crosses
  EXPECT_EQ(PlaneCrossingBound(closed_form(X_WB1), closed_form(X_WB2), p_W, n_W), 0.0);
}

}  // namespace
}  // namespace implicit_sim
