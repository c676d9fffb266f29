// An independent distance oracle: Ipopt solving paper eq. 7, min |x1 - x2|^2 subject to both bodies' inequalities.
// It shares nothing with the time stepper but the shape functions, so tests use it to check the stepper's closest
// points and that no step end interpenetrates; the stepper uses it to seed the closest points of a new pair.
#pragma once

#include <algorithm>

#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {

struct ClosestPointsResult {
  bool solved = false;    // Ipopt reported success (or an acceptable point)
  double distance = 0.0;  // |p_W1 - p_W2| at the solution (m); 0 when the bodies touch or overlap
  Vec3 p_W1 = Vec3::Zero();  // closest point on body 1, world frame
  Vec3 p_W2 = Vec3::Zero();  // closest point on body 2, world frame
};

// Paper eq. 7 for two posed shapes (X_WB: pose of each body; the shape carries its own X_BS).
ClosestPointsResult ComputeClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                         const Pose& X_WB2);

// Support value max { u . x : x in the posed shape } for a unit direction u (m). A single half-space is
// handled in closed form (+inf unless u is its outward normal within 1e-9); other unbounded shapes are clipped to
// a cube of half side 1e4 m.
double SupportValue(const ConvexShape& shape, const Pose& X_WB, const Vec3& u_W);

// An upper bound on the penetration depth of two posed bodies, certified by the plane through p_W on normal n_W
// (pointing from body 2 towards body 1): body 2 must lie in n.(x - p) <= 0 and body 1 in n.(x - p) >= 0. Returns how
// far each body crosses that plane, summed (m, >= 0). Translating body 1 by that amount along n separates them.
double PenetrationBound(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                        const Vec3& p_W, const Vec3& n_W);

// The same bound from any support functions of the two bodies, support_k(u) = max { u . x : x in body k } (m): how
// far body 2 reaches beyond the plane along n, plus how far body 1 reaches below it. n_W must be a unit vector.
template <typename Support1, typename Support2>
double PlaneCrossingBound(const Support1& support1, const Support2& support2, const Vec3& p_W, const Vec3& n_W) {
  const double np = n_W.dot(p_W);
  return std::max(0.0, np + support1(-n_W)) + std::max(0.0, support2(n_W) - np);
}

}  // namespace implicit_sim
