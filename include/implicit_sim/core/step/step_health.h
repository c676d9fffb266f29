// Health checks of a step (StepFault in step_report.h): bodies that overlap where a cold step would start, and
// velocities beyond any physical motion.
#pragma once

#include <string>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/core/step/kinematics.h"

namespace implicit_sim {

// True if two bodies of `state` overlap by more than `tolerance` (m); *detail then names the pair and the depth.
// Candidates come from the broad phase (bounding spheres), the depth is the certified bound of MaxPenetrationBound
// (closed forms and support-function descent first: the Ipopt oracle only where those do not settle it). Uses the
// broad phase and its workspace in *data.
bool FindInitialOverlap(const Model& model, const State& state, double tolerance, Data* data, std::string* detail);

// An upper bound on the deepest overlap of two bodies of `state` (m), from the geometry alone (none of a step's
// unknowns). Over the broad phase's candidate pairs: the closed-form signed distance where there is one (a primitive
// on a half-space, two spheres); otherwise the least c(n) = support1(-n) + support2(n) over unit n found by descent
// from the centre line with closed-form support points (how far body 1 must move along n to clear body 2: its
// positive part bounds the depth from above for every n, a negative value is a separation), and, when that is still
// above `tolerance`, also c(n) at the normals of both bodies at the distance oracle's closest points; the smallest of
// these, at least 0. Every value is certified by a plane: none rests on the oracle's distance. Uses the broad phase and its
// workspace in *data (a Data of its own: the stepper's warm start is not touched, but its broad-phase workspace is).
double MaxPenetrationBound(const Model& model, const State& state, double tolerance, Data* data);

// Tunnelling: an end-of-step solution z of the step from `start` in which a body has passed through another. The
// end-of-step conditions alone allow it (a ball against the FAR face of a thin wall is a legal NCP solution), so each
// pair of the problem is checked against the start of the step: its end-of-step separating plane (through a2, normal
// n), carried back with body 2 to body 2's start pose, must not have all of body 1's start pose strictly behind it
// (closed-form support points, or the bounding sphere). Returns the block of the first pair that crossed, -1 if none;
// *detail (if not null) then names the pair. No heap allocation unless a pair crossed and detail is given.
// kinematics: the step's (its layout's pairs are checked, its end poses used).
int FindCrossing(const Model& model, const State& start, const StepKinematics& kinematics, const Eigen::VectorXd& z,
                 std::string* detail);

// True if a moving body is faster than max_speed (m/s) or spins faster than max_angular_speed (rad/s).
bool FindDivergence(const Model& model, const State& state, double max_speed, double max_angular_speed,
                    std::string* detail);

}  // namespace implicit_sim
