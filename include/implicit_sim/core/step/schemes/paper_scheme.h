// The paper's step as an island scheme (island_scheme.h): one problem (problems/paper_step.h), whose solution gives
// the end-of-step poses and velocities.
#pragma once

#include "implicit_sim/core/step/problems/paper_step.h"
#include "implicit_sim/core/step/schemes/island_scheme.h"

namespace implicit_sim {

class PaperScheme final : public IslandScheme {
 public:
  PaperScheme(const StepLayout& layout, const StepKinematics& kinematics, const std::vector<JointDrive>& drives);
  StepperOptions::Scheme scheme() const override { return StepperOptions::Scheme::kPaper; }
  void SetFrictionForm(const FrictionForm& form) override { problem_.set_friction_form(form); }
  StepProblem& pose_problem() override { return problem_; }
  NewtonSolvers& pose_solvers() override { return solvers_; }
  void BeginStep(IslandSolve*) override {}
  bool FinishStep(const StepperOptions&, bool converged, IslandSolve*, StepReport*) override { return converged; }
  const Eigen::VectorXd& velocity_solution(const IslandSolve& island) const override;
  const StepProblem& velocity_problem() const override { return problem_; }
  double ComplementarityError(IslandSolve* island) override;
  int lm_fallbacks() const override { return solvers_.lm_fallbacks(); }

 private:
  PaperStepProblem problem_;
  NewtonSolvers solvers_;
};

}  // namespace implicit_sim
