// Seeds of the step NCP's unknowns: the initial guess of a solve. A cold start takes closest points from closed forms
// (geometry/support.h) or the distance oracle, normals and normal-cone multipliers consistent with them, and friction
// from the start-of-step slip; a warm start takes the previous step's solution, carried over the step. The tangent
// axes of the friction basis (StepProblem::UpdateTangentAxes) and the problem's own seeds are implemented beside them
// in src/core/step/seeding.cpp.
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/step_problem.h"

namespace implicit_sim {

// Closest points without the oracle, for a pair entering the NCP through the broad phase (apart by about the
// margin): the closed form where there is one; for an ellipsoid and a sphere or an ellipsoid the support-function
// descent (geometry/support.h, microseconds); otherwise the support points of both bodies along the line of their
// shape origins (a fair guess for convex bodies near each other).
ClosestPointsResult QuickClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                       const Pose& X_WB2);

// Fills the contact block c of z from closest points at the configuration `state` (with use_oracle FindClosestPoints:
// a closed form, the support-function descent for spheres and ellipsoids, else the Ipopt oracle; otherwise
// QuickClosestPoints) for a cold start, with multipliers consistent with the normal
// and a normal force guess.
void SeedPair(const Model& model, const State& state, int c, const StepProblem& problem, Eigen::VectorXd* z,
              bool use_oracle = true);

// The cold-start guess of every unknown: the state's velocities, the joint seeds, every pair seeded by SeedPair,
// fresh tangent axes and the friction seeds. BeginStep must have been called for `state`.
void SeedColdStart(const Model& model, const State& state, StepProblem* problem, Eigen::VectorXd* z);

// The warm-start guess from the previous step's solution in *z: the state's velocities, the tangent axes kept where
// they still suit the normals, and the closest points carried with their bodies over the step.
void SeedWarmStart(const Model& model, const State& state, StepProblem* problem, Eigen::VectorXd* z);

}  // namespace implicit_sim
