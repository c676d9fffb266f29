#include "implicit_sim/core/ncp/condensed_lu.h"

#include <algorithm>

#include <Eigen/LU>

namespace implicit_sim {
namespace {

// Index of `value` in the sorted range [begin, end) (present by construction).
int IndexIn(const int* begin, const int* end, int value) {
  return static_cast<int>(std::lower_bound(begin, end, value) - begin);
}

// The slot of entry (row, col) in a compressed matrix whose pattern holds it.
int SlotOf(const Eigen::SparseMatrix<double>& M, int row, int col) {
  const int* inner = M.innerIndexPtr();
  const int first = M.outerIndexPtr()[col];
  return first + IndexIn(inner + first, inner + M.outerIndexPtr()[col + 1], row);
}

void SortUnique(std::vector<int>* v) {
  std::sort(v->begin(), v->end());
  v->erase(std::unique(v->begin(), v->end()), v->end());
}

}  // namespace

void CondensedLu::SetBlocks(const std::vector<int>& starts, const std::vector<int>& indices) {
  if (starts == starts_ && indices == indices_) return;
  starts_ = starts;
  indices_ = indices;
  analyzed_ = false;
}

void CondensedLu::Analyze(const Eigen::SparseMatrix<double>& J) {
  const int n = static_cast<int>(J.rows());
  const int* outer = J.outerIndexPtr();
  const int* inner = J.innerIndexPtr();
  // Candidate blocks: valid indices, at most kMaxBlock unknowns, no unknown in two blocks.
  const int num_candidates = starts_.empty() ? 0 : static_cast<int>(starts_.size()) - 1;
  block_of_.assign(n, -1);
  std::vector<char> rejected(num_candidates, 0);
  for (int p = 0; p < num_candidates; ++p) {
    const int size = starts_[p + 1] - starts_[p];
    bool valid = size > 0 && size <= kMaxBlock;
    for (int k = starts_[p]; valid && k < starts_[p + 1]; ++k) {
      valid = indices_[k] >= 0 && indices_[k] < n && block_of_[indices_[k]] < 0;
    }
    for (int k = starts_[p]; valid && k < starts_[p + 1]; ++k) block_of_[indices_[k]] = p;
    rejected[p] = !valid;
  }
  // A row of one block that touches an unknown of another: both stay global (removing blocks adds no such entry).
  for (int col = 0; col < n; ++col) {
    for (int k = outer[col]; k < outer[col + 1]; ++k) {
      const int pr = block_of_[inner[k]], pc = block_of_[col];
      if (pr >= 0 && pc >= 0 && pr != pc) rejected[pr] = rejected[pc] = 1;
    }
  }
  // Number the kept blocks and the global unknowns.
  std::vector<int> kept(num_candidates, -1);
  blocks_.clear();
  for (int p = 0; p < num_candidates; ++p) {
    if (rejected[p]) continue;
    kept[p] = static_cast<int>(blocks_.size());
    Block block;
    block.size = starts_[p + 1] - starts_[p];
    block.first_index = starts_[p];
    blocks_.push_back(block);
  }
  global_.clear();
  position_.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    block_of_[i] = block_of_[i] >= 0 ? kept[block_of_[i]] : -1;
    if (block_of_[i] < 0) {
      position_[i] = static_cast<int>(global_.size());
      global_.push_back(i);
    }
  }
  for (const Block& block : blocks_) {
    for (int k = 0; k < block.size; ++k) position_[indices_[block.first_index + k]] = k;
  }
  // Border rows (B_p) and columns (C_p) of each block, as indices into S.
  std::vector<std::vector<int>> rows(blocks_.size()), cols(blocks_.size());
  for (int col = 0; col < n; ++col) {
    for (int k = outer[col]; k < outer[col + 1]; ++k) {
      const int row = inner[k];
      if (block_of_[col] >= 0 && block_of_[row] < 0) rows[block_of_[col]].push_back(position_[row]);
      if (block_of_[col] < 0 && block_of_[row] >= 0) cols[block_of_[row]].push_back(position_[col]);
    }
  }
  border_.clear();
  int dense_size = 0, schur_size = 0;  // the sizes of dense_ and schur_slot_
  for (size_t p = 0; p < blocks_.size(); ++p) {
    SortUnique(&rows[p]);
    SortUnique(&cols[p]);
    Block& block = blocks_[p];
    block.border_rows = static_cast<int>(rows[p].size());
    block.border_cols = static_cast<int>(cols[p].size());
    block.border_first = static_cast<int>(border_.size());
    border_.insert(border_.end(), rows[p].begin(), rows[p].end());
    border_.insert(border_.end(), cols[p].begin(), cols[p].end());
    block.dense_first = dense_size;
    dense_size += block.size * (block.size + block.border_rows + block.border_cols);
    block.schur_first = schur_size;
    schur_size += block.border_rows * block.border_cols;
  }
  dense_.assign(dense_size, 0.0);
  schur_slot_.resize(schur_size);
  BuildSchurPattern(J);
  MapEntries(J);
  rhs_global_.resize(static_cast<Eigen::Index>(global_.size()));
  ++schur_version_;
  analyzed_ = true;
}

