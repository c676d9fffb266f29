// CondensedLu against a dense LU of the whole matrix: random matrices with interleaved local blocks, refactorization
// on the same pattern, blocks that must stay global (coupled to each other, too large, invalid), and singular blocks.
#include "implicit_sim/core/ncp/condensed_lu.h"

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "ncp/test_ncp_problems.h"

namespace implicit_sim {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using ncp_test::RandomVector;

// n unknowns, of which `num_blocks` blocks of 3-12 unknowns at random (interleaved) indices; the rest are global.
// Each block's rows touch its own unknowns (dense, diagonally dominant) and up to 12 global unknowns; each global row
// touches up to 4 global unknowns and the unknowns of at most 3 blocks.
struct BlockSystem {
  int n = 0;
  std::vector<int> starts{0}, indices;
  std::vector<Eigen::Triplet<double>> pattern;  // values set by Values()
};

BlockSystem RandomBlockSystem(int num_global, int num_blocks, std::mt19937* rng) {
  std::uniform_int_distribution<int> block_size(3, 12);
  std::vector<int> sizes(num_blocks);
  int n = num_global;
  for (int& s : sizes) n += (s = block_size(*rng));
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), *rng);
  BlockSystem system;
  system.n = n;
  int next = 0;
  for (int s : sizes) {
    system.indices.insert(system.indices.end(), order.begin() + next, order.begin() + next + s);
    next += s;
    system.starts.push_back(next);
  }
  const std::vector<int> global(order.begin() + next, order.end());
  std::uniform_int_distribution<int> pick_global(0, num_global - 1);
  for (int g : global) {
    system.pattern.emplace_back(g, g, 0.0);
    for (int k = 0; k < 4; ++k) system.pattern.emplace_back(g, global[pick_global(*rng)], 0.0);
  }
  for (int p = 0; p < num_blocks; ++p) {
    const int* first = system.indices.data() + system.starts[p];
    const int* last = system.indices.data() + system.starts[p + 1];
    std::vector<int> border;
    for (int k = 0; k < 12; ++k) border.push_back(global[pick_global(*rng)]);
    for (const int* r = first; r != last; ++r) {
      for (const int* c = first; c != last; ++c) system.pattern.emplace_back(*r, *c, 0.0);
      for (int k = 0; k < 3; ++k) {
        system.pattern.emplace_back(*r, border[(*r + k) % border.size()], 0.0);   // C_p
        system.pattern.emplace_back(border[(*r + 2 * k) % border.size()], *r, 0.0);  // B_p
      }
    }
  }
  return system;
}

// Random values on the pattern; diagonal entries dominate so that the matrix and every block are regular.
SparseMatrix Values(const BlockSystem& system, std::mt19937* rng) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<Eigen::Triplet<double>> triplets;
  for (const auto& t : system.pattern) {
    triplets.emplace_back(t.row(), t.col(), t.row() == t.col() ? 20.0 + value(*rng) : value(*rng));
  }
  SparseMatrix A(system.n, system.n);
  A.setFromTriplets(triplets.begin(), triplets.end());
  A.makeCompressed();
  return A;
}

// |x - A^-1 b| / |A^-1 b| for x from the condensed LU (infinity if it fails).
double CondensedError(CondensedLu* lu, const SparseMatrix& A, int version, const Eigen::VectorXd& b) {
  Eigen::VectorXd x = b;
  if (!lu->Factorize(A, version) || !lu->Solve(&x)) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd expected = Eigen::MatrixXd(A).partialPivLu().solve(b);
  return (x - expected).norm() / expected.norm();
}

TEST(CondensedLu, SolvesLikeADenseLuOfTheWholeMatrix) {
  std::mt19937 rng(3);
  for (const auto& [num_global, num_blocks] : {std::pair{1, 1}, {12, 5}, {60, 40}}) {
    SCOPED_TRACE(::testing::Message() << num_global << " global unknowns, " << num_blocks << " blocks");
    const BlockSystem system = RandomBlockSystem(num_global, num_blocks, &rng);
    CondensedLu lu;
    lu.SetBlocks(system.starts, system.indices);
    EXPECT_LT(CondensedError(&lu, Values(system, &rng), 1, RandomVector(system.n, &rng)), 1e-12);
    EXPECT_EQ(lu.global_size(), num_global);  // every block condensed
  }
}

TEST(CondensedLu, RefactorizesNewValuesOnTheSamePattern) {
  std::mt19937 rng(5);
  const BlockSystem system = RandomBlockSystem(30, 20, &rng);
  CondensedLu lu;
  lu.SetBlocks(system.starts, system.indices);
  for (int round = 0; round < 3; ++round) {
    EXPECT_LT(CondensedError(&lu, Values(system, &rng), 7, RandomVector(system.n, &rng)), 1e-12) << round;
  }
}

TEST(CondensedLu, KeepsCoupledOversizedAndInvalidBlocksGlobal) {
  std::mt19937 rng(9);
  BlockSystem system = RandomBlockSystem(20, 6, &rng);
  // Couple block 0 to block 1: a row of block 0 touches an unknown of block 1.
  system.pattern.emplace_back(system.indices[system.starts[0]], system.indices[system.starts[1]], 0.0);
  std::vector<int> starts = system.starts, indices = system.indices;
  // An invalid block (an index out of range), one that repeats an index of block 5, and one too large.
  indices.push_back(system.n);
  starts.push_back(static_cast<int>(indices.size()));
  indices.push_back(system.indices[system.starts[5]]);
  starts.push_back(static_cast<int>(indices.size()));
  for (int k = 0; k <= CondensedLu::kMaxBlock; ++k) indices.push_back(k);
  starts.push_back(static_cast<int>(indices.size()));
  CondensedLu lu;
  lu.SetBlocks(starts, indices);
  EXPECT_LT(CondensedError(&lu, Values(system, &rng), 1, RandomVector(system.n, &rng)), 1e-12);
  const int size0 = system.starts[1] - system.starts[0], size1 = system.starts[2] - system.starts[1];
  EXPECT_EQ(lu.global_size(), 20 + size0 + size1);  // blocks 0 and 1 stay global, 2 to 5 are condensed
}

TEST(CondensedLu, RefusesASingularBlockAndSolvesAgainOnceItIsRegular) {
  std::mt19937 rng(13);
  const BlockSystem system = RandomBlockSystem(10, 3, &rng);
  SparseMatrix A = Values(system, &rng);
  // Block 1's first row becomes 0 within the block (its rows then have rank size - 1).
  const int* first = system.indices.data() + system.starts[1];
  const int* last = system.indices.data() + system.starts[2];
  for (const int* c = first; c != last; ++c) A.coeffRef(*first, *c) = 0.0;
  CondensedLu lu;
  lu.SetBlocks(system.starts, system.indices);
  EXPECT_FALSE(lu.Factorize(A, 1));
  EXPECT_LT(CondensedError(&lu, Values(system, &rng), 1, RandomVector(system.n, &rng)), 1e-12);
}

TEST(CondensedLu, WithoutBlocksSolvesTheWholeMatrix) {
  std::mt19937 rng(17);
  const BlockSystem system = RandomBlockSystem(25, 4, &rng);
  CondensedLu lu;
  lu.SetBlocks({0}, {});
  EXPECT_FALSE(lu.has_blocks());
  EXPECT_LT(CondensedError(&lu, Values(system, &rng), 1, RandomVector(system.n, &rng)), 1e-12);
  EXPECT_EQ(lu.global_size(), system.n);
}

}  // namespace
}  // namespace implicit_sim
