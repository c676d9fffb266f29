// The paper's three examples (doc/paper_figures.md; reference numbers in test/data/reference/)
// run from the scene files in scenes/, with the bars of the README's table. Non-penetration is checked independently of the
// solver: closed-form lowest points for the discs and the sphere, the Ipopt distance oracle for P3.
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

using testing_support::RunScene;
using testing_support::RunStats;
using testing_support::ScenePath;


// Lowest world z of the (only) moving body's shape, from closed forms: cylinder or regular prism.
double LowestPointZ(const Body& body, const Pose& X_WB) {
  const ConvexShape& shape = body.shapes[0];
  const Pose X_WS = X_WB * shape.X_BS;
  const double r = shape.size[0], half_length = shape.size[2];
  if (shape.type == ShapeType::kCylinder) {
    const double uz = X_WS.linear()(2, 2);  // z component of the axis
    return X_WS.translation().z() - r * std::sqrt(std::max(0.0, 1.0 - uz * uz)) - half_length * std::abs(uz);
  }
  double lowest = 1e300;
  for (int k = 0; k < shape.sides; ++k) {
    const double angle = 2.0 * kPi * k / shape.sides;
    for (double s : {-1.0, 1.0}) {
      lowest = std::min(lowest, (X_WS * Vec3(r * std::cos(angle), r * std::sin(angle), s * half_length)).z());
    }
  }
  return lowest;
}

struct DiscRun {
  RunStats stats;
  double x_final = 0.0;
  double max_penetration = 0.0;  // independent: -(lowest point z), ground at z = 0
};

DiscRun RunDisc(const std::string& scene, double h) {
  const Model model = LoadSceneFromFile(ScenePath(scene));
  const int disc = model.FindBody("disc");
  DiscRun run;
  run.stats = RunScene(model, h, 5.0, [&](const Model& m, const State& s, const Data&, const StepReport&) {
    run.max_penetration = std::max(run.max_penetration, -LowestPointZ(m.bodies[disc], s.X_WB(m, disc)));
    run.x_final = s.q[0];
  });
  return run;
}

class P1SmoothDisc : public ::testing::TestWithParam<double> {};

TEST_P(P1SmoothDisc, RollsForeverWithoutEnergyLossOrPenetration) {
  const DiscRun run = RunDisc("p1_disc_rolling.urdf", GetParam());
  EXPECT_EQ(run.stats.nonconverged, 0);
  EXPECT_DOUBLE_EQ(run.stats.ke0, 6.75);
  EXPECT_LE(std::abs(run.stats.ke_final / run.stats.ke0 - 1.0), 1e-6);
  EXPECT_LE(std::abs(run.x_final + 15.0), 1e-6);
  EXPECT_LE(run.max_penetration, 1e-8);
  EXPECT_LE(run.stats.max_solver_penetration, 1e-8);
}

INSTANTIATE_TEST_SUITE_P(StepSizes, P1SmoothDisc, ::testing::Values(0.01, 0.005, 0.001));

TEST(P1PolygonalDisc, EnergyAtFiveSecondsGrowsWithTheNumberOfSidesAndStaysBelowTheSmoothDisc) {
  const DiscRun smooth = RunDisc("p1_disc_rolling.urdf", 0.01);
  const double smooth_ratio = smooth.stats.ke_final / smooth.stats.ke0;
  double previous_ratio = 0.0;
  for (int sides : {10, 20, 40, 100}) {
    SCOPED_TRACE("N = " + std::to_string(sides));
    const DiscRun run = RunDisc("p1_ngon" + std::to_string(sides) + ".urdf", 0.01);
    const double ratio = run.stats.ke_final / run.stats.ke0;
    EXPECT_EQ(run.stats.nonconverged, 0);
    EXPECT_GT(ratio, previous_ratio);   // Fig. 1(a): finer polygons lose less energy at their vertex impacts
    EXPECT_LT(ratio, smooth_ratio);
    EXPECT_LE(run.max_penetration, 1e-8);
    EXPECT_LE(run.stats.max_solver_penetration, 1e-8);
    previous_ratio = ratio;
  }
}

struct SpinCase {
  double h;
  double stop_time;  // first step end with |w_z| < 1e-6 (exact for this h)
};

class P2SpinningSphere : public ::testing::TestWithParam<SpinCase> {};

