#include "implicit_sim/core/step/data.h"

#include <algorithm>
#include <stdexcept>

#include "implicit_sim/core/model/joints.h"

namespace implicit_sim {

IslandSolve::IslandSolve(const Model& model)
    : problem(model, /*all_pairs=*/false, /*all_bodies=*/false), dense_solver(0, false), sparse_solver(0, true),
      velocity_dense_solver(0, false), velocity_sparse_solver(0, true), z_backup(Data::kMaxSubstepDepth + 1) {
  problem.set_regular_separated_friction(true);  // keeps the Newton matrix regular at separated pairs
}

Data::Data(const Model& model, PairSelection selection)
    : model_(&model),
      broad_phase(selection == PairSelection::kBroadPhase ||
                  (selection == PairSelection::kAuto && static_cast<int>(model.pairs.size()) > kAllPairsLimit)),
      problem(model, !broad_phase),
      z(Eigen::VectorXd::Zero(problem.size())),
      island_root(model.num_moving()),
      island_of_slot(model.num_moving()),
      broad(MakeBroadPhase(model)),
      X_WB(model.bodies.size(), Pose::Identity()),
      inflation(model.bodies.size(), 0.0),
      driven(model.joints.size(), 0),
      joint_drives(model.joints.size()),
      contacts(problem.blocks().size()),
      joint_limit_effort(model.joints.size(), 0.0),
      joint_drive_effort(model.joints.size(), 0.0) {
  for (size_t c = 0; c < contacts.size(); ++c) contacts[c].pair = problem.blocks()[c].pair;
  problem.set_regular_separated_friction(true);
}

Data::~Data() = default;

void Data::LayOut(const std::vector<int>& pairs_in_ncp, const Eigen::VectorXd* z_old) {
  problem.SetActivePairs(pairs_in_ncp, z_old, &z_remap, &new_blocks);
  contacts.resize(problem.blocks().size());
}

bool Data::LayOutDrives(const State& state) {
  bool changed = false;
  for (size_t j = 0; j < joint_drives.size(); ++j) {
    driven[j] = JointDriveActive(joint_drives[j]) && model_->joints[j].has_coordinate();
    changed = changed || driven[j] != problem.driven_joints()[j];
  }
  if (!changed) return false;
  const std::vector<char> was_driven = problem.driven_joints();
  problem.SetDrivenJoints(driven, &z, &z_remap);
  z.swap(z_remap);
  for (int j : problem.joints()) {
    if (!driven[j] || was_driven[j]) continue;
    const Joint& joint = model_->joints[j];
    z[problem.joint_offset(j) + joint.size()] = JointDriveEffortAt(
        joint, joint_drives[j], JointPosition(*model_, state, j), JointVelocity(*model_, state, j));
  }
  return true;
}

int Data::lm_fallbacks() const {
  int total = 0;
  for (const auto& island : islands) {
    total += island->dense_solver.lm_fallbacks() + island->sparse_solver.lm_fallbacks() +
             island->velocity_dense_solver.lm_fallbacks() + island->velocity_sparse_solver.lm_fallbacks();
  }
  return total;
}

void SaveWarmStart(const Data& data, WarmStart* out) {
  out->valid = data.has_warm_start;
  data.problem.ActivePairs(&out->pairs);
  out->z = data.z;
  out->tangent_axes = data.problem.tangent_axes();
  out->driven_joints.clear();
  const std::vector<char>& driven = data.problem.driven_joints();
  for (size_t j = 0; j < driven.size(); ++j) {
    if (driven[j]) out->driven_joints.push_back(static_cast<int>(j));
  }
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
  if (!pairs_ok || saved.tangent_axes.size() != saved.pairs.size() || !driven_ok) {
    throw std::invalid_argument("warm start does not belong to this model (pairs, tangent axes or driven joints)");
  }
  // The layout of saved.z; kept_driven: the layout of data->z, restored if saved.z does not fit.
  const std::vector<char> kept_driven = data->problem.driven_joints();
  std::fill(data->driven.begin(), data->driven.end(), 0);
  for (int j : driven) data->driven[j] = 1;
  if (data->driven != kept_driven) data->problem.SetDrivenJoints(data->driven, nullptr, &data->z_remap);
  if (data->broad_phase) {
    data->problem.ActivePairs(&data->pairs);
    data->LayOut(saved.pairs, nullptr);
  }
  if (saved.z.size() != data->problem.size()) {
    const int expected = data->problem.size();
    if (data->broad_phase) data->LayOut(data->pairs, nullptr);  // back to the layout of data->z
    if (data->driven != kept_driven) data->problem.SetDrivenJoints(kept_driven, nullptr, &data->z_remap);
    throw std::invalid_argument("warm start does not belong to this model: z has " + std::to_string(saved.z.size()) +
                                " values, the step problem " + std::to_string(expected));
  }
  data->z = saved.z;
  data->problem.set_tangent_axes(saved.tangent_axes);
  data->has_warm_start = saved.valid;
}

void ClearWarmStart(Data* data) {
  if (data->broad_phase) data->LayOut({}, nullptr);
  data->z.setZero(data->problem.size());
  data->has_warm_start = false;
  data->forced_pairs.clear();
}

}  // namespace implicit_sim
