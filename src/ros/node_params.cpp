// Reading and validating the node's parameters.
#include "implicit_sim/ros/node_params.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>
#include <stdexcept>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/urdf_loader.h"

namespace implicit_sim {
namespace {

template <typename T>
T ReadParam(const ros::NodeHandle& pnh, const std::string& name, T fallback) {
  T value = fallback;
  if (pnh.hasParam(name) && !pnh.getParam(name, value)) {
    throw std::invalid_argument("parameter ~" + name + " has the wrong type");
  }
  return value;
}


// The solver parameters, through the options table: a number is read as a double (an integer parameter given as a
// double must be whole: roscpp's int reading would round 1.5 to 2), a choice as a string.
void ReadOptionParams(const ros::NodeHandle& pnh, StepperOptions* options) {
  for (const OptionRow& row : OptionTable()) {
    if (*row.ros_param == '\0' || !pnh.hasParam(row.ros_param)) continue;
    const std::string label = std::string("parameter ~") + row.ros_param;
    double value = 0.0;
    std::string error;
    if (row.kind == OptionKind::kChoice) {
      const std::string text = ReadParam<std::string>(pnh, row.ros_param, "");
      if (!ParseOptionValue(row, text, label, &value, &error)) throw std::invalid_argument(error);
    } else {
      value = ReadParam<double>(pnh, row.ros_param, 0.0);
      if (!CheckOptionValue(row, value, label, &error)) throw std::invalid_argument(error);
    }
    row.set(options, value);
  }
}

// The node's own private parameters besides the options table's.
const char* const kNodeParams[] = {"scene", "scenes_dir", "read_dirs", "paused", "on_fault", "on_master_loss", "world_frame", "publish_joint_link_tf",
                                   "drive_gravity_compensation", "enforce_velocity_limits", "min_real_time_fraction",
                                   "interactive_markers", "floating_root", "input_journal", "replay_journal"};

void RefuseUnknownParams(const ros::NodeHandle& pnh) {
  std::vector<std::string> names;
  if (!ros::param::getParamNames(names)) return;
  const std::string prefix = pnh.getNamespace() + "/";
  std::set<std::string> known(std::begin(kNodeParams), std::end(kNodeParams));
  for (const OptionRow& row : OptionTable()) {
    if (*row.ros_param != '\0') known.insert(row.ros_param);
  }
  for (const LiveParamRange& range : LiveParamRanges()) known.insert(range.name);
  for (const std::string& name : names) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string own = name.substr(prefix.size());
    if (known.count(own.substr(0, own.find('/')))) continue;
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    throw std::invalid_argument("unknown parameter ~" + own + " (the node reads: " + list + ")");
  }
}

}  // namespace

const std::vector<LiveParamRange>& LiveParamRanges() {
  static const std::vector<LiveParamRange> ranges = {
      {"real_time_factor", 0.0, 1000.0, false, "(0: as fast as possible)", &LiveParams::real_time_factor},
      {"publish_rate", 0.0, 1000.0, true, "Hz", &LiveParams::publish_rate},
      {"clock_rate", 0.0, 1e6, true, "Hz of simulation time", &LiveParams::clock_rate},
      {"force_marker_scale", 0.0, 100.0, true, "m/N", &LiveParams::force_marker_scale},
      {"contact_marker_size", 0.0, 100.0, true, "m", &LiveParams::contact_marker_size},
      {"drive_stiffness", 0.0, 1e12, false, "N m/rad or N/m", &LiveParams::drive_stiffness},
      {"drive_damping", 0.0, 1e12, false, "N m s/rad or N s/m", &LiveParams::drive_damping},
      {"drag_frequency", 0.0, 100.0, true, "Hz", &LiveParams::drag_frequency}};
  return ranges;
}

std::string CheckLiveParam(const LiveParamRange& r, double value) {
  const bool ok = std::isfinite(value) && (r.lo_open ? value > r.lo : value >= r.lo) && value <= r.hi;
  if (ok) return "";
  return std::string("parameter ~") + r.name + " = " + FormatNumber(value) + " is out of range " +
         (r.lo_open ? "(" : "[") + FormatNumber(r.lo) + ", " + FormatNumber(r.hi) + "] " + r.unit;
}