TEST_P(P2SpinningSphere, TorsionalFrictionStopsItLinearly) {
  const SpinCase c = GetParam();
  const Model model = LoadSceneFromFile(ScenePath("p2_sphere_spinning.urdf"));
  std::vector<double> t, wz;
  double stop_time = -1.0, max_v = 0.0, max_wxy = 0.0, max_ft = 0.0, max_penetration = 0.0;
  const RunStats stats = RunScene(model, c.h, 2.0, [&](const Model&, const State& s, const Data& d, const StepReport&) {
    if (s.t <= 0.9 + 1e-9) {
      t.push_back(s.t);
      wz.push_back(s.v[5]);
    }
    if (stop_time < 0.0 && std::abs(s.v[5]) < 1e-6) stop_time = s.t;
    max_v = std::max(max_v, s.v.head<3>().cwiseAbs().maxCoeff());
    max_wxy = std::max({max_wxy, std::abs(s.v[3]), std::abs(s.v[4])});
    max_ft = std::max(max_ft, d.contacts[0].friction_force_W.norm());
    max_penetration = std::max(max_penetration, 1.0 - s.q[2]);  // independent: sphere of radius 1 above z = 0
  });
  // Least-squares slope of w_z over [0, 0.9] s, the initial point included.
  t.insert(t.begin(), 0.0);
  wz.insert(wz.begin(), 1.962);
  const double n = static_cast<double>(t.size());
  double st = 0, sw = 0, stt = 0, stw = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    st += t[i];
    sw += wz[i];
    stt += t[i] * t[i];
    stw += t[i] * wz[i];
  }
  const double slope = (n * stw - st * sw) / (n * stt - st * st);
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_NEAR(slope, -1.962, 1e-3);
  EXPECT_NEAR(stop_time, c.stop_time, 0.25 * c.h);
  EXPECT_LE(max_v, 1e-8);
  EXPECT_LE(max_wxy, 1e-8);
  EXPECT_LE(max_ft, 1e-8);
  EXPECT_LE(max_penetration, 1e-8);
}

INSTANTIATE_TEST_SUITE_P(PaperAndFineStep, P2SpinningSphere,
                         ::testing::Values(SpinCase{0.07, 1.05}, SpinCase{0.01, 1.00}));

