#include "implicit_sim/core/ncp/sparse_lu.h"

#include <klu.h>

namespace implicit_sim {

struct SparseLu::Impl {
  klu_common common;
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  int pattern_version = -1;
  int n = 0;
  Impl() { klu_defaults(&common); }
  void FreeNumeric() {
    if (numeric) klu_free_numeric(&numeric, &common);
  }
  ~Impl() {
    FreeNumeric();
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
};

SparseLu::SparseLu() : impl_(new Impl) {}
SparseLu::~SparseLu() = default;

bool SparseLu::Factorize(const Eigen::SparseMatrix<double>& A, int pattern_version) {
  Impl& k = *impl_;
  int* Ap = const_cast<int*>(A.outerIndexPtr());
  int* Ai = const_cast<int*>(A.innerIndexPtr());
  double* Ax = const_cast<double*>(A.valuePtr());
  if (k.pattern_version != pattern_version || !k.symbolic) {
    k.FreeNumeric();
    if (k.symbolic) klu_free_symbolic(&k.symbolic, &k.common);
    k.n = static_cast<int>(A.rows());
    k.symbolic = klu_analyze(k.n, Ap, Ai, &k.common);
    k.pattern_version = pattern_version;
    if (!k.symbolic) return false;
  }
  if (k.numeric) {
    // Same pattern: reuse the pivot order (no search); a zero pivot means a fresh factorization with pivoting.
    if (klu_refactor(Ap, Ai, Ax, k.symbolic, k.numeric, &k.common) && k.common.status == KLU_OK) return true;
    k.FreeNumeric();
  }
  k.numeric = klu_factor(Ap, Ai, Ax, k.symbolic, &k.common);
  return k.numeric != nullptr && k.common.status == KLU_OK;
}

void SparseLu::ForgetPivots() { impl_->FreeNumeric(); }

bool SparseLu::Solve(Eigen::VectorXd* b) {
  Impl& k = *impl_;
  if (!k.numeric || b->size() != k.n) return false;
  return klu_solve(k.symbolic, k.numeric, k.n, 1, b->data(), &k.common) != 0;
}

}  // namespace implicit_sim
