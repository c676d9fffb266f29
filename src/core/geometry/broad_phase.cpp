#include "implicit_sim/core/geometry/broad_phase.h"

#include <algorithm>
#include <cmath>

namespace implicit_sim {

BroadPhase::BroadPhase(std::vector<const ConvexShape*> shapes, std::vector<int> body_of,
                       std::function<int(int, int)> pair_index)
    : shapes_(std::move(shapes)),
      body_of_(std::move(body_of)),
      pair_index_(std::move(pair_index)),
      radius_(shapes_.size(), 0.0),
      centre_(shapes_.size(), Vec3::Zero()) {
  for (int b = 0; b < static_cast<int>(shapes_.size()); ++b) {
    const ConvexShape& shape = *shapes_[b];
    if (shape.inequalities.empty()) continue;
    if (shape.type == ShapeType::kHalfSpace) {
      half_spaces_.push_back(b);
    } else if (shape.IsBounded() && std::isfinite(shape.BoundingRadius())) {
      bounded_.push_back(b);
      radius_[b] = shape.BoundingRadius();
    } else {
      other_unbounded_.push_back(b);
    }
  }
  sweep_.reserve(bounded_.size());
}

bool BroadPhase::HalfSpaceCandidate(int plane_shape, const Pose& X_SW, int other_shape,
                                    const std::vector<double>& inflation) const {
  const ConvexShape& plane = *shapes_[plane_shape];
  const Vec3 p_S = X_SW * centre_[other_shape];
  double signed_distance = -1e300;  // of the other shape's centre from the half-space (|grad f| = 1 for a plane)
  for (const Inequality& inequality : plane.inequalities) signed_distance = std::max(signed_distance, inequality.Value(p_S));
  return signed_distance <= radius_[other_shape] + inflation[other_shape] + inflation[plane_shape];
}

void BroadPhase::FindPairs(const std::vector<Pose>& X_WB, const std::vector<double>& inflation,
                           std::vector<int>* pairs) {
  pairs->clear();
  for (int b : bounded_) centre_[b] = X_WB[body_of_[b]] * shapes_[b]->X_BS.translation();
  auto add = [&](int i, int j) {
    const int pair = pair_index_(i, j);
    if (pair >= 0) pairs->push_back(pair);
  };
  // Sweep and prune along x over the grown bounding spheres.
  sweep_.clear();
  for (int b : bounded_) sweep_.emplace_back(centre_[b].x() - radius_[b] - inflation[b], b);
  std::sort(sweep_.begin(), sweep_.end());
  for (size_t a = 0; a < sweep_.size(); ++a) {
    const int i = sweep_[a].second;
    const double reach_i = radius_[i] + inflation[i];
    const double max_x = centre_[i].x() + reach_i;
    for (size_t c = a + 1; c < sweep_.size() && sweep_[c].first <= max_x; ++c) {
      const int j = sweep_[c].second;
      const double reach = reach_i + radius_[j] + inflation[j];
      if ((centre_[i] - centre_[j]).squaredNorm() <= reach * reach) add(i, j);
    }
  }
  for (int plane : half_spaces_) {
    const Pose X_SW = (X_WB[body_of_[plane]] * shapes_[plane]->X_BS).inverse();  // world to the plane's shape frame
    for (int b : bounded_) {
      if (HalfSpaceCandidate(plane, X_SW, b, inflation)) add(plane, b);
    }
    for (int other : half_spaces_) {
      if (other > plane) add(plane, other);
    }
  }
  for (int u : other_unbounded_) {  // with every other shape (a pair of two such shapes is added twice, then deduplicated)
    for (int b = 0; b < static_cast<int>(shapes_.size()); ++b) add(u, b);
  }
  std::sort(pairs->begin(), pairs->end());
  pairs->erase(std::unique(pairs->begin(), pairs->end()), pairs->end());
}

}  // namespace implicit_sim
