// The joint rows of the step's problems (the paper's bilateral constraints, eq. 1 with joints; Section III notes the
// formulation holds with them). Per joint j, in its block at o = joint_offset(j) (m = num_equalities; layout.h):
//   rows o .. o+m-1     C_i(end-of-step poses) / h = 0: each equality of joints.h holds at the END of the step
//                       (position level, so drift stays at the solver tolerance), in velocity units
//   rows o+m, o+m+1     limits: FB(l_lo / Fs, q - lower) and FB(l_hi / Fs, upper - q), q the end-of-step position
//                       (0 <= limit impulse _|_ distance to the limit >= 0)
//   the next two rows   Coulomb joint friction (rows/friction_rows.h): qdot + s_f sigma_f = 0 and FB(sigma_f, 1 - s_f^2),
//                       friction force F_c s_f
//   the next row        a mimic joint (Joint::mimic_leader k): (q - c q_k - offset) / h = 0 at the end of the step,
//                       its multiplier mu acting as mu G_q on this joint and -c mu G_q(k) on its leader
//   the last row        the drive, if the joint is driven (rows/drive_rows.h)
// and on the body rows the generalized joint force G^T f / Fs with
//   f = sum_i lambda_i G_i + (l_lo - l_hi + F_c s_f - c qdot + tau) G_q,   qdot = G_q . nu (implicit damping c),
//   tau the scene's constant joint effort
// where G_i and G_q are the gradients of the equalities and of the position at the START of the step. Forces along the
// start-of-step gradients with constraints at the end is the SHAKE discretization: with the position update
// p1 = p0 + h v1 it is the symplectic Euler method for a constrained system, so a pendulum's energy oscillates about
// its true value instead of decaying, and the Jacobian needs no second derivatives of the constraints.
// Commanded joint efforts enter as external wrenches (AddJointEffortWrench) along the same G_q.
#pragma once

#include <vector>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/rows/row_context.h"

namespace implicit_sim {

// Every joint's rows. share: the share of the step's constant effort, friction bound, damping and drive effort these
// rows carry (1 in the paper's step, 1/2 in RATTLE's stage 1). drives: one per model joint (read for driven joints).
void AddJointRows(const RowContext& ctx, double share, const std::vector<JointDrive>& drives);

// Helpers shared with the velocity-level joint rows of RATTLE's stage 2 (problems/rattle_velocity.h):
// row += scale * dC/dz for a function C of the end-of-step poses with gradient g: dp = h dv, dtheta = h J_l(h w) dw.
void AddEndGradientRow(const RowContext& ctx, int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC,
                       double scale);
// row += scale * d(g . nu)/dz (a rate along the gradient g: linear in the velocities).
void AddRateRow(const RowContext& ctx, int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC,
                double scale);
// Body rows -= g * force / Fs (the generalized force along g) and their Jacobian column `col` -= g * dforce_dcol / Fs
// (no column: col < 0).
void AddJointForce(const RowContext& ctx, const JointGradient& g, double force, int col, double dforce_dcol,
                   const BodyEnd& eP, const BodyEnd& eC);
// Viscous damping -share c qdot along G_q, implicit in the end-of-step velocities.
void AddJointDamping(const RowContext& ctx, const Joint& joint, double share, const BodyEnd& eP, const BodyEnd& eC,
                     const JointGradient& G_q);
// The Coulomb friction rows of a joint at rows col, col + 1 for its end-of-step rate along G_q; returns the friction
// fraction s.
double AddJointFrictionRows(const RowContext& ctx, int col, const JointGradient& G_q, const BodyEnd& eP,
                            const BodyEnd& eC);

}  // namespace implicit_sim
