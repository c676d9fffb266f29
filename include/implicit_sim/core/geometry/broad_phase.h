// Broad phase: which pairs of the model's shapes may touch within a step. Each bounded shape is enclosed in its
// bounding sphere (centre at the shape frame origin, radius ConvexShape::BoundingRadius()), grown by a per-shape
// inflation (the motion possible within the step plus a margin); spheres are tested by sweep and prune along world x.
// A half-space is tested against the other shape's sphere by signed distance. Pairs with an unbounded shape of any
// other kind (a general intersection) are always candidates.
//
// With zero inflation at the end-of-step poses the test is exact in one direction: two bodies whose bounding
// volumes do not overlap cannot interpenetrate, which is what the stepper's check of the pairs left out of the NCP
// relies on.
#pragma once

#include <functional>
#include <utility>
#include <vector>

#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {

class BroadPhase {
 public:
  // shapes[s]: shape s in the frame of its body body_of[s] (no inequalities: the shape takes part in no pair); the
  // shapes must outlive the broad phase. pair_index(i, j) names the pair of shapes i and j (either order), -1 for
  // none (two shapes of one body must have none).
  BroadPhase(std::vector<const ConvexShape*> shapes, std::vector<int> body_of, std::function<int(int, int)> pair_index);
  // The candidate pairs (pair_index values, ascending) for body poses X_WB (one per body) and inflations (m, one per
  // shape, >= 0).
  void FindPairs(const std::vector<Pose>& X_WB, const std::vector<double>& inflation, std::vector<int>* pairs);

 private:
  // X_SW: world to the half-space's shape frame.
  bool HalfSpaceCandidate(int plane_shape, const Pose& X_SW, int other_shape, const std::vector<double>& inflation) const;
  std::vector<const ConvexShape*> shapes_;
  std::vector<int> body_of_;
  std::function<int(int, int)> pair_index_;
  std::vector<int> bounded_;            // bounded shapes
  std::vector<int> half_spaces_;        // half-spaces
  std::vector<int> other_unbounded_;    // unbounded shapes of another kind
  std::vector<double> radius_;          // per shape: bounding radius (m)
  std::vector<std::pair<double, int>> sweep_;  // (lowest x of the grown sphere, shape)
  std::vector<Vec3> centre_;            // per shape, world
};

}  // namespace implicit_sim
