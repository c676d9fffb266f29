// The rows of one contact pair in the paper's step and in RATTLE's stage 1 (paper eq. 10-11 and Appendix eq. 19-22,
// in the normal-distance form of doc/method.md, pitfall 1), in the pair's block (layout.h), scaled so that each is
// O(1) with the force scale Fs:
//   a1 - a2 - d n = 0;  n - sum beta grad g = 0;  -n - sum alpha grad f = 0;  (n.n - 1)/2 = 0
//   alpha_i _|_ -f_i(a1),  beta_j _|_ -g_j(a2),  ln / Fs _|_ d                (as Fischer-Burmeister rows)
//   the friction rows of rows/friction_rows.h
// and the contact wrench on the body rows of both bodies (paper eq. 1: W_n p_n + W_t p_t + W_o p_o + W_r p_r).
// Body 1 and body 2 are at their end-of-step poses (paper eq. 2), so every geometric quantity depends on the
// velocities: that is what makes the step geometrically implicit.
// The frame policy: by default the impulse acts along the END-of-step frame (n, t, o at the closest points). With
// start_frame (RATTLE stage 1 for a pair closed at the start), along the frame of the start-of-step solution
// *start_frame (its normal and closest points), and the slip is measured on the average of both frames
// (doc/method.md, "The second-order step").
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/step/rows/row_context.h"

namespace implicit_sim {

struct ContactRowOptions {
  const Eigen::VectorXd* start_frame = nullptr;  // see above; null: the end frame
  // Friction rows with sigma + max(d, 0) / h in place of sigma: keeps the Newton matrix regular at separated pairs
  // (exactly the paper's row at a touching one, d = 0).
  bool regular_separated_friction = false;
};

void AddContactRows(const RowContext& ctx, int block, const ContactRowOptions& options);

}  // namespace implicit_sim
