// FischerBurmeister: value and derivatives against finite differences away from the kink, the diagonal element of the
// generalized Jacobian at (0, 0), the root set of the smoothed function (a, b > 0, a b = mu^2), and the raw mode.
#include "implicit_sim/core/ncp/fischer_burmeister.h"

#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace implicit_sim {
namespace {

const std::vector<std::pair<double, double>> kPoints = {{1.0, 2.0}, {-0.5, 0.3}, {0.7, -1.1}, {-2.0, -0.4},
                                                        {3.0, 0.0}, {0.0, 0.25}, {1e-3, 1e-3}, {-1.0, 1.0}};

double Value(double a, double b, double mu) { return FischerBurmeister(a, b, mu, false).value; }

TEST(FischerBurmeister, IsZeroExactlyOnTheComplementaritySet) {
  for (double t : {0.0, 1e-8, 0.5, 3.0}) {
    EXPECT_EQ(Value(t, 0.0, 0.0), 0.0);
    EXPECT_EQ(Value(0.0, t, 0.0), 0.0);
  }
  EXPECT_GT(Value(1.0, 1.0, 0.0), 0.0);                             // both positive: 2 - sqrt 2
  EXPECT_NEAR(Value(1.0, 1.0, 0.0), 2.0 - std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(Value(-1.0, 2.0, 0.0), 1.0 - std::sqrt(5.0), 1e-15);  // a < 0
  EXPECT_NEAR(Value(3.0, -4.0, 0.0), -6.0, 1e-15);                  // 3 - 4 - 5
}

TEST(FischerBurmeister, DerivativesMatchCentralDifferencesAwayFromTheKink) {
  for (double mu : {0.0, 0.3}) {
    for (const auto& [a, b] : kPoints) {
      SCOPED_TRACE(::testing::Message() << "a " << a << " b " << b << " mu " << mu);
      const double h = 1e-6 * std::sqrt(a * a + b * b + 2 * mu * mu);  // relative to the distance to the kink
      const FB fb = FischerBurmeister(a, b, mu, false);
      EXPECT_EQ(fb.value, a + b - std::sqrt(a * a + b * b + 2 * mu * mu));
      EXPECT_NEAR(fb.da, (Value(a + h, b, mu) - Value(a - h, b, mu)) / (2 * h), 1e-8);
      EXPECT_NEAR(fb.db, (Value(a, b + h, mu) - Value(a, b - h, mu)) / (2 * h), 1e-8);
    }
  }
}

TEST(FischerBurmeister, TakesTheDiagonalElementAtTheKink) {
  const double diagonal = 1.0 - 1.0 / std::sqrt(2.0);
  const FB kink = FischerBurmeister(0.0, 0.0, 0.0, false);
  EXPECT_EQ(kink.value, 0.0);
  EXPECT_EQ(kink.da, diagonal);
  EXPECT_EQ(kink.db, diagonal);
  // The limit of the gradient along a = b > 0, so an element of the generalized Jacobian.
  const FB near = FischerBurmeister(1e-9, 1e-9, 0.0, false);
  EXPECT_NEAR(near.da, diagonal, 1e-15);
  EXPECT_NEAR(near.db, diagonal, 1e-15);
  // Every element (1 - cos t, 1 - sin t) of the subdifferential has both derivatives in [0, 2], not both 0.
  EXPECT_GT(kink.da + kink.db, 0.0);
}

TEST(FischerBurmeister, SmoothedRootsAreThePositiveHyperbolaBranch) {
  for (double mu : {0.1, 0.5, 2.0}) {
    for (double b : {0.01, 0.3, 1.0, 7.0}) {
      const double a = mu * mu / b;  // a b = mu^2
      EXPECT_NEAR(Value(a, b, mu), 0.0, 1e-14 * (a + b)) << "mu " << mu << " b " << b;
      EXPECT_LT(Value(-a, -b, mu), -(a + b));  // the negative branch: a b = mu^2 but not a root
    }
    EXPECT_LT(Value(0.0, 1.0, mu), 0.0);  // the complementarity set is no longer a root
    EXPECT_LT(Value(1.0, 0.0, mu), 0.0);
  }
}

TEST(FischerBurmeister, SmoothedSignFollowsABMinusMuSquaredWhereAPlusBIsPositive) {
  // (a + b)^2 - (a^2 + b^2 + 2 mu^2) = 2 (a b - mu^2): so FB_mu = 0 iff a + b >= 0 and a b = mu^2.
  const double mu = 0.5;
  for (double a = -2.0; a <= 2.0; a += 0.125) {
    for (double b = -2.0; b <= 2.0; b += 0.125) {
      if (a + b <= 0.0 || std::abs(a * b - mu * mu) < 1e-12) continue;
      EXPECT_EQ(Value(a, b, mu) > 0.0, a * b > mu * mu) << "a " << a << " b " << b;
    }
  }
}

TEST(FischerBurmeister, SmoothingVanishesWithMu) {
  for (const auto& [a, b] : kPoints) {
    EXPECT_NEAR(Value(a, b, 1e-9), Value(a, b, 0.0), 1e-14) << "a " << a << " b " << b;
  }
  EXPECT_NEAR(Value(0.0, 0.0, 1e-3), -std::sqrt(2.0) * 1e-3, 1e-18);
}

TEST(FischerBurmeister, RawModeReturnsTheFunctionSide) {
  for (double mu : {0.0, 0.4}) {
    for (const auto& [a, b] : kPoints) {
      const FB raw = FischerBurmeister(a, b, mu, true);
      EXPECT_EQ(raw.value, b);
      EXPECT_EQ(raw.da, 0.0);
      EXPECT_EQ(raw.db, 1.0);
    }
  }
}

}  // namespace
}  // namespace implicit_sim
