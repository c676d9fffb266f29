#include "implicit_sim/core/step/problems/rattle_position.h"

#include <algorithm>

#include "implicit_sim/core/step/rows/body_rows.h"
#include "implicit_sim/core/step/rows/contact_rows.h"
#include "implicit_sim/core/step/rows/joint_rows.h"

namespace implicit_sim {
namespace pi = pair_index;
namespace {

// An inequality counts as active at a closest point when its multiplier exceeds this share of the largest.
constexpr double kActiveShare = 1e-6;

// Whether the multipliers x[0 .. count) have the same active set as y[0 .. count).
bool SameActiveSet(const double* x, const double* y, int count) {
  double x_max = 0.0, y_max = 0.0;
  for (int k = 0; k < count; ++k) {
    x_max = std::max(x_max, x[k]);
    y_max = std::max(y_max, y[k]);
  }
  for (int k = 0; k < count; ++k) {
    if ((x[k] > kActiveShare * x_max) != (y[k] > kActiveShare * y_max)) return false;
  }
  return true;
}

}  // namespace

// Only a pair closed at the start has a start frame worth acting along: for an impact (a pair apart at the start,
// closed at the end) the start-of-step closest points say nothing about where the bodies meet, so the impulse takes
// the end frame, as in the paper's step.
void RattlePositionProblem::SetStartFrames(const Eigen::VectorXd& z_start, const std::vector<char>& known) {
  frame_z_ = z_start;
  const std::vector<PairBlock>& blocks = layout().blocks();
  use_start_frame_.resize(blocks.size());
  for (size_t c = 0; c < blocks.size(); ++c) {
    const PairBlock& blk = blocks[c];
    const bool closed =
        IsClosed(z_start[blk.offset + pi::kD], z_start[blk.normal_force()], kinematics().force_scale());
    use_start_frame_[c] = known[c] && closed;
  }
}

int RattlePositionProblem::FallBackWhereActiveSetsChanged(const Eigen::VectorXd& z) {
  int count = 0;
  const std::vector<PairBlock>& blocks = layout().blocks();
  for (size_t c = 0; c < blocks.size(); ++c) {
    const PairBlock& blk = blocks[c];
    if (!use_start_frame_[c]) continue;
    const int first = blk.offset + pi::kAlpha;
    if (SameActiveSet(&z[first], &frame_z_[first], blk.k1) &&
        SameActiveSet(&z[blk.beta()], &frame_z_[blk.beta()], blk.k2)) {
      continue;
    }
    use_start_frame_[c] = 0;
    ++count;
  }
  return count;
}

int RattlePositionProblem::UseFallbackFrames() {
  int count = 0;
  for (char& use : use_start_frame_) {
    count += use;
    use = 0;
  }
  return count;
}

void RattlePositionProblem::SeedVelocities(const State& state, Eigen::VectorXd* z) const {
  StepProblem::SeedVelocities(state, z);
  if (!layout().blocks().empty() || !layout().joints().empty()) return;
  const double h = kinematics().h();
  for (size_t i = 0; i < layout().slots().size(); ++i) {
    const Body& body = layout().model().bodies[layout().bodies()[layout().slot_body(static_cast<int>(i))]];
    const int row = static_cast<int>(6 * i);
    const Vec3 f_ext = kinematics().ExternalForce(static_cast<int>(i));
    for (int k = 0; k < 3; ++k) {
      if (!layout().locked_rows()[row + k]) (*z)[row + k] += 0.5 * h * f_ext[k] / body.mass;
    }
  }
}

void RattlePositionProblem::AddRows(const RowContext& ctx) const {
  AddHalfStepMomentumRows(ctx);
  AddJointRows(ctx, 0.5, drives_);
  for (size_t c = 0; c < layout().blocks().size(); ++c) {
    ContactRowOptions options;
    options.regular_separated_friction = regular_separated_friction_;
    if (use_start_frame_[c]) options.start_frame = &frame_z_;
    AddContactRows(ctx, static_cast<int>(c), options);
  }
}

}  // namespace implicit_sim
