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

#include <utility>
#include <vector>

#include "implicit_sim/core/model.h"

namespace implicit_sim {

class BroadPhase {
 public:
  explicit BroadPhase(const Model& model);
  // The candidate pairs (model pair indices, ascending) for body poses X_WB (one per model body) and inflations (m,
  // one per model body, >= 0).
  void FindPairs(const std::vector<Pose>& X_WB, const std::vector<double>& inflation, std::vector<int>* pairs);

 private:
  // X_SW: world to the half-space's shape frame.
  bool HalfSpaceCandidate(int plane_body, const Pose& X_SW, int other_body, const std::vector<double>& inflation) const;
  const Model& model_;
  std::vector<int> bounded_;            // bodies with a bounded shape
  std::vector<int> half_spaces_;        // bodies whose shape is a half-space
  std::vector<int> other_unbounded_;    // bodies with an unbounded shape of another kind
  std::vector<double> radius_;          // per body: bounding radius (m)
  std::vector<std::pair<double, int>> sweep_;  // (lowest x of the grown sphere, body)
  std::vector<Vec3> centre_;            // per body, world
};

}  // namespace implicit_sim
