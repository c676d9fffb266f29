// Stage 1 of the RATTLE step (StepperOptions::Scheme::kRattle; doc/method.md, "The second-order step"): the unknowns
// of the paper's step, with rows at half impulses, m (v_half - v0) / h = f / 2 + ..., the Lie-group variational
// rotation row (rows/body_rows.h), half the joints' constant effort, friction bound, damping and drive effort, and
// the contact impulse along the START-of-step frame of each pair closed at the start (the slip on the average of the
// start and end frames; rows/contact_rows.h). The closest points and the gap stay at the END of the step.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/problems/step_problem.h"

namespace implicit_sim {

class RattlePositionProblem final : public StepProblem {
 public:
  RattlePositionProblem(const StepLayout& layout, const StepKinematics& kinematics,
                        const std::vector<JointDrive>& drives, bool regular_separated_friction)
      : StepProblem(layout, kinematics), drives_(drives), regular_separated_friction_(regular_separated_friction) {}

  // The start-of-step frames from z_start, a solution at the start of the step (the previous step's stage 1): per
  // block whose entry of `known` is nonzero and that is closed in z_start (touching or pushing), its normal and closest
  // points. Any other block (a new pair, an impact) uses the end-of-step frame like the paper's step. Call after the
  // kinematics' BeginStep.
  void SetStartFrames(const Eigen::VectorXd& z_start, const std::vector<char>& known);
  bool uses_start_frame(int block) const { return use_start_frame_[block] != 0; }
  const Eigen::VectorXd& start_frames() const { return frame_z_; }
  // After a solution z: the pairs with a start frame whose active inequalities (alpha, beta > 0) differ from the
  // start's (a vertex or face switch of a polytope) fall back to the end-of-step frame; returns how many.
  int FallBackWhereActiveSetsChanged(const Eigen::VectorXd& z);
  // Every pair on the end-of-step frame (rung 1a); returns how many had a start frame.
  int UseFallbackFrames() override;
  // The state's velocities; without pairs or joints (a body in free flight) v_half = v0 + h f / (2 m), the solution of
  // its linear rows, so that a falling body's stage 1 needs no Newton iteration for them.
  void SeedVelocities(const State& state, Eigen::VectorXd* z) const override;

 private:
  void AddRows(const RowContext& ctx) const override;
  const std::vector<JointDrive>& drives_;
  const bool regular_separated_friction_;
  std::vector<char> use_start_frame_;  // per block: stage 1 acts along the start frame
  Eigen::VectorXd frame_z_;            // the start-of-step solution the start frames come from
};

// A pair counts as closed (for the start frames and for stage 2) within this gap (m) or with a force.
constexpr double kClosedGap = 1e-9;
inline bool IsClosed(double gap, double normal_force, double force_scale) {
  return gap <= kClosedGap || normal_force > 1e-12 * force_scale;
}

}  // namespace implicit_sim
