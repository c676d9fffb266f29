#include "implicit_sim/core/step/schemes/paper_scheme.h"

#include "implicit_sim/core/ncp/ncp_error.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {

PaperScheme::PaperScheme(const StepLayout& layout, const StepKinematics& kinematics,
                         const std::vector<JointDrive>& drives)
    : problem_(layout, kinematics, drives, /*regular_separated_friction=*/true) {}

const Eigen::VectorXd& PaperScheme::velocity_solution(const IslandSolve& island) const { return island.z; }

double PaperScheme::ComplementarityError(IslandSolve* island) {
  return ComputeNcpError(problem_, island->z, &island->ncp_error_rows).complementarity;
}

}  // namespace implicit_sim
