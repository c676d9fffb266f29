// The S1 pile generator: the scene loads, has the specified layout and draws, and starts without overlaps.
#include "implicit_sim/core/pile_scene.h"

#include <random>

#include <gtest/gtest.h>

#include "implicit_sim/core/urdf_loader.h"

namespace implicit_sim {
namespace {

TEST(PileScene, LayoutFollowsTheScenarioAndSpheresStartApart) {
  for (PileShape shape : {PileShape::kSphere, PileShape::kEllipsoid}) {
    const Model model = LoadSceneFromString(MakePileUrdf(100, shape), "pile");
    ASSERT_EQ(model.num_moving(), 100);
    ASSERT_EQ(model.bodies.size(), 105u);  // + floor and four walls
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> jitter(-0.01, 0.01);
    double min_spacing = 1e9;
    for (int i = 0; i < 100; ++i) {
      const double j1 = jitter(rng), j2 = jitter(rng), j3 = jitter(rng);
      const Vec3 expected(-0.42 + 0.12 * (i % 8) + j1, -0.42 + 0.12 * ((i / 8) % 8) + j2, 0.08 + 0.12 * (i / 64) +
                                                                                            std::abs(j3));
      const Body& body = model.bodies[model.FindBody("body_" + std::to_string(i))];
      EXPECT_LT((body.X_WB0.translation() - expected).norm(), 1e-15) << i;
      EXPECT_DOUBLE_EQ(body.mass, 0.1);
      for (int k = 0; k < i; ++k) {
        const Body& other = model.bodies[model.FindBody("body_" + std::to_string(k))];
        min_spacing = std::min(min_spacing, (body.X_WB0.translation() - other.X_WB0.translation()).norm());
      }
      // Inside the box and above the floor, with the largest semi-axis as margin.
      EXPECT_GT(body.X_WB0.translation().z(), 0.06);
      EXPECT_LT(body.X_WB0.translation().cwiseAbs().head<2>().maxCoeff(), 0.5 - 0.06);
    }
    // Spheres (r = 0.05) never overlap at the start: the grid spacing 0.12 less two jitters of 0.01 leaves 0.10.
    // (The scenario's ellipsoids, 0.12 m long along x, can: see README.md.)
    if (shape == PileShape::kSphere) EXPECT_GE(min_spacing, 0.1);
    // The walls hold the bodies in: every wall's half-space excludes the box's centre.
    for (const char* wall : {"floor", "wall_px", "wall_nx", "wall_py", "wall_ny"}) {
      const Body& w = model.bodies[model.FindBody(wall)];
      const Pose X_WS = w.X_WB0 * w.shape.X_BS;
      EXPECT_GT(w.shape.inequalities[0].Value(X_WS.inverse() * Vec3(0, 0, 0.2)), 0.0) << wall;
    }
  }
  EXPECT_THROW(MakePileUrdf(0, PileShape::kSphere), std::invalid_argument);
}

}  // namespace
}  // namespace implicit_sim
