// The two-stage RATTLE step as an island scheme (island_scheme.h; doc/method.md, "The second-order step"):
//   stage 1 (problems/rattle_position.h) from the start frames of the warm start, by the ladder's warm rungs; its pairs
//     whose active inequalities changed or whose contact point drifted fall back to the end frame and stage 1 is
//     solved again (if that fails, the first solution is kept and the energy guard judges it);
//   stage 2 (problems/rattle_velocity.h) from stage 1 repeated, by Newton within the warm rungs' budget;
//   the energy guard (energy_guard.h): a step that creates energy is solved again with every pair on its end frame.
// Where a stage does not converge within its budget or the guard still fails, the island's step is the paper's
// (fallback(), problems/paper_step.h), which dissipates, with the whole retry ladder.
// IslandSolve::z keeps stage 1's solution (the poses, and the warm start of the next step); stage 2's is velocities_.
#pragma once

#include "implicit_sim/core/step/problems/rattle_position.h"
#include "implicit_sim/core/step/problems/rattle_velocity.h"
#include "implicit_sim/core/step/schemes/island_scheme.h"
#include "implicit_sim/core/step/schemes/paper_scheme.h"

namespace implicit_sim {

class RattleScheme final : public IslandScheme {
 public:
  RattleScheme(const StepLayout& layout, const StepKinematics& kinematics, const std::vector<JointDrive>& drives);
  StepperOptions::Scheme scheme() const override { return StepperOptions::Scheme::kRattle; }
  void SetFrictionForm(const FrictionForm& form) override {
    position_.set_friction_form(form);
    velocity_.set_friction_form(form);
    paper_.SetFrictionForm(form);
  }
  StepProblem& pose_problem() override { return position_; }
  NewtonSolvers& pose_solvers() override { return position_solvers_; }
  void BeginStep(IslandSolve* island) override;
  bool FinishStep(const StepperOptions& options, bool converged, IslandSolve* island, StepReport* report) override;
  const Eigen::VectorXd& velocity_solution(const IslandSolve&) const override { return velocities_; }
  const StepProblem& velocity_problem() const override { return velocity_; }
  double ComplementarityError(IslandSolve* island) override;
  int lm_fallbacks() const override {
    return position_solvers_.lm_fallbacks() + velocity_solvers_.lm_fallbacks() + paper_.lm_fallbacks();
  }
  IslandScheme* fallback() override { return &paper_; }

 private:
  // Stage 1 again from IslandSolve::z (after its frames changed), then stage 2; whether both converged.
  bool SolveStagesAgain(const StepperOptions& options, IslandSolve* island, StepReport* report);
  // Stage 2 after a solved stage 1; whether it converged to finite velocities.
  bool SolveVelocityStage(const StepperOptions& options, IslandSolve* island, StepReport* report);
  bool EnergyHolds(const IslandSolve& island) const;
  const StepKinematics& kinematics_;
  RattlePositionProblem position_;
  RattleVelocityProblem velocity_;
  PaperScheme paper_;  // the fallback
  NewtonSolvers position_solvers_, velocity_solvers_;
  Eigen::VectorXd stage1_seed_;           // the step's starting iterate of stage 1 (the energy guard's re-solve)
  Eigen::VectorXd start_frame_solution_;  // stage 1's solution before its stale frames were re-solved
  Eigen::VectorXd velocities_;            // stage 2's solution
  double position_complementarity_ = 0.0;  // stage 1's complementarity error
};

}  // namespace implicit_sim
