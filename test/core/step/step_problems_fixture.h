// The step's problems over one layout of the whole model (every moving body, joint and pair), for tests that evaluate
// a problem directly: the layout, the kinematics, the drives (one per model joint) and one problem of each stage.
#pragma once

#include <vector>

#include "implicit_sim/core/step/problems/paper_step.h"
#include "implicit_sim/core/step/problems/rattle_position.h"
#include "implicit_sim/core/step/problems/rattle_velocity.h"

namespace implicit_sim {
namespace testing_support {

struct StepProblems {
  // regular_separated_friction: as the stepper's islands (true) or the paper's plain rows (false).
  explicit StepProblems(const Model& model, bool regular_separated_friction = false)
      : layout(model),
        kinematics(layout),
        drives(model.joints.size()),
        paper(layout, kinematics, drives, regular_separated_friction),
        position(layout, kinematics, drives, regular_separated_friction),
        velocity(layout, kinematics, drives) {}
  void SetFrictionForm(const FrictionForm& form) {
    paper.set_friction_form(form);
    position.set_friction_form(form);
    velocity.set_friction_form(form);
  }
  StepLayout layout;
  StepKinematics kinematics;
  std::vector<JointDrive> drives;
  PaperStepProblem paper;
  RattlePositionProblem position;
  RattleVelocityProblem velocity;
};

}  // namespace testing_support
}  // namespace implicit_sim
