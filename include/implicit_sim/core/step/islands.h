// Islands: the moving bodies joined in the current step by a pair in the NCP or by a joint (fixed bodies and the world
// join nothing). Islands share no unknown, so each is a step problem of its own with its own warm start, retry ladder
// and sub-steps, solved on Data's thread pool; a hard landing then retries a few bodies instead of the whole pile.
// Islands are numbered by their lowest velocity slot and each one's solve reads and writes only its own data, so the
// results do not depend on the number of threads.
#pragma once

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {

// Partitions the moving bodies by the pairs of data->problem and the model's joints into data->islands[0,
// num_islands), each with its membership; an island's problem is laid out again only when its membership changed.
void PartitionIslands(const Model& model, Data* data);

// Copies the island's part of the warm start (data.z in the layout of data.problem: velocities, joint blocks, pair
// blocks, tangent axes) into the island, and data.has_warm_start.
void GatherIsland(const Data& data, IslandSolve* island);

// Copies the island's solution and tangent axes back into data->z and data->problem, and its contact results into
// data->contacts.
void ScatterIsland(const IslandSolve& island, Data* data);

}  // namespace implicit_sim
