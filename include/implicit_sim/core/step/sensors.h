// Readings of the scene's sensors (Model::sensors) from a step's results: what a ROS user closes loops on.
// - contact: the contacts touching the sensor's link (Gazebo's bumper), and the total force and moment they exert on it;
// - IMU: the orientation of the link frame, its angular velocity and its specific force (acceleration minus gravity,
//   what an accelerometer reads: 0 in free fall, +g upwards at rest), in the link frame;
// - force-torque: the wrench a joint carries into its child link (Gazebo's force_torque sensor: child frame, the
//   parent's side acting on the child's), at the joint origin, in the child link frame.
#pragma once

#include <vector>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/contact_result.h"
#include "implicit_sim/core/step/options.h"

namespace implicit_sim {

struct ContactSensorReading {
  std::vector<int> contacts;    // indices into the step's contacts touching the link with a normal force > threshold
  Vec3 force_W = Vec3::Zero();  // N: the sum of their forces on the link (normal and friction), world frame
  Vec3 moment_W = Vec3::Zero(); // N m: their moment on the link about its link frame's origin (with the torsional and
                                // rolling moments), world frame
};
// `contacts`: the step's contact results (Data::contacts); a contact counts when its normal force > threshold (N).
// Clears and fills *reading; allocates only when more contacts touch than ever before.
void ReadContactSensor(const Model& model, const State& state, const Sensor& sensor,
                       const std::vector<ContactResult>& contacts, double threshold, ContactSensorReading* reading);

struct ImuReading {
  Eigen::Quaterniond q_WS = Eigen::Quaterniond::Identity();  // the sensor (link) frame's orientation in the world
  Vec3 w_S = Vec3::Zero();       // rad/s: angular velocity, sensor frame
  Vec3 a_S = Vec3::Zero();       // m/s^2: specific force (acceleration of the frame's origin minus gravity), sensor frame
};
// The IMU of `sensor` over the step from `before` to `after` (h s apart): orientation and angular velocity at the end
// of the step, the acceleration as the change of the frame origin's velocity over the step (first order, the step's
// own).
ImuReading ReadImu(const Model& model, const Sensor& sensor, const State& before, const State& after, double h);

struct ForceTorqueReading {
  Vec3 force_L = Vec3::Zero();   // N: the force on the child link, in its link frame L (at the start of the step)
  Vec3 torque_L = Vec3::Zero();  // N m: the moment about L's origin (the joint origin), in L
};
// The wrench `sensor`'s joint carried over the step from `before` to `after` (h s apart), from the step's own results:
// every body of the subtree below the joint (its child and, through joints, every body below) balances its change of
// momentum against gravity, the scene's applied forces, `external_wrench_W` (the step's input, 6 values per moving
// slot; null: none) and its contacts (the step's `contacts`); what is left is what the joints carried, and the
// subtree's inner joints cancel. So the reading holds this joint's constraint force, limit, friction, damping and
// drive efforts, plus its commanded effort joint_efforts[joint] (N or N m; null: none), which the step took as part
// of `external_wrench_W`. A lock on a subtree body's axis (Body::locked) counts as carried by the joint.
// `scheme`: the scheme that solved the step (kPaper also for a RATTLE step whose island fell back to the paper's,
// StepReport::paper_fallbacks); the levers are where it applies joint forces (rows/joint_rows.h), so a free hinge's
// axis reads 0 to the solver's tolerance with the paper's step and to O(h^2) with RATTLE's. *in_subtree is a
// workspace (one flag per body).
ForceTorqueReading ReadForceTorque(const Model& model, const Sensor& sensor, const State& before, const State& after,
                                   double h, StepperOptions::Scheme scheme, const std::vector<ContactResult>& contacts,
                                   const Eigen::VectorXd* external_wrench_W, const Eigen::VectorXd* joint_efforts,
                                   std::vector<char>* in_subtree);

}  // namespace implicit_sim