// S's pattern: A's entries and every (border row, border column) of each block; and the slot of each of the latter.
void CondensedLu::BuildSchurPattern(const Eigen::SparseMatrix<double>& J) {
  const int n = static_cast<int>(J.rows());
  const int* outer = J.outerIndexPtr();
  const int* inner = J.innerIndexPtr();
  std::vector<Eigen::Triplet<double>> triplets;
  for (int col = 0; col < n; ++col) {
    for (int k = outer[col]; k < outer[col + 1]; ++k) {
      const int row = inner[k];
      if (block_of_[col] < 0 && block_of_[row] < 0) triplets.emplace_back(position_[row], position_[col], 0.0);
    }
  }
  for (const Block& block : blocks_) {
    const int* border_rows = border_.data() + block.border_first;
    const int* border_cols = border_rows + block.border_rows;
    for (int j = 0; j < block.border_cols; ++j) {
      for (int i = 0; i < block.border_rows; ++i) triplets.emplace_back(border_rows[i], border_cols[j], 0.0);
    }
  }
  const int m = static_cast<int>(global_.size());
  S_.resize(m, m);
  S_.setFromTriplets(triplets.begin(), triplets.end());
  S_.makeCompressed();
  for (const Block& block : blocks_) {
    const int* border_rows = border_.data() + block.border_first;
    const int* border_cols = border_rows + block.border_rows;
    for (int j = 0; j < block.border_cols; ++j) {
      for (int i = 0; i < block.border_rows; ++i) {
        schur_slot_[block.schur_first + i + j * block.border_rows] = SlotOf(S_, border_rows[i], border_cols[j]);
      }
    }
  }
}

// Where each stored entry of J goes: S (its slot) or a dense block (-1 - index).
void CondensedLu::MapEntries(const Eigen::SparseMatrix<double>& J) {
  const int n = static_cast<int>(J.rows());
  const int* outer = J.outerIndexPtr();
  const int* inner = J.innerIndexPtr();
  entry_target_.resize(J.nonZeros());
  for (int col = 0; col < n; ++col) {
    for (int k = outer[col]; k < outer[col + 1]; ++k) {
      const int row = inner[k];
      const int pr = block_of_[row], pc = block_of_[col];
      if (pr < 0 && pc < 0) {
        entry_target_[k] = SlotOf(S_, position_[row], position_[col]);
        continue;
      }
      const Block& block = blocks_[pr >= 0 ? pr : pc];
      const int s = block.size;
      const int* border_rows = border_.data() + block.border_first;
      int index;
      if (pr >= 0 && pc >= 0) {  // D_p (row, col), column-major
        index = block.dense_first + position_[row] + position_[col] * s;
      } else if (pc >= 0) {      // B_p
        const int i = IndexIn(border_rows, border_rows + block.border_rows, position_[row]);
        index = block.dense_first + s * s + i + position_[col] * block.border_rows;
      } else {                   // C_p
        const int* border_cols = border_rows + block.border_rows;
        const int j = IndexIn(border_cols, border_cols + block.border_cols, position_[col]);
        index = block.dense_first + s * s + block.border_rows * s + position_[row] + j * s;
      }
      entry_target_[k] = -1 - index;
    }
  }
}

