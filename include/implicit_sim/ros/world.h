// The world the node's physics thread steps, with the commands applied to it, and how a world is read from a request,
// built and edited for ~spawn, ~delete and ~load_scene (doc/ros_node.md, "The open world"). Free of the node's
// threads: the node calls these from its service handlers and swaps the world on the physics thread.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/ros/node_params.h"

namespace implicit_sim {

// A wrench of ~apply_body_wrench, active over a span of simulation time.
struct TimedWrench {
  int body;            // moving body receiving it
  int frame_body;      // body whose link frame expresses it, -1 for the world frame
  Vec3 point, force, torque;  // in that frame (m, N, N m)
  double start, end;   // simulation time (s); end < 0: until cleared
};

// A mouse drag (world_commands.h ApplyDragFeedback): a spring from the grabbed point G of a body to the target the marker gives.
struct DragSpring {
  int body;
  Vec3 p_LG;      // the grabbed point in the body's link frame (m)
  Vec3 target_W;  // where the spring pulls it, world frame (m)
  Vec3 p_GM_W;    // from the grabbed point to the marker origin at the grab, world frame (m)
};

// A ~joint_trajectory being followed (world_drives.cpp); times in s, positions in rad or m.
struct Trajectory {
  uint64_t id = 0;          // unique for the node's life (StartTrajectory): ~follow_trajectory finds its own by it
  std::vector<int> joints;  // model joints; -1 where a later command took the joint over
  double start = 0.0;       // simulation time of time_from_start = 0 (s)
  std::vector<double> times, from;  // time_from_start of each point; the joints' positions at the start
  std::vector<std::vector<double>> positions, velocities;  // per point, per joint
  double stiffness = 0.0, damping = 0.0;  // the drive gains (~drive_stiffness, ~drive_damping when received)
  bool gravity_compensation = false;      // ~drive_gravity_compensation when received
};

// What the node's physics thread steps (it alone touches a World). Data keeps a pointer to its model, so the model
// lives on the heap.
struct World {
  std::shared_ptr<const Model> model;
  State state, initial_state;
  std::unique_ptr<Data> data;
  std::vector<TimedWrench> wrenches;
  Eigen::VectorXd commanded_W;    // ~wrench_cmd per moving slot (Model::v_offset): f_W (N), tau_W (N m) at the link
                                  // origin
  Eigen::VectorXd wrench_W;       // the wrench handed to the core (at the centre of mass; core/model/wrench.h)
  Eigen::VectorXd joint_efforts;  // per model joint: the commanded effort (N m or N; fixed joints 0)
  std::vector<DragSpring> drags;
  std::vector<Trajectory> trajectories;
  std::string urdf;       // the scene's URDF text (what ~spawn and ~delete edit)
  std::string scene_dir;  // where its relative mesh paths resolve ("" for a scene given as text)
  explicit World(std::shared_ptr<const Model> loaded);
};

// A 'package://pkg/path' URI as a file path through rospack; "" when the package is unknown or it is no such URI.
std::string ResolvePackageUri(const std::string& uri);

// The scene a request names: its text (urdf), or a file: a name or relative path looked up in ~scenes_dir, then the
// package's scenes/ (".urdf" added when missing), an absolute path, or a package:// URI, each read only inside the
// node's sandbox (doc/ros_node.md, "Security"; one message for every refusal). False with *error otherwise (both or
// neither given, a path outside, a missing or unreadable file, an unknown package).
bool ReadRequestedScene(const NodeParams& params, const std::string& urdf, const std::string& file, SceneText* out,
                        std::string* error);

// Loads `scene` as a world at its initial state; throws std::invalid_argument (the loader's message, or a
// ~world_frame that names a link), LoadInterrupted once `stop` (may be null) is due.
std::unique_ptr<World> BuildWorld(const NodeParams& params, const SceneText& scene, const StepInterrupt* stop);

// `current` edited to `urdf` (the same scene name and mesh directory): the bodies and joints the two share, matched by
// name, keep their state, wrenches, efforts, drives, trajectories and drags. Throws as BuildWorld.
std::unique_ptr<World> EditedWorld(const NodeParams& params, const World& current, const std::string& urdf,
                                   const StepInterrupt* stop);

}  // namespace implicit_sim
