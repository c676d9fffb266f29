#include "implicit_sim/core/step/islands.h"

#include <algorithm>

namespace implicit_sim {
namespace {

int FindRoot(std::vector<int>* parent, int k) {
  while ((*parent)[k] != k) {
    (*parent)[k] = (*parent)[(*parent)[k]];  // path halving
    k = (*parent)[k];
  }
  return k;
}

void Join(std::vector<int>* parent, int a, int b) {
  if (a < 0 || b < 0) return;
  a = FindRoot(parent, a);
  b = FindRoot(parent, b);
  if (a != b) (*parent)[std::max(a, b)] = std::min(a, b);  // the root is the lowest slot
}

int SlotOf(const Model& model, int body) { return body < 0 ? -1 : model.velocity_slot[body]; }

// The island of model pair `pair` (its moving body's).
int IslandOfPair(const Model& model, const Data& data, int pair) {
  const ContactPair& p = model.pairs[pair];
  const int k = SlotOf(model, p.body1) >= 0 ? SlotOf(model, p.body1) : SlotOf(model, p.body2);
  return data.island_of_slot[k];
}

// Sizes the island's vectors for its problem (after a new layout).
void SizeWorkspace(IslandSolve* island) {
  const int n = island->layout.size();
  island->z.setZero(n);
  island->z_start.setZero(n);
  island->z_best.setZero(n);
  island->z_center.setZero(n);
  island->z_cold.setZero(n);
  island->ncp_error_rows.setZero(n);
  for (Eigen::VectorXd& backup : island->z_backup) backup.setZero(n);
  island->contacts.resize(island->pairs.size());
  island->joint_limit_effort.assign(island->joints.size(), 0.0);
  island->joint_drive_effort.assign(island->joints.size(), 0.0);
  island->axes_warm_failed.reserve(island->pairs.size());
}

// Whether the island's problem has the drive unknowns of the whole model's for the joints it will hold.
bool SameDrivenJoints(const StepLayout& global, const IslandSolve& island) {
  for (int j : island.next_joints) {
    if (global.driven_joints()[j] != island.layout.driven_joints()[j]) return false;
  }
  return true;
}

}  // namespace

void PartitionIslands(const Model& model, Data* data) {
  std::vector<int>& root = data->island_root;
  const int num_slots = model.num_moving();
  for (int k = 0; k < num_slots; ++k) root[k] = k;
  for (const PairBlock& blk : data->layout.blocks()) {
    Join(&root, SlotOf(model, model.pairs[blk.pair].body1), SlotOf(model, model.pairs[blk.pair].body2));
  }
  for (const Joint& joint : model.joints) {
    Join(&root, SlotOf(model, joint.parent), SlotOf(model, joint.child));
    if (joint.mimics()) Join(&root, SlotOf(model, joint.child), SlotOf(model, model.joints[joint.mimic_leader].child));
  }
  // Number the islands by their lowest slot (every root is its island's lowest slot) and collect their members into
  // the islands' membership lists, kept apart until compared with the current ones.
  std::vector<int>& island_of = data->island_of_slot;
  int count = 0;
  for (int k = 0; k < num_slots; ++k) island_of[k] = root[k] == k ? count++ : island_of[FindRoot(&root, k)];
  while (static_cast<int>(data->islands.size()) < count) data->islands.push_back(std::make_unique<IslandSolve>(model, data->joint_drives));
  for (int i = 0; i < count; ++i) {
    IslandSolve& island = *data->islands[i];
    island.next_slots.clear();
    island.next_joints.clear();
    island.next_pairs.clear();
    island.blocks.clear();
  }
  for (int k = 0; k < num_slots; ++k) data->islands[island_of[k]]->next_slots.push_back(k);
  for (int j = 0; j < static_cast<int>(model.joints.size()); ++j) {
    const Joint& joint = model.joints[j];
    const int k = SlotOf(model, joint.child) >= 0 ? SlotOf(model, joint.child) : SlotOf(model, joint.parent);
    if (k >= 0) data->islands[island_of[k]]->next_joints.push_back(j);
  }
  const std::vector<PairBlock>& blocks = data->layout.blocks();
  for (int c = 0; c < static_cast<int>(blocks.size()); ++c) {
    IslandSolve& island = *data->islands[IslandOfPair(model, *data, blocks[c].pair)];
    island.next_pairs.push_back(blocks[c].pair);
    island.blocks.push_back(c);
  }
  for (int i = 0; i < count; ++i) {
    IslandSolve& island = *data->islands[i];
    if (island.next_slots == island.slots && island.next_joints == island.joints && island.next_pairs == island.pairs &&
        SameDrivenJoints(data->layout, island)) {
      continue;
    }
    island.slots = island.next_slots;  // copies (not swaps), so that both keep their capacity
    island.joints = island.next_joints;
    island.pairs = island.next_pairs;
    Eigen::VectorXd unused;
    island.layout.SetDrivenJoints(data->layout.driven_joints(), nullptr, &unused);
    island.layout.SetBodies(island.slots, island.joints);
    island.layout.SetActivePairs(island.pairs, nullptr, &unused, &island.new_blocks);
    SizeWorkspace(&island);
  }
  data->num_islands = count;
}

void GatherIsland(const Data& data, IslandSolve* island) {
  const StepLayout& global = data.layout;
  StepLayout& local = island->layout;
  for (size_t i = 0; i < island->slots.size(); ++i) {
    island->z.segment<6>(6 * i) = data.z.segment<6>(Model::v_offset(island->slots[i]));
  }
  for (int j : island->joints) {
    const int size = global.joint_size(j);
    island->z.segment(local.joint_offset(j), size) = data.z.segment(global.joint_offset(j), size);
  }
  for (size_t c = 0; c < island->blocks.size(); ++c) {
    const PairBlock& from = global.blocks()[island->blocks[c]];
    const PairBlock& to = local.blocks()[c];
    island->z.segment(to.offset, to.size()) = data.z.segment(from.offset, from.size());
    local.set_tangent_axis(static_cast<int>(c), global.tangent_axes()[island->blocks[c]]);
  }
  island->frame_known.resize(island->blocks.size());
  for (size_t c = 0; c < island->blocks.size(); ++c) island->frame_known[c] = data.frame_known[island->blocks[c]];
  island->has_warm_start = data.has_warm_start;
}

void ScatterIsland(const IslandSolve& island, Data* data) {
  StepLayout& global = data->layout;
  const StepLayout& local = island.layout;
  for (size_t i = 0; i < island.slots.size(); ++i) {
    data->z.segment<6>(Model::v_offset(island.slots[i])) = island.z.segment<6>(6 * i);
  }
  for (size_t i = 0; i < island.joints.size(); ++i) {
    const int j = island.joints[i];
    const int size = global.joint_size(j);
    data->z.segment(global.joint_offset(j), size) = island.z.segment(local.joint_offset(j), size);
    data->joint_limit_effort[j] = island.joint_limit_effort[i];
    data->joint_drive_effort[j] = island.joint_drive_effort[i];
  }
  for (size_t c = 0; c < island.blocks.size(); ++c) {
    const PairBlock& from = local.blocks()[c];
    const PairBlock& to = global.blocks()[island.blocks[c]];
    data->z.segment(to.offset, to.size()) = island.z.segment(from.offset, from.size());
    global.set_tangent_axis(island.blocks[c], local.tangent_axes()[c]);
    data->contacts[island.blocks[c]] = island.contacts[c];
  }
}

}  // namespace implicit_sim
