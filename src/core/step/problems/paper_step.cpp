#include "implicit_sim/core/step/problems/paper_step.h"

#include "implicit_sim/core/step/rows/body_rows.h"
#include "implicit_sim/core/step/rows/contact_rows.h"
#include "implicit_sim/core/step/rows/joint_rows.h"

namespace implicit_sim {

void PaperStepProblem::AddRows(const RowContext& ctx) const {
  AddEndMomentumRows(ctx);
  AddJointRows(ctx, 1.0, drives_);
  ContactRowOptions options;
  options.regular_separated_friction = regular_separated_friction_;
  for (size_t c = 0; c < layout().blocks().size(); ++c) AddContactRows(ctx, static_cast<int>(c), options);
}

}  // namespace implicit_sim
