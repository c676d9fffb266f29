// The options of a step: time step, solver choice, tolerances and health limits. They live outside the Model and
// validate themselves (IsValid names the option and its allowed range).
#pragma once

#include <string>

#include "implicit_sim/core/ncp/ipopt_ncp.h"
#include "implicit_sim/core/ncp/semismooth_newton.h"

namespace implicit_sim {

struct StepperOptions {
  enum class Solver { kNewton, kIpopt };
  double h = 0.01;                // time step (s), in (0, 1]
  Solver solver = Solver::kNewton;  // the primary solver; Newton's retry ladder also tries Ipopt
  NewtonOptions newton;
  int ipopt_max_iterations = 500; // [1, 100000]
  double contact_threshold = 1e-9;  // a pair counts as an active contact when its normal force exceeds this (N)
  // Broad phase (when Data uses one): a pair enters the NCP when the bounding spheres of its bodies, each grown by the
  // motion possible within the step (h |v| + h |w| |offset| + |g| h^2 / 2) plus this margin, overlap. (m, [0, 10])
  double broad_phase_margin = 0.005;
  // Health checks (see StepFault). A step whose end velocities exceed these diverged (m/s, rad/s; (0, 1e12]).
  double max_speed = 1e5;
  double max_angular_speed = 1e6;
  // A cold step (the first, or after a reset or a set state) refuses to start from bodies overlapping by more than
  // this (m, [0, 1]): the step's end-of-step contact would throw them apart with an impulse of overlap / h.
  double overlap_tolerance = 1e-6;
  bool IsValid(std::string* error) const;
  // The Ipopt solver's options (its convergence bar: IpoptNcpOptions::tolerance).
  IpoptNcpOptions IpoptOptions() const {
    IpoptNcpOptions ipopt;
    ipopt.max_iterations = ipopt_max_iterations;
    return ipopt;
  }
};

}  // namespace implicit_sim
