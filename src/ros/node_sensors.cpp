#include "implicit_sim/ros/node_sensors.h"

#include <algorithm>
#include <utility>

#include <geometry_msgs/WrenchStamped.h>
#include <sensor_msgs/Imu.h>

#include "implicit_sim/ContactSensor.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;

NodeSensors::NodeSensors(ros::NodeHandle pnh, std::string world_frame, double contact_threshold)
    : pnh_(pnh), world_frame_(std::move(world_frame)), contact_threshold_(contact_threshold) {}

void NodeSensors::SetWorld(const Model& model, double sim_time) {
  std::map<std::string, ros::Publisher> kept;
  for (const Sensor& sensor : model.sensors) {
    // A sensor keeps its topic when its name and type are unchanged (the topic's type cannot change).
    const std::string key = sensor.name + "/" + SensorTypeName(sensor.type);
    auto old = publishers_.find(key);
    if (old != publishers_.end()) {
      kept[key] = old->second;
    } else if (sensor.type == SensorType::kImu) {
      kept[key] = pnh_.advertise<sensor_msgs::Imu>("sensors/" + sensor.name, 10);
    } else if (sensor.type == SensorType::kForceTorque) {
      kept[key] = pnh_.advertise<geometry_msgs::WrenchStamped>("sensors/" + sensor.name, 10);
    } else {
      kept[key] = pnh_.advertise<implicit_sim::ContactSensor>("sensors/" + sensor.name, 10);
    }
  }
  publishers_ = std::move(kept);  // the others are shut down with their last copy
  by_sensor_.clear();
  for (const Sensor& sensor : model.sensors) {
    by_sensor_.push_back(&publishers_[sensor.name + "/" + SensorTypeName(sensor.type)]);
  }
  next_time_.assign(model.sensors.size(), sim_time);
}

void NodeSensors::Sample(const Model& model, const State& before, const State& after, double h,
                         StepperOptions::Scheme scheme, const std::vector<ContactResult>& contacts,
                         const Eigen::VectorXd& wrench_W, const Eigen::VectorXd& joint_efforts, double sim_time) {
  const ros::Time stamp = ros::Time().fromSec(sim_time);
  for (size_t s = 0; s < model.sensors.size(); ++s) {
    if (sim_time < next_time_[s]) continue;
    const Sensor& sensor = model.sensors[s];
    const double period = 1.0 / sensor.rate_hz;
    next_time_[s] = std::max(next_time_[s] + period, sim_time);  // no burst after a pause or a long step
    if (sensor.type == SensorType::kImu) {
      const ImuReading reading = ReadImu(model, sensor, before, after, h);
      sensor_msgs::Imu msg;
      msg.header.stamp = stamp;
      msg.header.frame_id = sensor.link;
      msg.orientation.w = reading.q_WS.w();
      msg.orientation.x = reading.q_WS.x();
      msg.orientation.y = reading.q_WS.y();
      msg.orientation.z = reading.q_WS.z();
      msg.angular_velocity = conv::ToVectorMsg(reading.w_S);
      msg.linear_acceleration = conv::ToVectorMsg(reading.a_S);
      by_sensor_[s]->publish(msg);
    } else if (sensor.type == SensorType::kForceTorque) {
      const bool efforts = joint_efforts.size() == static_cast<int>(model.joints.size());
      const ForceTorqueReading reading = ReadForceTorque(model, sensor, before, after, h, scheme, contacts, &wrench_W,
                                                         efforts ? &joint_efforts : nullptr, &in_subtree_);
      geometry_msgs::WrenchStamped msg;
      msg.header.stamp = stamp;
      msg.header.frame_id = sensor.link;
      msg.wrench.force = conv::ToVectorMsg(reading.force_L);
      msg.wrench.torque = conv::ToVectorMsg(reading.torque_L);
      by_sensor_[s]->publish(msg);
    } else {
      ReadContactSensor(model, after, sensor, contacts, contact_threshold_, &contact_reading_);
      implicit_sim::ContactSensor msg;
      msg.header.stamp = stamp;
      msg.header.frame_id = world_frame_;
      msg.link = sensor.link;
      for (int c : contact_reading_.contacts) {
        msg.contacts.push_back(conv::ToContactMsg(model, contacts[c].pair, contacts[c]));
      }
      msg.wrench.force = conv::ToVectorMsg(contact_reading_.force_W);
      msg.wrench.torque = conv::ToVectorMsg(contact_reading_.moment_W);
      by_sensor_[s]->publish(msg);
    }
  }
}

}  // namespace implicit_sim
