// Scenes as URDF: a root link `world`, moving bodies on `floating` joints, static bodies on `fixed` joints. A robot
// URDF whose root link is not `world` loads with its root fixed to the world (or free: LoaderOptions::floating_root),
// and a <mesh> collision becomes the convex hull of the mesh's vertices.
// The implicit shapes and the simulation parameters live in extension elements that stock URDF tools ignore:
//   inside <collision>:   <implicit type="..." .../>    (optional for stock sphere, box and cylinder geometry)
//   under <robot>:        <implicit_sim gravity="0 0 -9.81">
//                           <friction mu=".." e_t=".." e_o=".." e_r=".."/>                   default of every pair
//                           <friction link1=".." link2=".." mu=".." .../>                     one pair
//                           <body link=".." velocity="vx vy vz" angular_velocity="wx wy wz"
//                                 force="fx fy fz" torque="tx ty tz" locked="y rx rz"/>
//                         </implicit_sim>
// doc/scenes.md documents every element and attribute with units and allowed ranges.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "implicit_sim/core/base/file_sandbox.h"
#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/model/mesh_hull_cache.h"
#include "implicit_sim/core/model/model.h"

namespace implicit_sim {

// What one load may take (doc/scenes.md#limits): larger scene files are refused before they are read (bytes; the
// largest shipped pile, 4000 ellipsoids, is 2.3 MB), scenes with more <link> or <joint> elements right after the XML
// parse. Together they bound a load to a few seconds and a few hundred MB; the contact pairs are bounded by
// Model::kMaxContactPairs.
constexpr size_t kMaxSceneBytes = size_t{16} << 20;
constexpr int kMaxSceneLinks = 50000;

struct LoaderOptions {
  // A root link other than 'world': false welds it to the world at X_W_root (a static body), true makes it a free
  // body starting at X_W_root. Both must stay at their defaults when the root link is 'world'.
  bool floating_root = false;
  Pose X_W_root = Pose::Identity();  // pose of the root link frame in the world
  // Resolves a 'package://pkg/path' mesh URI to a file path ("" when it cannot); tried before ROS_PACKAGE_PATH. The
  // ROS layer sets it; the core never includes ROS headers.
  std::function<std::string(const std::string& uri)> resolve_package_uri;
  // Where mesh files may be read from (core/base/file_sandbox.h; default: anywhere). When restricted, a package:// URI
  // must also stay inside its package, and every refusal has the same message. The node sets it.
  FileSandbox mesh_sandbox;
  // A mesh file larger than this is refused before it is read (bytes, > 0).
  uint64_t max_mesh_bytes = uint64_t{64} << 20;
  // Directory of relative mesh paths. Empty: the URDF file's directory (LoadSceneFromFile) or the working directory
  // (LoadSceneFromString).
  std::string mesh_directory;
  // A mesh hull with more faces is simplified by merging nearly coplanar facets until it has at most this many: each
  // face is one inequality, hence one multiplier per contact in the step NCP. Range [4, 10000].
  int max_hull_faces = 64;
  // Hulls computed before, reused by file content, scale and max_hull_faces; a reused hull adds no note. Null: every
  // mesh is read and hulled.
  std::shared_ptr<MeshHullCache> hull_cache;
  // Start positions (rad or m) of joints by name, over the scene's <implicit_sim><joint position>: each joint must be
  // revolute, continuous or prismatic, not a mimic follower, and the position within its limits (give or take
  // kJointLimitRoundOff). A limited joint given no start anywhere starts at 0, which must then lie within its limits.
  std::map<std::string, double> joint_positions;
  // true: the step bounds the rate of every joint with a URDF <limit velocity> > 0 to +-velocity (a mimic follower
  // through its leader); a joint's <implicit_sim><joint enforce_velocity_limit> overrides it. Default off, as Gazebo,
  // MuJoCo and Drake leave passive joints' rates unbounded (doc/scenes.md#velocity-limits).
  bool enforce_velocity_limits = false;
  // The loader's notes, one line each (mesh hulls, vendor attributes ignored, mass from geometry, wide revolute
  // ranges) are appended here; null: written to std::cerr.
  std::vector<std::string>* warnings = nullptr;
  // Watched between the loader's stages and between links (a mesh hull each at most): once it is due, the load throws
  // LoadInterrupted. Null: never. The node and the Python API point it at their SIGINT and SIGTERM handling; the
  // longest stretch without a check is urdfdom's parse (about 1 s for a file at kMaxSceneBytes).
  const StepInterrupt* interrupt = nullptr;
};

// Throws std::invalid_argument naming the link, joint or attribute and the allowed range, LoadInterrupted when
// options.interrupt became due. Never returns a partial model.
Model LoadSceneFromString(const std::string& urdf_xml, const std::string& scene_name = "scene",
                          const LoaderOptions& options = LoaderOptions());
Model LoadSceneFromFile(const std::string& path, const LoaderOptions& options = LoaderOptions());
// The text of a scene file, refused (std::invalid_argument naming the file) when it is not a readable regular file or
// is larger than kMaxSceneBytes, before reading it.
std::string ReadSceneFile(const std::string& path);

}  // namespace implicit_sim
