#include "implicit_sim/core/step/schemes/rattle_scheme.h"

#include <algorithm>

#include "implicit_sim/core/ncp/ncp_error.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/core/step/retry_ladder.h"
#include "implicit_sim/core/step/schemes/paper_scheme.h"

namespace implicit_sim {

RattleScheme::RattleScheme(const StepLayout& layout, const StepKinematics& kinematics,
                           const std::vector<JointDrive>& drives)
    : position_(layout, kinematics, drives, /*regular_separated_friction=*/true),
      velocity_(layout, kinematics, drives) {}

// Start frames from the warm start: the previous step's closest points, at this step's start.
void RattleScheme::BeginStep(IslandSolve* island) {
  if (!island->has_warm_start) std::fill(island->frame_known.begin(), island->frame_known.end(), 0);
  position_.SetStartFrames(island->z, island->frame_known);
  position_complementarity_ = 0.0;
}

bool RattleScheme::FinishStep(const StepperOptions& options, bool converged, IslandSolve* island,
                              StepReport* report) {
  if (converged && position_.FallBackWhereActiveSetsChanged(island->z) > 0) {
    const NcpSummary again = position_solvers_.For(position_).Solve(position_, options.newton, &island->z);
    report->iterations += again.iterations;
    report->residual_evaluations += again.residual_evaluations;
    converged = again.converged;
  }
  position_complementarity_ = ComputeNcpError(position_, island->z, &island->ncp_error_rows).complementarity;
  velocity_.Begin(position_, island->z, island->ncp_error_rows, &velocities_);
  const NcpSummary velocity = SolveFromGuess(options, velocity_, &velocity_solvers_, &velocities_, island, report);
  report->residual = std::max(report->residual, velocity.residual);
  return converged && velocity.converged && velocities_.allFinite();
}

double RattleScheme::ComplementarityError(IslandSolve* island) {
  const NcpError velocity_error = ComputeNcpError(velocity_, velocities_, &island->ncp_error_rows);
  return std::max(position_complementarity_, velocity_error.complementarity);
}

std::unique_ptr<IslandScheme> MakeIslandScheme(StepperOptions::Scheme scheme, const StepLayout& layout,
                                               const StepKinematics& kinematics,
                                               const std::vector<JointDrive>& drives) {
  switch (scheme) {
    case StepperOptions::Scheme::kPaper:
      return std::make_unique<PaperScheme>(layout, kinematics, drives);
    case StepperOptions::Scheme::kRattle:
      break;
  }
  return std::make_unique<RattleScheme>(layout, kinematics, drives);
}

}  // namespace implicit_sim
