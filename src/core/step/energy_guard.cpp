#include "implicit_sim/core/step/energy_guard.h"

#include <algorithm>
#include <cmath>

#include "implicit_sim/core/model/joints.h"

namespace implicit_sim {

EnergyBalance StepEnergyBalance(const StepKinematics& kinematics, const Eigen::VectorXd& z_pose,
                                const Eigen::VectorXd& z_velocity) {
  const StepLayout& layout = kinematics.layout();
  const Model& model = layout.model();
  const double h = kinematics.h();
  EnergyBalance balance;
  double force_sum = 0.0;  // N
  for (size_t i = 0; i < layout.slots().size(); ++i) {
    const int local = layout.slot_body(static_cast<int>(i));
    const int body = layout.bodies()[local];
    const Body& b = model.bodies[body];
    const BodyStart& start = kinematics.start(local);
    const int col = static_cast<int>(6 * i);
    const Pose X_WB1 = kinematics.EndPose(body, z_pose);
    const Mat3& R1 = X_WB1.linear();
    const Vec3 v1 = z_velocity.segment<3>(col), w1 = z_velocity.segment<3>(col + 3);
    balance.kinetic_start += 0.5 * b.mass * start.v0.squaredNorm() + 0.5 * start.w0.dot(start.I_W0 * start.w0);
    balance.kinetic_end += 0.5 * b.mass * v1.squaredNorm() + 0.5 * w1.dot(R1 * b.I_B * R1.transpose() * w1);
    // Paper eq. 2: p1 = p0 + h v, R1 = Exp(h w) R0 with the pose velocities, so the rotation vector is h w.
    const Vec3 f = kinematics.ExternalForce(static_cast<int>(i)), tau = kinematics.ExternalTorque(static_cast<int>(i));
    balance.external_work += f.dot(X_WB1.translation() - start.p0) + tau.dot(h * z_pose.segment<3>(col + 3));
    force_sum += f.norm();
  }
  // A drive's effort u (the step's) over the joint's motion h qdot at the pose velocities.
  for (int joint : layout.joints()) {
    if (!layout.driven_joints()[joint]) continue;
    const JointBodies& bodies = layout.joint_bodies(joint);
    const auto velocity = [&](int local, int part) -> Vec3 {
      const int col = local < 0 ? -1 : layout.column(local);
      return col < 0 ? Vec3::Zero() : Vec3(z_pose.segment<3>(col + part));
    };
    const double rate = kinematics.position_gradient(joint).Rate(velocity(bodies.parent, 0), velocity(bodies.parent, 3),
                                                                 velocity(bodies.child, 0), velocity(bodies.child, 3));
    balance.drive_work += layout.JointDriveEffort(z_velocity, joint) * h * rate;
  }
  balance.allowance = kSmoothMotionEnergyShare *
                          (std::max(balance.kinetic_start, balance.kinetic_end) + std::abs(balance.external_work) +
                           std::abs(balance.drive_work)) +
                      kEnergyFloorDistance * force_sum;
  return balance;
}

}  // namespace implicit_sim
