#include "implicit_sim/core/ncp/sparse_lu.h"

#include <algorithm>
#include <vector>

#include <klu.h>
#include <umfpack.h>

namespace implicit_sim {
namespace {

// KLU: the left-looking factorization of small matrices, reusing its pivot order within a solve.
struct KluFactors {
  klu_common common;
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  KluFactors() { klu_defaults(&common); }
  ~KluFactors() {
    FreeNumeric();
    FreeSymbolic();
  }
  void FreeNumeric() {
    if (numeric) klu_free_numeric(&numeric, &common);
  }
  void FreeSymbolic() {
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
  bool Analyze(int n, int* Ap, int* Ai) {
    FreeNumeric();
    FreeSymbolic();
    symbolic = klu_analyze(n, Ap, Ai, &common);
    return symbolic != nullptr;
  }
  bool Factorize(int* Ap, int* Ai, double* Ax) {
    if (numeric) {
      // Same pattern: reuse the pivot order (no search); a zero pivot means a fresh factorization with pivoting.
      if (klu_refactor(Ap, Ai, Ax, symbolic, numeric, &common) && common.status == KLU_OK) return true;
      FreeNumeric();
    }
    numeric = klu_factor(Ap, Ai, Ax, symbolic, &common);
    return numeric != nullptr && common.status == KLU_OK;
  }
  bool Solve(int n, double* b) { return numeric && klu_solve(symbolic, numeric, n, 1, b, &common) != 0; }
};

// UMFPACK: the multifrontal factorization of large matrices, pivoting afresh in every factorization.
struct UmfpackFactors {
  double control[UMFPACK_CONTROL];
  double info[UMFPACK_INFO];
  void* symbolic = nullptr;
  void* numeric = nullptr;
  // The matrix of the last factorization (wsolve reads it only for iterative refinement, which is off) and the
  // solve's workspace.
  const int* Ap = nullptr;
  const int* Ai = nullptr;
  const double* Ax = nullptr;
  std::vector<double> x, work;
  std::vector<int> work_indices;
  UmfpackFactors() {
    umfpack_di_defaults(control);
    control[UMFPACK_IRSTEP] = 0;  // no iterative refinement: the Newton solver checks its directions itself
  }
  ~UmfpackFactors() {
    FreeNumeric();
    FreeSymbolic();
  }
  void FreeNumeric() {
    if (numeric) umfpack_di_free_numeric(&numeric);
  }
  void FreeSymbolic() {
    if (symbolic) umfpack_di_free_symbolic(&symbolic);
  }
  bool Analyze(int n, const int* Ap, const int* Ai, const double* Ax) {
    FreeNumeric();
    FreeSymbolic();
    x.resize(n);
    work.resize(n);  // n doubles without iterative refinement
    work_indices.resize(n);
    return umfpack_di_symbolic(n, n, Ap, Ai, Ax, &symbolic, control, info) == UMFPACK_OK;
  }
  bool Factorize(const int* ap, const int* ai, const double* ax) {
    FreeNumeric();
    Ap = ap;
    Ai = ai;
    Ax = ax;
    // UMFPACK_WARNING_singular_matrix (a zero pivot) counts as a failure, as KLU's KLU_SINGULAR does.
    if (umfpack_di_numeric(Ap, Ai, Ax, symbolic, &numeric, control, info) == UMFPACK_OK) return true;
    FreeNumeric();
    return false;
  }
  bool Solve(double* b) {
    if (!numeric) return false;
    if (umfpack_di_wsolve(UMFPACK_A, Ap, Ai, Ax, x.data(), b, numeric, control, info, work_indices.data(),
                          work.data()) != UMFPACK_OK) {
      return false;
    }
    std::copy(x.begin(), x.end(), b);
    return true;
  }
};

}  // namespace

struct SparseLu::Impl {
  int multifrontal_min_size = 0;
  int pattern_version = -1;
  int n = 0;
  bool analyzed = false;
  bool multifrontal = false;
  KluFactors klu;
  UmfpackFactors umfpack;
};

SparseLu::SparseLu(int multifrontal_min_size) : impl_(new Impl) {
  impl_->multifrontal_min_size = multifrontal_min_size;
}
SparseLu::~SparseLu() = default;

bool SparseLu::Factorize(const Eigen::SparseMatrix<double>& A, int pattern_version) {
  Impl& k = *impl_;
  int* Ap = const_cast<int*>(A.outerIndexPtr());
  int* Ai = const_cast<int*>(A.innerIndexPtr());
  double* Ax = const_cast<double*>(A.valuePtr());
  if (k.pattern_version != pattern_version || !k.analyzed) {
    k.klu.FreeNumeric();
    k.umfpack.FreeNumeric();
    k.n = static_cast<int>(A.rows());
    k.multifrontal = k.n >= k.multifrontal_min_size;
    k.analyzed = k.multifrontal ? k.umfpack.Analyze(k.n, Ap, Ai, Ax) : k.klu.Analyze(k.n, Ap, Ai);
    k.pattern_version = pattern_version;
    if (!k.analyzed) return false;
  }
  return k.multifrontal ? k.umfpack.Factorize(Ap, Ai, Ax) : k.klu.Factorize(Ap, Ai, Ax);
}

void SparseLu::ForgetPivots() { impl_->klu.FreeNumeric(); }

bool SparseLu::Solve(Eigen::VectorXd* b) {
  Impl& k = *impl_;
  if (!k.analyzed || b->size() != k.n) return false;
  return k.multifrontal ? k.umfpack.Solve(b->data()) : k.klu.Solve(k.n, b->data());
}

bool SparseLu::multifrontal() const { return impl_->multifrontal; }

}  // namespace implicit_sim
