// Sparse LU of a Newton matrix with small local blocks condensed out first (a Schur complement per block).
//
// A problem may name local blocks (NcpProblem::CondensableBlocks): sets of unknowns, each with its own rows (row i
// belongs to unknown i), such that no row of one block touches an unknown of another. The step's blocks are the
// closest-point unknowns of each pair (a1, a2, n, d, alpha, beta: 10 + k1 + k2 of them): they couple only to the
// velocities of the pair's two bodies. Ordering the Newton matrix as
//   [ A  B ] [x_g]   [r_g]      A: the global rows and unknowns (velocities, joint blocks, forces, friction)
//   [ C  D ] [x_l] = [r_l]      D = diag(D_1 ... D_m): the local blocks, each dense and small,
// the system reduces to the global one
//   S x_g = r_g - sum_p B_p D_p^-1 r_p,   S = A - sum_p B_p D_p^-1 C_p,   then x_p = D_p^-1 (r_p - C_p x_g),
// which KLU (sparse_lu.h) factorizes. S has 6 unknowns per body plus 5 per pair instead of 15 + k1 + k2 per pair, and
// B_p D_p^-1 C_p only couples the two bodies' velocities to the pair's force rows, entries that the LU of the whole
// matrix would fill in anyway. The direction is the same as the uncondensed LU's up to rounding.
//
// Factorize fails (and the caller solves the whole matrix) when a D_p is numerically singular: the closest points
// of two flat faces in contact are not unique. The pattern of S, and where each entry of the Newton matrix goes,
// are built once per pattern; a factorization with the same pattern allocates nothing of ours.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "implicit_sim/core/ncp/sparse_lu.h"

namespace implicit_sim {

class CondensedLu {
 public:
  // The largest block condensed; larger ones stay in the global system.
  static constexpr int kMaxBlock = 32;
  // The smallest condensed system (unknowns) factorized by UMFPACK instead of KLU (sparse_lu.h): an island of several
  // hundred bodies.
  static constexpr int kMultifrontalMinSize = 3000;

  // Sets the blocks: block p holds the unknowns indices[starts[p] .. starts[p + 1]). Forces a new analysis when they
  // differ from the last ones.
  void SetBlocks(const std::vector<int>& starts, const std::vector<int>& indices);
  bool has_blocks() const { return starts_.size() > 1; }
  // Condenses J (n x n, compressed columns; `pattern_version` tells when its pattern changed) and factorizes S. False
  // if a block or S is singular.
  bool Factorize(const Eigen::SparseMatrix<double>& J, int pattern_version);
  // The next factorization searches pivots afresh (SparseLu::ForgetPivots).
  void ForgetPivots() { lu_.ForgetPivots(); }
  // b = J^-1 b in place for the last successful Factorize.
  bool Solve(Eigen::VectorXd* b);
  int global_size() const { return static_cast<int>(global_.size()); }

 private:
  using BlockMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxBlock, kMaxBlock>;
  struct Block {
    int size = 0;
    int first_index = 0;          // into indices_ (the block's unknowns)
    int border_rows = 0;          // global rows touching the block's unknowns (B_p's rows), listed at border_first
    int border_cols = 0;          // global unknowns the block's rows touch (C_p's columns), listed at border_first +
                                  // border_rows
    int border_first = 0;         // into border_
    int dense_first = 0;          // into dense_: D_p^-1 (size^2), B_p (border_rows x size), C_p (size x border_cols)
    int schur_first = 0;          // into schur_slot_: S's slot of each (border row, border col), column-major
  };
  // Analyze: which blocks are condensed, the global numbering, each block's border and dense layout; then S's
  // pattern and the slots of each block's Schur update, and where each stored entry of J goes.
  void Analyze(const Eigen::SparseMatrix<double>& J);
  void BuildSchurPattern(const Eigen::SparseMatrix<double>& J);
  void MapEntries(const Eigen::SparseMatrix<double>& J);

  std::vector<int> starts_, indices_;  // the blocks as set
  bool analyzed_ = false;
  int pattern_version_ = -1;
  int schur_version_ = 0;              // S's pattern version for KLU
  std::vector<Block> blocks_;          // the condensed blocks
  std::vector<int> block_of_;          // per unknown: its condensed block, -1 when global
  std::vector<int> position_;          // per unknown: its index in S (global) or in its block (local)
  std::vector<int> global_;            // the global unknowns, ascending
  std::vector<int> border_;            // per block: its border rows, then its border columns (indices into S)
  std::vector<int> entry_target_;      // per stored entry of J: an index into S's values (>= 0) or -1 - dense index
  std::vector<double> dense_;
  std::vector<int> schur_slot_;
  Eigen::SparseMatrix<double> S_;
  Eigen::VectorXd rhs_global_;
  SparseLu lu_{kMultifrontalMinSize};
};

}  // namespace implicit_sim
