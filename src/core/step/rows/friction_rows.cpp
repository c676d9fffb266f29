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

void AddFrictionRows(const FrictionRows& rows, const RowWriter& out) {
  const NcpEvalMode& mode = out.mode;
  const double cp = rows.proximal_weight;
  for (int k = 0; k < rows.count; ++k) {
    const int row = rows.Row(k);
    if (rows.locked[k]) {
      out.Phi[row] = rows.s[k];
      continue;
    }
    out.Phi[row] = rows.rate[k] + rows.s[k] * rows.slip;
    if (cp > 0.0) out.Phi[row] += cp * (rows.s[k] - (*rows.proximal_center)[row]);
  }
  const FB fb = FischerBurmeister(rows.sigma_value, rows.zeta, mode.smoothing, mode.raw);
  out.Phi[rows.sigma] = fb.value;
  if (!out.WantJacobian()) return;
  for (int k = 0; k < rows.count; ++k) {
    const int row = rows.Row(k);
    const double on = rows.locked[k] ? 0.0 : 1.0;  // a locked row emits the same entries: 1 on its diagonal, else 0
    // The diagonal entries carry the sparse solver's proximal regularization (never Phi).
    out.AddJ(row, row, rows.locked[k] ? 1.0 : rows.slip + mode.regularization + cp);
    out.AddJ(row, rows.sigma, on * rows.s[k] * rows.dslip_dsigma);
    if (rows.gap >= 0) out.AddJ(row, rows.gap, on * rows.s[k] * rows.dslip_dgap);
  }
  out.AddJ(rows.sigma, rows.sigma, fb.da);
  for (int k = 0; k < rows.count; ++k) out.AddJ(rows.sigma, rows.Row(k), -2.0 * fb.db * rows.s[k]);
}

}  // namespace implicit_sim
