// The S1 scaling scene (doc/scenes.md) as a generator: N spheres (r = 0.05 m) or ellipsoids
// (semi-axes 0.06, 0.05, 0.04 m), or of the two unions below (brackets, T-pipes), 0.1 kg each, at rest in a 1 m x 1 m box (a floor z = 0 and four walls at
// x, y = +-0.5, all half-spaces), mu = 0.5 (e_t = e_o = 1, e_r = 0.01 m: not given by the scenario).
// Body i: layer = i / 64, row = (i / 8) % 8, col = i % 8;
// x = -0.42 + 0.12 col + j1, y = -0.42 + 0.12 row + j2, z = 0.08 + 0.12 layer + |j3|, with j1, j2, j3 drawn in that
// order from std::uniform_real_distribution(-0.01, 0.01) over std::mt19937(seed).
//
// The ellipsoid layout overlaps: centre spacing along x is 0.12 +- 0.02 m for bodies 0.12 m long along x (the
// distance oracle finds 44 touching or overlapping pairs at N = 100), and a step that starts overlapping ends separated
// only through a large impulse (about 4 m/s within one 5 ms step). By default the generator therefore spreads each
// row of 8 to a spacing of at least 0.12 m along x, the least-squares change of the x-centres (isotonic regression by
// pool-adjacent-violators); y and z spacings cannot overlap (>= 0.10 m for a 0.10 m width, 0.12 m for a 0.08 m
// height), so the result overlaps nowhere, and a row needs 0.84 m of the 0.88 m the walls leave. The URDF comment
// says how many bodies moved and the largest shift. Spheres never overlap and are left as they are; neither do
// brackets (80 mm long) and T-pipes (90 mm).
//
// With random orientations (PileOrientation::kRandom, used by the batch studies) the layout is coarser, so that the
// bounding spheres (radius 0.06 m for either shape) cannot overlap whatever the orientations:
// body i: layer = i / 49, row = (i / 7) % 7, col = i % 7;
// x = -0.42 + 0.14 col + j1, y = -0.42 + 0.14 row + j2, z = 0.08 + 0.14 layer + |j3|, then the orientation from
// u1, u2, u3 (Shoemake's uniform quaternion on SO(3)); j1, j2, j3 from uniform_real_distribution(-0.01, 0.01) and
// u1, u2, u3 from uniform_real_distribution(0, 1), drawn per body in that order over std::mt19937(seed). Centres are
// at least 0.12 m apart (two bounding spheres at most touch), at least 0.07 m from every wall and 0.08 m above the
// floor (a bounding sphere needs 0.06 m). No row is spread.
#pragma once

#include <string>
#include <vector>

#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {

// kBracket: an L of two rounded boxes (superellipsoids of exponent 8): a base leg 80 x 30 x 15 mm centred at
// (0, 0, -22.5) mm and an upright 15 x 30 x 40 mm centred at (-32.5, 0, 5) mm of the link frame, 1/15 and 1/30 kg.
// kTee: a solid T-pipe of two cylinders: a pipe along x (r = 15 mm, 90 mm long) centred at (0, 0, -10) mm and a
// branch along z (r = 12 mm, 40 mm long) from z = 5 to 45 mm, masses in the ratio of their volumes.
// Every part has 0.1 kg and lies within 0.06 m of its link origin (the bounding sphere of the layouts below); the
// unions take their mass properties from their shapes (doc/scenes.md#mass).
enum class PileShape { kSphere, kEllipsoid, kBracket, kTee };
// "sphere", "ellipsoid", "bracket", "tee"; ParsePileShape is its inverse (false for any other name).
std::string PileShapeName(PileShape shape);
bool ParsePileShape(const std::string& name, PileShape* shape);
enum class PileOrientation { kAligned, kRandom };

// The scenario's poses of bodies 0 .. n-1 (axis-aligned).
std::vector<Pose> PileLayout(int n, unsigned seed);

// The poses of bodies 0 .. n-1 with orientations uniform on SO(3) (the 7 x 7 layout above).
std::vector<Pose> RandomPileLayout(int n, unsigned seed);

// Spreads each row of 8 consecutive bodies (ascending x) so that x-centres are at least `length` apart, with the
// least-squares change of the x-centres; returns how many bodies moved.
int SeparateRows(std::vector<Pose>* X_WB, double length);

// The largest pile of `shape` a model holds (Model::kMaxContactPairs): 4000 sphere or ellipsoid parts, 2000 bracket
// or tee parts (two shapes each).
int MaxPileSize(PileShape shape);

// The S1 pile's torsional lever e_r (m) unless asked otherwise. The scenario gives only mu; MuJoCo's side of the
// comparison gets the same torsion (condim 4, torsional coefficient e_r mu).
constexpr double kPileTorsionLever = 0.01;

// The scene as URDF text (links "floor", "wall_px", "wall_nx", "wall_py", "wall_ny", "body_<i>"), friction mu = 0.5
// with the torsional lever e_r (m; 0: point contacts without torsional friction) and rolling resistance e_roll (m)
// when > 0. Throws std::invalid_argument for n outside [1, MaxPileSize] or e_r, e_roll outside [0, 1000]. With
// PileOrientation::kRandom the layout is RandomPileLayout and separate_overlaps has no effect (nothing overlaps).
std::string MakePileUrdf(int n, PileShape shape, unsigned seed = 42, bool separate_overlaps = true,
                         PileOrientation orientation = PileOrientation::kAligned, double e_roll = 0.0,
                         double e_r = kPileTorsionLever);

}  // namespace implicit_sim
