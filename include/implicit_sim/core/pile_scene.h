// The S1 scaling scene of ../shared/scenarios/SCENARIOS.md as a generator: N spheres (r = 0.05 m) or ellipsoids
// (semi-axes 0.06, 0.05, 0.04 m), 0.1 kg each, at rest in a 1 m x 1 m box (a floor z = 0 and four walls at
// x, y = +-0.5, all half-spaces), mu = 0.5 (e_t = e_o = 1, e_r = 0.01 m: not given by the scenario).
// Body i: layer = i / 64, row = (i / 8) % 8, col = i % 8;
// x = -0.42 + 0.12 col + j1, y = -0.42 + 0.12 row + j2, z = 0.08 + 0.12 layer + |j3|, with j1, j2, j3 drawn in that
// order from std::uniform_real_distribution(-0.01, 0.01) over std::mt19937(seed).
#pragma once

#include <string>

namespace implicit_sim {

enum class PileShape { kSphere, kEllipsoid };

// The scene as URDF text (links "floor", "wall_px", "wall_nx", "wall_py", "wall_ny", "body_<i>").
// Throws std::invalid_argument for n outside [1, 100000].
std::string MakePileUrdf(int n, PileShape shape, unsigned seed = 42);

}  // namespace implicit_sim
