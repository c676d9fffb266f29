#include "implicit_sim/ros/world.h"

#include <filesystem>
#include <mutex>
#include <set>

#include <ros/console.h>
#include <ros/package.h>

#include "implicit_sim/core/base/file_sandbox.h"
#include "implicit_sim/core/model/urdf_loader.h"

namespace implicit_sim {
namespace {

namespace fs = std::filesystem;

// What the node reads files from on a request (doc/ros_node.md, "Security"): ~scenes_dir, the package's scenes/,
// ~read_dirs, ROS packages and, for meshes, the directory of the scene being loaded.
FileSandbox NodeSandbox(const NodeParams& params, const std::string& scene_dir) {
  FileSandbox sandbox;
  sandbox.roots = {params.scenes_dir, IMPLICIT_SIM_SCENES_DIR};
  sandbox.roots.insert(sandbox.roots.end(), params.read_dirs.begin(), params.read_dirs.end());
  if (!scene_dir.empty()) sandbox.roots.push_back(scene_dir);
  sandbox.package_files = true;
  return sandbox;
}

}  // namespace

World::World(std::shared_ptr<const Model> loaded)
    : model(std::move(loaded)), data(std::make_unique<Data>(*model)) {
  state = initial_state = State::Initial(*model);
  commanded_W = Eigen::VectorXd::Zero(model->nv());
  wrench_W = Eigen::VectorXd::Zero(model->nv());
  joint_efforts = Eigen::VectorXd::Zero(model->joints.size());
}

std::string ResolvePackageUri(const std::string& uri) {
  const std::string scheme = "package://";
  if (uri.compare(0, scheme.size(), scheme) != 0) return "";
  const std::string rest = uri.substr(scheme.size());
  const size_t slash = rest.find('/');
  const std::string package = ros::package::getPath(rest.substr(0, slash));
  if (package.empty()) return "";
  return slash == std::string::npos ? package : package + rest.substr(slash);
}

namespace {

LoaderOptions SceneLoaderOptions(const NodeParams& params, const std::string& mesh_directory,
                                 std::vector<std::string>* warnings, const StepInterrupt* stop) {
  LoaderOptions options;
  options.interrupt = stop;
  options.floating_root = params.floating_root;
  options.enforce_velocity_limits = params.enforce_velocity_limits;
  options.resolve_package_uri = ResolvePackageUri;
  options.mesh_directory = mesh_directory;
  options.mesh_sandbox = NodeSandbox(params, mesh_directory);
  options.warnings = warnings;
  // One cache for the node's life: a world edit re-loads the scene, but hulls each mesh (and notes it) only once.
  static const std::shared_ptr<MeshHullCache> hull_cache = std::make_shared<MeshHullCache>();
  options.hull_cache = hull_cache;
  return options;
}

// Every world edit re-loads the whole scene: a loader note (a robot's self-overlap, a vendor attribute) is logged the
// first time only, for the node's life.
void LogNewWarnings(const std::vector<std::string>& warnings) {
  static std::mutex mutex;
  static std::set<std::string> logged;
  const std::lock_guard<std::mutex> lock(mutex);
  for (const std::string& warning : warnings) {
    if (logged.insert(warning).second) ROS_WARN("%s", warning.c_str());
  }
}

// The state and commands of the bodies and joints `to` shares with `from`, by name.
void CarryOver(const World& from, World* to) {
  const Model &old_model = *from.model, &model = *to->model;
  to->state.t = from.state.t;
  for (int slot = 0; slot < model.num_moving(); ++slot) {
    const int b = model.moving_bodies[slot];
    const int old = old_model.FindBody(model.bodies[b].name);
    if (old < 0 || old_model.bodies[old].is_fixed) continue;
    const int old_slot = old_model.velocity_slot[old];
    to->state.q.segment<7>(Model::q_offset(slot)) = from.state.q.segment<7>(Model::q_offset(old_slot));
    to->state.v.segment<6>(Model::v_offset(slot)) = from.state.v.segment<6>(Model::v_offset(old_slot));
    to->commanded_W.segment<6>(Model::v_offset(slot)) = from.commanded_W.segment<6>(Model::v_offset(old_slot));
  }
  std::vector<int> joint_in_new(old_model.joints.size(), -1);
  for (size_t j = 0; j < model.joints.size(); ++j) {
    const int old = old_model.FindJoint(model.joints[j].name);
    if (old < 0) continue;
    joint_in_new[old] = static_cast<int>(j);
    to->joint_efforts[j] = from.joint_efforts[old];
    to->data->joint_drives[j] = from.data->joint_drives[old];
  }
  for (Trajectory trajectory : from.trajectories) {
    for (int& j : trajectory.joints) j = j < 0 ? -1 : joint_in_new[j];
    to->trajectories.push_back(std::move(trajectory));
  }
  const auto body_in_new = [&](int old_body) {
    return old_body < 0 ? -1 : model.FindBody(old_model.bodies[old_body].name);
  };
  for (TimedWrench w : from.wrenches) {
    const int body = body_in_new(w.body), frame = body_in_new(w.frame_body);
    if (body < 0 || (w.frame_body >= 0 && frame < 0)) continue;  // on (or expressed in) a removed body
    w.body = body;
    w.frame_body = frame;
    to->wrenches.push_back(w);
  }
  for (DragSpring drag : from.drags) {
    drag.body = body_in_new(drag.body);
    if (drag.body >= 0) to->drags.push_back(drag);
  }
}

}  // namespace

bool ReadRequestedScene(const NodeParams& params, const std::string& urdf, const std::string& file, SceneText* out,
                        std::string* error) {
  if (!urdf.empty() && !file.empty()) {
    *error = "give urdf or file, not both";
    return false;
  }
  if (!urdf.empty()) {
    *out = SceneText{urdf, "scene", ""};
    return true;
  }
  if (file.empty()) {
    *error = "give the scene as urdf (its text) or file";
    return false;
  }
  const FileSandbox sandbox = NodeSandbox(params, "");
  std::string path;  // canonical, inside the sandbox; "" when refused
  if (file.compare(0, 10, "package://") == 0) {  // a package URI stays inside its package
    const std::string package_dir = ResolvePackageUri(file.substr(0, file.find('/', 10)));
    if (package_dir.empty()) {
      *error = "file '" + file + "': no such package";
      return false;
    }
    FileSandbox in_package;
    in_package.roots = {package_dir};
    path = in_package.Allowed(ResolvePackageUri(file));
  } else if (fs::path(file).is_absolute()) {
    path = sandbox.Allowed(file);
  } else {  // a name or a relative path: in ~scenes_dir, then the package's scenes/; ".urdf" added when it has none
    const bool has_extension = fs::path(file).extension() == ".urdf";
    for (const std::string& dir : {params.scenes_dir, std::string(IMPLICIT_SIM_SCENES_DIR)}) {
      if (path.empty() && !has_extension) path = sandbox.Allowed((fs::path(dir) / (file + ".urdf")).string());
      if (path.empty()) path = sandbox.Allowed((fs::path(dir) / file).string());
    }
  }
  if (path.empty()) {  // one message for every refusal: it must not tell whether a path exists
    *error = "file '" + file + "': no readable scene file there inside what the node may read (" + sandbox.Describe() +
             "; a name or relative path is looked up in ~scenes_dir, then the package's scenes/; a package:// URI "
             "must stay inside its package)";
    return false;
  }
  try {
    *out = SceneText{ReadSceneFile(path), fs::path(path).stem().string(), fs::path(path).parent_path().string()};
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  return true;
}

std::unique_ptr<World> BuildWorld(const NodeParams& params, const SceneText& scene, const StepInterrupt* stop) {
  std::vector<std::string> warnings;
  auto model = std::make_shared<const Model>(
      LoadSceneFromString(scene.urdf, scene.name, SceneLoaderOptions(params, scene.dir, &warnings, stop)));
  LogNewWarnings(warnings);
  CheckWorldFrame(*model, params.world_frame);
  auto world = std::make_unique<World>(std::move(model));
  world->urdf = scene.urdf;
  world->scene_dir = scene.dir;
  return world;
}

std::unique_ptr<World> EditedWorld(const NodeParams& params, const World& current, const std::string& urdf,
                                   const StepInterrupt* stop) {
  std::unique_ptr<World> next = BuildWorld(params, SceneText{urdf, current.model->scene_name, current.scene_dir}, stop);
  CarryOver(current, next.get());
  return next;
}

}  // namespace implicit_sim
