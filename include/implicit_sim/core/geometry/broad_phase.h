// Broad phase: which pairs of the model may touch within a step. Each bounded shape is enclosed in its bounding
// sphere (centre at the shape frame origin, radius ConvexShape::BoundingRadius()), grown by a per-body inflation
// (the motion possible within the step plus a margin); spheres are tested by sweep and prune along world x. A
// half-space is tested against the other body's sphere by signed distance. Pairs with an unbounded shape of any
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
  // shapes[b]: the shape of body b in its body frame (no inequalities: the body takes part in no pair); the shapes
  // must outlive the broad phase. pair_index(i, j) names the pair of bodies i and j (either order), -1 for none.
  BroadPhase(std::vector<const ConvexShape*> shapes, std::function<int(int, int)> pair_index);
  // The candidate pairs (pair_index values, ascending) for body poses X_WB (one per body) and inflations (m, one per
  // body, >= 0).
  void FindPairs(const std::vector<Pose>& X_WB, const std::vector<double>& inflation, std::vector<int>* pairs);

 private:
  // X_SW: world to the half-space's shape frame.
  bool HalfSpaceCandidate(int plane_body, const Pose& X_SW, int other_body, const std::vector<double>& inflation) const;
  std::vector<const ConvexShape*> shapes_;
  std::function<int(int, int)> pair_index_;
  std::vector<int> bounded_;            // bodies with a bounded shape
  std::vector<int> half_spaces_;        // bodies whose shape is a half-space
  std::vector<int> other_unbounded_;    // bodies with an unbounded shape of another kind
  std::vector<double> radius_;          // per body: bounding radius (m)
  std::vector<std::pair<double, int>> sweep_;  // (lowest x of the grown sphere, body)
  std::vector<Vec3> centre_;            // per body, world
};

}  // namespace implicit_sim
