#include "implicit_sim/core/model/wrench.h"

#include <stdexcept>
#include <string>

namespace implicit_sim {

void AddWrenchAtPoint(const Model& model, const State& state, int body, int frame_body, const Vec3& p_FP,
                      const Vec3& f_F, const Vec3& tau_F, Eigen::VectorXd* wrench_W) {
  const int num_bodies = static_cast<int>(model.bodies.size());
  if (body < 0 || body >= num_bodies || model.velocity_slot[body] < 0) {
    throw std::invalid_argument("AddWrenchAtPoint: body " + std::to_string(body) + " is not a moving body");
  }
  if (frame_body < -1 || frame_body >= num_bodies) {
    throw std::invalid_argument("AddWrenchAtPoint: no frame body " + std::to_string(frame_body));
  }
  if (wrench_W->size() != model.nv()) {
    throw std::invalid_argument("AddWrenchAtPoint: expected a wrench vector of " + std::to_string(model.nv()));
  }
  Vec3 p_WP = p_FP, f_W = f_F, tau_W = tau_F;  // the world frame: nothing to transform
  if (frame_body >= 0) {
    const Pose X_WF = state.X_WL(model, frame_body);
    p_WP = X_WF * p_FP;
    f_W = X_WF.linear() * f_F;
    tau_W = X_WF.linear() * tau_F;
  }
  const Vec3 p_BcmP_W = p_WP - state.X_WB(model, body).translation();  // lever arm from the centre of mass (m)
  const int v = Model::v_offset(model.velocity_slot[body]);
  wrench_W->segment<3>(v) += f_W;
  wrench_W->segment<3>(v + 3) += tau_W + p_BcmP_W.cross(f_W);
}

}  // namespace implicit_sim
