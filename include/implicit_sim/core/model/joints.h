// Joint kinematics: the constraint functions of a joint, its position and velocity, and the wrench of a joint effort.
// The step (step/rows/joint_rows.h), the runner and the ROS node share them.
//
// A joint joins the joint origin x_P = p_P + R_P p_PJ on its parent to x_C = p_C + R_C p_CJ on its child, and the
// joint frames' axes U_k = R_P R_PJ e_k and W_k = R_C R_CJ e_k (k = 0: the axis a, 1 and 2: b1 and b2 normal to it).
// Equalities (zero when the joint holds; the paper's bilateral constraints, its eq. 1 with joints):
//   linear rows    (x_C - x_P) . U_k   for k = 0, 1, 2 (revolute, continuous, fixed) or k = 1, 2 (prismatic)
//   angular rows   U_0 . W_1 and U_0 . W_2 (the axes stay parallel), and for prismatic and fixed also U_1 . W_2
//                  (no turning about the axis)
// Positions: revolute and continuous theta = offset + atan2(U_2 . W_1, U_1 . W_1) (rad), prismatic (x_C - x_P) . U_0
// (m), fixed 0.
#pragma once

#include <string>

#include <Eigen/Core>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"

namespace implicit_sim {

// The gradient of a scalar joint function with respect to small motions of the parent (P) and the child (C): a
// translation dp (m) and a rotation dtheta (rad, world frame, R -> Exp(dtheta) R) of each. Read as a generalized
// force, it is the force (dp) and the torque about the centre of mass (dth) that a unit multiplier of the function
// exerts on each body (world frame).
struct JointGradient {
  Vec3 dp_P = Vec3::Zero(), dth_P = Vec3::Zero(), dp_C = Vec3::Zero(), dth_C = Vec3::Zero();
  // The function's rate for the bodies' velocities (world frame, at the centres of mass).
  double Rate(const Vec3& v_P, const Vec3& w_P, const Vec3& v_C, const Vec3& w_C) const {
    return dp_P.dot(v_P) + dth_P.dot(w_P) + dp_C.dot(v_C) + dth_C.dot(w_C);
  }
};

// Equality i in [0, joint.num_equalities()) at the body poses X_WP (the parent; the world: identity) and X_WC, with
// its gradient if `gradient` is not null. Linear rows in m, angular rows dimensionless (the sine of an angle).
double JointEquality(const Joint& joint, int i, const Pose& X_WP, const Pose& X_WC, JointGradient* gradient);
bool IsLinearEquality(const Joint& joint, int i);
// The joint position (rad or m; 0 for a fixed joint) and its gradient.
double JointPosition(const Joint& joint, const Pose& X_WP, const Pose& X_WC, JointGradient* gradient);

Pose ParentPose(const Model& model, const State& state, const Joint& joint);  // identity for the world
double JointPosition(const Model& model, const State& state, int joint);      // rad or m
double JointVelocity(const Model& model, const State& state, int joint);      // rad/s or m/s
// The largest violation of any joint equality in `state`: of the linear rows (m) and of the angular rows (rad).
void JointDrift(const Model& model, const State& state, double* position_m, double* angle_rad);

// A commanded effort (N m or N) clamped to +-joint.effort_limit when that is > 0.
double ClampJointEffort(const Joint& joint, double commanded);

// A PD drive of one joint (MuJoCo's position and velocity actuators, Gazebo's and PhysX's joint drives), one per model
// joint in Data::joint_drives. The step evaluates it implicitly, at the END of the step (step/rows/drive_rows.h):
//   tau = clamp(stiffness (position_target - q) + damping (velocity_target - qdot) + tau_g, -E, E)
// with q, qdot the end-of-step joint position and rate, E = Joint::effort_limit (no clamp when it is 0), so that it is
// stable at any gain, and tau_g the gravity feed-forward: with gravity_compensation, JointGravityEffort at the start of
// each step (Step sets gravity_effort), so a held arm does not sag by its weight over the stiffness. It adds to a
// commanded effort (AddJointEffortWrench) and to the joint's own damping. Inactive when stiffness == 0,
// damping == 0 and no gravity compensation (JointDriveActive).
struct JointDrive {            // one per model joint
  double position_target = 0;  // rad or m
  double velocity_target = 0;  // rad/s or m/s
  double stiffness = 0;        // kp >= 0: N m/rad or N/m
  double damping = 0;          // kd >= 0: N m s/rad or N s/m
  bool gravity_compensation = false;
  double gravity_effort = 0;   // N m or N: set by Step at the start of each step (0 without gravity_compensation)
};
// A joint position this close to a limit (rad or m) counts as on it: a drive may hold a finger measured at -1e-16
// below its lower limit of 0.
constexpr double kJointLimitRoundOff = 1e-12;
// The largest stiffness (N m/rad or N/m) and damping (N m s/rad or N s/m) CheckJointDrive accepts.
constexpr double kMaxJointDriveGain = 1e12;
inline bool JointDriveActive(const JointDrive& drive) {
  return drive.stiffness != 0.0 || drive.damping != 0.0 || drive.gravity_compensation;
}
// Per body b: the mass (kg) of b's subtree (b and every body below it through joints) and its first moment
// sum_c m_c p_Wc (kg m) in `state`, in one pass from the leaves up (O(bodies + joints); no allocation once sized).
void SubtreeMassMoments(const Model& model, const State& state, std::vector<double>* mass,
                        std::vector<Vec3>* first_moment_W);
// The effort (N m or N) that holds joint j's subtree (other joints held) against gravity in `state`:
// -sum_b m_b g . dp_b/dq, dp_b/dq = a x (p_b - o) for a revolute or continuous joint with axis a through o, a for a
// prismatic one; 0 for a fixed joint. With M and S the subtree's mass and first moment (SubtreeMassMoments) this is
// -a . ((S - M o) x g), or -M a . g. A mimic follower below j is taken as held. No allocation.
double JointGravityEffort(const Model& model, const State& state, int joint, const std::vector<double>& subtree_mass,
                          const std::vector<Vec3>& subtree_first_moment_W);
// Whether `drive` is valid for `joint`: finite targets, gains in [0, kMaxJointDriveGain], and if active a joint with a
// coordinate (never a fixed joint, nor a mimic joint: its leader is driven) and a position target within [lower, upper] (give or take kJointLimitRoundOff) for
// a limited joint. Otherwise false,
// with a message naming the joint in *error (if not null).
bool CheckJointDrive(const Joint& joint, const JointDrive& drive, std::string* error);
// position_target - q (rad or m); for a revolute or continuous joint without limits, whose position is an angle in
// (-pi, pi] (JointPosition), the shorter way round, in [-pi, pi].
double JointDrivePositionError(const Joint& joint, double position_target, double q);
// The drive's effort (N m or N) at joint position q and rate qdot, clamped to +-joint.effort_limit when that is > 0.
double JointDriveEffortAt(const Joint& joint, const JointDrive& drive, double q, double qdot);

// Adds the wrench of joint efforts (one per model joint: N m for revolute and continuous joints, N for prismatic;
// fixed joints take none) at the configuration of `state` to wrench_W (6 values per moving body slot: force, torque;
// world frame, at the centre of mass). Each effort is clamped by ClampJointEffort. Throws
// std::invalid_argument (and adds nothing) if the sizes do not match or an effort is not finite.
void AddJointEffortWrench(const Model& model, const State& state, const Eigen::VectorXd& efforts,
                          Eigen::VectorXd* wrench_W);

}  // namespace implicit_sim
