// The two-stage RATTLE step as an island scheme (island_scheme.h; doc/method.md, "The second-order step"):
//   stage 1 (problems/rattle_position.h) from the start frames of the warm start, by the retry ladder; its pairs whose
//     active inequalities changed or whose contact point drifted fall back to the end frame and stage 1 is solved
//     again (if that fails, the first solution is kept and the energy guard judges it);
//   stage 2 (problems/rattle_velocity.h) from stage 1 repeated, by its own short ladder (SolveFromGuess);
//   the energy guard (energy_guard.h): a step that creates energy is solved again with every pair on its end frame,
//     and if that still fails, as the paper's step (problems/paper_step.h), which dissipates; so is a step whose
//     re-solve after stale start frames fails.
// IslandSolve::z keeps stage 1's solution (the poses, and the warm start of the next step); stage 2's is velocities_.
// After the paper's fallback, IslandSolve::z holds the paper step's solution, poses and velocities.
#pragma once

#include "implicit_sim/core/step/problems/paper_step.h"
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
  const Eigen::VectorXd& velocity_solution(const IslandSolve& island) const override;
  const StepProblem& velocity_problem() const override;
  double ComplementarityError(IslandSolve* island) override;
  int lm_fallbacks() const override {
    return position_solvers_.lm_fallbacks() + velocity_solvers_.lm_fallbacks() + paper_solvers_.lm_fallbacks();
  }

 private:
  // Stage 1 again from IslandSolve::z (after its frames changed), then stage 2; whether both converged.
  bool SolveStagesAgain(const StepperOptions& options, IslandSolve* island, StepReport* report);
  // Stage 2 after a solved stage 1; whether it converged to finite velocities.
  bool SolveVelocityStage(const StepperOptions& options, IslandSolve* island, StepReport* report);
  bool EnergyHolds(const IslandSolve& island) const;
  const StepKinematics& kinematics_;
  RattlePositionProblem position_;
  RattleVelocityProblem velocity_;
  PaperStepProblem paper_;  // the energy guard's last fallback
  NewtonSolvers position_solvers_, velocity_solvers_, paper_solvers_;
  Eigen::VectorXd stage1_seed_;           // the step's starting iterate of stage 1 (the fallbacks start from it)
  Eigen::VectorXd start_frame_solution_;  // stage 1's solution before its stale frames were re-solved
  bool paper_step_ = false;               // this step fell back to the paper's step
  Eigen::VectorXd velocities_;            // stage 2's solution
  double position_complementarity_ = 0.0;  // stage 1's complementarity error
};

}  // namespace implicit_sim
