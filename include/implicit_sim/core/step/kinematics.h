// The kinematics of one step over a layout (layout.h): the start-of-step state of its bodies and joints and the
// external wrenches (BeginStep), and the end-of-step poses of paper eq. 2, p = p0 + h v, R = Exp(h w) R0, for the
// velocities in z. Every problem of the step (problems/) reads the same start.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/layout.h"

namespace implicit_sim {

struct BodyStart {  // a body at the start of the step
  Vec3 p0 = Vec3::Zero();
  Mat3 R0 = Mat3::Identity();
  Vec3 v0 = Vec3::Zero(), w0 = Vec3::Zero();
  Mat3 I_W0 = Mat3::Zero();  // world inertia at the start of the step (kg m^2)
};

struct BodyEnd {  // a body at the end of the step, for the current iterate z
  Vec3 p = Vec3::Zero();
  Mat3 R = Mat3::Identity();
  Vec3 v = Vec3::Zero(), w = Vec3::Zero();  // zero for a fixed body
  Mat3 dtheta_dw = Mat3::Zero();             // h J_l(h w): rotation increment per change of w (zero when fixed)
  int col = -1;                              // column of v in z (w at col + 3), -1 when fixed
};

class StepKinematics {
 public:
  explicit StepKinematics(const StepLayout& layout);
  const StepLayout& layout() const { return layout_; }

  // Stores the start-of-step quantities (poses, velocities, world inertia, the joints' gradients) and the external
  // wrenches of the step: 6 values per model velocity slot (force N, torque N m; world frame, at the centre of mass),
  // or null. Call again after the layout changed.
  void BeginStep(const State& start, double h, const Eigen::VectorXd* external_wrench_W);
  double h() const { return h_; }
  // The force scale Fs of the step's rows (N): the model's (Model::ForceScale), or a larger external force.
  double force_scale() const { return force_scale_; }
  const BodyStart& start(int local) const { return start_[local]; }  // local: an index into layout().bodies()

  // The constant external force (N) and torque (N m) on the i-th moving body over the step: gravity, the model's
  // applied wrench and BeginStep's external wrench (world frame, at the centre of mass).
  Vec3 ExternalForce(int i) const;
  Vec3 ExternalTorque(int i) const;

  // The gradients of joint j's equalities and of its position at the start of the step (joints.h).
  const JointGradient& equality_gradient(int joint, int i) const { return joint_equality_start_[joint][i]; }
  const JointGradient& position_gradient(int joint) const { return joint_position_start_[joint]; }

  // Every body of the layout at the end of the step for the velocities in z (paper eq. 2).
  void EndOfStep(const Eigen::VectorXd& z, std::vector<BodyEnd>* ends) const;
  // End-of-step pose of model body b (one of layout().bodies()) for velocities in z (paper eq. 2).
  Pose EndPose(int body, const Eigen::VectorXd& z) const;

 private:
  const StepLayout& layout_;
  const double model_force_scale_;  // Model::ForceScale(), computed once
  double h_ = 0.0;
  double force_scale_ = 1.0;
  std::vector<BodyStart> start_;       // per entry of layout().bodies()
  Eigen::VectorXd external_wrench_W_;  // per moving body: force, torque (world, at the centre of mass)
  std::vector<std::array<JointGradient, 6>> joint_equality_start_;  // per model joint
  std::vector<JointGradient> joint_position_start_;
};

}  // namespace implicit_sim
