// The quasi-static limit of a dropped thick coin (issue 36, doc/validation.md): a cylinder of thickness t and diameter
// d released at rest just above a plane in a uniformly random orientation rests on its side with probability
// t / sqrt(t^2 + d^2): it tips about its lowest point toward the side of the vertical through its centre of mass, and
// that vertical meets the side band for a fraction t / sqrt(t^2 + d^2) of the directions on the sphere.
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

std::string CoinOnPlaneUrdf(double radius, double length) {
  const std::string r = std::to_string(radius), l = std::to_string(length);
  return "<robot name='coin'><implicit_sim gravity='0 0 -9.81'><friction mu='0.5' e_t='1' e_o='1' e_r='0.01'/>"
         "</implicit_sim><link name='world'/><link name='ground'><collision><geometry><box size='4 4 0.001'/>"
         "</geometry><implicit type='halfspace'/></collision></link><joint name='g' type='fixed'><parent link='world'/>"
         "<child link='ground'/></joint><link name='coin'><collision><geometry><cylinder radius='" + r +
         "' length='" + l + "'/></geometry><implicit type='cylinder' radius='" + r + "' length='" + l +
         "' mass='0.01'/></collision></link><joint name='c' type='floating'><parent link='world'/><child link='coin'/>"
         "<origin xyz='0 0 1'/></joint></robot>";
}

enum class CoinRest { kFace, kSide, kMoving };

// Drops the coin from rest, its lowest point `clearance` (m) above the plane, with R_WB; returns where it rests (the
// kinetic energy under 1e-9 J for 0.1 s) after at most 2 s.
CoinRest DropCoin(const Model& model, const Eigen::Quaterniond& R_WB, double radius, double length, double clearance,
                  Data* data) {
  State state = State::Initial(model);
  const double a_z = std::abs((R_WB * Vec3::UnitZ()).z());  // the axis' vertical component
  const double below = 0.5 * length * a_z + radius * std::sqrt(std::max(0.0, 1.0 - a_z * a_z));  // m
  state.q.segment<3>(0) = Vec3(0, 0, below + clearance);
  state.q.segment<4>(3) << R_WB.w(), R_WB.x(), R_WB.y(), R_WB.z();
  state.v.setZero();
  StepperOptions options;
  const double h = 0.005;  // s
  options.h = h;
  int quiet_steps = 0;
  for (int i = 0; i < 400 && quiet_steps < 20; ++i) {
    const StepReport report = Step(model, options, &state, data);
    EXPECT_TRUE(report.converged) << "step " << i;
    quiet_steps = KineticEnergy(model, state) < 1e-9 ? quiet_steps + 1 : 0;
  }
  if (quiet_steps < 20) return CoinRest::kMoving;
  const Eigen::Quaterniond R_end(state.q[3], state.q[4], state.q[5], state.q[6]);
  const double tilt = std::abs((R_end.normalized() * Vec3::UnitZ()).z());
  return tilt > 0.5 ? CoinRest::kFace : CoinRest::kSide;
}

TEST(QuasiStaticCoin, RestsOnItsSideWithTheProbabilityTheCentreOfMassPicks) {
  const int samples = 240;
  std::mt19937_64 rng(36);
  std::normal_distribution<double> normal;
  for (const double t_over_d : {0.3, 0.6, 1.0}) {
    const double radius = 0.01, length = 2 * radius * t_over_d;  // m
    const Model model = LoadSceneFromString(CoinOnPlaneUrdf(radius, length), "coin");
    Data data(model);
    const double p = t_over_d / std::sqrt(t_over_d * t_over_d + 1.0);
    int side = 0, moving = 0, disagree = 0;
    for (int s = 0; s < samples; ++s) {
      // A uniformly random rotation: a normalized 4-vector of independent normals.
      const Eigen::Quaterniond R_WB =
          Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized();
      const CoinRest rest = DropCoin(model, R_WB, radius, length, 1e-4, &data);
      side += rest == CoinRest::kSide;
      moving += rest == CoinRest::kMoving;
      // Each sample's own prediction: the side when the axis is further than acos(p) from the vertical.
      const bool side_predicted = std::abs((R_WB * Vec3::UnitZ()).z()) < p;
      disagree += rest != (side_predicted ? CoinRest::kSide : CoinRest::kFace);
    }
    // 99.9 % of the binomial B(samples, p) lies within 3.29 standard deviations (normal approximation).
    const double sigma = std::sqrt(samples * p * (1 - p));
    std::printf("[ coin ] t/d = %.2f: side %d of %d (%.3f; closed form %.3f, 99.9%% band +-%.3f), still moving %d, "
                "%d samples not where their centre of mass points\n",
                t_over_d, side, samples, double(side) / samples, p, 3.29 * sigma / samples, moving, disagree);
    EXPECT_EQ(moving, 0) << "t/d = " << t_over_d;
    EXPECT_LE(disagree, samples / 50) << "t/d = " << t_over_d;  // only orientations near the edge may tip either way
    EXPECT_NEAR(side, samples * p, 3.29 * sigma) << "t/d = " << t_over_d;
  }
}

}  // namespace
}  // namespace implicit_sim
