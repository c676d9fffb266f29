// An open world: ~spawn, ~delete and ~load_scene. The model is const, so each edits the scene's URDF text
// (core/io/scene_edit.h), loads a new model and swaps the whole world on the physics thread between two steps; the
// bodies the old and new worlds share keep their state, wrenches, joint efforts and drags, matched by name. A refused
// request (a name clash, an overlap, the loader's message) changes nothing. ~set_joint_positions changes only the
// state (core/model/joint_configuration.h).
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <filesystem>
#include <map>
#include <fstream>
#include <sstream>

#include <ros/package.h>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/joint_configuration.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/step_health.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {

namespace fs = std::filesystem;

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

// Names and values of a request as a map; false with *error for unequal lengths or a name given twice.
bool NamedValues(const std::vector<std::string>& names, const std::vector<double>& values, const char* what,
                 std::map<std::string, double>* out, std::string* error) {
  if (names.size() != values.size()) {
    *error = std::string(what) + ": " + std::to_string(names.size()) + " names but " + std::to_string(values.size()) +
             " positions (need one per name)";
    return false;
  }
  for (size_t i = 0; i < names.size(); ++i) {
    if (!out->emplace(names[i], values[i]).second) {
      *error = std::string(what) + ": joint '" + names[i] + "' given twice";
      return false;
    }
  }
  return true;
}

}  // namespace

void SimNode::ReplaceWorld(std::unique_ptr<World> next) {
  world_ = std::move(next);
  sensors_->SetWorld(*world_->model, SimTime());
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
  if (error.empty()) NamedValues(req.joint_names, req.joint_positions, "joint_names", &addition.joint_positions, &error);
  addition.self_collide = req.self_collide;
  addition.srdf = req.srdf;
  if (error.empty()) ReadRequestedScene(params_, req.urdf, req.file, &addition_text, &error);
  if (!error.empty()) {
    res.success = false;
    res.message = error;
    return true;
  }
  addition.urdf = addition_text.urdf;
  addition.base_dir = addition_text.dir;
  return mailbox_.RunBetweenSteps([&] {
           res.success = false;
           try {
             std::vector<std::string> added;
             const std::string urdf = AddToScene(world_->urdf, addition, &added);
             std::unique_ptr<World> next = EditedWorld(params_, *world_, urdf, stop_);
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
  return mailbox_.RunBetweenSteps([&] {
           res.success = false;
           try {
             std::vector<std::string> removed;
             const std::string urdf = RemoveFromScene(world_->urdf, req.bodies, &removed);
             std::unique_ptr<World> next = EditedWorld(params_, *world_, urdf, stop_);
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
  if (!ReadRequestedScene(params_, req.urdf, req.file, &scene, &error)) {
    res.success = false;
    res.message = error;
    return true;
  }
  std::map<std::string, double> positions;
  if (!NamedValues(req.joint_names, req.joint_positions, "joint_names", &positions, &error)) {
    res.success = false;
    res.message = error;
    return true;
  }
  std::unique_ptr<World> next;
  try {
    scene.urdf = WithStartEntries(scene.urdf, positions, req.srdf);
    next = BuildWorld(params_, scene, stop_);  // off the physics thread: loading a large scene does not hold the steps up
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    return true;
  }
  return mailbox_.RunBetweenSteps([&] {
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

bool SimNode::OnSetJointPositions(implicit_sim::SetJointPositions::Request& req,
                                  implicit_sim::SetJointPositions::Response& res) {
  std::map<std::string, double> by_name;
  std::string error;
  if (!NamedValues(req.names, req.positions, "names", &by_name, &error)) {
    res.success = false;
    res.message = error;
    return true;
  }
  return mailbox_.RunBetweenSteps([&] {
           const Model& model = *world_->model;
           std::map<int, double> positions;
           for (const auto& [name, q] : by_name) {
             const int j = model.FindJoint(name);
             if (j < 0) {
               res.success = false;
               res.message = "unknown joint '" + name + "'";
               return;
             }
             positions[j] = q;
           }
           State next = world_->state;
           res.success = SetJointPositions(model, positions, &next, &error);
           if (!res.success) {
             res.message = error;
             return;
           }
           std::string overlap;
           Data check(model);
           if (FindInitialOverlap(model, next, options_.overlap_tolerance, &check, &overlap)) {
             res.success = false;
             res.message = "refused: " + overlap + " (more than the overlap tolerance " +
                           FormatNumber(options_.overlap_tolerance) + " m)";
             return;
           }
           world_->state = next;
           JournalUnreplayable("~set_joint_positions");
           ClearWarmStart(world_->data.get());  // the next step starts cold from the new configuration
           SaveSnapshot();
           res.message = "set " + std::to_string(positions.size()) + " joints at t = " + FormatNumber(SimTime()) + " s";
         }) || ShuttingDownAnswer(res);
}

}  // namespace implicit_sim
