// Closed-form support points and closest points of primitive shapes. The stepper seeds a pair's closest points with
// these (microseconds) and falls back to the Ipopt distance oracle (about 10 ms) only for general intersections.
#pragma once

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {

// The point of the posed shape farthest along the unit direction u_W: argmax { u . x }. Returns false for shapes
// without a closed form (a half-space, a general intersection without vertices).
bool SupportPoint(const ConvexShape& shape, const Pose& X_WB, const Vec3& u_W, Vec3* p_W);

// Closest points in closed form for a sphere and a sphere, or any primitive with a closed-form support point and a
// half-space (the support point along the plane's inward normal, and its projection on the plane). `distance` is
// signed here: negative when the shapes overlap. Returns false when no closed form applies.
bool ClosedFormClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                             const Pose& X_WB2, ClosestPointsResult* result);

// The least crossing c(n) = support1(-n) + support2(n) over unit directions n (pointing from body 2 towards body 1),
// found by projected-gradient descent from the centre line with closed-form support points. c(n) is how far body 1
// must move along n to clear body 2: its positive part bounds the penetration depth from above for every n, and for
// separated bodies its minimum is minus their distance, reached where the two support points are the closest points.
struct CrossingDescent {
  double value = 0.0;        // c(n) at the last n (m); +inf when a shape has no closed-form support point
  Vec3 n_W = Vec3::UnitZ();  // the last direction
  Vec3 p_W1 = Vec3::Zero();  // support point of body 1 along -n (world)
  Vec3 p_W2 = Vec3::Zero();  // support point of body 2 along n (world)
  bool stationary = false;   // the tangential gradient p2 - p1 fell below 1e-9 m (1e-7 m where rounding stalls c)
};
// Stops at a stationary n, once c(n) < stop_below (a certified separation; -inf: never), or after max_steps steps.
CrossingDescent DescendCrossing(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                const Pose& X_WB2, double stop_below, int max_steps);

// Closest points of a sphere or an ellipsoid and a sphere or an ellipsoid by DescendCrossing (distance >= 0). Returns
// false for other shapes, and with require_stationary when the descent did not reach a stationary direction.
bool DescentClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                          bool require_stationary, ClosestPointsResult* result);

// The closed form when there is one; for two spheres or ellipsoids the support-function descent run to a stationary
// direction (microseconds); the Ipopt oracle (paper eq. 7, milliseconds) otherwise.
ClosestPointsResult FindClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                      const Pose& X_WB2);

// An upper bound on how deep two posed shapes overlap (m; 0 when they are apart): the closed form where there is one,
// else the least crossing found by DescendCrossing, stopped once it certifies an overlap of at most `tolerance`, and
// beyond that the smaller of it and the crossing along the distance oracle's normals.
double PenetrationBound(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                        double tolerance);

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