bool CondensedLu::Factorize(const Eigen::SparseMatrix<double>& J, int pattern_version) {
  if (!analyzed_ || pattern_version != pattern_version_ || J.nonZeros() != static_cast<int>(entry_target_.size())) {
    Analyze(J);
    pattern_version_ = pattern_version;
  }
  std::fill(S_.valuePtr(), S_.valuePtr() + S_.nonZeros(), 0.0);
  std::fill(dense_.begin(), dense_.end(), 0.0);
  const double* values = J.valuePtr();
  for (size_t k = 0; k < entry_target_.size(); ++k) {
    const int target = entry_target_[k];
    if (target >= 0) {
      S_.valuePtr()[target] += values[k];
    } else {
      dense_[-1 - target] += values[k];
    }
  }
  double* S_values = S_.valuePtr();
  for (const Block& block : blocks_) {
    const int s = block.size, br = block.border_rows, bc = block.border_cols;
    double* D = dense_.data() + block.dense_first;
    const double* B = D + s * s;
    const double* C = B + br * s;
    Eigen::PartialPivLU<BlockMatrix> lu(Eigen::Map<const Eigen::MatrixXd>(D, s, s));
    // A singular D_p (flat faces in contact, a degenerate normal cone): no condensed direction.
    if (!(lu.rcond() > 1e-12)) return false;
    Eigen::Map<Eigen::MatrixXd>(D, s, s) = lu.inverse();  // D_p^-1 in place of D_p
    // S(border) -= B_p (D_p^-1 C_p), column by column of C_p.
    const int* slot = schur_slot_.data() + block.schur_first;
    for (int j = 0; j < bc; ++j) {
      double x[kMaxBlock];
      for (int i = 0; i < s; ++i) {
        double sum = 0.0;
        for (int k = 0; k < s; ++k) sum += D[i + k * s] * C[k + j * s];
        x[i] = sum;
      }
      for (int i = 0; i < br; ++i) {
        double sum = 0.0;
        for (int k = 0; k < s; ++k) sum += B[i + k * br] * x[k];
        S_values[slot[i + j * br]] -= sum;
      }
    }
  }
  return lu_.Factorize(S_, schur_version_);
}

bool CondensedLu::Solve(Eigen::VectorXd* b) {
  if (!analyzed_ || b->size() != static_cast<Eigen::Index>(position_.size())) return false;
  Eigen::VectorXd& x = *b;
  const int m = static_cast<int>(global_.size());
  for (int g = 0; g < m; ++g) rhs_global_[g] = x[global_[g]];
  // r_g -= B_p D_p^-1 r_p.
  for (const Block& block : blocks_) {
    const int s = block.size, br = block.border_rows;
    const double* D_inv = dense_.data() + block.dense_first;
    const double* B = D_inv + s * s;
    const int* index = indices_.data() + block.first_index;
    const int* border_rows = border_.data() + block.border_first;
    double y[kMaxBlock];
    for (int i = 0; i < s; ++i) {
      double sum = 0.0;
      for (int k = 0; k < s; ++k) sum += D_inv[i + k * s] * x[index[k]];
      y[i] = sum;
    }
    for (int i = 0; i < br; ++i) {
      double sum = 0.0;
      for (int k = 0; k < s; ++k) sum += B[i + k * br] * y[k];
      rhs_global_[border_rows[i]] -= sum;
    }
  }
  if (!lu_.Solve(&rhs_global_)) return false;
  // x_p = D_p^-1 (r_p - C_p x_g).
  for (const Block& block : blocks_) {
    const int s = block.size, br = block.border_rows, bc = block.border_cols;
    const double* D_inv = dense_.data() + block.dense_first;
    const double* C = D_inv + s * s + br * s;
    const int* index = indices_.data() + block.first_index;
    const int* border_cols = border_.data() + block.border_first + br;
    double t[kMaxBlock];
    for (int i = 0; i < s; ++i) t[i] = x[index[i]];
    for (int j = 0; j < bc; ++j) {
      const double x_g = rhs_global_[border_cols[j]];
      for (int i = 0; i < s; ++i) t[i] -= C[i + j * s] * x_g;
    }
    for (int i = 0; i < s; ++i) {
      double sum = 0.0;
      for (int k = 0; k < s; ++k) sum += D_inv[i + k * s] * t[k];
      x[index[i]] = sum;
    }
  }
  for (int g = 0; g < m; ++g) x[global_[g]] = rhs_global_[g];
  return true;
}

}  // namespace implicit_sim
