// The friction rows' two forms (step/rows/friction_rows.h) on one set of fractions: the projected rows' Jacobian
// against central differences, inside and outside the ball, with a locked component, a separated pair and the proximal
// term; and both forms vanish at the same sliding and sticking solutions.
#include "implicit_sim/core/step/rows/friction_rows.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace implicit_sim {
namespace {

// The unknowns of the test: s_0..s_{n-1}, sigma, d, then rate_0..rate_{n-1} (which the caller's rows would compute).
struct FrictionRowsPoint {
  int count = 3;
  bool locked[FrictionRows::kMaxCount] = {};
  double h = 0.01;  // s
  bool separated_rows = true;
  double r = 1.0;   // s/m
  double proximal_weight = 0.0;
  Eigen::VectorXd center;
  int size() const { return 2 * count + 2; }
};

// Rows 0..n-1 the slip rows, n the sigma row; the rate gradients go to the rate columns.
void EvaluateFrictionRows(const FrictionRowsPoint& p, const Eigen::VectorXd& x, bool projected, bool raw,
                          Eigen::VectorXd* Phi, Eigen::MatrixXd* J) {
  const int n = p.count;
  FrictionRows rows;
  rows.first_row = 0;
  rows.roll_row = 3;
  rows.count = n;
  rows.sigma = n;
  rows.gap = n + 1;
  const double d = x[n + 1];
  for (int k = 0; k < n; ++k) {
    rows.s[k] = x[k];
    rows.rate[k] = x[n + 2 + k];
    rows.locked[k] = p.locked[k];
  }
  rows.sigma_value = x[n];
  rows.separation = p.separated_rows ? std::max(d, 0.0) / p.h : 0.0;
  rows.slip = x[n] + rows.separation;
  rows.dslip_dgap = p.separated_rows && d > 0.0 ? 1.0 / p.h : 0.0;
  rows.zeta = 1.0;
  for (int k = 0; k < n; ++k) rows.zeta -= x[k] * x[k];
  rows.projected = projected;
  rows.projection_scale = p.r;
  rows.proximal_weight = p.proximal_weight;
  if (p.proximal_weight > 0.0) rows.proximal_center = &p.center;
  NcpEvalMode mode;
  mode.raw = raw;
  Phi->setZero(p.size());
  J->setZero(p.size(), p.size());
  const std::vector<char> no_locked_velocities;
  const auto rate_gradient = [&](int k, int row, double coeff) { (*J)(row, n + 2 + k) += coeff; };
  AddFrictionRows(rows, RowWriter(mode, Phi, J, nullptr, no_locked_velocities), RateGradient(rate_gradient));
}

void ExpectFrictionRowsJacobianMatches(const FrictionRowsPoint& p, const Eigen::VectorXd& x) {
  Eigen::VectorXd Phi, Phi_plus, Phi_minus;
  Eigen::MatrixXd J, unused;
  EvaluateFrictionRows(p, x, true, false, &Phi, &J);
  const double eps = 1e-6;
  for (int j = 0; j < p.size(); ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus[j] += eps;
    minus[j] -= eps;
    EvaluateFrictionRows(p, plus, true, false, &Phi_plus, &unused);
    EvaluateFrictionRows(p, minus, true, false, &Phi_minus, &unused);
    const Eigen::VectorXd column = (Phi_plus - Phi_minus) / (2.0 * eps);
    for (int i = 0; i <= p.count; ++i) {
      EXPECT_NEAR(J(i, j), column[i], 1e-6 * (1.0 + std::abs(J(i, j)))) << "row " << i << ", column " << j;
    }
  }
}

TEST(FrictionRows, ProjectedJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int inside = 0, outside = 0;
  for (int trial = 0; trial < 40; ++trial) {
    FrictionRowsPoint p;
    p.count = trial % 2 == 0 ? 3 : 5;
    p.locked[1] = trial % 4 == 1;
    p.r = trial % 3 == 0 ? 1.0 : 20.0;
    p.separated_rows = trial % 5 != 0;
    Eigen::VectorXd x(p.size());
    for (int i = 0; i < x.size(); ++i) x[i] = 0.5 * u(rng);
    x[p.count + 1] = trial % 2 == 0 ? -0.001 : 0.002 * (1.0 + u(rng));  // d: touching or apart
    for (int k = 0; k < p.count; ++k) x[p.count + 2 + k] *= trial % 3 == 0 ? 0.1 : 0.02;  // rates (m/s)
    if (trial % 7 == 3) {
      p.proximal_weight = 0.5;
      p.center = Eigen::VectorXd::Constant(p.size(), 0.1);
    }
    double norm2 = 0.0;  // which side of the ball the point is on (the rows' own y)
    const double g = p.separated_rows ? std::max(x[p.count + 1], 0.0) / p.h : 0.0;
    for (int k = 0; k < p.count; ++k) {
      if (p.locked[k]) continue;
      const double y = x[k] * (1.0 - p.r * g) - p.r * x[p.count + 2 + k];
      norm2 += y * y;
    }
    (norm2 <= 1.0 ? inside : outside)++;
    SCOPED_TRACE("trial " + std::to_string(trial));
    ExpectFrictionRowsJacobianMatches(p, x);
  }
  EXPECT_GE(inside, 5);
  EXPECT_GE(outside, 5);
}

// Sliding (s = -rate / |rate|, sigma = |rate| - g) and sticking (rate + g s = 0, sigma = 0) zero both forms' rows, and
// a point that slides with its friction inside the ellipsoid (the bilinear rows' stall) zeroes the bilinear slip rows
// but not the projected ones.
TEST(FrictionRows, BothFormsShareTheirSolutions) {
  FrictionRowsPoint p;
  p.count = 3;
  Eigen::VectorXd Phi;
  Eigen::MatrixXd J;
  for (const double d : {0.0, 0.0005}) {  // touching, and apart by 0.5 mm (g = 0.05 m/s)
    const double g = d / p.h;
    const Eigen::Vector3d rate(0.3, -0.4, 0.12);
    Eigen::VectorXd sliding(p.size());
    sliding << -rate / rate.norm(), rate.norm() - g, d, rate;
    Eigen::VectorXd sticking(p.size());
    const Eigen::Vector3d s_stick(0.2, -0.5, 0.1);
    sticking << s_stick, 0.0, d, -g * s_stick;
    for (const bool projected : {true, false}) {
      for (const Eigen::VectorXd* x : {&sliding, &sticking}) {
        EvaluateFrictionRows(p, *x, projected, false, &Phi, &J);
        EXPECT_LT(Phi.head(4).lpNorm<Eigen::Infinity>(), 1e-15) << (projected ? "projected" : "bilinear") << ", d " << d;
        EvaluateFrictionRows(p, *x, projected, true, &Phi, &J);  // raw rows: the bilinear ones, zeta >= 0 _|_ sigma >= 0
        EXPECT_LT(Phi.head(3).lpNorm<Eigen::Infinity>(), 1e-15);
        EXPECT_LT(std::abs(std::min(Phi[3], (*x)[3])), 1e-15);
      }
    }
  }
  Eigen::VectorXd stalled(p.size());
  const Eigen::Vector3d s_in(0.3, 0.2, 0.1), slip_rate = -0.05 * s_in;  // sigma = 0.05 m/s, |s| < 1
  stalled << s_in, 0.05, 0.0, slip_rate;
  EvaluateFrictionRows(p, stalled, false, false, &Phi, &J);
  EXPECT_LT(Phi.head(3).lpNorm<Eigen::Infinity>(), 1e-15);  // the bilinear slip rows hold; only the FB row does not
  EXPECT_GT(std::abs(Phi[3]), 1e-3);
  EvaluateFrictionRows(p, stalled, true, false, &Phi, &J);
  EXPECT_GT(Phi.head(3).lpNorm<Eigen::Infinity>(), 1e-3);  // the projected rows see it in the slip rows themselves
}

}  // namespace
}  // namespace implicit_sim
