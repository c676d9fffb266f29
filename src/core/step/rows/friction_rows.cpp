#include "implicit_sim/core/step/rows/friction_rows.h"

#include <algorithm>
#include <cmath>

#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/rows/row_context.h"

namespace implicit_sim {

const BodyEnd RowContext::kWorld = BodyEnd();

double ProjectedSlip(const NcpEvalMode& mode, double sigma, double* derivative) {
  const bool clamp = mode.project_multipliers && !mode.raw && sigma < 0.0;
  *derivative = clamp ? 0.0 : 1.0;
  return clamp ? 0.0 : sigma;
}

bool FrictionComponentLocked(const StepLayout& layout, const BodyEnd& e1, const Vec3& v1, const Vec3& w1,
                             const BodyEnd& e2, const Vec3& v2, const Vec3& w2) {
  const std::vector<char>& locked = layout.locked_rows();
  const BodyEnd* ends[2] = {&e1, &e2};
  const Vec3* dirs[2][2] = {{&v1, &w1}, {&v2, &w2}};
  for (int i = 0; i < 2; ++i) {
    if (ends[i]->col < 0) continue;  // a fixed body
    for (int part = 0; part < 2; ++part) {
      const Vec3& dir = *dirs[i][part];
      const double negligible = 1e-9 * std::max(1.0, dir.lpNorm<Eigen::Infinity>());
      for (int j = 0; j < 3; ++j) {
        if (!locked[ends[i]->col + 3 * part + j] && std::abs(dir[j]) > negligible) return false;
      }
    }
  }
  return true;
}

namespace {

// D = dP/dy of the projection P onto the unit ball at y (over the unlocked components), and P(y) / y's scale.
struct BallProjection {
  double y[FrictionRows::kMaxCount] = {};
  double D[FrictionRows::kMaxCount][FrictionRows::kMaxCount] = {};
  double scale = 1.0;  // P(y) = scale * y
};

// y = s (1 - r g) - r rate (paper eq. 10 as the projection equation s = P(y), Alart-Curnier).
BallProjection ProjectFriction(const FrictionRows& rows) {
  BallProjection p;
  const double r = rows.projection_scale, g = rows.separation;
  double norm2 = 0.0;
  for (int k = 0; k < rows.count; ++k) {
    if (rows.locked[k]) continue;
    p.y[k] = rows.s[k] * (1.0 - r * g) - r * rows.rate[k];
    norm2 += p.y[k] * p.y[k];
  }
  const double norm = std::sqrt(norm2);
  const bool inside = norm <= 1.0;
  p.scale = inside ? 1.0 : 1.0 / norm;
  for (int i = 0; i < rows.count; ++i) {
    for (int k = 0; k < rows.count; ++k) {
      if (rows.locked[i] || rows.locked[k]) continue;
      const double identity = i == k ? 1.0 : 0.0;
      p.D[i][k] = inside ? identity : (identity - p.y[i] * p.y[k] / norm2) / norm;
    }
  }
  return p;
}

}  // namespace

void AddFrictionRows(const FrictionRows& rows, const RowWriter& out, const RateGradient& rate_gradient) {
  const NcpEvalMode& mode = out.mode;
  const int n = rows.count;
  const double r = rows.projection_scale, g = rows.separation;
  const double cp = rows.proximal_weight;
  const bool bilinear = !rows.projected || mode.raw;
  const bool want_J = out.WantJacobian();
  const bool held = rows.hold != nullptr;
  // The projected form's pattern couples every fraction, rate and the gap into every row; the bilinear form keeps the
  // paper's entries (a form has a pattern of its own: StepProblem::pattern_version).
  const bool coupled = rows.projected;
  const BallProjection p = bilinear || held ? BallProjection() : ProjectFriction(rows);
  // Every form emits the same entries: per slip row, the fractions, sigma, the gap and the rates.
  for (int i = 0; i < n; ++i) {
    const int row = rows.Row(i);
    const bool locked = rows.locked[i] || held;  // both rows read s_i = its value
    if (locked) {
      out.Phi[row] = held ? rows.s[i] - (*rows.hold)[row] : rows.s[i];
    } else if (bilinear) {
      out.Phi[row] = rows.rate[i] + rows.s[i] * rows.slip;
    } else {
      out.Phi[row] = rows.s[i] - p.scale * p.y[i];
    }
    if (!locked && cp > 0.0) out.Phi[row] += (bilinear ? cp : r * cp) * (rows.s[i] - (*rows.proximal_center)[row]);
    if (!want_J) continue;
    for (int j = 0; j < n; ++j) {
      if (!coupled && j != i) continue;
      const double identity = i == j ? 1.0 : 0.0;
      double a = identity;  // a locked row: s_i = 0
      if (!locked && bilinear) a = identity * (rows.slip + mode.regularization + cp);
      if (!locked && !bilinear) a = identity * (1.0 + r * cp + mode.regularization) - p.D[i][j] * (1.0 - r * g);
      out.AddJ(row, rows.Row(j), a);  // the diagonal entries carry the sparse solver's regularization
    }
    out.AddJ(row, rows.sigma, !locked && bilinear ? rows.s[i] * rows.dslip_dsigma : 0.0);
    if (rows.gap >= 0) {
      double c = 0.0;
      if (!locked && bilinear) c = rows.s[i] * rows.dslip_dgap;
      for (int k = 0; k < n && !locked && !bilinear; ++k) c += p.D[i][k] * r * rows.s[k] * rows.dslip_dgap;
      out.AddJ(row, rows.gap, c);
    }
    for (int k = 0; k < n; ++k) {
      if (!coupled && k != i) continue;
      double c = 0.0;
      if (!locked) c = bilinear ? (i == k ? 1.0 : 0.0) : r * p.D[i][k];
      rate_gradient(k, row, c);
    }
  }
  // The slip speed: bilinear, FB(sigma, zeta) (paper eq. 5); projected, sigma + s . rate + g |s|^2 = 0 (no other row
  // reads sigma there).
  if (held) {
    out.Phi[rows.sigma] = rows.sigma_value - (*rows.hold)[rows.sigma];
    if (!want_J) return;
    out.AddJ(rows.sigma, rows.sigma, 1.0);
    for (int j = 0; j < n; ++j) out.AddJ(rows.sigma, rows.Row(j), 0.0);
    if (!coupled) return;
    if (rows.gap >= 0) out.AddJ(rows.sigma, rows.gap, 0.0);
    for (int k = 0; k < n; ++k) rate_gradient(k, rows.sigma, 0.0);
    return;
  }
  double s_dot_rate = 0.0, s_norm2 = 0.0;
  for (int k = 0; k < n; ++k) {
    if (rows.locked[k]) continue;
    s_dot_rate += rows.s[k] * rows.rate[k];
    s_norm2 += rows.s[k] * rows.s[k];
  }
  const FB fb = FischerBurmeister(rows.sigma_value, rows.zeta, mode.smoothing, mode.raw);
  out.Phi[rows.sigma] = bilinear ? fb.value : rows.sigma_value + s_dot_rate + g * s_norm2;
  if (!want_J) return;
  out.AddJ(rows.sigma, rows.sigma, bilinear ? fb.da : 1.0);
  for (int j = 0; j < n; ++j) {
    double a = -2.0 * fb.db * rows.s[j];
    if (!bilinear) a = rows.locked[j] ? 0.0 : rows.rate[j] + 2.0 * g * rows.s[j];
    out.AddJ(rows.sigma, rows.Row(j), a);
  }
  if (!coupled) return;
  if (rows.gap >= 0) out.AddJ(rows.sigma, rows.gap, bilinear ? 0.0 : s_norm2 * rows.dslip_dgap);
  for (int k = 0; k < n; ++k) rate_gradient(k, rows.sigma, !bilinear && !rows.locked[k] ? rows.s[k] : 0.0);
}

}  // namespace implicit_sim
