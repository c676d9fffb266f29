// Sparse LU of the Newton matrix by SuiteSparse, made for the very sparse, unsymmetric matrices of contact problems.
// Two factorizations, chosen by the matrix's size (KLU for every size unless the owner sets `multifrontal_min_size`):
// - below `multifrontal_min_size` unknowns, KLU (block triangular form, AMD ordering, left-looking partial
//   pivoting). Within a Newton solve its numeric factorization is refreshed with the previous pivot order
//   (klu_refactor), falling back to a fresh pivoting factorization when that meets a zero pivot; every solve starts
//   with a fresh one (ForgetPivots). KLU mallocs its numeric object once per solve.
// - from `multifrontal_min_size` unknowns on, UMFPACK (multifrontal, dense frontal matrices through the BLAS). Every
//   factorization searches its pivots afresh within the kept symbolic analysis, so a stale pivot order never costs
//   accuracy, and ForgetPivots has nothing to forget. UMFPACK mallocs its numeric object once per factorization.
// CondensedLu takes UMFPACK for the condensed systems of islands of several hundred bodies, where KLU's left-looking
// kernel was 88 % of a landing step; on smaller ones KLU's steady pivot order measured better over whole piles
// (bench/README.md, "The factorization of large islands").
// The symbolic analysis is kept while the pattern stays the same. Our code allocates nothing once a pattern has been
// factorized.
#pragma once

#include <limits>
#include <memory>

#include <Eigen/SparseCore>

namespace implicit_sim {

class SparseLu {
 public:
  static constexpr int kNeverMultifrontal = std::numeric_limits<int>::max();

  // Matrices of at least `multifrontal_min_size` unknowns go to UMFPACK, smaller ones to KLU.
  explicit SparseLu(int multifrontal_min_size = kNeverMultifrontal);
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
  // Whether the last Factorize went to UMFPACK.
  bool multifrontal() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace implicit_sim
