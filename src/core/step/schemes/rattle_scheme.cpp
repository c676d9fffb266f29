#include "implicit_sim/core/step/schemes/rattle_scheme.h"

#include <algorithm>

#include "implicit_sim/core/ncp/ncp_error.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/core/step/energy_guard.h"
#include "implicit_sim/core/step/retry_ladder.h"
#include "implicit_sim/core/step/schemes/paper_scheme.h"

namespace implicit_sim {

RattleScheme::RattleScheme(const StepLayout& layout, const StepKinematics& kinematics,
                           const std::vector<JointDrive>& drives)
    : kinematics_(kinematics),
      position_(layout, kinematics, drives, /*regular_separated_friction=*/true),
      velocity_(layout, kinematics, drives),
      paper_(layout, kinematics, drives) {}

// Start frames from the warm start: the previous step's closest points, at this step's start.
void RattleScheme::BeginStep(IslandSolve* island) {
  if (!island->has_warm_start) std::fill(island->frame_known.begin(), island->frame_known.end(), 0);
  position_.SetStartFrames(island->z, island->frame_known);
  position_complementarity_ = 0.0;
  // Sized here, so that a warm step allocates nothing even when the first step did not reach them.
  stage1_seed_.resize(island->z.size());
  start_frame_solution_.resize(island->z.size());
  velocities_.resize(island->z.size());
}

bool RattleScheme::FinishStep(const StepperOptions& options, bool converged, IslandSolve* island,
                              StepReport* report) {
  if (!converged) return false;  // stage 1 within its budget failed: the paper's step
  stage1_seed_ = island->z_start;  // the ladder's starting iterate
  // Pairs whose start frame turned out stale: stage 1 again from its solution, which is close. Where that re-solve
  // fails (a landing island), the start-frame solution stands if the energy guard passes it: the drift rule is a
  // preference for the better root, the guard is the law.
  bool solved;
  if (position_.FallBackWhereFramesMoved(island->z) > 0) {
    start_frame_solution_ = island->z;
    solved = SolveStagesAgain(options, island, report);
    if (!solved) {
      report->stale_frames_kept++;
      position_.UndoFramesMovedFallback();
      island->z = start_frame_solution_;
      solved = SolveVelocityStage(options, island, report);
    }
  } else {
    solved = SolveVelocityStage(options, island, report);
  }
  if (!solved) return false;
  if (EnergyHolds(*island)) return true;
  // The energy guard: every pair on its end frame, then the paper's step (the fallback).
  report->energy_fallbacks++;
  island->z = stage1_seed_;
  return position_.UseFallbackFrames() > 0 && SolveStagesAgain(options, island, report) && EnergyHolds(*island);
}

bool RattleScheme::SolveStagesAgain(const StepperOptions& options, IslandSolve* island, StepReport* report) {
  const NcpSummary again = SolveFromGuess(options, position_, &position_solvers_, &island->z, island, report);
  return SolveVelocityStage(options, island, report) && again.converged;
}

bool RattleScheme::SolveVelocityStage(const StepperOptions& options, IslandSolve* island, StepReport* report) {
  position_complementarity_ = ComputeNcpError(position_, island->z, &island->ncp_error_rows).complementarity;
  velocity_.Begin(position_, island->z, island->ncp_error_rows, &velocities_);
  const int iterations_before = report->iterations;
  const NcpSummary velocity = SolveFromGuess(options, velocity_, &velocity_solvers_, &velocities_, island, report);
  report->velocity_iterations += report->iterations - iterations_before;
  report->residual = std::max(report->residual, velocity.residual);
  return velocity.converged && velocities_.allFinite();
}

bool RattleScheme::EnergyHolds(const IslandSolve& island) const {
  return StepEnergyBalance(kinematics_, island.z, velocities_).holds();
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
