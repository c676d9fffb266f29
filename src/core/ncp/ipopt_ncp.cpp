#include "implicit_sim/core/ncp/ipopt_ncp.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <sstream>
#include <vector>

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

namespace implicit_sim {
namespace {

using Ipopt::Index;
using Ipopt::Number;

class StepNlp : public Ipopt::TNLP {
 public:
  StepNlp(StepProblem* problem, const Eigen::VectorXd& z0) : problem_(problem), z0_(z0), z_(z0) {
    const int n = problem->size();
    scale_.assign(n, 0.0);
    for (int i = 0; i < n; ++i) {
      double s;
      if (problem->IsComplementarityRow(i, &s)) scale_[i] = s;
    }
  }
  const Eigen::VectorXd& z() const { return z_; }
  bool finalized() const { return finalized_; }
  Ipopt::SolverReturn status() const { return status_; }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override {
    n = m = problem_->size();
    Update(n, z0_.data(), true);  // records the sparsity pattern
    nnz_jac_g = static_cast<Index>(jacobian_.matrix.nonZeros());
    nnz_h_lag = 0;      // limited-memory Hessian approximation
    style = TNLP::C_STYLE;
    return true;
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

  void finalize_solution(Ipopt::SolverReturn status, Index n, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    finalized_ = true;
    status_ = status;
    z_ = Eigen::Map<const Eigen::VectorXd>(x, n);
  }

 private:
  bool Update(Index n, const Number* x, bool new_x) {
    if (new_x || !evaluated_) {
      problem_->EvaluateSparse(Eigen::Map<const Eigen::VectorXd>(x, n), &raw_, &jacobian_);
      evaluated_ = true;
    }
    const Eigen::SparseMatrix<double>& J = jacobian_.matrix;
    return raw_.allFinite() && std::all_of(J.valuePtr(), J.valuePtr() + J.nonZeros(), [](double v) {
             return std::isfinite(v);
           });
  }

  StepProblem* problem_;
  Eigen::VectorXd z0_, z_, raw_;
  SparseJacobian jacobian_;  // the pattern is fixed for the solve: every entry is emitted at every evaluation
  std::vector<double> scale_;
  bool evaluated_ = false, finalized_ = false;
  Ipopt::SolverReturn status_ = Ipopt::INTERNAL_ERROR;
};

}  // namespace

IpoptNcpResult SolveStepWithIpopt(StepProblem* problem, int max_iterations, Eigen::VectorXd* z) {
  IpoptNcpResult result;
  problem->set_raw_complementarity(true);
  try {
    Ipopt::SmartPtr<StepNlp> nlp = new StepNlp(problem, *z);
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
    app->Options()->SetIntegerValue("print_level", 0);
    app->Options()->SetStringValue("sb", "yes");
    app->Options()->SetStringValue("hessian_approximation", "limited-memory");
    app->Options()->SetStringValue("mu_strategy", "adaptive");
    app->Options()->SetNumericValue("tol", 1e-10);
    app->Options()->SetNumericValue("acceptable_tol", 1e-8);
    app->Options()->SetIntegerValue("max_iter", std::max(1, max_iterations));
    std::istringstream no_option_file("");
    if (app->Initialize(no_option_file) == Ipopt::Solve_Succeeded) {
      const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
      result.solved = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
      if (IsValid(app->Statistics())) result.iterations = app->Statistics()->IterationCount();
      if (nlp->finalized() && nlp->z().allFinite()) *z = nlp->z();
    }
  } catch (const std::exception&) {
    result.solved = false;
  }
  problem->set_raw_complementarity(false);
  problem->RawResiduals(*z, &result.equation_residual, &result.complementarity);
  if (!std::isfinite(result.equation_residual) || !std::isfinite(result.complementarity)) result.solved = false;
  return result;
}

}  // namespace implicit_sim
