// The node's parameters (private namespace ~): read and validated at startup. The solver parameters (time_step,
// tolerance, max_iterations, solver) are rows of the core's options table (core/step/options.h), which gives their
// defaults and ranges.
#pragma once

#include <string>
#include <vector>

#include <ros/ros.h>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/step/options.h"

namespace implicit_sim {

// The parameters that can change while the node runs (dynamic_reconfigure, cfg/SimNode.cfg; the solver's tolerance
// and max_iterations too, through the options). Each has a range (LiveParamRanges) checked at startup and on every
// change.
struct LiveParams {
  double real_time_factor = 1.0;  // [0, 1000]; 0 = as fast as possible
  double publish_rate = 30.0;     // Hz of wall time, (0, 1000]: /tf and the per-state topics
  // Hz of simulation time, (0, 1e6]: the physics thread sends /clock when the simulation time has moved 1 / clock_rate
  // since the last one (at most 1000 per second of wall time); the publish thread adds one per publish cycle.
  double clock_rate = 1000.0;
  double force_marker_scale = 0.05;   // m/N, (0, 100]: length of a contact force arrow per newton
  double contact_marker_size = 0.05;  // m, (0, 100]: diameter of a contact point (arrows scale with it)
  double drive_stiffness = 0.0;   // [0, 1e12] N m/rad or N/m: gains of a ~joint_command that gives none
  double drive_damping = 0.0;     // [0, 1e12] N m s/rad or N s/m
  double drag_frequency = 2.0;    // Hz, (0, 100]: natural frequency of the interactive markers' drag spring
};

// One row per live parameter: its name, range and unit, and where it lives in LiveParams.
struct LiveParamRange {
  const char* name;
  double lo, hi;
  bool lo_open;
  const char* unit;
  double LiveParams::*field;
};
const std::vector<LiveParamRange>& LiveParamRanges();
// "" when value is finite and in range; otherwise the refusal, naming the parameter and its range.
std::string CheckLiveParam(const LiveParamRange& range, double value);

// What a refused step (initial overlap, divergence, no finite solution) does after the state is restored (~on_fault):
// "pause" the simulation, or "reset" the bodies to their initial state and run on (pausing instead if the initial
// state itself is refused).
enum class OnFault { kPause, kReset };

struct NodeParams {
  // Scene file path, or a name resolved as <scenes_dir>/<name>.urdf; "" -> the robot_description parameter.
  std::string scene;
  std::string scenes_dir;         // where scene names are looked up
  // ~read_dirs (a ':'-separated list): directories whose scene and mesh files the services may read besides
  // ~scenes_dir, the package's scenes/ and ROS packages (doc/ros_node.md, "Security").
  std::vector<std::string> read_dirs;
  StepperOptions options;         // ~time_step (h), ~scheme, ~tolerance, ~max_iterations, ~solver, ~threads
  LiveParams live;
  bool paused = false;
  OnFault on_fault = OnFault::kPause;  // ~on_fault: "pause" or "reset"
  // ~on_master_loss: "reregister" (register again with a master that returns) or "exit" (status 1); master_watch.h.
  bool exit_on_master_loss = false;
  std::string world_frame = "world";
  // Whether /tf carries the links that hang on joints (world -> link, like every other body). Set false to leave them
  // to robot_state_publisher fed by /joint_states (it publishes parent -> child along the URDF tree).
  bool publish_joint_link_tf = true;
  // /diagnostics is WARN while the real-time factor of the last second is below this fraction of ~real_time_factor,
  // or a step has run longer than a second; [0, 1], 0: never (doc/ros_node.md, "Diagnostics").
  double min_real_time_fraction = 0.5;
  // Joint drives of ~joint_command and ~joint_trajectory add the gravity feed-forward (JointDrive::gravity_compensation).
  bool drive_gravity_compensation = false;
  bool interactive_markers = true;  // an interactive marker per moving body (~drag) that pushes it with the mouse
  // A scene whose root link is not `world` (a robot URDF): false welds the root to the world, true makes it free.
  bool floating_root = false;
  // Every load (the scene, ~spawn, ~load_scene) bounds the rates of joints with a URDF <limit velocity> > 0
  // (LoaderOptions::enforce_velocity_limits; a joint's <implicit_sim><joint enforce_velocity_limit> overrides it).
  bool enforce_velocity_limits = false;
  // The input journal (ros/input_journal.h): a file to record every applied command into, and one to replay.
  std::string input_journal, replay_journal;
  // Reads and validates; throws std::invalid_argument naming the parameter and its range, or an unknown private
  // parameter (a misspelt name would otherwise be ignored silently).
  static NodeParams Read(const ros::NodeHandle& pnh);
};

// Throws std::invalid_argument when ~world_frame names a link of the model (tf would get world_frame -> world_frame).
void CheckWorldFrame(const Model& model, const std::string& world_frame);

// A scene's URDF text, its name and the directory its relative mesh paths resolve against ("" for text).
struct SceneText {
  std::string urdf, name, dir;
};

// The scene the parameters name (~scene, else the robot_description parameter of nh); throws std::invalid_argument
// naming ~scene or robot_description when there is none, or the loader's message.
SceneText ReadNodeScene(const ros::NodeHandle& nh, const NodeParams& params);

}  // namespace implicit_sim
