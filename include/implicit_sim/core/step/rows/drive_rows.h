// Joint drives (joints.h, JointDrive) as rows of the step's problems: per driven joint j one unknown u, the drive
// effort (N m or N), the last of the joint's block (StepLayout::SetDrivenJoints), with the box law (doc/method.md,
// "Joint drives")
//   u = mid(-E, E, P),  P = kp e(q_target, q) + kd (v_target - qdot) + tau_g
// where q and qdot are the joint position and rate at the END of the step (implicit, hence stable at any gain), e the
// position error, tau_g the gravity feed-forward (JointDrive::gravity_effort, constant over the step) and
// E = Joint::effort_limit (P itself when E = 0). The row is (u - mid(-E, E, P)) / S with
// S = Fs + kp h + kd (times 1 rad/s or 1 m/s): a force row for soft gains, a velocity-level constraint row like the
// joint equalities' for stiff ones. mid is the min-map of the box complementarity problem -E <= u <= E _|_ u - P,
// piecewise linear: its generalized Jacobian takes the slope 1 inside the box (and on its edge), 0 outside. The
// effort acts along the position gradient G_q like the joint's damping and constant effort (rows/joint_rows.h).
//
// Paper's step: share 1, P at the end of the step (implicit Euler). RATTLE: stage 1 applies u1 / 2 with P at the end
// of stage 1 (q1 and the stage's velocity); stage 2's unknown is the step's average effort U, applying U - u1 / 2, with
//   2 U - u1 = mid(-E, E, kp e(q_target, q1) + (kd + kp h / 2) (v_target - qdot1))
// the spring taken at the position half a step past q1 along the end velocity, q1 + h/2 (qdot1 - v_target) (relative
// to the moving target): without that term a stiff spring pins q1 and leaves qdot1 ringing at +-qdot (an eigenvalue
// -1 of the step for kp -> infinity); with it the step damps every mode for any gain and h.
#pragma once

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/rows/row_context.h"

namespace implicit_sim {

// The drive row of joint j at the end of the step; the body rows get share * u along G_q.
void AddDriveRow(const RowContext& ctx, int joint, const JointDrive& drive, double share, const BodyEnd& eP,
                 const BodyEnd& eC, const JointGradient& G_q);
// RATTLE stage 2's drive row of joint j: the step's average effort U for the stage-1 effort u1 and the stage-1 end
// position q1 (rad or m); the body rows get U - u1 / 2 along G_q.
void AddAverageDriveRow(const RowContext& ctx, int joint, const JointDrive& drive, double u1, double q1,
                        const BodyEnd& eP, const BodyEnd& eC, const JointGradient& G_q);

}  // namespace implicit_sim
