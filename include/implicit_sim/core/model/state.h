// The state of a simulation: time, configuration and velocity of the moving bodies. Nothing else.
#pragma once

#include <string>

#include <Eigen/Core>

#include "implicit_sim/core/model/model.h"

namespace implicit_sim {

struct State {
  double t = 0.0;          // s
  Eigen::VectorXd q;       // per moving body: p_WB (3, m), then the unit quaternion of R_WB (w, x, y, z)
  Eigen::VectorXd v;       // per moving body: v_WB (3, m/s), then w_WB (3, rad/s), world frame

  static State Initial(const Model& model);
  Pose X_WB(const Model& model, int body) const;  // fixed bodies: their constant pose
  Pose X_WL(const Model& model, int body) const;  // the body's URDF link frame L in the world: X_WB * Body::X_BL
  Vec3 v_WB(int slot) const { return v.segment<3>(Model::v_offset(slot)); }
  Vec3 w_WB(int slot) const { return v.segment<3>(Model::v_offset(slot) + 3); }
};

double KineticEnergy(const Model& model, const State& state);  // J

// How far from 1 the norm of a state's quaternion may be (CheckState).
constexpr double kUnitQuaternionTolerance = 1e-9;

// Whether `state` is one of `model`: q of model.nq() and v of model.nv() values, t, positions and velocities finite,
// and every quaternion of unit norm within kUnitQuaternionTolerance. When not, sets *error (if not null) to a message
// naming the first offending value (the body, its entry of q or v, the allowed range) and returns false. Allocates
// nothing when the state is valid.
bool CheckState(const Model& model, const State& state, std::string* error);

}  // namespace implicit_sim
