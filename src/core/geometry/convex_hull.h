// The convex hull of a point cloud as half-spaces (qhull, reentrant C library). Internal to the core: the scene
// loader turns collision meshes into polytopes with it.
#pragma once

#include <vector>

#include "implicit_sim/core/base/types.h"

namespace implicit_sim {

// One face of a hull: the half-space normal . x <= offset (unit outward normal; offset in m).
struct HullFace {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
};

struct ConvexHull {
  std::vector<Vec3> vertices;     // the corners of the faces' polytope (m): hull vertices unless simplified
  std::vector<HullFace> faces;    // coplanar facets merged into one face
  int coplanar_faces = 0;         // face count with only coplanar facets merged, before any simplification
  double merge_radius = 0.0;      // m: qhull's pre-merge centrum radius that gave `faces` (0: coplanar merging only)
};

// The convex hull of `points` (m). Coplanar facets are merged (qhull option C-0), so a box gives 6 faces. When that
// leaves more than `max_faces` faces, the facets are merged again with a centrum radius that doubles from 1e-4 of
// the points' extent until at most `max_faces` remain (at most 30 doublings); every face is then moved out until it
// touches the farthest point, so the hull still contains every point (and its corners are recomputed). Throws
// std::invalid_argument if a point is not finite or the points do not span a volume (fewer than 4 non-coplanar
// points).
ConvexHull ComputeConvexHull(const std::vector<Vec3>& points, int max_faces);

}  // namespace implicit_sim
