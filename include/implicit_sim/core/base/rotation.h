// SO(3) helpers for the kinematic map (paper eq. 2): R(l+1) = Exp(h w) R(l) with w the world-frame angular velocity.
#pragma once

#include <cmath>

#include "implicit_sim/core/base/types.h"

namespace implicit_sim {

inline Mat3 Skew(const Vec3& a) {
  Mat3 S;
  S << 0.0, -a[2], a[1], a[2], 0.0, -a[0], -a[1], a[0], 0.0;
  return S;
}

// Exp(phi): rotation by |phi| about phi / |phi|.
inline Mat3 ExpSO3(const Vec3& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Mat3::Identity() + Skew(phi);
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

// Left Jacobian J_l(phi): Exp(phi + d) = Exp(J_l(phi) d) Exp(phi) to first order in d.
inline Mat3 LeftJacobianSO3(const Vec3& phi) {
  const double angle = phi.norm();
  const Mat3 S = Skew(phi);
  if (angle < 1e-6) return Mat3::Identity() + 0.5 * S + S * S / 6.0;
  const double a2 = angle * angle;
  return Mat3::Identity() + (1.0 - std::cos(angle)) / a2 * S + (angle - std::sin(angle)) / (a2 * angle) * S * S;
}

}  // namespace implicit_sim
