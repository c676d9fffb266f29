// An open world: ~spawn, ~delete and ~load_scene. The model is const, so each edits the scene's URDF text
// (core/io/scene_edit.h), loads a new model and swaps the whole world on the physics thread between two steps; the
// bodies the old and new worlds share keep their state, wrenches, joint efforts and drags, matched by name. A refused
// request (a name clash, an overlap, the loader's message) changes nothing.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <filesystem>
#include <fstream>
#include <sstream>

#include <ros/package.h>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/step_health.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {

namespace fs = std::filesystem;

// Whether `path` lies inside directory `dir` (both made canonical; a missing path never does).
bool IsInside(const fs::path& path, const std::string& dir) {
  std::error_code ec;
  const fs::path canonical_dir = fs::canonical(dir, ec);
  if (ec) return false;
  const fs::path canonical = fs::canonical(path, ec);
  if (ec) return false;
  const std::string d = canonical_dir.string() + "/", p = canonical.string();
  return p.compare(0, d.size(), d) == 0;
}

Pose PoseFromMsg(const geometry_msgs::Pose& msg, std::string* error) {
  const Vec3 p = conv::ToVec3(msg.position);
  Eigen::Quaterniond q(msg.orientation.w, msg.orientation.x, msg.orientation.y, msg.orientation.z);
  if (!p.allFinite() || !q.coeffs().allFinite()) {
    *error = "pose must be finite";
  } else if (q.norm() < 1e-9) {
    if (q.coeffs().isZero()) q = Eigen::Quaterniond::Identity();  // an unset orientation: identity
    else *error = "pose orientation is a zero quaternion";
  }
  if (!error->empty()) return Pose::Identity();
  Pose X = Pose::Identity();
  X.linear() = q.normalized().toRotationMatrix();
  X.translation() = p;
  return X;
}

}  // namespace

std::string ResolvePackageUri(const std::string& uri) {
  const std::string scheme = "package://";
  if (uri.compare(0, scheme.size(), scheme) != 0) return "";
  const std::string rest = uri.substr(scheme.size());
  const size_t slash = rest.find('/');
  const std::string package = ros::package::getPath(rest.substr(0, slash));
  if (package.empty()) return "";
  return slash == std::string::npos ? package : package + rest.substr(slash);
}

LoaderOptions SimNode::SceneLoaderOptions(const std::string& mesh_directory,
                                          std::vector<std::string>* warnings) const {
  LoaderOptions options;
  options.floating_root = params_.floating_root;
  options.resolve_package_uri = ResolvePackageUri;
  options.mesh_directory = mesh_directory;
  options.warnings = warnings;
  return options;
}

