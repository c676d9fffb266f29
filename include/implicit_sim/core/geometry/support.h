// Closed-form support points and closest points of primitive shapes. The stepper seeds a pair's closest points with
// these (microseconds) and falls back to the Ipopt distance oracle (about 10 ms) only for general intersections.
#pragma once

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/geometry/shapes.h"

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

// Multipliers >= 0 of the inequalities active at p_W (within 1e-5 of the most active) whose combination of world
// gradients sum_k m_k grad f_k(p) best matches `direction_W` (the normal cone condition of the step NCP), written to
// multipliers[0 .. shape.inequalities.size()); the others are 0. At an edge or a corner several are positive: seeding
// only the most active one leaves the others' curvature out of the Jacobian, which is then singular (a tilted
// cylinder resting on its rim). Combinations of up to three active gradients are tried (Caratheodory); without a
// non-negative one, the most active inequality carries the whole normal. No heap allocation.
void SeedNormalConeMultipliers(const ConvexShape& shape, const Pose& X_WB, const Vec3& p_W, const Vec3& direction_W,
                               double* multipliers);

}  // namespace implicit_sim
