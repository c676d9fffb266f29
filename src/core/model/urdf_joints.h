// The scene loader's joint part (internal to the core): checks of <joint> elements before urdfdom parses them, the
// joint starts of <implicit_sim><joint>, the initial link poses along the joint tree, and Model::joints.
#pragma once

#include <optional>
#include <unordered_map>
#include <vector>

#include <map>
#include <string>

#include <tinyxml2.h>
#include <urdf_model/model.h>

#include "implicit_sim/core/model/model.h"
#include "loader_util.h"

namespace implicit_sim {
namespace loader {

// Refuses an unsupported type or a malformed <axis>, <limit> or <dynamics> (naming the joint and attribute), so that
// urdfdom never refuses one with a message that names nothing. Attributes of other tools on <limit> and <dynamics>
// are noted and ignored; the <axis> of a fixed or floating joint is ignored, as urdfdom ignores it.
void CheckJointElement(const tinyxml2::XMLElement* joint, const std::string& where, LoadNotes* notes);

// Initial joint position (rad or m) and velocity (rad/s or m/s) and a constant effort, from
// <implicit_sim><joint name position velocity effort/>.
struct JointStart {
  double position = 0.0;
  double velocity = 0.0;
  double effort = 0.0;  // constant applied effort, N m or N
  // <implicit_sim><joint enforce_velocity_limit="true|false">; unset: LoaderOptions::enforce_velocity_limits.
  std::optional<bool> enforce_velocity_limit;
};
using JointStarts = std::map<std::string, JointStart>;
// `positions` (LoaderOptions::joint_positions) override the file's positions.
JointStarts ReadJointStarts(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf,
                            const std::map<std::string, double>& positions);

// Where the root of the link tree is: 'world' (fixed, identity), or a robot's base link welded to the world or free
// at X_W_root (LoaderOptions).
struct RootPlacement {
  bool fixed = true;
  Pose X_W_root = Pose::Identity();
};

// The value of the first link at or above `link` for which `known` holds one or `stop` gives one (std::optional), noted
// for every link walked: tree walks that cost a chain's length once per load, without recursion. The links belong to
// the urdf::ModelInterface, so the keys stay valid.
template <typename T, typename Stop>
T FirstValueUp(const urdf::Link& link, std::unordered_map<const urdf::Link*, T>* known, Stop stop) {
  std::vector<const urdf::Link*> walked;
  const urdf::Link* l = &link;
  T value{};
  while (true) {
    const auto found = known->find(l);
    if (found != known->end()) {
      value = found->second;
      break;
    }
    walked.push_back(l);
    const std::optional<T> own = stop(*l);
    if (own) {
      value = *own;
      break;
    }
    l = l->getParent().get();
  }
  for (const urdf::Link* w : walked) (*known)[w] = value;
  return value;
}

// Whether a chain of fixed joints welds the link to a fixed root (then it is a fixed body); a fixed root is welded.
// `known`: the answers so far of this load.
bool IsWeldedToWorld(const urdf::Link& link, const RootPlacement& root,
                     std::unordered_map<const urdf::Link*, bool>* known);
// A link that only marks a frame on a moving link: no <inertial>, no <collision>, on a fixed joint. It is no body:
// joints below it hang on its nearest ancestor that is one.
bool IsFrameLink(const urdf::Link& link);
// The initial poses of link frames in the world: the joint origins and initial joint motions from the root down. Each
// link's pose is computed once per object, without recursion, so a chain of any depth costs its length. Throws
// std::invalid_argument naming the joint for a non-finite origin.
class InitialLinkPoses {
 public:
  InitialLinkPoses(const JointStarts& starts, const RootPlacement& root) : starts_(starts), root_(root) {}
  const Pose& Of(const urdf::Link& link);

 private:
  const JointStarts& starts_;
  const RootPlacement& root_;
  std::unordered_map<const urdf::Link*, Pose> known_;
};

// Fills model->joints, parents before children, with every revolute, continuous and prismatic joint and every fixed
// joint whose child moves, and gives each jointed child its initial velocity from its parent's and the joint's.
// Frame links (IsFrameLink) are skipped. The bodies must be loaded (poses, body settings) and model->joints must be
// empty; call before Model::Finalize.
// A revolute joint whose range is 2 pi or wider keeps no limit rows (its angle is measured in one turn, where such a
// limit is never reached from one side): one note in `notes`.
// `enforce_velocity_limits` (LoaderOptions) bounds the rate of every joint with a <limit velocity> > 0 that mimics none,
// unless its <implicit_sim><joint enforce_velocity_limit> says otherwise.
void BuildJoints(const urdf::ModelInterface& urdf, const JointStarts& starts, const RootPlacement& root,
                 bool enforce_velocity_limits, InitialLinkPoses* poses, Model* model, LoadNotes* notes);

}  // namespace loader
}  // namespace implicit_sim
