// Stage 2 of the RATTLE step (doc/method.md, "The second-order step"): the velocities at the fixed end-of-step
// geometry of stage 1. Per moving body, at the end-of-step pose (p1, R1) of stage 1 (rows/body_rows.h):
//   m (v1 - v_half) / h = f / 2 + sum F2,   (I_W(R1) w1 - L_half) / h = tau / 2 + sum (r1 x F2 + torsion2)
// per pair closed at the end of stage 1 (IsClosed), with the TOTAL force Ln of the step and the total friction
// fractions S of its end frame (n1, t1, o1), in the ln, s_t, s_o, s_r, sigma slots of the pair's block:
//   0 <= Ln / Fs _|_ n1 . v_rel1 >= 0                        (restitution 0 on the total impulse)
//   e_t (t1 . v_rel1) + S_t sigma = 0 (and o, r alike),  0 <= sigma _|_ 1 - |S|^2 >= 0   (rows/friction_rows.h)
//   F2 = Ln (n1 + mu (e_t S_t t1 + e_o S_o o1)) - F1,  torsion2 = mu e_r Ln S_r n1 - torsion1
// where F1, torsion1 are stage 1's force and torsion vector: the step's impulse is h (F1 + F2), inside the friction
// ellipsoid of the total. The closest-point unknowns stay at stage 1's values (rows z - z1 = 0); an open pair keeps its
// stage-1 values (Ln = ln1, S = s1, sigma = sigma1: no stage-2 force).
// Joints: the equalities' rates G_i(q1) . nu1 = 0 with multipliers along G_i(q1); a closed limit 0 <= L _|_ rate;
// friction on the total fraction S; half the damping and constant effort, as in stage 1; a drive's step-average
// effort (rows/drive_rows.h).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/problems/rattle_position.h"
#include "implicit_sim/core/step/rows/body_rows.h"

namespace implicit_sim {

class RattleVelocityProblem final : public StepProblem {
 public:
  RattleVelocityProblem(const StepLayout& layout, const StepKinematics& kinematics,
                        const std::vector<JointDrive>& drives);

  // Fixes the end-of-step geometry of stage 1's solution z1 (poses, closest points, the stage-1 impulses, which pairs
  // and joint limits are closed) and writes this stage's initial guess into *z2: stage 1 repeated (totals 2 x stage
  // 1's force, the same fractions and slip, v1 = 2 v_half - v0), which Newton finishes in a few iterations.
  // raw_rows1: stage 1's raw rows at z1 (ComputeNcpError's), whose body rows correct the momenta.
  void Begin(const RattlePositionProblem& stage1, const Eigen::VectorXd& z1, const Eigen::VectorXd& raw_rows1,
             Eigen::VectorXd* z2);

 protected:
  const std::vector<RowKind>& row_kinds() const override { return row_kinds_; }
  // The stage-1 poses, with the velocities of z.
  void EndsOf(const Eigen::VectorXd& z, std::vector<BodyEnd>* ends) const override;

 private:
  void AddRows(const RowContext& ctx) const override;
  void AddPairRows(const RowContext& ctx, int block) const;
  void AddJointRateRows(const RowContext& ctx) const;

  const std::vector<JointDrive>& drives_;
  std::vector<BodyEnd> ends1_;       // stage 1's bodies at the end of the step
  std::vector<BodyHalf> half_;       // per entry of layout().bodies()
  std::vector<RowKind> row_kinds_;   // the complementarity rows of closed pairs and limits only
  Eigen::VectorXd stage1_z_;         // stage 1's solution (the frozen closest points, ln, s, sigma)
  std::vector<Vec3> stage1_force_, stage1_torsion_;  // per block: stage 1's force on body 1 and torsion vector
  std::vector<Vec3> stage1_rolling_;  // per block: stage 1's rolling moment on body 1 (N m; zero without e_roll)
  std::vector<char> closed_;                         // per block: closed at the end of stage 1
  // Per model joint: the gradients and the position at the end of stage 1, and which limits are closed there.
  std::vector<std::array<JointGradient, 6>> joint_equality_end_;
  std::vector<JointGradient> joint_position_end_;
  std::vector<double> joint_q_end_;
  std::vector<std::array<char, 2>> limit_closed_;
};

}  // namespace implicit_sim
