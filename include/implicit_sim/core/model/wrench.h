// Applied wrenches: a force and torque given at a point in some frame, moved to the centre of mass of the body that
// receives it, in the layout of Step's external wrench vector (6 per moving slot at Model::v_offset: the force f_W
// (N), then the torque about the centre of mass tau_W (N m), both in the world frame W).
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"

namespace implicit_sim {

// Adds to *wrench_W the wrench that the force f_F (N) acting at the point p_FP (m) plus the torque tau_F (N m) exert
// on the moving body `body`. F is the URDF link frame L of body `frame_body` (at its pose in `state`), or the world
// for frame_body = -1. The torque about the centre of mass Bcm is tau_W + p_BcmP_W x f_W. Throws
// std::invalid_argument for a fixed or unknown body, an unknown frame body or a wrench vector not of size model.nv().
void AddWrenchAtPoint(const Model& model, const State& state, int body, int frame_body, const Vec3& p_FP,
                      const Vec3& f_F, const Vec3& tau_F, Eigen::VectorXd* wrench_W);

}  // namespace implicit_sim