// e_r = 0: point contact without torsional friction (MuJoCo's condim 3). The torsion component leaves the friction
// ellipsoid, so the sphere spins on at its initial rate while it stays in contact, with no other motion.
TEST(P2SpinningSphere, WithoutTorsionalFrictionSpinsOn) {
  std::ifstream file(ScenePath("p2_sphere_spinning.urdf"));
  std::string urdf((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::string torsion = "e_r=\"0.4\"";
  ASSERT_NE(urdf.find(torsion), std::string::npos);
  urdf.replace(urdf.find(torsion), torsion.size(), "e_r=\"0\"");
  const Model model = LoadSceneFromString(urdf, "p2_no_torsion");
  ASSERT_EQ(model.pairs[0].friction.e_r, 0.0);
  for (const double h : {0.07, 0.01}) {
    SCOPED_TRACE("h = " + std::to_string(h));
    double max_wz_change = 0.0, max_moment = 0.0, max_ft = 0.0, max_other = 0.0, max_penetration = 0.0;
    double min_normal_force = 1e300;
    int iterations = 0, factorizations = 0;
    const RunStats stats = RunScene(model, h, 2.0, [&](const Model&, const State& s, const Data& d, const StepReport& r) {
      iterations += r.iterations;
      factorizations += r.factorizations;
      max_wz_change = std::max(max_wz_change, std::abs(s.v[5] - 1.962));
      max_other = std::max(max_other, s.v.head<5>().cwiseAbs().maxCoeff());
      max_moment = std::max(max_moment, std::abs(d.contacts[0].torsional_moment));
      max_ft = std::max(max_ft, d.contacts[0].friction_force_W.norm());
      min_normal_force = std::min(min_normal_force, d.contacts[0].normal_force);
      max_penetration = std::max(max_penetration, 1.0 - s.q[2]);  // independent: sphere of radius 1 above z = 0
    });
    EXPECT_EQ(stats.nonconverged, 0);
    EXPECT_LE(max_wz_change, 1e-9);
    EXPECT_LE(max_moment, 1e-9);
    EXPECT_LE(max_ft, 1e-8);
    EXPECT_LE(max_other, 1e-8);
    EXPECT_NEAR(min_normal_force, 9.81, 1e-6);  // m = 1 kg: it rests on the floor throughout
    EXPECT_LE(max_penetration, 1e-8);
    // The Newton matrix stays regular without the torsion: one factorization an iteration (a singular one takes the
    // singular direction's extra factorizations).
    EXPECT_EQ(factorizations, iterations);
  }
}

TEST(P3SphereOnTwoSpheres, EventsVelocityAndNonPenetrationMatchTheReference) {
  const Model model = LoadSceneFromFile(ScenePath("p3_sphere_on_two_spheres.urdf"));
  const int ball = model.FindBody("ball");
  const int pair_a = 0, pair_b = 1;
  ASSERT_EQ(model.PairName(pair_a), "ball-sphere_a");
  ASSERT_EQ(model.PairName(pair_b), "ball-sphere_b");
  int toggles[2] = {0, 0};
  bool active[2] = {true, true};  // both touch at t = 0
  double separation[2] = {-1.0, -1.0}, slide_b = -1.0, max_bound = 0.0, max_closed_form = 0.0;
  double max_oracle_gap_error = 0.0;
  int oracle_checks = 0;
  Vec3 v_at_3_5 = Vec3::Constant(NAN);
  const RunStats stats = RunScene(model, 0.01, 5.0, [&](const Model& m, const State& s, const Data& d, const StepReport&) {
    for (int c : {pair_a, pair_b}) {
      const ContactResult& contact = d.contacts[c];
      const bool now = contact.normal_force > 1e-9;
      if (now != active[c]) ++toggles[c];
      if (!now && separation[c] < 0.0) separation[c] = s.t;
      active[c] = now;
      const int other = m.pairs[c].body2;
      // Independent checks: the oracle certifies the solver's separating plane; the closed form for spheres.
      max_bound = std::max(max_bound, PenetrationBound(m.bodies[ball].shapes[0], s.X_WB(m, ball), m.bodies[other].shapes[0],
                                                       s.X_WB(m, other), contact.p_WA2, contact.n_W));
      const double centre_distance = (s.X_WB(m, ball).translation() - s.X_WB(m, other).translation()).norm();
      if (contact.gap > 1e-3 && std::lround(s.t * 100) % 10 == 0) {  // separated: the oracle's closest points
        const ClosestPointsResult cp =
            ComputeClosestPoints(m.bodies[ball].shapes[0], s.X_WB(m, ball), m.bodies[other].shapes[0], s.X_WB(m, other));
        ASSERT_TRUE(cp.solved);
        max_oracle_gap_error = std::max({max_oracle_gap_error, std::abs(cp.distance - contact.gap),
                                         (cp.p_W1 - contact.p_WA1).norm(), (cp.p_W2 - contact.p_WA2).norm()});
        ++oracle_checks;
      }
      max_closed_form = std::max(max_closed_form, m.bodies[other].shapes[0].size[0] + 1.0 - centre_distance);
    }
    if (slide_b < 0.0 && active[pair_b] && d.contacts[pair_b].slip_speed > 1e-4) slide_b = s.t;
    if (std::abs(s.t - 3.5) < 1e-9) v_at_3_5 = s.v.head<3>();
  });
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_EQ(toggles[pair_a], 1);  // separates once and never touches again
  EXPECT_EQ(toggles[pair_b], 1);
  EXPECT_NEAR(separation[pair_a], 3.2132, 0.02);
  EXPECT_NEAR(separation[pair_b], 3.7016, 0.02);
  EXPECT_NEAR(slide_b, 2.9448, 0.02);
  const Vec3 v_ref(4.852055739686922, 0.14948342010862542, -4.083242953676649);
  EXPECT_LE((v_at_3_5 - v_ref).norm(), 0.03 * v_ref.norm()) << "v(3.5 s) = " << v_at_3_5.transpose();
  EXPECT_LE(max_bound, 1e-8);
  EXPECT_LE(max_closed_form, 1e-8);
  EXPECT_GT(oracle_checks, 20);
  EXPECT_LE(max_oracle_gap_error, 1e-6);
  EXPECT_LE(stats.max_solver_penetration, 1e-8);
}

}  // namespace
}  // namespace implicit_sim
