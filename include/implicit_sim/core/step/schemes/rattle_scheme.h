// The two-stage RATTLE step as an island scheme (island_scheme.h; doc/method.md, "The second-order step"):
//   stage 1 (problems/rattle_position.h) from the start frames of the warm start, by the retry ladder; its pairs whose
//     active inequalities changed fall back to the end frame and stage 1 is solved again;
//   stage 2 (problems/rattle_velocity.h) from stage 1 repeated, by its own short ladder (SolveFromGuess).
// IslandSolve::z keeps stage 1's solution (the poses, and the warm start of the next step); stage 2's is velocities_.
#pragma once

#include "implicit_sim/core/step/problems/rattle_position.h"
#include "implicit_sim/core/step/problems/rattle_velocity.h"
#include "implicit_sim/core/step/schemes/island_scheme.h"

namespace implicit_sim {

class RattleScheme final : public IslandScheme {
 public:
  RattleScheme(const StepLayout& layout, const StepKinematics& kinematics, const std::vector<JointDrive>& drives);
  StepperOptions::Scheme scheme() const override { return StepperOptions::Scheme::kRattle; }
  StepProblem& pose_problem() override { return position_; }
  NewtonSolvers& pose_solvers() override { return position_solvers_; }
  void BeginStep(IslandSolve* island) override;
  bool FinishStep(const StepperOptions& options, bool converged, IslandSolve* island, StepReport* report) override;
  const Eigen::VectorXd& velocity_solution(const IslandSolve&) const override { return velocities_; }
  const StepProblem& velocity_problem() const override { return velocity_; }
  double ComplementarityError(IslandSolve* island) override;
  int lm_fallbacks() const override { return position_solvers_.lm_fallbacks() + velocity_solvers_.lm_fallbacks(); }

 private:
  RattlePositionProblem position_;
  RattleVelocityProblem velocity_;
  NewtonSolvers position_solvers_, velocity_solvers_;
  Eigen::VectorXd velocities_;            // stage 2's solution
  double position_complementarity_ = 0.0;  // stage 1's complementarity error
};

}  // namespace implicit_sim
