// The node's parameters (private namespace ~): read and validated at startup. The solver parameters (time_step,
// tolerance, max_iterations, solver) are rows of the core's options table (core/step/options.h), which gives their
// defaults and ranges.
#pragma once

#include <string>

#include <ros/ros.h>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/step/options.h"

namespace implicit_sim {

struct NodeParams {
  // Scene file path, or a name resolved as <scenes_dir>/<name>.urdf; "" -> the robot_description parameter.
  std::string scene;
  std::string scenes_dir;         // where scene names are looked up
  StepperOptions options;         // ~time_step (h), ~tolerance, ~max_iterations, ~solver; the rest at their defaults
  double publish_rate = 30.0;     // Hz, (0, 1000]: /tf, ~body_states, ~contacts, ~markers
  double real_time_factor = 1.0;  // [0, 1000]; 0 = as fast as possible
  // Hz of simulation time, (0, 1e6]: the physics thread sends /clock when the simulation time has moved 1 / clock_rate
  // since the last one (at most 1000 per second of wall time); the publish thread adds one per publish cycle.
  double clock_rate = 1000.0;
  bool paused = false;
  // What a refused step (initial overlap, divergence, no finite solution) does after the state is restored: "pause"
  // the simulation, or "reset" the bodies to their initial state and run on (pausing instead if the initial state
  // itself is refused).
  std::string on_fault = "pause";
  std::string world_frame = "world";
  double force_marker_scale = 0.05;  // m/N, (0, 100]: length of a contact force arrow per newton
  double contact_marker_size = 0.05;  // m, (0, 100]: diameter of a contact point (arrows scale with it)
  // Whether /tf carries the links that hang on joints (world -> link, like every other body). Set false to leave them
  // to robot_state_publisher fed by /joint_states (it publishes parent -> child along the URDF tree).
  bool publish_joint_link_tf = true;
  // Reads and validates; throws std::invalid_argument naming the parameter and its range, or an unknown private
  // parameter (a misspelt name would otherwise be ignored silently).
  static NodeParams Read(const ros::NodeHandle& pnh);
};

// Throws std::invalid_argument when ~world_frame names a link of the model (tf would get world_frame -> world_frame).
void CheckWorldFrame(const Model& model, const std::string& world_frame);

// The scene the parameters name (~scene, else the robot_description parameter of nh); throws std::invalid_argument
// naming ~scene or robot_description when there is none.
Model LoadNodeScene(const ros::NodeHandle& nh, const NodeParams& params);

}  // namespace implicit_sim