bool SimNode::ReadRequestedScene(const std::string& urdf, const std::string& file, SceneText* out,
                                 std::string* error) const {
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
  fs::path path;
  if (file.compare(0, 10, "package://") == 0) {
    path = ResolvePackageUri(file);
    if (path.empty()) {
      *error = "file '" + file + "': no such package";
      return false;
    }
  } else if (file.find('/') == std::string::npos && fs::path(file).extension() != ".urdf") {
    path = fs::path(params_.scenes_dir) / (file + ".urdf");  // a scene name
  } else {
    path = file;
    if (!IsInside(path, params_.scenes_dir) && !IsInside(path, IMPLICIT_SIM_SCENES_DIR)) {
      *error = "file '" + file + "' is not a file under ~scenes_dir (" + params_.scenes_dir +
               ") or the package's scenes/: the node reads scene files there and from package:// URIs only";
      return false;
    }
  }
  try {
    *out = SceneText{ReadSceneFile(path.string()), path.stem().string(), path.parent_path().string()};
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  return true;
}

std::unique_ptr<SimNode::World> SimNode::BuildWorld(const SceneText& scene) const {
  std::vector<std::string> warnings;
  auto model = std::make_shared<const Model>(
      LoadSceneFromString(scene.urdf, scene.name, SceneLoaderOptions(scene.dir, &warnings)));
  for (const std::string& warning : warnings) ROS_WARN("%s", warning.c_str());
  CheckWorldFrame(*model, params_.world_frame);
  auto world = std::make_unique<World>(std::move(model));
  world->urdf = scene.urdf;
  world->scene_dir = scene.dir;
  return world;
}

void SimNode::CarryOver(const World& from, World* to) const {
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

std::unique_ptr<SimNode::World> SimNode::EditedWorld(const std::string& urdf) const {
  std::unique_ptr<World> next = BuildWorld(SceneText{urdf, world_->model->scene_name, world_->scene_dir});
  CarryOver(*world_, next.get());
  return next;
}

void SimNode::ReplaceWorld(std::unique_ptr<World> next) {
  world_ = std::move(next);
  stepped_ = false;  // a new Data: no contact results, the next step starts cold
  restart_pacing_ = true;
  SaveSnapshot();
  PublishRobotDescription(world_->urdf);
}

void SimNode::PublishRobotDescription(const std::string& urdf) const {
  if (params_.scene.empty()) return;  // the scene came from robot_description: that is the user's to keep
  try {
    nh_.setParam("robot_description", RobotDescriptionOf(urdf));
  } catch (const std::exception& e) {
    ROS_WARN("implicit_sim: robot_description not updated: %s", e.what());
  }
}

bool SimNode::OnSpawn(implicit_sim::Spawn::Request& req, implicit_sim::Spawn::Response& res) {
  std::string error;
  SceneText addition_text;
  SceneAddition addition;
  addition.prefix = req.prefix;
  addition.floating_root = req.floating_root;
  addition.X_WO = PoseFromMsg(req.pose, &error);
  addition.v_WO = conv::ToVec3(req.twist.linear);
  addition.w_WO = conv::ToVec3(req.twist.angular);
  if (error.empty() && (!addition.v_WO.allFinite() || !addition.w_WO.allFinite())) error = "twist must be finite";
  if (error.empty()) ReadRequestedScene(req.urdf, req.file, &addition_text, &error);
  if (!error.empty()) {
    res.success = false;
    res.message = error;
    return true;
  }
  addition.urdf = addition_text.urdf;
  addition.base_dir = addition_text.dir;
  return RunBetweenSteps([&] {
           res.success = false;
           try {
             std::vector<std::string> added;
             const std::string urdf = AddToScene(world_->urdf, addition, &added);
             std::unique_ptr<World> next = EditedWorld(urdf);
             std::string overlap;
             Data check(*next->model);
             if (FindInitialOverlap(*next->model, next->state, options_.overlap_tolerance, &check, &overlap)) {
               res.message = "refused: " + overlap + " (more than the overlap tolerance " +
                             FormatNumber(options_.overlap_tolerance) + " m)";
               return;
             }
             ReplaceWorld(std::move(next));
             JournalUnreplayable("~spawn");
             res.bodies = added;
             res.success = true;
             res.message = "spawned " + std::to_string(added.size()) + " links";
           } catch (const std::exception& e) {
             res.message = e.what();
           }
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnDelete(implicit_sim::Delete::Request& req, implicit_sim::Delete::Response& res) {
  return RunBetweenSteps([&] {
           res.success = false;
           try {
             std::vector<std::string> removed;
             const std::string urdf = RemoveFromScene(world_->urdf, req.bodies, &removed);
             std::unique_ptr<World> next = EditedWorld(urdf);
             ReplaceWorld(std::move(next));
             JournalUnreplayable("~delete");
             res.deleted = removed;
             res.success = true;
             res.message = "deleted " + std::to_string(removed.size()) + " links";
           } catch (const std::exception& e) {
             res.message = e.what();
           }
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnLoadScene(implicit_sim::LoadScene::Request& req, implicit_sim::LoadScene::Response& res) {
  SceneText scene;
  std::string error;
  if (!ReadRequestedScene(req.urdf, req.file, &scene, &error)) {
    res.success = false;
    res.message = error;
    return true;
  }
  std::unique_ptr<World> next;
  try {
    next = BuildWorld(scene);  // off the physics thread: loading a large scene does not hold the steps up
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    return true;
  }
  return RunBetweenSteps([&] {
           time_offset_ = SimTime();  // simulation time goes on from where it was
           next->state.t = 0.0;
           const std::string name = next->model->scene_name;
           const int moving = next->model->num_moving();
           ReplaceWorld(std::move(next));
           JournalUnreplayable("~load_scene");
           res.success = true;
           res.message = "loaded scene '" + name + "' (" + std::to_string(moving) + " moving bodies) at t = " +
                         FormatNumber(SimTime()) + " s";
         }) || ShuttingDownAnswer(res);
}

}  // namespace implicit_sim
