// The paper's step (paper eq. 10-11 with the kinematic map eq. 2 and the closest-point conditions eq. 19-22): the
// impulses, levers and inertia at the END of the step, first order. Rows: end-of-step momentum (rows/body_rows.h),
// joints with their whole effort (rows/joint_rows.h), contacts on their end-of-step frame (rows/contact_rows.h).
#pragma once

#include <vector>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/problems/step_problem.h"

namespace implicit_sim {

class PaperStepProblem final : public StepProblem {
 public:
  // drives: one per model joint, read for the driven joints; kept by reference.
  PaperStepProblem(const StepLayout& layout, const StepKinematics& kinematics, const std::vector<JointDrive>& drives,
                   bool regular_separated_friction)
      : StepProblem(layout, kinematics), drives_(drives), regular_separated_friction_(regular_separated_friction) {}

 private:
  void AddRows(const RowContext& ctx) const override;
  const std::vector<JointDrive>& drives_;
  const bool regular_separated_friction_;
};

}  // namespace implicit_sim
