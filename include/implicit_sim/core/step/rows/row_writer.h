// Where one evaluation of a step problem writes: the residual Phi and, if wanted, the Jacobian, dense or sparse. The
// row emitters of rows/ add their entries through it. Every evaluation of a layout emits the same Jacobian entries in
// the same order (zeros included), so that the sparse pattern recorded once stays valid (ncp_problem.h). The rows of
// locked velocities (Body::locked) become "velocity = 0" at the end (Finish); their other entries are left out.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/ncp/ncp_problem.h"

namespace implicit_sim {

class RowWriter {
 public:
  RowWriter(const NcpEvalMode& mode, Eigen::VectorXd* Phi, Eigen::MatrixXd* J_dense, SparseJacobian* J_sparse,
            const std::vector<char>& locked_rows)
      : mode(mode), Phi(*Phi), J_dense_(J_dense), J_sparse_(J_sparse), locked_rows_(locked_rows) {}
  const NcpEvalMode& mode;
  Eigen::VectorXd& Phi;
  bool WantJacobian() const { return J_dense_ || J_sparse_; }
  // Adds `block` (or `value`) to the Jacobian at (row, col).
  template <typename Block>
  void AddJ(int row, int col, const Block& block) const {
    if (J_dense_) {  // rows of locked velocities are overwritten by Finish
      J_dense_->block(row, col, block.rows(), block.cols()) += block;
    } else if (J_sparse_) {
      for (int j = 0; j < block.cols(); ++j) {
        for (int i = 0; i < block.rows(); ++i) AddJ(row + i, col + j, static_cast<double>(block(i, j)));
      }
    }
  }
  void AddJ(int row, int col, double value) const {
    if (J_sparse_ && row < static_cast<int>(locked_rows_.size()) && locked_rows_[row]) return;  // left out
    AddJUnlocked(row, col, value);
  }
  // The locked velocities' rows: "velocity = 0".
  void Finish(const Eigen::VectorXd& z) const {
    for (int row = 0; row < static_cast<int>(locked_rows_.size()); ++row) {
      if (!locked_rows_[row]) continue;
      Phi[row] = z[row];
      if (J_dense_) J_dense_->row(row).setZero();
      AddJUnlocked(row, row, 1.0);
    }
  }

 private:
  void AddJUnlocked(int row, int col, double value) const {
    if (J_dense_) {
      (*J_dense_)(row, col) += value;
    } else if (J_sparse_) {
      J_sparse_->Add(row, col, value);
    }
  }
  Eigen::MatrixXd* J_dense_;
  SparseJacobian* J_sparse_;
  const std::vector<char>& locked_rows_;
};

}  // namespace implicit_sim
