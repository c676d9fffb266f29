// What every row emitter of rows/ reads: the layout, the step's kinematics, the bodies at the end of the step for the
// current iterate, the iterate z, and where the rows go (RowWriter).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/step/kinematics.h"
#include "implicit_sim/core/step/layout.h"
#include "implicit_sim/core/step/rows/row_writer.h"

namespace implicit_sim {

// How the friction rows are written (rows/friction_rows.h): projected, with the projection scale r (s/m), or the
// paper's bilinear rows (IslandSolve::SchemeFor from StepperOptions::projected_friction and friction_projection_scale).
struct FrictionForm {
  bool projected = true;
  double projection_scale = 1.0;
};

struct RowContext {
  const StepLayout& layout;
  const StepKinematics& kinematics;
  const std::vector<BodyEnd>& ends;  // per entry of layout.bodies()
  const Eigen::VectorXd& z;
  const RowWriter& out;
  const FrictionForm& friction;
  const Model& model() const { return layout.model(); }
  double h() const { return kinematics.h(); }
  double Fs() const { return kinematics.force_scale(); }
  // A joint's parent (the world: identity pose, no velocity unknowns) and child at the end of the step.
  const BodyEnd& ParentEnd(int joint) const {
    const int parent = layout.joint_bodies(joint).parent;
    return parent < 0 ? kWorld : ends[parent];
  }
  const BodyEnd& ChildEnd(int joint) const { return ends[layout.joint_bodies(joint).child]; }
  static const BodyEnd kWorld;
};

}  // namespace implicit_sim
