// Contact between moving bodies of every kind of shape: resting stacks carry exactly their weight without drift,
// with non-penetration checked independently (closed-form corners, the distance oracle).
#include <cmath>

#include <gtest/gtest.h>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

using test_models::FixedBody;
using test_models::MakePose;
using test_models::MovingBody;

double ForceBetween(const Model& model, const Data& data, const std::string& a, const std::string& b) {
  for (size_t c = 0; c < model.pairs.size(); ++c) {
    if (model.PairName(c) == a + "-" + b || model.PairName(c) == b + "-" + a) return data.contacts[c].normal_force;
  }
  ADD_FAILURE() << "no pair " << a << "-" << b;
  return NAN;
}

TEST(BodyContacts, StackOfThreeBoxesCarriesItsWeightWithoutDrift) {
  Model m;
  m.bodies.push_back(FixedBody("ground", MakeHalfSpace()));
  const Vec3 half(0.1, 0.08, 0.05);
  for (int i = 0; i < 3; ++i) {
    m.bodies.push_back(MovingBody("box" + std::to_string(i), MakeBox(half), 1.0 + i,
                                  MakePose(Vec3(0.0, 0.0, 0.05 + 0.1 * i))));
  }
  const Model model = test_models::Finish(m);
  const double g = 9.81;
  double max_drift = 0.0, max_error = 0.0, lowest_gap = 1.0;
  const auto stats = testing_support::RunScene(model, 0.01, 10.0,
                                               [&](const Model& mm, const State& s, const Data& d, const StepReport&) {
    for (int i = 0; i < 3; ++i) {
      max_drift = std::max(max_drift, (s.q.segment<3>(Model::q_offset(i)) - mm.bodies[1 + i].X_WB0.translation()).norm());
    }
    // Masses 1, 2, 3 kg from the bottom: each interface carries the weight of everything above it.
    max_error = std::max({max_error, std::abs(ForceBetween(mm, d, "box0", "ground") - 6.0 * g) / (6.0 * g),
                          std::abs(ForceBetween(mm, d, "box0", "box1") - 5.0 * g) / (5.0 * g),
                          std::abs(ForceBetween(mm, d, "box1", "box2") - 3.0 * g) / (3.0 * g)});
    for (const ContactResult& c : d.contacts) lowest_gap = std::min(lowest_gap, c.gap);
  });
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_LT(max_error, 1e-3);   // normal forces equal the weight above within 0.1 %
  EXPECT_LT(max_drift, 1e-6);   // no drift over 10 s
  EXPECT_GE(lowest_gap, -1e-8);
}

TEST(BodyContacts, TwoEllipsoidsRestOnEachOtherOnTheGround) {
  Model m;
  m.bodies.push_back(FixedBody("ground", MakeHalfSpace()));
  m.bodies.push_back(MovingBody("lower", MakeEllipsoid(Vec3(0.3, 0.2, 0.1)), 2.0, MakePose(Vec3(0, 0, 0.1))));
  m.bodies.push_back(MovingBody("upper", MakeEllipsoid(Vec3(0.15, 0.1, 0.08)), 0.5, MakePose(Vec3(0, 0, 0.28))));
  const Model model = test_models::Finish(m);
  double max_bound = 0.0, max_drift = 0.0;
  double f_lower = 0.0, f_upper = 0.0;
  int step = 0;
  const auto stats = testing_support::RunScene(model, 0.01, 3.0,
                                               [&](const Model& mm, const State& s, const Data& d, const StepReport&) {
    f_lower = ForceBetween(mm, d, "lower", "ground");
    f_upper = ForceBetween(mm, d, "lower", "upper");
    max_drift = std::max(max_drift, (s.q.segment<3>(7) - Vec3(0, 0, 0.28)).norm());
    if (++step % 30 == 0) {  // the oracle certifies the solver's separating planes
      for (size_t c = 0; c < mm.pairs.size(); ++c) {
        const ContactPair& p = mm.pairs[c];
        max_bound = std::max(max_bound, PenetrationBound(mm.shape(p.geom1), s.X_WB(mm, p.body1),
                                                         mm.shape(p.geom2), s.X_WB(mm, p.body2),
                                                         d.contacts[c].p_WA2, d.contacts[c].n_W));
      }
    }
  });
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_NEAR(f_lower, 2.5 * 9.81, 1e-6);
  EXPECT_NEAR(f_upper, 0.5 * 9.81, 1e-6);
  EXPECT_LT(max_drift, 1e-9);
  EXPECT_LE(max_bound, 1e-8);
}

}  // namespace
}  // namespace implicit_sim

namespace implicit_sim {
namespace {

// A moving shape falls onto a fixed one; while separated the stepper's closest points match the oracle's.
void ExpectClosestPointsMatchOracleWhileFalling(const ConvexShape& moving, const ConvexShape& fixed) {
  Model m;
  m.gravity_W = Vec3(0.0, 0.0, -3.0);
  m.bodies.push_back(test_models::FixedBody("base", fixed, MakePose(Vec3::Zero(), test_models::Rot(0.4, Vec3(1, 0, 1)))));
  m.bodies.push_back(MovingBody("part", moving, 1.0, MakePose(Vec3(0.05, -0.03, 0.7), test_models::Rot(1.1, Vec3(0, 1, 1)))));
  m.bodies.back().w_WB0 = Vec3(0.4, -0.8, 1.5);
  const Model model = test_models::Finish(m);
  const testing_support::OracleComparison r = testing_support::CompareClosestPointsWithOracle(model, 0.01, 0.6);
  ASSERT_EQ(r.nonconverged, 0);
  EXPECT_GT(r.checks, 10);
  EXPECT_LT(r.worst, 1e-5);
  EXPECT_GE(r.min_gap, -1e-8);
}

TEST(BodyContacts, SuperellipsoidOnSuperellipsoidMatchesTheOracle) {
  ExpectClosestPointsMatchOracleWhileFalling(MakeSuperellipsoid(Vec3(0.15, 0.1, 0.08), 4.0),
                                             MakeSuperellipsoid(Vec3(0.4, 0.3, 0.2), 6.0));
}

TEST(BodyContacts, MixedPairsMatchTheOracle) {
  ExpectClosestPointsMatchOracleWhileFalling(MakeSphere(0.1), MakeEllipsoid(Vec3(0.4, 0.3, 0.2)));
  ExpectClosestPointsMatchOracleWhileFalling(MakeEllipsoid(Vec3(0.15, 0.1, 0.08)), MakeSphere(0.3));
  ExpectClosestPointsMatchOracleWhileFalling(MakeSuperellipsoid(Vec3(0.15, 0.1, 0.08), 4.0), MakeSphere(0.3));
  ExpectClosestPointsMatchOracleWhileFalling(MakeCylinder(0.1, 0.08), MakeEllipsoid(Vec3(0.4, 0.3, 0.2)));
}

}  // namespace
}  // namespace implicit_sim
