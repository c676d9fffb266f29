// The geometric overlap checks of step_health.h: MaxPenetrationBound (the runner's --check-penetration) on poses
// whose depth is known in closed form.
#include "implicit_sim/core/step/step_health.h"

#include <cmath>

#include <gtest/gtest.h>

#include "test_models.h"

namespace implicit_sim {
namespace {

using test_models::FixedBody;
using test_models::Finish;
using test_models::MakePose;
using test_models::MovingBody;
using test_models::Rot;

// The pile's ellipsoid (semi-axes 0.06, 0.05, 0.04 m) tilted about x, its lowest point `lift` above the floor z = 0.
double FloorBound(double lift, double tilt) {
  Model m;
  m.bodies.push_back(FixedBody("floor", MakeHalfSpace()));
  const double half_height = std::hypot(0.05 * std::sin(tilt), 0.04 * std::cos(tilt));  // support along -z
  m.bodies.push_back(MovingBody("egg", MakeEllipsoid(Vec3(0.06, 0.05, 0.04)), 0.1,
                                MakePose(Vec3(0, 0, half_height + lift), Rot(tilt, Vec3::UnitX()))));
  const Model model = Finish(m);
  Data data(model);
  return MaxPenetrationBound(model, State::Initial(model), 1e-9, &data);
}

TEST(MaxPenetrationBound, IsTheDepthOfAnEllipsoidInTheFloor) {
  for (double tilt : {0.0, 0.6}) {
    EXPECT_EQ(FloorBound(0.01, tilt), 0.0) << tilt;
    EXPECT_NEAR(FloorBound(-0.002, tilt), 0.002, 1e-12) << tilt;  // the closed form
  }
}

TEST(MaxPenetrationBound, MeasuresTheOverlapOfTwoEllipsoidsThroughTheOracle) {
  // Side by side at the same height: centres along x, tips overlapping by 1 mm, 1 um, touching, 1 um apart.
  const auto pair = [](double distance, double tilt) {
    Model m;
    const ConvexShape egg = MakeEllipsoid(Vec3(0.06, 0.05, 0.04));
    m.bodies.push_back(MovingBody("a", egg, 0.1, MakePose(Vec3(0, 0, 0.3), Rot(tilt, Vec3::UnitX()))));
    m.bodies.push_back(MovingBody("b", egg, 0.1, MakePose(Vec3(distance, 0, 0.3), Rot(-tilt, Vec3::UnitX()))));
    const Model model = Finish(m);
    Data data(model);
    return MaxPenetrationBound(model, State::Initial(model), 1e-9, &data);
  };
  for (double tilt : {0.0, 0.7}) {
    const double deep = pair(0.119, tilt);
    EXPECT_GE(deep, 1e-3 - 1e-12) << tilt;  // an upper bound: at least the depth along x
    EXPECT_LT(deep, 1.05e-3) << tilt;
    const double shallow = pair(0.12 - 1e-6, tilt);
    EXPECT_GE(shallow, 1e-6 - 1e-12) << tilt;
    EXPECT_LT(shallow, 1.5e-6) << tilt;
    EXPECT_LT(pair(0.12, tilt), 1e-9) << tilt;
    EXPECT_EQ(pair(0.12 + 1e-6, tilt), 0.0) << tilt;
  }
}

}  // namespace
}  // namespace implicit_sim
