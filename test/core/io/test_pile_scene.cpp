// The S1 pile generator: the scene loads, has the specified layout and draws, and starts without overlaps.
#include "implicit_sim/core/io/pile_scene.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/geometry/support.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {
namespace {

TEST(PileScene, LayoutFollowsTheScenarioAndSpheresStartApart) {
  for (PileShape shape : {PileShape::kSphere, PileShape::kEllipsoid}) {
    const Model model = LoadSceneFromString(MakePileUrdf(100, shape, 42, false), "pile");  // the scenario's layout
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
    // (The scenario's ellipsoids, 0.12 m long along x, can: see doc/scenes.md.)
    if (shape == PileShape::kSphere) EXPECT_GE(min_spacing, 0.1);
    // The walls hold the bodies in: every wall's half-space excludes the box's centre.
    for (const char* wall : {"floor", "wall_px", "wall_nx", "wall_py", "wall_ny"}) {
      const Body& w = model.bodies[model.FindBody(wall)];
      const Pose X_WS = w.X_WB0 * w.shapes[0].X_BS;
      EXPECT_GT(w.shapes[0].inequalities[0].Value(X_WS.inverse() * Vec3(0, 0, 0.2)), 0.0) << wall;
    }
  }
  EXPECT_THROW(MakePileUrdf(0, PileShape::kSphere), std::invalid_argument);
}

// pile.launch documents n in [1, 4000] (spheres, ellipsoids) and [1, 2000] (brackets, tees): the largest pile of each
// kind of part loads and gets its step workspace; one part more is refused by the generator with the range.
TEST(PileScene, TheLargestDocumentedPilesLoadAndOneMorePartIsRefused) {
  EXPECT_EQ(MaxPileSize(PileShape::kEllipsoid), 4000);
  EXPECT_EQ(MaxPileSize(PileShape::kTee), 2000);
  for (PileShape shape : {PileShape::kEllipsoid, PileShape::kTee}) {
    SCOPED_TRACE(PileShapeName(shape));
    const int n = MaxPileSize(shape);
    const Model model = LoadSceneFromString(MakePileUrdf(n, shape), "pile");
    EXPECT_EQ(model.num_moving(), n);
    EXPECT_LE(static_cast<int64_t>(model.pairs.size()), Model::kMaxContactPairs);
    const Data data(model);
    EXPECT_EQ(data.X_WB.size(), model.bodies.size());
    try {
      MakePileUrdf(n + 1, shape);
      ADD_FAILURE() << "accepted " << n + 1 << " parts";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(std::to_string(n)), std::string::npos) << e.what();
    }
  }
}

TEST(PileScene, EllipsoidRowsAreSpreadToTheNearestNonOverlappingLayout) {
  const Model layout = LoadSceneFromString(MakePileUrdf(100, PileShape::kEllipsoid, 42, false), "layout");
  const Model spread = LoadSceneFromString(MakePileUrdf(100, PileShape::kEllipsoid), "spread");
  int overlapping_before = 0, overlapping_after = 0;
  double max_shift = 0.0;
  for (int i = 0; i < 100; ++i) {
    const Body& a = layout.bodies[layout.FindBody("body_" + std::to_string(i))];
    const Body& b = spread.bodies[spread.FindBody("body_" + std::to_string(i))];
    const Vec3 shift = b.X_WB0.translation() - a.X_WB0.translation();
    max_shift = std::max(max_shift, shift.norm());
    EXPECT_EQ(shift.y(), 0.0);
    EXPECT_EQ(shift.z(), 0.0);
    EXPECT_TRUE(b.X_WB0.linear().isApprox(Mat3::Identity(), 1e-15));
    EXPECT_LT(std::abs(b.X_WB0.translation().x()), 0.5 - 0.06);  // inside the walls
    if (i % 8 == 0) continue;
    // x-neighbours in a row, by the independent distance oracle (negative distance: overlap).
    for (const auto& [model, count] : {std::make_pair(&layout, &overlapping_before),
                                       std::make_pair(&spread, &overlapping_after)}) {
      const Body& left = model->bodies[model->FindBody("body_" + std::to_string(i - 1))];
      const Body& right = model->bodies[model->FindBody("body_" + std::to_string(i))];
      const ClosestPointsResult cp = FindClosestPoints(left.shapes[0], left.X_WB0, right.shapes[0], right.X_WB0);
      *count += cp.distance < 1e-6;
    }
    EXPECT_GE(b.X_WB0.translation().x() - spread.bodies[spread.FindBody("body_" + std::to_string(i - 1))]
                                              .X_WB0.translation().x(), 0.12 - 1e-12);
  }
  EXPECT_GT(overlapping_before, 10);
  EXPECT_EQ(overlapping_after, 0);
  EXPECT_LT(max_shift, 0.02);
}

