// Seeds of the step NCP's unknowns: the initial guess of a solve. A cold start takes closest points from closed forms
// (geometry/support.h) or the distance oracle, normals and normal-cone multipliers consistent with them, and friction
// from the start-of-step slip; a warm start takes the previous step's solution, carried over the step, with the
// tangent axes of the friction basis kept where they still suit the normals (StepLayout::UpdateTangentAxes).
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/kinematics.h"
#include "implicit_sim/core/step/layout.h"
#include "implicit_sim/core/step/problems/step_problem.h"

namespace implicit_sim {

// Closest points without the oracle, for a pair entering the NCP through the broad phase (apart by about the
// margin): the closed form where there is one; for an ellipsoid and a sphere or an ellipsoid the support-function
// descent (geometry/support.h, microseconds); otherwise the support points of both bodies along the line of their
// shape origins (a fair guess for convex bodies near each other).
ClosestPointsResult QuickClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                       const Pose& X_WB2);

// Fills the contact block c of z from closest points at the configuration `state` (with use_oracle FindClosestPoints:
// a closed form, the support-function descent for spheres and ellipsoids, else the Ipopt oracle; otherwise
// QuickClosestPoints) for a cold start, with multipliers consistent with the normal and a normal force guess (half the
// force scale Fs, N, when touching).
void SeedPair(const Model& model, const State& state, int c, const StepLayout& layout, double force_scale,
              Eigen::VectorXd* z, bool use_oracle = true);

// Cold-start friction guess of block c (or every block) from the start-of-step relative velocity at the points in *z:
// sigma = the generalized slip speed and s = the sliding direction (sigma = 0, s = 0 is a saddle of the merit function
// for a sliding or separated contact).
void SeedFriction(const StepLayout& layout, const StepKinematics& kinematics, int c, Eigen::VectorXd* z);
void SeedFriction(const StepLayout& layout, const StepKinematics& kinematics, Eigen::VectorXd* z);

// The cold-start guess of every unknown of `problem`: its velocity seed (StepProblem::SeedVelocities), zero joint
// multipliers with joint friction seeded like SeedFriction, every pair seeded by SeedPair, fresh tangent axes (in
// *layout, the problem's) and the friction seeds. The kinematics' BeginStep must have been called for `state`.
void SeedColdStart(const Model& model, const State& state, const StepProblem& problem, StepLayout* layout,
                   Eigen::VectorXd* z);

// The warm-start guess from the previous step's solution in *z: the problem's velocity seed, the tangent axes kept
// where they still suit the normals, and the closest points carried with their bodies over the step (a += h v0; not
// as material points: a rolling sphere's contact point moves with its centre) with d = n . (a1 - a2), so that a fast
// body's warm start stays near the new solution instead of a spurious one (the far sides of two spheres also satisfy
// the normal cones).
void SeedWarmStart(const Model& model, const State& state, const StepProblem& problem, StepLayout* layout,
                   Eigen::VectorXd* z);

}  // namespace implicit_sim
