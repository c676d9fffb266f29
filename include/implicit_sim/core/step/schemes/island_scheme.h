// The time-stepping scheme of an island (StepperOptions::scheme) as a strategy: the problems of its stages, their
// solvers, and what a step does between the pose problem's retry ladder and the commit of the step. MakeIslandScheme
// is the one place that switches on the scheme (as MuJoCo's mj_step switches once on the integrator); the island's
// step (time_stepper.cpp, AdvanceIsland) calls the strategy.
//   paper_scheme.h   the paper's step: one problem, its solution gives the poses and the velocities;
//   rattle_scheme.h  the two-stage RATTLE step: stage 1 gives the poses, stage 2 the velocities.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/ncp/semismooth_newton.h"
#include "implicit_sim/core/step/options.h"
#include "implicit_sim/core/step/problems/step_problem.h"
#include "implicit_sim/core/step/step_report.h"

namespace implicit_sim {

struct IslandSolve;  // step/data.h

// A problem's Newton solvers: dense LU up to kDenseSizeLimit unknowns, sparse (KLU) above, where a dense LU would cost
// O(n^3) per iteration (a pile, or a 1000-gon disc: one pair with about 1000 unknowns). One pair per problem, so that
// each keeps the analysis of its own Jacobian pattern.
struct NewtonSolvers {
  static constexpr int kDenseSizeLimit = 200;
  SemismoothNewton dense{0, false}, sparse{0, true};
  SemismoothNewton& For(const NcpProblem& problem) { return problem.size() > kDenseSizeLimit ? sparse : dense; }
  int lm_fallbacks() const { return dense.lm_fallbacks() + sparse.lm_fallbacks(); }
};

class IslandScheme {
 public:
  virtual ~IslandScheme() = default;
  virtual StepperOptions::Scheme scheme() const = 0;
  // How every problem of the scheme writes its friction rows.
  virtual void SetFrictionForm(const FrictionForm& form) = 0;
  // The problem whose solution in IslandSolve::z gives the end-of-step poses (the retry ladder solves it).
  virtual StepProblem& pose_problem() = 0;
  virtual NewtonSolvers& pose_solvers() = 0;
  // Before the pose problem's ladder, after the kinematics' BeginStep (RATTLE: the start frames).
  virtual void BeginStep(IslandSolve* island) = 0;
  // After the pose problem's solve (converged, or the best iterate of the shortest sub-step): the rest of the step.
  // Returns whether the whole step converged.
  virtual bool FinishStep(const StepperOptions& options, bool converged, IslandSolve* island, StepReport* report) = 0;
  // The solution that holds the end-of-step velocities, and the problem that states them.
  virtual const Eigen::VectorXd& velocity_solution(const IslandSolve& island) const = 0;
  virtual const StepProblem& velocity_problem() const = 0;
  // The complementarity error of the accepted step (ncp_error.h; every stage's largest).
  virtual double ComplementarityError(IslandSolve* island) = 0;
  virtual int lm_fallbacks() const = 0;
  // The scheme that takes the island's step where this one does not converge within the budget of the ladder's warm
  // rungs (RATTLE: the paper's step); nullptr: none, this scheme climbs every rung of the ladder.
  virtual IslandScheme* fallback() { return nullptr; }
};

// The strategy of `scheme` for an island (its layout, kinematics and the drives it reads: IslandSolve's).
std::unique_ptr<IslandScheme> MakeIslandScheme(StepperOptions::Scheme scheme, const StepLayout& layout,
                                               const StepKinematics& kinematics,
                                               const std::vector<JointDrive>& drives);

}  // namespace implicit_sim
