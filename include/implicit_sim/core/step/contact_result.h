// The contact quantities of one pair at the end of a step, derived from a step solution (problems/step_problem.h).
#pragma once

#include "implicit_sim/core/base/types.h"

namespace implicit_sim {

struct ContactResult {
  int pair = -1;                                     // the model pair
  Vec3 p_WA1 = Vec3::Zero(), p_WA2 = Vec3::Zero();  // closest points (m)
  Vec3 n_W = Vec3::UnitZ();                          // unit normal from body 2 towards body 1
  double gap = 0.0;                                  // signed distance d (m)
  double normal_force = 0.0;                         // N
  Vec3 friction_force_W = Vec3::Zero();              // tangential force on body 1 (N)
  double torsional_moment = 0.0;                     // about n (N m)
  Vec3 rolling_moment_W = Vec3::Zero();              // rolling resistance on body 1, tangent to n (N m)
  double slip_speed = 0.0;                           // tangential relative speed at the contact (m/s)
};

}  // namespace implicit_sim
