#include "implicit_sim/core/step/data.h"

#include <algorithm>
#include <stdexcept>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/schemes/island_scheme.h"

namespace implicit_sim {

IslandSolve::IslandSolve(const Model& model, const std::vector<JointDrive>& drives)
    : layout(model, /*all_pairs=*/false, /*all_bodies=*/false),
      kinematics(layout),
      drives(drives),
      z_backup(Data::kMaxSubstepDepth + 1) {}

IslandSolve::~IslandSolve() = default;

IslandScheme& IslandSolve::SchemeFor(const StepperOptions& options) {
  const StepperOptions::Scheme kind = options.scheme;
  if (!scheme || scheme->scheme() != kind) scheme = MakeIslandScheme(kind, layout, kinematics, drives);
  // The projected friction rows where the sparse LU solves (piles); a dense island's resting contacts make its matrix
  // singular under them, and the dense singular direction is costly (doc/method.md).
  const bool sparse = layout.size() > NewtonSolvers::kDenseSizeLimit;
  const bool projected = options.projected_friction == 2 || (options.projected_friction == 1 && sparse);
  scheme->SetFrictionForm(FrictionForm{projected, options.friction_projection_scale});
  return *scheme;
}

Data::Data(const Model& model, PairSelection selection)
    : model_(&model),
      broad_phase(selection == PairSelection::kBroadPhase ||
                  (selection == PairSelection::kAuto && static_cast<int>(model.pairs.size()) > kAllPairsLimit)),
      layout(model, !broad_phase),
      kinematics(layout),
      z(Eigen::VectorXd::Zero(layout.size())),
      island_root(model.num_moving()),
      island_of_slot(model.num_moving()),
      broad(MakeBroadPhase(model)),
      X_WB(model.bodies.size(), Pose::Identity()),
      inflation(model.geoms.size(), 0.0),
      velocity_reversals(model.num_moving(), 0),
      driven(model.joints.size(), 0),
      joint_drives(model.joints.size()),
      contacts(layout.blocks().size()),
      joint_limit_effort(model.joints.size(), 0.0),
      joint_drive_effort(model.joints.size(), 0.0) {
  subtree_mass.reserve(model.bodies.size());
  subtree_first_moment_W.reserve(model.bodies.size());
  for (size_t c = 0; c < contacts.size(); ++c) contacts[c].pair = layout.blocks()[c].pair;
}

Data::~Data() = default;

void Data::LayOut(const std::vector<int>& pairs_in_ncp, const Eigen::VectorXd* z_old) {
  layout.SetActivePairs(pairs_in_ncp, z_old, &z_remap, &new_blocks);
  contacts.resize(layout.blocks().size());
}

bool Data::LayOutDrives(const State& state) {
  bool changed = false, compensated = false;
  for (size_t j = 0; j < joint_drives.size(); ++j) {
    driven[j] = JointDriveActive(joint_drives[j]) && model_->joints[j].has_coordinate();
    changed = changed || driven[j] != layout.driven_joints()[j];
    compensated = compensated || (driven[j] && joint_drives[j].gravity_compensation);
  }
  if (compensated) SubtreeMassMoments(*model_, state, &subtree_mass, &subtree_first_moment_W);
  for (size_t j = 0; j < joint_drives.size(); ++j) {
    JointDrive& drive = joint_drives[j];
    drive.gravity_effort = driven[j] && drive.gravity_compensation
                               ? JointGravityEffort(*model_, state, static_cast<int>(j), subtree_mass,
                                                    subtree_first_moment_W)
                               : 0.0;
  }
  if (!changed) return false;
  const std::vector<char> was_driven = layout.driven_joints();
  layout.SetDrivenJoints(driven, &z, &z_remap);
  z.swap(z_remap);
  for (int j : layout.joints()) {
    if (!driven[j] || was_driven[j]) continue;
    const Joint& joint = model_->joints[j];
    z[layout.joint_offset(j) + joint.size()] = JointDriveEffortAt(
        joint, joint_drives[j], JointPosition(*model_, state, j), JointVelocity(*model_, state, j));
  }
  return true;
}

int Data::lm_fallbacks() const {
  int total = 0;
  for (const auto& island : islands) {
    if (island->scheme) total += island->scheme->lm_fallbacks();
  }
  return total;
}

void SaveWarmStart(const Data& data, WarmStart* out) {
  out->valid = data.has_warm_start;
  data.layout.ActivePairs(&out->pairs);
  out->z = data.z;
  out->tangent_axes = data.layout.tangent_axes();
  out->driven_joints.clear();
  const std::vector<char>& driven = data.layout.driven_joints();
  for (size_t j = 0; j < driven.size(); ++j) {
    if (driven[j]) out->driven_joints.push_back(static_cast<int>(j));
  }
  out->velocity_reversals = data.velocity_reversals;
}

void RestoreWarmStart(const Model& model, const WarmStart& saved, Data* data) {
  if (!data->BelongsTo(model)) throw std::invalid_argument("Data was built from another Model");
  const bool pairs_ok = std::is_sorted(saved.pairs.begin(), saved.pairs.end()) &&
                        std::adjacent_find(saved.pairs.begin(), saved.pairs.end()) == saved.pairs.end() &&
                        std::all_of(saved.pairs.begin(), saved.pairs.end(), [&](int p) {
                          return p >= 0 && p < static_cast<int>(model.pairs.size());
                        }) &&
                        (data->broad_phase || saved.pairs.size() == model.pairs.size());
  const std::vector<int>& driven = saved.driven_joints;
  const bool driven_ok = std::is_sorted(driven.begin(), driven.end()) &&
                         std::adjacent_find(driven.begin(), driven.end()) == driven.end() &&
                         std::all_of(driven.begin(), driven.end(), [&](int j) {
                           return j >= 0 && j < static_cast<int>(model.joints.size()) &&
                                  model.joints[j].has_coordinate();
                         });
  const std::vector<int>& reversals = saved.velocity_reversals;
  const bool reversals_ok =
      (reversals.empty() || static_cast<int>(reversals.size()) == model.num_moving()) &&
      std::all_of(reversals.begin(), reversals.end(), [](int count) { return count >= 0; });
  if (!pairs_ok || saved.tangent_axes.size() != saved.pairs.size() || !driven_ok || !reversals_ok) {
    throw std::invalid_argument(
        "warm start does not belong to this model (pairs, tangent axes, driven joints or velocity reversals)");
  }
  // The layout of saved.z; kept_driven: the layout of data->z, restored if saved.z does not fit.
  const std::vector<char> kept_driven = data->layout.driven_joints();
  std::fill(data->driven.begin(), data->driven.end(), 0);
  for (int j : driven) data->driven[j] = 1;
  if (data->driven != kept_driven) data->layout.SetDrivenJoints(data->driven, nullptr, &data->z_remap);
  if (data->broad_phase) {
    data->layout.ActivePairs(&data->pairs);
    data->LayOut(saved.pairs, nullptr);
  }
  if (saved.z.size() != data->layout.size()) {
    const int expected = data->layout.size();
    if (data->broad_phase) data->LayOut(data->pairs, nullptr);  // back to the layout of data->z
    if (data->driven != kept_driven) data->layout.SetDrivenJoints(kept_driven, nullptr, &data->z_remap);
    throw std::invalid_argument("warm start does not belong to this model: z has " + std::to_string(saved.z.size()) +
                                " values, the step problem " + std::to_string(expected));
  }
  data->z = saved.z;
  data->layout.set_tangent_axes(saved.tangent_axes);
  data->has_warm_start = saved.valid;
  if (reversals.empty()) {
    std::fill(data->velocity_reversals.begin(), data->velocity_reversals.end(), 0);
  } else {
    data->velocity_reversals = reversals;
  }
}

void ClearWarmStart(Data* data) {
  if (data->broad_phase) data->LayOut({}, nullptr);
  data->z.setZero(data->layout.size());
  data->has_warm_start = false;
  data->forced_pairs.clear();
  std::fill(data->velocity_reversals.begin(), data->velocity_reversals.end(), 0);
}

}  // namespace implicit_sim
