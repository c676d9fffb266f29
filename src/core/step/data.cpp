#include "implicit_sim/core/step/data.h"

#include <algorithm>
#include <stdexcept>

namespace implicit_sim {

Data::Data(const Model& model, PairSelection selection)
    : model_(&model),
      broad_phase(selection == PairSelection::kBroadPhase ||
                  (selection == PairSelection::kAuto && static_cast<int>(model.pairs.size()) > kAllPairsLimit)),
      problem(model, !broad_phase),
      sparse(broad_phase || problem.size() > kDenseSizeLimit),
      solver(problem.size(), sparse),
      broad(MakeBroadPhase(model)),
      z(Eigen::VectorXd::Zero(problem.size())),
      z_start(Eigen::VectorXd::Zero(problem.size())),
      z_best(Eigen::VectorXd::Zero(problem.size())),
      ncp_error_rows(Eigen::VectorXd::Zero(problem.size())),
      z_backup(kMaxSubstepDepth + 1, Eigen::VectorXd::Zero(problem.size())),
      pairs_backup(kMaxSubstepDepth + 1),
      X_WB(model.bodies.size(), Pose::Identity()),
      inflation(model.bodies.size(), 0.0),
      contacts(problem.blocks().size()) {
  for (size_t c = 0; c < contacts.size(); ++c) contacts[c].pair = problem.blocks()[c].pair;
  axes_warm_failed.reserve(model.pairs.size());  // a cold restart keeps the failed warm axes without allocating
  problem.set_regular_separated_friction(true);  // keeps the Newton matrix regular at separated pairs
}

void Data::LayOut(const std::vector<int>& pairs_in_ncp, const Eigen::VectorXd* z_old) {
  problem.SetActivePairs(pairs_in_ncp, z_old, &z_remap, &new_blocks);
  z_start.resize(problem.size());
  z_best.resize(problem.size());
  ncp_error_rows.resize(problem.size());
}

void SaveWarmStart(const Data& data, WarmStart* out) {
  out->valid = data.has_warm_start;
  data.problem.ActivePairs(&out->pairs);
  out->z = data.z;
  out->tangent_axes = data.problem.tangent_axes();
}

void RestoreWarmStart(const Model& model, const WarmStart& saved, Data* data) {
  if (!data->BelongsTo(model)) throw std::invalid_argument("Data was built from another Model");
  const bool pairs_ok = std::is_sorted(saved.pairs.begin(), saved.pairs.end()) &&
                        std::adjacent_find(saved.pairs.begin(), saved.pairs.end()) == saved.pairs.end() &&
                        std::all_of(saved.pairs.begin(), saved.pairs.end(), [&](int p) {
                          return p >= 0 && p < static_cast<int>(model.pairs.size());
                        }) &&
                        (data->broad_phase || saved.pairs.size() == model.pairs.size());
  if (!pairs_ok || saved.tangent_axes.size() != saved.pairs.size()) {
    throw std::invalid_argument("warm start does not belong to this model (pairs or tangent axes)");
  }
  if (data->broad_phase) {
    data->problem.ActivePairs(&data->pairs);
    data->LayOut(saved.pairs, nullptr);
  }
  if (saved.z.size() != data->problem.size()) {
    const int expected = data->problem.size();
    if (data->broad_phase) data->LayOut(data->pairs, nullptr);  // back to the layout of data->z
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
  data->z_start.setZero(data->problem.size());
  data->has_warm_start = false;
  data->forced_pairs.clear();
}

}  // namespace implicit_sim
