#include "implicit_sim/core/step/rows/friction_rows.h"

#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/rows/row_context.h"

namespace implicit_sim {

const BodyEnd RowContext::kWorld = BodyEnd();

double ProjectedSlip(const NcpEvalMode& mode, double sigma, double* derivative) {
  const bool clamp = mode.project_multipliers && !mode.raw && sigma < 0.0;
  *derivative = clamp ? 0.0 : 1.0;
  return clamp ? 0.0 : sigma;
}

void AddFrictionRows(const FrictionRows& rows, const RowWriter& out) {
  const NcpEvalMode& mode = out.mode;
  const double cp = rows.proximal_weight;
  for (int k = 0; k < rows.count; ++k) {
    const int row = rows.Row(k);
    out.Phi[row] = rows.rate[k] + rows.s[k] * rows.slip;
    if (cp > 0.0) out.Phi[row] += cp * (rows.s[k] - (*rows.proximal_center)[row]);
  }
  const FB fb = FischerBurmeister(rows.sigma_value, rows.zeta, mode.smoothing, mode.raw);
  out.Phi[rows.sigma] = fb.value;
  if (!out.WantJacobian()) return;
  for (int k = 0; k < rows.count; ++k) {
    const int row = rows.Row(k);
    // The diagonal entries carry the sparse solver's proximal regularization (never Phi).
    out.AddJ(row, row, rows.slip + mode.regularization + cp);
    out.AddJ(row, rows.sigma, rows.s[k] * rows.dslip_dsigma);
    if (rows.gap >= 0) out.AddJ(row, rows.gap, rows.s[k] * rows.dslip_dgap);
  }
  out.AddJ(rows.sigma, rows.sigma, fb.da);
  for (int k = 0; k < rows.count; ++k) out.AddJ(rows.sigma, rows.Row(k), -2.0 * fb.db * rows.s[k]);
}

}  // namespace implicit_sim
