// The Coulomb friction rows, one emitter for contact friction (three components: t, o and the torsion r; five with
// rolling resistance: the rolling about t and o) and joint friction (one component), in every problem of the step.
// Paper eq. 10 (its typo fixed) divided by mu e ln so that it stays regular at ln = 0, with the fractions s_k
// (friction force mu e_k ln s_k) and the slip speed sigma, in one of two forms with the same solutions:
//   bilinear (the paper's rows; also every form's raw rows, which the error check and Ipopt read):
//     slip rows        rate_k + s_k slip = 0                        (k < count; rate_k = e_k times the sliding rate)
//     ellipsoid row    FB(sigma, zeta) = 0,  zeta = 1 - sum s_k^2   (sigma _|_ the friction ellipsoid, paper eq. 5)
//   projected (the projection equations of Alart and Curnier in the fractions; by default on sparse islands):
//     slip rows        s - P(y) = 0,  y = s (1 - r g) - r rate      (P: the projection onto the unit ball)
//     slip-speed row   sigma + s . rate + g |s|^2 = 0
// slip is sigma as the rows read it (ProjectedSlip) plus the separation rate g = max(d, 0) / h of the
// separated-friction regularization; r > 0 is the projection scale (s/m). Sliding, both give s = -rate / |rate| and
// sigma = |rate| - g; sticking, rate + g s = 0 and sigma = 0. Newton on the bilinear rows can stall at a pair that
// slides with its friction strictly inside the ellipsoid (sigma > 0, |s| < 1), a point the projected rows do not have
// (doc/method.md, "The friction rows as projection equations"). The projected rows couple every component's rate
// into every slip row: the caller emits the rates' gradients (by the velocities, the normal and the closest points)
// through a RateGradient. Each form has its own Jacobian pattern (the projected one couples every fraction, rate and
// the gap into every row), the same in every mode.
// A locked component (FrictionComponentLocked: its rate reads only locked velocities, a planar body's out-of-plane
// friction) has the slip row s_k = 0 instead and is left out of the ball: the locks carry that force. Its fraction
// would otherwise be free while the contact sticks (a singular Newton matrix at every step of a planar scene) and
// would take a share of the ellipsoid that belongs to the free directions.
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/base/types.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/step/kinematics.h"
#include "implicit_sim/core/step/layout.h"
#include "implicit_sim/core/step/rows/row_writer.h"

namespace implicit_sim {

struct FrictionRows {
  static constexpr int kMaxCount = 5;
  int first_row = 0;   // the row (and unknown) of s_0; s_k at first_row + k for k < 3
  int roll_row = -1;   // the row of s_3 (a contact's rolling about t); s_4 at roll_row + 1
  int count = 1;       // 1 (a joint), 3 (a contact: t, o, r) or 5 (a contact with rolling resistance: t, o, r, q1, q2)
  int sigma = 0;       // the row and unknown of sigma
  double rate[kMaxCount] = {};  // e_k times the sliding rate along component k (m/s or rad/s)
  bool locked[kMaxCount] = {};  // the component's slip row is s_k = 0 (see above)
  double s[kMaxCount] = {};     // the friction fractions s_k
  double slip = 0.0;          // the slip speed as the slip rows read it
  double dslip_dsigma = 1.0;  // its derivative by sigma
  int gap = -1;               // the gap unknown d if slip depends on it (-1: none)
  double dslip_dgap = 0.0;
  double sigma_value = 0.0;   // sigma itself (the ellipsoid row's variable side)
  double zeta = 1.0;          // 1 - sum s_k^2, as the caller writes it
  // The proximal rung's term (ncp_problem.h) on the slip rows: weight (m/s per unit of s) and the centre (the whole
  // unknown vector, read at Row(k)).
  double proximal_weight = 0.0;
  const Eigen::VectorXd* proximal_center = nullptr;
  // The projected form (see AddFrictionRows): its switch, the projection scale r (s/m) and the separation rate
  // g = max(d, 0) / h of a separated pair (the part of `slip` beyond sigma; 0 without the regularization).
  bool projected = false;
  double projection_scale = 1.0;
  double separation = 0.0;
  // RATTLE stage 2's open pair: every row holds its unknown at (*hold)[row] (s_k and sigma), with the same entries.
  const Eigen::VectorXd* hold = nullptr;
  int Row(int k) const { return k < 3 ? first_row + k : roll_row + (k - 3); }
};

// Emits coeff times the gradient of rate_k into `row` (the caller knows the rates' frame derivatives). A non-owning
// reference to the caller's callable: no allocation.
class RateGradient {
 public:
  template <typename F>
  explicit RateGradient(const F& f)
      : object_(&f), call_([](const void* o, int k, int row, double c) { (*static_cast<const F*>(o))(k, row, c); }) {}
  void operator()(int k, int row, double coeff) const { call_(object_, k, row, coeff); }

 private:
  const void* object_;
  void (*call_)(const void*, int, int, double);
};

// The slip speed of NcpEvalMode::project_multipliers: max(sigma, 0) on the slip rows (equal at every solution), so
// that a negative iterate does not make friction push along the slip; the raw rows keep sigma. derivative: 0 or 1.
double ProjectedSlip(const NcpEvalMode& mode, double sigma, double* derivative);

// The rows above for one set of fractions; a form emits the same Jacobian entries in the same order in every mode.
void AddFrictionRows(const FrictionRows& rows, const RowWriter& out, const RateGradient& rate_gradient);

// Whether a friction component's rate reads only locked velocities (Body::locked; a fixed body's count as locked):
// per body end e_i, the rate's derivative by its linear velocity is along v_i and by its angular velocity along w_i
// (world frame; either may be zero), and every component of them on a free velocity is negligible.
bool FrictionComponentLocked(const StepLayout& layout, const BodyEnd& e1, const Vec3& v1, const Vec3& w1,
                             const BodyEnd& e2, const Vec3& v2, const Vec3& w2);

// A pair's rolling moment on body 1 per newton of normal force, mu e_roll (s_q1 t + s_q2 o) (m), with the fractions
// s_q1, s_q2 of z at PairBlock::roll() and the tangent axes t, o; zero without rolling resistance.
inline Vec3 RollingMomentPerNormalForce(const PairBlock& blk, const FrictionParams& fr, const Eigen::VectorXd& z,
                                        const Vec3& t, const Vec3& o) {
  if (!blk.rolling) return Vec3::Zero();
  return fr.mu * fr.e_roll * (z[blk.roll()] * t + z[blk.roll() + 1] * o);
}

}  // namespace implicit_sim
