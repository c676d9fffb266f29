#include "implicit_sim/core/ncp/ipopt_ncp.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <vector>

#include <IpSolveStatistics.hpp>

#include "base/ipopt_app.h"
#include "implicit_sim/core/ncp/ncp_error.h"

namespace implicit_sim {
namespace {

using Ipopt::Index;
using Ipopt::Number;

class PenaltyNlp : public CapturingTnlp {
 public:
  int evaluations() const { return evaluations_; }
  PenaltyNlp(const NcpProblem& problem, const Eigen::VectorXd& z0, const StepInterrupt* interrupt)
      : CapturingTnlp(z0), problem_(problem), z0_(z0), interrupt_(interrupt) {
    raw_mode_.raw = true;
    const int n = problem.size();
    scale_.assign(n, 0.0);
    for (int i = 0; i < n; ++i) {
      double s;
      if (problem.IsComplementarityRow(i, &s)) scale_[i] = s;
    }
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override {
    n = m = problem_.size();
    Update(n, z0_.data(), true);  // records the sparsity pattern
    nnz_jac_g = static_cast<Index>(jacobian_.matrix.nonZeros());
    nnz_h_lag = 0;      // limited-memory Hessian approximation
    style = TNLP::C_STYLE;
    return true;
  }

  // Ipopt stops (User_Requested_Stop) once the interrupt is due.
  bool intermediate_callback(Ipopt::AlgorithmMode, Index, Number, Number, Number, Number, Number, Number, Number,
                             Number, Index, const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    return !InterruptDue(interrupt_);
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index, Number* g_l, Number* g_u) override {
    for (Index i = 0; i < n; ++i) {
      const bool pair = scale_[i] > 0.0;
      x_l[i] = pair ? 0.0 : -2e19;  // a_i >= 0
      x_u[i] = 2e19;
      g_l[i] = 0.0;                 // E(z) = 0 and b_i(z) >= 0
      g_u[i] = pair ? 2e19 : 0.0;
    }
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    if (init_x) {
      for (Index i = 0; i < n; ++i) x[i] = scale_[i] > 0.0 ? std::max(z0_[i], 0.0) : z0_[i];
    }
    return true;
  }

  bool eval_f(Index n, const Number* x, bool new_x, Number& f) override {
    if (!Update(n, x, new_x)) return false;
    f = 0.0;
    for (Index i = 0; i < n; ++i) {
      if (scale_[i] > 0.0) f += scale_[i] * x[i] * raw_[i];
    }
    return std::isfinite(f);
  }

  bool eval_grad_f(Index n, const Number* x, bool new_x, Number* grad) override {
    if (!Update(n, x, new_x)) return false;
    std::fill(grad, grad + n, 0.0);
    const Eigen::SparseMatrix<double>& J = jacobian_.matrix;
    for (Index j = 0; j < n; ++j) {
      if (scale_[j] > 0.0) grad[j] += scale_[j] * raw_[j];
      for (Eigen::SparseMatrix<double>::InnerIterator it(J, j); it; ++it) {
        const int i = static_cast<int>(it.row());
        if (scale_[i] > 0.0) grad[j] += scale_[i] * x[i] * it.value();
      }
    }
    return true;
  }

  bool eval_g(Index n, const Number* x, bool new_x, Index, Number* g) override {
    if (!Update(n, x, new_x)) return false;
    for (Index i = 0; i < n; ++i) g[i] = raw_[i];
    return true;
  }

  bool eval_jac_g(Index n, const Number* x, bool new_x, Index, Index, Index* rows, Index* cols,
                  Number* values) override {
    const Eigen::SparseMatrix<double>& J = jacobian_.matrix;
    if (!values) {
      Index k = 0;
      for (Index j = 0; j < n; ++j) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(J, j); it; ++it, ++k) {
          rows[k] = static_cast<Index>(it.row());
          cols[k] = j;
        }
      }
      return true;
    }
    if (!Update(n, x, new_x)) return false;
    std::copy(J.valuePtr(), J.valuePtr() + J.nonZeros(), values);  // column by column, as the structure above
    return true;
  }

 private:
  bool Update(Index n, const Number* x, bool new_x) {
    if (new_x || !evaluated_) {
      problem_.EvaluateSparse(Eigen::Map<const Eigen::VectorXd>(x, n), raw_mode_, &raw_, &jacobian_);
      evaluated_ = true;
      ++evaluations_;
    }
    const Eigen::SparseMatrix<double>& J = jacobian_.matrix;
    return raw_.allFinite() && std::all_of(J.valuePtr(), J.valuePtr() + J.nonZeros(), [](double v) {
             return std::isfinite(v);
           });
  }

  const NcpProblem& problem_;
  NcpEvalMode raw_mode_;
  Eigen::VectorXd z0_, raw_;
  const StepInterrupt* interrupt_;
  SparseJacobian jacobian_;  // the pattern is fixed for the solve: every entry is emitted at every evaluation
  std::vector<double> scale_;
  bool evaluated_ = false;
  int evaluations_ = 0;
};

}  // namespace

NcpSummary SolveNcpWithIpopt(const NcpProblem& problem, const IpoptNcpOptions& options, Eigen::VectorXd* z) {
  NcpSummary summary;
  if (InterruptDue(options.interrupt)) {
    summary.termination = NcpTermination::kInterrupted;
    summary.residual = std::numeric_limits<double>::infinity();
    return summary;
  }
  bool solved = false;
  try {
    const std::lock_guard<std::mutex> lock(IpoptMutex());
    Ipopt::SmartPtr<PenaltyNlp> nlp = new PenaltyNlp(problem, *z, options.interrupt);
    IpoptSettings settings;
    settings.tol = options.ipopt_tol;
    settings.acceptable_tol = options.ipopt_acceptable_tol;
    settings.max_iter = std::max(1, options.max_iterations);
    settings.limited_memory_hessian = true;
    const Ipopt::SmartPtr<Ipopt::IpoptApplication> app = MakeQuietIpopt(settings);
    if (IsValid(app)) {
      solved = IpoptSolved(app->OptimizeTNLP(Ipopt::GetRawPtr(nlp)));
      if (IsValid(app->Statistics())) summary.iterations = app->Statistics()->IterationCount();
      if (nlp->finalized() && nlp->x().allFinite()) *z = nlp->x();
    }
    summary.residual_evaluations = nlp->evaluations() + 1;  // and the error check below
  } catch (const std::exception&) {
    solved = false;
  }
  Eigen::VectorXd raw_rows;
  const NcpError error = ComputeNcpError(problem, *z, &raw_rows);
  summary.equation_residual = error.equations;
  summary.complementarity = error.complementarity;
  summary.residual = std::max(error.equations, error.complementarity);
  if (!std::isfinite(error.equations) || !std::isfinite(error.complementarity)) {
    summary.termination = NcpTermination::kNonFinite;
  } else if (!solved) {
    summary.termination = InterruptDue(options.interrupt) ? NcpTermination::kInterrupted : NcpTermination::kSolverFailure;
  } else {
    summary.converged = summary.residual <= options.tolerance;
    summary.termination = summary.converged ? NcpTermination::kConverged : NcpTermination::kInaccurate;
  }
  return summary;
}

}  // namespace implicit_sim
