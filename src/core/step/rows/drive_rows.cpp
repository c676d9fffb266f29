#include "implicit_sim/core/step/rows/drive_rows.h"

#include <cmath>

#include "implicit_sim/core/step/rows/joint_rows.h"
#include "step/contact_frame.h"

namespace implicit_sim {
namespace {

// mid(-E, E, P) with E = joint.effort_limit (P itself when E is 0), and its derivative by P.
struct ClampedEffort {
  double value, slope;
};
ClampedEffort ClampToEffortLimit(const Joint& joint, double P) {
  const double E = joint.effort_limit;
  if (!(E > 0.0) || std::abs(P) <= E) return {P, 1.0};
  return {P > 0.0 ? E : -E, 0.0};
}

// S = Fs + kp h + kd: kp h + kd is the effort per unit of end-of-step joint rate (N m s/rad or N s/m), taken per
// 1 rad/s or 1 m/s.
double DriveRowScale(const RowContext& ctx, const JointDrive& drive) {
  return ctx.Fs() + drive.stiffness * ctx.h() + drive.damping;
}

}  // namespace

void AddDriveRow(const RowContext& ctx, int j, const JointDrive& drive, double share, const BodyEnd& eP,
                 const BodyEnd& eC, const JointGradient& G_q) {
  const Joint& joint = ctx.model().joints[j];
  const int col = ctx.layout.drive_column(j);
  JointGradient g;
  const double q = JointPosition(joint, MakePose(eP.p, eP.R), MakePose(eC.p, eC.R), &g);  // end of step
  const double rate = G_q.Rate(eP.v, eP.w, eC.v, eC.w);
  const ClampedEffort target = ClampToEffortLimit(
      joint, drive.stiffness * JointDrivePositionError(joint, drive.position_target, q) +
                 drive.damping * (drive.velocity_target - rate) + drive.gravity_effort);
  const double inv_scale = 1.0 / DriveRowScale(ctx, drive);
  ctx.out.Phi[col] = (ctx.z[col] - target.value) * inv_scale;
  if (ctx.out.WantJacobian()) ctx.out.AddJ(col, col, inv_scale);
  AddEndGradientRow(ctx, col, g, eP, eC, target.slope * drive.stiffness * inv_scale);
  AddRateRow(ctx, col, G_q, eP, eC, target.slope * drive.damping * inv_scale);
  AddJointForce(ctx, G_q, share * ctx.z[col], col, share, eP, eC);
}

void AddAverageDriveRow(const RowContext& ctx, int j, const JointDrive& drive, double u1, double q1,
                        const BodyEnd& eP, const BodyEnd& eC, const JointGradient& G_q) {
  const Joint& joint = ctx.model().joints[j];
  const int col = ctx.layout.drive_column(j);
  const double rate_gain = drive.damping + 0.5 * ctx.h() * drive.stiffness;  // N m s/rad or N s/m
  const double rate = G_q.Rate(eP.v, eP.w, eC.v, eC.w);
  const ClampedEffort target = ClampToEffortLimit(
      joint, drive.stiffness * JointDrivePositionError(joint, drive.position_target, q1) +
                 rate_gain * (drive.velocity_target - rate) + drive.gravity_effort);
  const double inv_scale = 1.0 / DriveRowScale(ctx, drive);
  ctx.out.Phi[col] = (ctx.z[col] - 0.5 * (u1 + target.value)) * inv_scale;
  if (ctx.out.WantJacobian()) ctx.out.AddJ(col, col, inv_scale);
  AddRateRow(ctx, col, G_q, eP, eC, 0.5 * target.slope * rate_gain * inv_scale);
  AddJointForce(ctx, G_q, ctx.z[col] - 0.5 * u1, col, 1.0, eP, eC);
}

}  // namespace implicit_sim