// --orientation random: the layout of pile_scene.h from the seed's draws, orientations uniform on SO(3), and no two
// bodies (nor a body and a wall) overlap at the start.
TEST(PileScene, RandomOrientationsFollowTheSeedAndStartApart) {
  const std::string urdf = MakePileUrdf(50, PileShape::kEllipsoid, 7, true, PileOrientation::kRandom);
  EXPECT_EQ(urdf, MakePileUrdf(50, PileShape::kEllipsoid, 7, true, PileOrientation::kRandom));
  EXPECT_NE(urdf, MakePileUrdf(50, PileShape::kEllipsoid, 8, true, PileOrientation::kRandom));
  const int n = 1000;
  const std::vector<Pose> X_WB = RandomPileLayout(n, 7);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01), uniform(0.0, 1.0);
  Mat3 mean = Mat3::Zero();
  double min_spacing = 1e9;
  for (int i = 0; i < n; ++i) {
    const double j1 = jitter(rng), j2 = jitter(rng), j3 = jitter(rng);
    for (int k = 0; k < 3; ++k) uniform(rng);
    const Vec3 expected(-0.42 + 0.14 * (i % 7) + j1, -0.42 + 0.14 * ((i / 7) % 7) + j2,
                        0.08 + 0.14 * (i / 49) + std::abs(j3));
    EXPECT_EQ(X_WB[i].translation(), expected) << i;
    const Mat3 R = X_WB[i].linear();
    EXPECT_TRUE((R.transpose() * R).isApprox(Mat3::Identity(), 1e-12)) << i;
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12) << i;
    mean += R / n;
    // The bounding sphere (0.06 m) inside the walls and above the floor.
    EXPECT_LE(X_WB[i].translation().head<2>().cwiseAbs().maxCoeff(), 0.5 - 0.07 + 1e-12) << i;
    EXPECT_GE(X_WB[i].translation().z(), 0.08) << i;
    for (int k = std::max(0, i - 60); k < i; ++k) {  // neighbours in the row, the rows around and the layer below
      min_spacing = std::min(min_spacing, (X_WB[i].translation() - X_WB[k].translation()).norm());
    }
  }
  EXPECT_GE(min_spacing, 0.12);  // two bounding spheres of 0.06 m at most touch
  // Uniform on SO(3): every entry of R has mean 0 (standard deviation 1/sqrt(3) per rotation: 0.018 over 1000).
  EXPECT_LT(mean.cwiseAbs().maxCoeff(), 0.1) << mean;
  // The generated scene by the distance oracle: no pair of ellipsoids within 1e-6 m.
  const Model model = LoadSceneFromString(urdf, "random");
  ASSERT_EQ(model.num_moving(), 50);
  int close_pairs = 0;
  for (int i = 0; i < 50; ++i) {
    const Body& a = model.bodies[model.FindBody("body_" + std::to_string(i))];
    for (int k = 0; k < i; ++k) {
      const Body& b = model.bodies[model.FindBody("body_" + std::to_string(k))];
      if ((a.X_WB0.translation() - b.X_WB0.translation()).norm() > 0.14) continue;
      ++close_pairs;
      EXPECT_GT(FindClosestPoints(a.shapes[0], a.X_WB0, b.shapes[0], b.X_WB0).distance, 1e-6) << i << " " << k;
    }
  }
  EXPECT_GT(close_pairs, 10);  // the check saw neighbours
}

