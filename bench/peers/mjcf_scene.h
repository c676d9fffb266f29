// MJCF (MuJoCo's model format) for one of our scenes, written from our loaded Model so that both engines simulate the
// same bodies, masses, inertias, initial poses and velocities, applied forces, gravity and friction. The modelling
// choices are described in bench/README.md#side-by-side-with-mujoco:
//   - a fixed half-space is a `plane` geom with the same frame (both occupy local z <= 0); fixed spheres are world
//     geoms; moving spheres, ellipsoids and cylinders are the same primitives; an N-gon prism is a convex `mesh`
//     with its 2N vertices;
//   - a moving body has a free joint, or slide x, slide z and hinge y when it is locked to the x-z plane (P1);
//   - inertias explicit (`fullinertia`), friction "mu e_r*mu 0" on every geom (MuJoCo's torsional coefficient is a
//     length), condim 4 (3 for a planar scene, which cannot spin about the normal), elliptic cone, semi-implicit
//     Euler, solref/solimp, iterations and tolerance at MuJoCo's defaults.
// Throws std::invalid_argument for what MuJoCo cannot mirror here (joints, anisotropic friction, other shapes).
#pragma once

#include <string>

#include "implicit_sim/core/model/model.h"

namespace implicit_sim {

struct MjcfOptions {
  double h = 0.01;                 // time step (s)
  std::string solver = "Newton";  // MuJoCo's "Newton", "CG" or "PGS"
  int max_contacts = 0;           // <size nconmax>; 0: MuJoCo's default
  int max_constraint_rows = 0;    // <size njmax>; 0: MuJoCo's default
};

// Geoms and bodies are named after our links, so a MuJoCo contact maps back to our bodies by name.
std::string MjcfFromModel(const Model& model, const MjcfOptions& options);

}  // namespace implicit_sim
