// The energy balance of an island's step (doc/method.md, "The energy guard"). Contact, friction, joint constraints,
// limits, joint friction and damping never do positive work, so over one step the kinetic energy of an island may rise
// by at most the work of the constant external wrenches (gravity, applied wrenches, joint efforts: all in
// StepKinematics' external wrench) and of the joint drives, plus the scheme's smooth-motion bound. The RATTLE scheme
// checks every step against it and solves a step that fails again on a cheaper path (schemes/rattle_scheme.h).
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/step/kinematics.h"

namespace implicit_sim {

struct EnergyBalance {
  double kinetic_start = 0.0;   // J, the island's bodies at the start of the step
  double kinetic_end = 0.0;     // J, at the end
  double external_work = 0.0;   // J, of the constant external forces and torques over the step's motion
  double drive_work = 0.0;      // J, of the joint drives' efforts over the joints' motion
  double allowance = 0.0;       // J, the smooth-motion bound and the solver's round-off floor
  // The rise of kinetic energy beyond what the wrenches supplied (J); positive means energy was created.
  double excess() const { return kinetic_end - kinetic_start - external_work - drive_work; }
  bool holds() const { return excess() <= allowance; }
};

// Share of the energy in motion (the larger kinetic energy and the external work) a second-order step may move up or
// down within one step for smooth motion (the O(h^2) oscillation of doc/method.md).
constexpr double kSmoothMotionEnergyShare = 1e-2;
// The floor of the allowance: the work of the external forces over this distance (m), the solver's position
// tolerance, so that a resting pile's round-off never counts.
constexpr double kEnergyFloorDistance = 1e-8;

// The balance of the step whose poses come from the velocities of z_pose (paper eq. 2) and whose end velocities are
// those of z_velocity (the same vector for the paper's step; stages 1 and 2 for RATTLE).
EnergyBalance StepEnergyBalance(const StepKinematics& kinematics, const Eigen::VectorXd& z_pose,
                                const Eigen::VectorXd& z_velocity);

}  // namespace implicit_sim
