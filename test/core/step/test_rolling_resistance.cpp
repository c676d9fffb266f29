// Rolling resistance (FrictionParams::e_roll; doc/method.md, "Rolling resistance"): a sphere rolling on a plane
// decelerates at the closed-form rate and stops at the closed-form time, with both schemes; a rocking rounded box comes
// to rest under the second-order step, which without it rocks on.
#include <cmath>

#include <gtest/gtest.h>

#include "implicit_sim/core/step/time_stepper.h"

#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

using testing_support::RunScene;

constexpr double kG = 9.81;

// The sphere's motion under Coulomb friction and rolling resistance in one friction ellipsoid. With the slip
// u = v - R w (contact point velocity along the motion, m/s) and the rolling rate w (rad/s), maximal dissipation
// gives the force F = -mu N e_t^2 u / S and the moment M = -mu N e_roll^2 w / S, S = sqrt(e_t^2 u^2 + e_roll^2 w^2).
// The ratio kappa = u / w stays constant when it solves
//   R e_t^2 kappa^2 + (e_t^2 (I/m + R^2) - e_roll^2) kappa - R e_roll^2 = 0,
// and then v and w fall linearly and reach zero together.
struct RollingSphere {
  double R = 0.1, m = 1.0, mu = 0.5, e_t = 1.0, e_roll = 0.005;
  double I() const { return 0.4 * m * R * R; }
  double kappa() const {
    const double a = R * e_t * e_t, b = e_t * e_t * (I() / m + R * R) - e_roll * e_roll, c = -R * e_roll * e_roll;
    return (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
  }
  double D() const { return std::hypot(e_t * kappa(), e_roll); }
  double w_dot() const { return mu * m * kG / (D() * I()) * (R * e_t * e_t * kappa() - e_roll * e_roll); }  // rad/s^2
  double v_dot() const { return -mu * m * kG * e_t * e_t * kappa() / (D() * m); }                          // m/s^2
};

Model SphereRollingOnPlane(const RollingSphere& s, double w0) {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  Body ball = test_models::MovingBody("ball", MakeSphere(s.R), s.m, test_models::MakePose(Vec3(0, 0, s.R)));
  ball.w_WB0 = Vec3(0, w0, 0);
  ball.v_WB0 = Vec3((s.R + s.kappa()) * w0, 0, 0);  // u = v - R w = kappa w: on the closed form's ray from the start
  m.bodies.push_back(ball);
  FrictionParams friction{s.mu, s.e_t, s.e_t, 0.01};
  friction.e_roll = s.e_roll;
  return test_models::Finish(m, friction);
}

void ExpectClosedFormRolling(StepperOptions::Scheme scheme) {
  const RollingSphere s;
  const double w0 = 5.0, h = 0.01, stop = w0 / -s.w_dot();
  ASSERT_GT(stop, 2.0);  // about 2.9 s
  ASSERT_NEAR(s.v_dot(), s.R * s.w_dot() + s.kappa() * s.w_dot(), 1e-12);  // the ray's consistency
  const Model model = SphereRollingOnPlane(s, w0);
  StepperOptions options;
  options.h = h;
  options.scheme = scheme;
  double worst_w = 0.0, worst_v = 0.0, rest_speed = 0.0, max_penetration = 0.0;
  int steps = 0;
  const auto stats = RunScene(model, options, stop + 0.5, [&](const Model&, const State& st, const Data& data,
                                                               const StepReport&) {
    ++steps;
    const double t = st.t;
    const Vec3 v = st.v.segment<3>(Model::v_offset(0)), w = st.v.segment<3>(Model::v_offset(0) + 3);
    for (const ContactResult& c : data.contacts) max_penetration = std::max(max_penetration, -c.gap);
    if (t < stop - 2 * h) {
      worst_w = std::max(worst_w, std::abs(w.y() - (w0 + s.w_dot() * t)));
      worst_v = std::max(worst_v, std::abs(v.x() - ((s.R + s.kappa()) * w0 + s.v_dot() * t)));
    } else if (t > stop + 2 * h) {
      rest_speed = std::max(rest_speed, std::max(v.norm(), w.norm()));
    }
  });
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_LT(worst_w, 1e-6 * w0) << "rolling rate off the closed form (rad/s)";
  EXPECT_LT(worst_v, 1e-6 * w0 * s.R) << "speed off the closed form (m/s)";
  EXPECT_LT(rest_speed, 1e-9) << "not at rest after the closed-form stop time " << stop << " s";
  EXPECT_LT(max_penetration, 1e-9);
}

TEST(RollingResistance, SphereDeceleratesAndStopsAtTheClosedFormTimeWithThePaperStep) {
  ExpectClosedFormRolling(StepperOptions::Scheme::kPaper);
}

TEST(RollingResistance, SphereDeceleratesAndStopsAtTheClosedFormTimeWithTheRattleStep) {
  ExpectClosedFormRolling(StepperOptions::Scheme::kRattle);
}

// A rounded box (superellipsoid of exponent 2.5, 0.2 x 0.14 x 0.1 m) dropped tilted by 0.3 rad rocks on; its kinetic
// energy after `duration` with and without rolling resistance, default options (the RATTLE step). Measured: 3.6e-3 J
// without, 1.4e-21 J with e_roll = 2 mm.
double RockingBoxEnergyAfter(double e_roll, double duration) {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  Body box = test_models::MovingBody("box", MakeSuperellipsoid(Vec3(0.1, 0.07, 0.05), 2.5), 1.0, Pose::Identity());
  box.X_WB0.linear() = test_models::Rot(0.3, Vec3::UnitY());
  box.X_WB0.translation() = Vec3(0, 0, 0.12);
  m.bodies.push_back(box);
  FrictionParams friction{0.8, 1.0, 1.0, 0.01};
  friction.e_roll = e_roll;
  const Model model = test_models::Finish(m, friction);
  StepperOptions options;
  options.h = 0.01;
  const auto stats = RunScene(model, options, duration);
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_LT(stats.max_solver_penetration, 1e-9);
  return stats.ke_final;
}

TEST(RollingResistance, RockingRoundedBoxComesToRest) {
  const double without = RockingBoxEnergyAfter(0.0, 3.0), with = RockingBoxEnergyAfter(0.002, 3.0);
  EXPECT_GT(without, 1e-4) << "the second-order step is expected to leave the box rocking without rolling resistance";
  EXPECT_LT(with, 1e-14) << "with rolling resistance the box comes to rest";
}

}  // namespace
}  // namespace implicit_sim
