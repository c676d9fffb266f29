// Private to the step: the contact frame of a pair and the kinematics shared by the rows, the seeds and the contact
// results of the step problem.
#pragma once

#include "implicit_sim/core/base/rotation.h"
#include "implicit_sim/core/base/types.h"

namespace implicit_sim {

// Tangent basis (t, o) from the normal n and a reference axis e fixed for the step (doc/method.md, pitfall 3):
// t = (e - (e.n) n) / |e - (e.n) n|, o = n x t, with their derivatives with respect to n.
inline void TangentBasis(const Vec3& n, const Vec3& e, Vec3* t, Vec3* o, Mat3* dt_dn, Mat3* do_dn) {
  const Vec3 u = e - e.dot(n) * n;
  const double len = u.norm();
  *t = u / len;
  *o = n.cross(*t);
  const Mat3 du_dn = -e.dot(n) * Mat3::Identity() - n * e.transpose();
  *dt_dn = (Mat3::Identity() - (*t) * t->transpose()) / len * du_dn;
  *do_dn = -Skew(*t) + Skew(n) * (*dt_dn);
}

inline Vec3 LeastAlignedAxis(const Vec3& n) {
  int axis;
  n.cwiseAbs().minCoeff(&axis);
  return Vec3::Unit(axis);
}

inline Pose MakePose(const Vec3& p, const Mat3& R) {
  Pose X = Pose::Identity();
  X.translation() = p;
  X.linear() = R;
  return X;
}

// Velocity of the material point of body 1 at lever arm r1 (from its centre of mass) relative to body 2's at r2, with
// each body's linear velocity v (at the centre of mass) and angular velocity w (world frame).
inline Vec3 RelativeVelocity(const Vec3& v1, const Vec3& w1, const Vec3& r1, const Vec3& v2, const Vec3& w2,
                             const Vec3& r2) {
  return (v1 + w1.cross(r1)) - (v2 + w2.cross(r2));
}

// The kinematic map of paper eq. 2 over a step of h: p = p0 + h v (Euler step of the position) and R = Exp(h w) R0
// (of the orientation, on SO(3)).
inline void EndOfStepPose(const Vec3& p0, const Mat3& R0, const Vec3& v, const Vec3& w, double h, Vec3* p, Mat3* R) {
  *p = p0 + h * v;
  *R = ExpSO3(h * w) * R0;
}

}  // namespace implicit_sim
