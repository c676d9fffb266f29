// The body rows of the step's problems: Newton-Euler in impulse form divided by h (paper eq. 1 discretized), in force
// units scaled by 1/Fs, per moving body (6 rows at its velocity column). The contact and joint rows add their
// impulses / h to them. Three discretizations:
//   end-of-step momentum (the paper's step): m (v1 - v0) / h = f and (I_W(R1) w1 - I_W(R0) w0) / h = tau, with the
//     inertia at the end-of-step orientation (doc/method.md, pitfall 7: the gyroscopic effect held implicitly);
//   half-step momentum (RATTLE stage 1): m (v_half - v0) / h = f / 2 and the Lie-group variational (Moser-Veselov)
//     rotation row L_disc(w_half) = L0 + h/2 tau (DiscreteMomentum);
//   fixed-geometry momentum (RATTLE stage 2): m (v1 - v_half) / h = f / 2 and (I_W(R1) w1 - L_half) / h = tau / 2 at
//     the end-of-step pose of stage 1.
#pragma once

#include <vector>

#include "implicit_sim/core/step/rows/row_context.h"

namespace implicit_sim {

// A body after RATTLE's stage 1 (per entry of layout.bodies()): its end-of-step pose and the momenta after the
// stage's impulses.
struct BodyHalf {
  Vec3 p1 = Vec3::Zero();
  Mat3 R1 = Mat3::Identity();
  Vec3 v_half = Vec3::Zero(), L_half = Vec3::Zero();
};

void AddEndMomentumRows(const RowContext& ctx);
void AddHalfStepMomentumRows(const RowContext& ctx);
void AddFixedGeometryMomentumRows(const RowContext& ctx, const std::vector<BodyHalf>& half);

// The discrete angular momentum (1/h) R0 vee(F Jd - Jd F^T) / sinc(h |w|), F = R0^T R1 = Exp(h R0^T w), of a body
// with body inertia I_B, and its derivatives with respect to the end-of-step rotation increment theta
// (R1 -> Exp(theta) R1) at fixed w and to w at fixed R1 (either may be null).
Vec3 DiscreteMomentum(const Mat3& I_B, const Mat3& R0, const Mat3& R1, const Vec3& w, double h, Mat3* dL_dtheta,
                      Mat3* dL_dw);

}  // namespace implicit_sim
