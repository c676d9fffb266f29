#include "implicit_sim/core/step/kinematics.h"

#include <algorithm>

#include "step/contact_frame.h"

namespace implicit_sim {

StepKinematics::StepKinematics(const StepLayout& layout)
    : layout_(layout), model_force_scale_(layout.model().ForceScale()), force_scale_(model_force_scale_) {
  joint_equality_start_.resize(layout.model().joints.size());
  joint_position_start_.resize(layout.model().joints.size());
}

void StepKinematics::BeginStep(const State& start, double h, const Eigen::VectorXd* external_wrench_W) {
  const Model& model = layout_.model();
  const std::vector<int>& slots = layout_.slots();
  h_ = h;
  force_scale_ = model_force_scale_;
  if (external_wrench_W_.size() != static_cast<int>(6 * slots.size())) external_wrench_W_.resize(6 * slots.size());
  for (size_t s = 0; s < slots.size(); ++s) {
    if (external_wrench_W) {
      external_wrench_W_.segment<6>(6 * s) = external_wrench_W->segment<6>(Model::v_offset(slots[s]));
      force_scale_ = std::max(force_scale_, external_wrench_W_.segment<3>(6 * s).norm());
    } else {
      external_wrench_W_.segment<6>(6 * s).setZero();
    }
  }
  const std::vector<int>& bodies = layout_.bodies();
  if (start_.size() != bodies.size()) start_.resize(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) {
    const int b = bodies[i];
    const Pose X_WB = start.X_WB(model, b);
    BodyStart& s = start_[i];
    s.p0 = X_WB.translation();
    s.R0 = X_WB.linear();
    const int k = model.velocity_slot[b];
    s.v0 = k < 0 ? Vec3::Zero() : start.v_WB(k);
    s.w0 = k < 0 ? Vec3::Zero() : start.w_WB(k);
    s.I_W0 = s.R0 * model.bodies[b].I_B * s.R0.transpose();
  }
  for (int j : layout_.joints()) {
    const Joint& joint = model.joints[j];
    const JointBodies& jb = layout_.joint_bodies(j);
    const Pose X_WP = jb.parent < 0 ? Pose::Identity() : MakePose(start_[jb.parent].p0, start_[jb.parent].R0);
    const Pose X_WC = MakePose(start_[jb.child].p0, start_[jb.child].R0);
    for (int i = 0; i < joint.num_equalities(); ++i) JointEquality(joint, i, X_WP, X_WC, &joint_equality_start_[j][i]);
    JointPosition(joint, X_WP, X_WC, &joint_position_start_[j]);
  }
}

Vec3 StepKinematics::ExternalForce(int i) const {
  const Model& model = layout_.model();
  const Body& body = model.bodies[layout_.bodies()[layout_.slot_body(i)]];
  return body.mass * model.gravity_W + body.f_applied_W + external_wrench_W_.segment<3>(6 * i);
}

Vec3 StepKinematics::ExternalTorque(int i) const {
  return layout_.model().bodies[layout_.bodies()[layout_.slot_body(i)]].tau_applied_W +
         external_wrench_W_.segment<3>(6 * i + 3);
}

void StepKinematics::EndOfStep(const Eigen::VectorXd& z, std::vector<BodyEnd>* ends) const {
  if (ends->size() != start_.size()) ends->resize(start_.size());
  for (size_t b = 0; b < start_.size(); ++b) {
    BodyEnd& e = (*ends)[b];
    const BodyStart& s = start_[b];
    e.col = layout_.column(static_cast<int>(b));
    if (e.col < 0) {
      e.p = s.p0;
      e.R = s.R0;
      e.v.setZero();
      e.w.setZero();
      e.dtheta_dw.setZero();
      continue;
    }
    e.v = z.segment<3>(e.col);
    e.w = z.segment<3>(e.col + 3);
    EndOfStepPose(s.p0, s.R0, e.v, e.w, h_, &e.p, &e.R);  // paper eq. 2
    e.dtheta_dw = h_ * LeftJacobianSO3(h_ * e.w);
  }
}

Pose StepKinematics::EndPose(int body, const Eigen::VectorXd& z) const {
  const int local = layout_.LocalBody(body);
  const BodyStart& s = start_[local];
  const int col = layout_.column(local);
  if (col < 0) return MakePose(s.p0, s.R0);
  Vec3 p;
  Mat3 R;
  EndOfStepPose(s.p0, s.R0, z.segment<3>(col), z.segment<3>(col + 3), h_, &p, &R);  // paper eq. 2
  return MakePose(p, R);
}

}  // namespace implicit_sim
