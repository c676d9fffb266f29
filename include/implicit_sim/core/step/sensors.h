// Readings of the scene's sensors (Model::sensors) from a step's results: what a ROS user closes loops on.
// - contact: the contacts touching the sensor's link (Gazebo's bumper), and the total force and moment they exert on it;
// - IMU: the orientation of the link frame, its angular velocity and its specific force (acceleration minus gravity,
//   what an accelerometer reads: 0 in free fall, +g upwards at rest), in the link frame.
#pragma once

#include <vector>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/contact_result.h"

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

}  // namespace implicit_sim