// The unions (bracket: two rounded boxes; tee: two cylinders): 0.1 kg bodies of two shapes each; in both layouts
// no shape of one part comes within 1e-6 m of a shape of another part or of the floor and walls.
TEST(PileScene, BracketsAndTeesAreTwoShapeBodiesThatStartApart) {
  for (PileShape shape : {PileShape::kBracket, PileShape::kTee}) {
    PileShape parsed;
    ASSERT_TRUE(ParsePileShape(PileShapeName(shape), &parsed));
    EXPECT_EQ(parsed, shape);
    for (PileOrientation orientation : {PileOrientation::kAligned, PileOrientation::kRandom}) {
      const Model model = LoadSceneFromString(MakePileUrdf(80, shape, 5, true, orientation), "unions");
      ASSERT_EQ(model.num_moving(), 80);
      int close_pairs = 0;
      for (int i = 0; i < static_cast<int>(model.bodies.size()); ++i) {
        const Body& a = model.bodies[i];
        if (!a.is_fixed) {
          EXPECT_EQ(a.shapes.size(), 2u);
          EXPECT_NEAR(a.mass, 0.1, 1e-15);
        }
        for (int k = 0; k < i; ++k) {
          const Body& b = model.bodies[k];
          if (a.is_fixed && b.is_fixed) continue;
          if (!a.is_fixed && !b.is_fixed &&
              (a.X_WB0.translation() - b.X_WB0.translation()).norm() > 0.2) continue;
          for (const ConvexShape& sa : a.shapes) {
            for (const ConvexShape& sb : b.shapes) {
              ++close_pairs;
              // A certificate: a wall's half-space in closed form; between parts, a direction n whose crossing
              // support_a(-n) + support_b(n) is below -1e-6 m (a separating plane with that margin).
              if (a.is_fixed || b.is_fixed) {
                ClosestPointsResult wall;
                ASSERT_TRUE(ClosedFormClosestPoints(sa, a.X_WB0, sb, b.X_WB0, &wall));
                EXPECT_GT(wall.distance, 1e-6) << PileShapeName(shape) << " " << a.name << " " << b.name;
              } else {
                EXPECT_LT(DescendCrossing(sa, a.X_WB0, sb, b.X_WB0, -1e-6, 2000).value, -1e-6)
                    << PileShapeName(shape) << " " << a.name << " " << b.name;
              }
            }
          }
        }
      }
      EXPECT_GT(close_pairs, 80 * 5 * 2);  // every part's shapes against the floor and walls, and neighbours
    }
  }
  PileShape unused;
  EXPECT_FALSE(ParsePileShape("cube", &unused));
}

// The documented pile sizes (launch/pile.launch, implicit_sim_make_pile --n) stay within the model's pair limit: n parts
// of k shapes over 5 half-spaces form k^2 n (n - 1) / 2 + 5 k n pairs at most.
TEST(PileScene, TheLargestPilesStayWithinThePairLimitAndLargerOnesAreRefused) {
  for (const PileShape shape : {PileShape::kSphere, PileShape::kEllipsoid, PileShape::kBracket, PileShape::kTee}) {
    const int64_t n = MaxPileSize(shape), k = shape == PileShape::kSphere || shape == PileShape::kEllipsoid ? 1 : 2;
    EXPECT_LE(k * k * n * (n - 1) / 2 + 5 * k * n, Model::kMaxContactPairs) << PileShapeName(shape);
    EXPECT_NO_THROW(MakePileUrdf(static_cast<int>(n), shape)) << PileShapeName(shape);
    try {
      MakePileUrdf(static_cast<int>(n) + 1, shape);
      ADD_FAILURE() << PileShapeName(shape) << ": " << n + 1 << " accepted";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("must be in [1, " + std::to_string(n) + "]"), std::string::npos)
          << error.what();
    }
  }
  // The bound is exact where no joint or exclusion removes a pair: a bracket pile's 2-shape parts.
  const Model brackets = LoadSceneFromString(MakePileUrdf(6, PileShape::kBracket), "brackets");
  EXPECT_EQ(static_cast<int64_t>(brackets.pairs.size()), brackets.ContactPairBound());
  EXPECT_EQ(brackets.ContactPairBound(), 4 * 6 * 5 / 2 + 5 * 2 * 6);
}

