// The scene's sensors on ROS topics (doc/ros_node.md#sensors): after each step of the physics thread, every sensor
// whose next sample time (simulation time, 1 / rate apart) has come publishes on ~sensors/<name>: a contact sensor
// implicit_sim/ContactSensor, an IMU sensor_msgs/Imu, a force-torque sensor geometry_msgs/WrenchStamped. Publishers follow the world: a new world (spawn, delete,
// load_scene) advertises its sensors' topics and drops those of sensors it no longer has. Touched by the physics thread
// only.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <ros/ros.h>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/contact_result.h"
#include "implicit_sim/core/step/sensors.h"

namespace implicit_sim {

class NodeSensors {
 public:
  NodeSensors(ros::NodeHandle pnh, std::string world_frame, double contact_threshold);
  // The sensors of a new world; sample times restart from sim_time (s).
  void SetWorld(const Model& model, double sim_time);
  // After a step from `before` to `after` (h s) ending at sim_time (s) with `contacts`, solved by `scheme` (see
  // ReadForceTorque) with the external wrench `wrench_W` and the commanded `joint_efforts` it was given.
  void Sample(const Model& model, const State& before, const State& after, double h, StepperOptions::Scheme scheme,
              const std::vector<ContactResult>& contacts, const Eigen::VectorXd& wrench_W,
              const Eigen::VectorXd& joint_efforts, double sim_time);

 private:
  ros::NodeHandle pnh_;
  const std::string world_frame_;
  const double contact_threshold_;  // N
  std::map<std::string, ros::Publisher> publishers_;  // by "<sensor name>/<type>": a topic keeps its type
  std::vector<ros::Publisher*> by_sensor_;            // per Model::sensors entry
  std::vector<double> next_time_;                     // s of simulation time
  ContactSensorReading contact_reading_;              // workspace
  std::vector<char> in_subtree_;                      // workspace of ReadForceTorque
};

}  // namespace implicit_sim
