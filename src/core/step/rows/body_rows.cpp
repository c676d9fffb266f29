#include "implicit_sim/core/step/rows/body_rows.h"

#include <cmath>

#include "implicit_sim/core/base/rotation.h"

namespace implicit_sim {
namespace {

Vec3 Vee(const Mat3& S) { return Vec3(S(2, 1), S(0, 2), S(1, 0)); }

// The i-th moving body of the layout as its body rows see it.
struct BodyRowsOf {
  BodyRowsOf(const RowContext& ctx, int i)
      : local(ctx.layout.slot_body(i)),
        body(ctx.model().bodies[ctx.layout.bodies()[local]]),
        row(6 * i),
        f_ext(ctx.kinematics.ExternalForce(i)),
        tau_ext(ctx.kinematics.ExternalTorque(i)) {}
  const int local;    // index into layout.bodies()
  const Body& body;
  const int row;      // its first row and velocity column
  const Vec3 f_ext, tau_ext;  // N, N m over the step
};

}  // namespace

void AddEndMomentumRows(const RowContext& ctx) {
  const double Fs = ctx.Fs(), h = ctx.h();
  const std::vector<int>& slots = ctx.layout.slots();
  for (size_t i = 0; i < slots.size(); ++i) {
    const BodyRowsOf b(ctx, static_cast<int>(i));
    const Body& body = b.body;
    const BodyStart& s = ctx.kinematics.start(b.local);
    const BodyEnd& e = ctx.ends[b.local];
    const int row = b.row;
    const Vec3& f_ext = b.f_ext;
    const Vec3& tau_ext = b.tau_ext;
    ctx.out.AddJ(row, row, Mat3(Mat3::Identity() * body.mass / (h * Fs)));
    ctx.out.Phi.segment<3>(row) = (body.mass * (ctx.z.segment<3>(row) - s.v0) / h - f_ext) / Fs;
    // Angular momentum form: (I_W(R1) w1 - I_W(R0) w0) / h = torque, with R1 = Exp(h w1) R0. It conserves angular
    // momentum exactly without torque.
    const Mat3 I_W1 = e.R * body.I_B * e.R.transpose();
    const Vec3 w1 = ctx.z.segment<3>(row + 3);
    ctx.out.Phi.segment<3>(row + 3) = ((I_W1 * w1 - s.I_W0 * s.w0) / h - tau_ext) / Fs;
    // d(I_W w)/dtheta = I_W [w]x - [I_W w]x for R -> Exp(dtheta) R, and dtheta/dw1 = h J_l(h w1).
    ctx.out.AddJ(row + 3, row + 3, Mat3((I_W1 + (I_W1 * Skew(w1) - Skew(I_W1 * w1)) * e.dtheta_dw) / (h * Fs)));
  }
}

void AddHalfStepMomentumRows(const RowContext& ctx) {
  const double Fs = ctx.Fs(), h = ctx.h();
  const std::vector<int>& slots = ctx.layout.slots();
  for (size_t i = 0; i < slots.size(); ++i) {
    const BodyRowsOf b(ctx, static_cast<int>(i));
    const Body& body = b.body;
    const BodyStart& s = ctx.kinematics.start(b.local);
    const BodyEnd& e = ctx.ends[b.local];
    const int row = b.row;
    const Vec3& f_ext = b.f_ext;
    const Vec3& tau_ext = b.tau_ext;
    ctx.out.AddJ(row, row, Mat3(Mat3::Identity() * body.mass / (h * Fs)));
    ctx.out.Phi.segment<3>(row) = (body.mass * (ctx.z.segment<3>(row) - s.v0) / h - 0.5 * f_ext) / Fs;
    Mat3 dL_dtheta, dL_dw;
    const Vec3 L_half = DiscreteMomentum(body.I_B, s.R0, e.R, e.w, h, &dL_dtheta, &dL_dw);
    ctx.out.Phi.segment<3>(row + 3) = ((L_half - s.I_W0 * s.w0) / h - 0.5 * tau_ext) / Fs;
    ctx.out.AddJ(row + 3, row + 3, Mat3((dL_dtheta * e.dtheta_dw + dL_dw) / (h * Fs)));
  }
}

void AddFixedGeometryMomentumRows(const RowContext& ctx, const std::vector<BodyHalf>& half) {
  const double Fs = ctx.Fs(), h = ctx.h();
  const std::vector<int>& slots = ctx.layout.slots();
  for (size_t i = 0; i < slots.size(); ++i) {
    const BodyRowsOf rows(ctx, static_cast<int>(i));
    const Body& body = rows.body;
    const BodyHalf& b = half[rows.local];
    const int row = rows.row;
    const Mat3 I_W1 = b.R1 * body.I_B * b.R1.transpose();
    ctx.out.Phi.segment<3>(row) = (body.mass * (ctx.z.segment<3>(row) - b.v_half) / h - 0.5 * rows.f_ext) / Fs;
    ctx.out.Phi.segment<3>(row + 3) = ((I_W1 * ctx.z.segment<3>(row + 3) - b.L_half) / h - 0.5 * rows.tau_ext) / Fs;
    ctx.out.AddJ(row, row, Mat3(Mat3::Identity() * body.mass / (h * Fs)));
    ctx.out.AddJ(row + 3, row + 3, Mat3(I_W1 / (h * Fs)));
  }
}

// Moser-Veselov / Lee-Leok-McClamroch: with Jd = tr(J)/2 I - J and F = R0^T R1 = Exp(h R0^T w), the discrete
// momentum (1/h) R0 vee(F Jd - Jd F^T), divided by g = sinc(h |w|). For R1 -> Exp(theta) R1, F -> Exp(R0^T theta) F
// and vee([e]x B + B^T [e]x) = (tr(B) I - B) e with B = F Jd.
// Why the division by g (our modification): the plain row spins a body about a principal axis by asin(h w) a step
// instead of h w, an O(h^2) phase error that a rolling disc turns into a drift of its position (P1). Divided by g, a
// principal spin is exact for any h w; the energy of a free body is still conserved exactly, and the row stays
// symmetric (g depends only on the angle of F), so the step stays second order (doc/method.md).
// Near h |w| = pi (g -> 0) a general rotation has no solution: the solve fails and the stepper splits the step.
Vec3 DiscreteMomentum(const Mat3& I_B, const Mat3& R0, const Mat3& R1, const Vec3& w, double h, Mat3* dL_dtheta,
                      Mat3* dL_dw) {
  const Mat3 Jd = 0.5 * I_B.trace() * Mat3::Identity() - I_B;
  const Mat3 B = R0.transpose() * R1 * Jd;
  const Vec3 L_plain = R0 * Vee(B - B.transpose()) / h;
  // g = sin(a) / a with a = h |w|, and dg/dw = g'(a) h w^T / |w| (series below a = 1e-4).
  const double a = h * w.norm();
  double g, dg_da_over_a;
  if (a < 1e-4) {
    g = 1.0 - a * a / 6.0;
    dg_da_over_a = -1.0 / 3.0 + a * a / 30.0;
  } else {
    g = std::sin(a) / a;
    dg_da_over_a = (a * std::cos(a) - std::sin(a)) / (a * a * a);
  }
  if (dL_dtheta) *dL_dtheta = R0 * (B.trace() * Mat3::Identity() - B) * R0.transpose() / (h * g);
  if (dL_dw) *dL_dw = -L_plain * (dg_da_over_a * h * h * w.transpose()) / (g * g);
  return L_plain / g;
}

}  // namespace implicit_sim
