// Sparse LU of the Newton matrix by SuiteSparse KLU (block triangular form, AMD ordering, partial pivoting), made for
// the very sparse, unsymmetric matrices of contact problems. The symbolic analysis is kept while the pattern stays
// the same. Within a Newton solve the numeric factorization is refreshed with the previous pivot order
// (klu_refactor), falling back to a fresh pivoting factorization when that meets a zero pivot; every solve starts
// with a fresh one (ForgetPivots). Our code allocates nothing once a pattern has been factorized; KLU mallocs its
// numeric object once per solve.
#pragma once

#include <memory>

#include <Eigen/SparseCore>

namespace implicit_sim {

class SparseLu {
 public:
  SparseLu();
  ~SparseLu();
  SparseLu(const SparseLu&) = delete;
  SparseLu& operator=(const SparseLu&) = delete;
  // Factorizes A (compressed columns). `pattern_version` tells when A's pattern changed. False if A is singular.
  bool Factorize(const Eigen::SparseMatrix<double>& A, int pattern_version);
  // The next Factorize searches pivots afresh (klu_factor) instead of reusing the last order, so that a solve does
  // not depend on the solves before it (determinism of a restored run). KLU then allocates its numeric object.
  void ForgetPivots();
  // x = A^-1 b in place; false if not factorized.
  bool Solve(Eigen::VectorXd* b);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace implicit_sim