// Every body of `a` starts where the same body of `b` does.
void ExpectSameLayout(const Model& a, const Model& b) {
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (size_t i = 0; i < a.bodies.size(); ++i) EXPECT_EQ(a.bodies[i].X_WB0.matrix(), b.bodies[i].X_WB0.matrix()) << i;
}

// make(value) refuses each value outside [0, 1000] with std::invalid_argument naming `range`.
template <typename Make>
void ExpectOutOfRangeRefused(const Make& make, const std::string& range) {
  for (const double bad : {-0.001, 2000.0, std::nan("")}) {
    try {
      make(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find(range), std::string::npos) << error.what();
    }
  }
}

// Rolling resistance on the pile's friction (the batch studies' e_roll): every pair gets it, the layout stays the same,
// and a value out of range is refused naming the range.
TEST(PileScene, RollingResistanceReachesEveryPairAndBadValuesAreRefused) {
  const Model without = LoadSceneFromString(MakePileUrdf(5, PileShape::kEllipsoid, 3, true, PileOrientation::kRandom), "a");
  const Model with =
      LoadSceneFromString(MakePileUrdf(5, PileShape::kEllipsoid, 3, true, PileOrientation::kRandom, 0.002), "b");
  ASSERT_EQ(with.pairs.size(), without.pairs.size());
  ASSERT_FALSE(with.pairs.empty());
  for (size_t k = 0; k < with.pairs.size(); ++k) {
    EXPECT_EQ(with.pairs[k].friction.e_roll, 0.002) << k;
    EXPECT_EQ(without.pairs[k].friction.e_roll, 0.0) << k;
  }
  ExpectSameLayout(with, without);
  ExpectOutOfRangeRefused(
      [](double e_roll) { MakePileUrdf(5, PileShape::kSphere, 3, true, PileOrientation::kAligned, e_roll); },
      "e_roll must be in [0, 1000] m");
}

// The torsional lever: 0.01 m unless asked otherwise, 0 (no torsional friction) reaches every pair with the same layout,
// and a value out of range is refused naming the range.
TEST(PileScene, TheTorsionalLeverReachesEveryPairAndBadValuesAreRefused) {
  const Model standard = LoadSceneFromString(MakePileUrdf(5, PileShape::kEllipsoid, 3), "a");
  const Model point =
      LoadSceneFromString(MakePileUrdf(5, PileShape::kEllipsoid, 3, true, PileOrientation::kAligned, 0.0, 0.0), "b");
  ASSERT_EQ(point.pairs.size(), standard.pairs.size());
  ASSERT_FALSE(point.pairs.empty());
  for (size_t k = 0; k < point.pairs.size(); ++k) {
    EXPECT_EQ(standard.pairs[k].friction.e_r, kPileTorsionLever) << k;
    EXPECT_EQ(point.pairs[k].friction.e_r, 0.0) << k;
    EXPECT_EQ(point.pairs[k].friction.mu, 0.5) << k;
  }
  ExpectSameLayout(point, standard);
  ExpectOutOfRangeRefused(
      [](double e_r) { MakePileUrdf(5, PileShape::kSphere, 3, true, PileOrientation::kAligned, 0.0, e_r); },
      "e_r must be in [0, 1000] m");
}

}  // namespace
}  // namespace implicit_sim
