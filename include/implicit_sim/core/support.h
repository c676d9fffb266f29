// Closed-form support points and closest points of primitive shapes. The stepper seeds a pair's closest points with
// these (microseconds) and falls back to the Ipopt distance oracle (about 10 ms) only for general intersections.
#pragma once

#include "implicit_sim/core/distance_oracle.h"
#include "implicit_sim/core/shapes.h"

namespace implicit_sim {

// The point of the posed shape farthest along the unit direction u_W: argmax { u . x }. Returns false for shapes
// without a closed form (a half-space, a general intersection).
bool SupportPoint(const ConvexShape& shape, const Pose& X_WB, const Vec3& u_W, Vec3* p_W);

// Closest points in closed form for a sphere and a sphere, or any primitive with a closed-form support point and a
// half-space (the support point along the plane's inward normal, and its projection on the plane). `distance` is
// signed here: negative when the shapes overlap. Returns false when no closed form applies.
bool ClosedFormClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                             const Pose& X_WB2, ClosestPointsResult* result);

// The closed form when there is one, the Ipopt oracle (paper eq. 7) otherwise.
ClosestPointsResult FindClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                      const Pose& X_WB2);

// The index of the inequality of `shape` (posed by X_WB) that is largest at p_W, its unit outward normal (world)
// and the norm of its gradient there.
int MostActiveInequality(const ConvexShape& shape, const Pose& X_WB, const Vec3& p_W, Vec3* normal_W,
                         double* grad_norm);

}  // namespace implicit_sim
