// The geometrically implicit time stepper (paper Sections III-IV): per island and step one mixed NCP (the paper's step)
// or two (the RATTLE step's stages; StepperOptions::scheme, schemes/), solved by semismooth Newton. Usage:
//   StepperOptions options;  options.h = 0.01;
//   Data data(model);        // every derived quantity and the solver workspace, allocated once
//   State state = State::Initial(model);
//   StepReport report = Step(model, options, &state, &data);
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/core/step/options.h"
#include "implicit_sim/core/step/step_report.h"

namespace implicit_sim {

// Advances *state by one step of options.h. A cold step (no warm start) first checks that no two bodies overlap; a
// step whose end velocities exceed options.max_speed / max_angular_speed is undone. StepReport::fault says what went
// wrong; the state is never left non-finite. `external_wrench_W`, if given, holds 6 values per moving body slot:
// force (N) then torque (N m), world frame, at the centre of mass, constant over the step (added to the model's
// constant applied wrench). data->joint_drives holds the joints' PD drives over the step (joints.h, JointDrive;
// data->joint_drive_effort receives their efforts). Throws std::invalid_argument for invalid options, a state
// CheckState refuses (size, non-finite value, quaternion not of unit norm), a wrench vector whose size does not match the model, a non-finite wrench, or a drive CheckJointDrive refuses (the
// message names the joint), and then changes nothing; solver trouble is reported, never thrown. With data->interrupt
// due (base/interrupt.h) the step stops between factorizations and is undone (StepFault::kInterrupted).
StepReport Step(const Model& model, const StepperOptions& options, State* state, Data* data,
                const Eigen::VectorXd* external_wrench_W = nullptr);

}  // namespace implicit_sim