NodeParams NodeParams::Read(const ros::NodeHandle& pnh) {
  RefuseUnknownParams(pnh);
  NodeParams p;
  p.scene = ReadParam<std::string>(pnh, "scene", "");
  p.scenes_dir = ReadParam<std::string>(pnh, "scenes_dir", IMPLICIT_SIM_SCENES_DIR);
  std::istringstream read_dirs(ReadParam<std::string>(pnh, "read_dirs", ""));
  for (std::string dir; std::getline(read_dirs, dir, ':');) {
    if (dir.empty()) continue;
    if (!std::filesystem::path(dir).is_absolute()) {
      throw std::invalid_argument("parameter ~read_dirs: '" + dir + "' is not an absolute directory path");
    }
    p.read_dirs.push_back(dir);
  }
  ReadOptionParams(pnh, &p.options);
  for (const LiveParamRange& range : LiveParamRanges()) {
    double& value = p.live.*range.field;
    value = ReadParam(pnh, range.name, value);
    const std::string error = CheckLiveParam(range, value);
    if (!error.empty()) throw std::invalid_argument(error);
  }
  p.paused = ReadParam(pnh, "paused", p.paused);
  const std::string on_fault = ReadParam<std::string>(pnh, "on_fault", "pause");
  if (on_fault != "pause" && on_fault != "reset") {
    throw std::invalid_argument("parameter ~on_fault = '" + on_fault + "' must be pause or reset");
  }
  p.on_fault = on_fault == "reset" ? OnFault::kReset : OnFault::kPause;
  const std::string on_master_loss = ReadParam<std::string>(pnh, "on_master_loss", "reregister");
  if (on_master_loss != "reregister" && on_master_loss != "exit") {
    throw std::invalid_argument("parameter ~on_master_loss = '" + on_master_loss + "' must be reregister or exit");
  }
  p.exit_on_master_loss = on_master_loss == "exit";
  p.world_frame = ReadParam(pnh, "world_frame", p.world_frame);
  p.publish_joint_link_tf = ReadParam(pnh, "publish_joint_link_tf", p.publish_joint_link_tf);
  p.drive_gravity_compensation = ReadParam(pnh, "drive_gravity_compensation", p.drive_gravity_compensation);
  p.enforce_velocity_limits = ReadParam(pnh, "enforce_velocity_limits", p.enforce_velocity_limits);
  p.min_real_time_fraction = ReadParam(pnh, "min_real_time_fraction", p.min_real_time_fraction);
  if (!(p.min_real_time_fraction >= 0.0 && p.min_real_time_fraction <= 1.0)) {
    throw std::invalid_argument("parameter ~min_real_time_fraction = " + FormatNumber(p.min_real_time_fraction) +
                                " is out of range [0, 1] (0: never warn about the real-time factor)");
  }
  p.interactive_markers = ReadParam(pnh, "interactive_markers", p.interactive_markers);
  p.floating_root = ReadParam(pnh, "floating_root", p.floating_root);
  p.input_journal = ReadParam(pnh, "input_journal", p.input_journal);
  p.replay_journal = ReadParam(pnh, "replay_journal", p.replay_journal);
  if (p.world_frame.empty()) throw std::invalid_argument("parameter ~world_frame must not be empty");
  std::string error;
  if (!p.options.IsValid(&error)) throw std::invalid_argument(error);
  return p;
}

void CheckWorldFrame(const Model& model, const std::string& world_frame) {
  if (model.FindBody(world_frame) >= 0) {
    throw std::invalid_argument("parameter ~world_frame = '" + world_frame +
                                "' is a link of the scene: it must be a frame name of its own (default world)");
  }
}

SceneText ReadNodeScene(const ros::NodeHandle& nh, const NodeParams& p) {
  if (!p.scene.empty()) {
    const bool is_path = p.scene.find('/') != std::string::npos ||
                         (p.scene.size() > 5 && p.scene.substr(p.scene.size() - 5) == ".urdf");
    const std::string path = is_path ? p.scene : p.scenes_dir + "/" + p.scene + ".urdf";
    if (!std::ifstream(path)) {
      throw std::invalid_argument("parameter ~scene = '" + p.scene + "': no scene file '" + path + "'");
    }
    const std::filesystem::path file(path);
    return SceneText{ReadSceneFile(path), file.stem().string(), file.parent_path().string()};
  }
  std::string xml;
  if (!nh.getParam("robot_description", xml)) {
    throw std::invalid_argument("no scene: set ~scene (file path or scene name) or the robot_description parameter");
  }
  std::string srdf;  // MoveIt's semantic description beside it: its <disable_collisions> pairs never collide
  if (nh.getParam("robot_description_semantic", srdf) && !srdf.empty()) {
    try {
      xml = WithStartEntries(xml, {}, srdf);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("parameter robot_description_semantic: " + std::string(e.what()));
    }
  }
  return SceneText{xml, "robot_description", ""};
}

}  // namespace implicit_sim
