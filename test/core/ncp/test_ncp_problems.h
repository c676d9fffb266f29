// Small mixed NCPs with known solutions for the solver tests (linear, simplex projection, nonlinear, arctangent),
// each with a dense and a sparse Jacobian honouring NcpEvalMode, and wrappers that record or poison evaluations;
// RandomVector for the linear solver tests.
#pragma once

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/ncp/ncp_problem.h"

namespace implicit_sim {
namespace ncp_test {

// n values uniform in [-1, 1).
inline Eigen::VectorXd RandomVector(int n, std::mt19937* rng) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = value(*rng);
  return b;
}

// A mixed NCP given row by row: row i is the equation f_i(z) = 0 (scale 0) or the complementarity pair
// 0 <= scale_i z_i _|_ f_i(z) >= 0, reformulated as FB(scale_i z_i, f_i(z)). The regularization of NcpEvalMode goes
// on the diagonal of the complementarity rows (if honour_regularization), never into Phi.
class RowNcp : public NcpProblem {
 public:
  struct Entry {
    int col;
    double value;
  };
  explicit RowNcp(std::vector<double> scales) : scales_(std::move(scales)) {}
  int size() const override { return static_cast<int>(scales_.size()); }
  bool IsComplementarityRow(int row, double* scale) const override {
    *scale = scales_[row];
    return scales_[row] > 0.0;
  }
  int pattern_version() const override { return 1; }
  void Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                Eigen::MatrixXd* J) const override {
    Phi->resize(size());
    if (J) J->setZero(size(), size());
    for (int i = 0; i < size(); ++i) {
      double diagonal;
      (*Phi)[i] = EvaluateRow(i, z, mode, &diagonal);
      if (!J) continue;
      (*J)(i, i) += diagonal;
      for (const Entry& e : gradient_) (*J)(i, e.col) += row_factor_ * e.value;
    }
  }
  void EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                      SparseJacobian* J) const override {
    Phi->resize(size());
    J->Begin(pattern_version());
    for (int i = 0; i < size(); ++i) {
      double diagonal;
      (*Phi)[i] = EvaluateRow(i, z, mode, &diagonal);
      J->Add(i, i, diagonal);  // every row has its diagonal entry (0 for an equation row): a fixed pattern
      for (const Entry& e : gradient_) J->Add(i, e.col, row_factor_ * e.value);
    }
    J->Finish(size());
  }
  bool honour_regularization = true;

 protected:
  // f_i(z) and its gradient's entries, the same columns at every z (zeros included).
  virtual double Row(int i, const Eigen::VectorXd& z, std::vector<Entry>* gradient) const = 0;

 private:
  // Phi_i; leaves f_i's gradient in gradient_, its factor in J in row_factor_ and J's extra diagonal in *diagonal.
  double EvaluateRow(int i, const Eigen::VectorXd& z, const NcpEvalMode& mode, double* diagonal) const {
    gradient_.clear();
    const double f = Row(i, z, &gradient_);
    if (scales_[i] <= 0.0) {
      *diagonal = 0.0;
      row_factor_ = 1.0;
      return f;
    }
    const FB fb = FischerBurmeister(scales_[i] * z[i], f, mode.smoothing, mode.raw);
    const bool regularize = honour_regularization && !mode.raw;
    *diagonal = fb.da * scales_[i] + (regularize ? mode.regularization : 0.0);
    row_factor_ = fb.db;
    return fb.value;
  }
  std::vector<double> scales_;
  mutable std::vector<Entry> gradient_;
  mutable double row_factor_ = 1.0;
};

// The mixed LCP w = M z + q: rows with scale > 0 are pairs 0 <= scale z_i _|_ w_i >= 0, the others equations w_i = 0.
class LinearNcp : public RowNcp {
 public:
  LinearNcp(Eigen::MatrixXd M, Eigen::VectorXd q, std::vector<double> scales)
      : RowNcp(std::move(scales)), M_(std::move(M)), q_(std::move(q)) {}
  LinearNcp(const Eigen::MatrixXd& M, const Eigen::VectorXd& q)
      : LinearNcp(M, q, std::vector<double>(static_cast<size_t>(q.size()), 1.0)) {}
  const Eigen::MatrixXd& M() const { return M_; }
  const Eigen::VectorXd& q() const { return q_; }

 protected:
  double Row(int i, const Eigen::VectorXd& z, std::vector<Entry>* gradient) const override {
    for (int j = 0; j < M_.cols(); ++j) {
      if (M_(i, j) != 0.0) gradient->push_back({j, M_(i, j)});
    }
    return M_.row(i).dot(z) + q_[i];
  }

 private:
  Eigen::MatrixXd M_;
  Eigen::VectorXd q_;
};

// A unique-solution LCP (M has a positive definite symmetric part): z* = (1, 0, 2), w* = (0, 1, 0).
inline LinearNcp UniqueLcp() {
  Eigen::MatrixXd M(3, 3);
  M << 4, 1, -1, 2, 3, 1, 0, -1, 2;
  return LinearNcp(M, Eigen::Vector3d(-2, -3, -4));
}
inline Eigen::VectorXd UniqueLcpSolution() { return Eigen::Vector3d(1, 0, 2); }

// The same M with row 2 biactive at the solution: z* = (1, 0, 2), w* = (0, 0, 0).
inline LinearNcp DegenerateLcp() {
  const LinearNcp unique = UniqueLcp();
  return LinearNcp(unique.M(), Eigen::Vector3d(-2, -4, -4));
}

// The KKT system of the projection of p = (0.75, 0.5, -0.5) onto the simplex {x >= 0, sum x = 1}, z = (x, lambda):
// 0 <= x_i _|_ x_i - p_i + lambda >= 0 and the equation sum x - 1 = 0. Solution x = (0.625, 0.375, 0),
// lambda = 0.125 (and w_3 = 0.625).
inline LinearNcp SimplexProjection() {
  Eigen::MatrixXd M(4, 4);
  M << 1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 0;
  return LinearNcp(M, Eigen::Vector4d(-0.75, -0.5, 0.5, -1), {1.0, 1.0, 1.0, 0.0});
}
inline Eigen::VectorXd SimplexProjectionSolution() { return Eigen::Vector4d(0.625, 0.375, 0, 0.125); }

// A nonlinear mixed NCP with the unique solution z* = (1, 0, 1):
//   0 <= z0 _|_ z0^2 + z1^2 + z0 z2 - 2 >= 0,  0 <= z1 _|_ exp(z1) + z0 - 1 >= 0,  z2^3 + z2 - z0 - 1 = 0.
// (z1 > 0 would need exp(z1) = 1 - z0 < 1; then z0 > 0 solves z0^2 + z0 z2(z0) = 2 with both terms increasing.)
class NonlinearNcp : public RowNcp {
 public:
  NonlinearNcp() : RowNcp({1.0, 1.0, 0.0}) {}
  static Eigen::VectorXd Solution() { return Eigen::Vector3d(1, 0, 1); }

 protected:
  double Row(int i, const Eigen::VectorXd& z, std::vector<Entry>* gradient) const override {
    if (i == 0) {
      *gradient = {{0, 2 * z[0] + z[2]}, {1, 2 * z[1]}, {2, z[0]}};
      return z[0] * z[0] + z[1] * z[1] + z[0] * z[2] - 2;
    }
    if (i == 1) {
      *gradient = {{0, 1.0}, {1, std::exp(z[1])}};
      return std::exp(z[1]) + z[0] - 1;
    }
    *gradient = {{0, -1.0}, {2, 3 * z[2] * z[2] + 1}};
    return z[2] * z[2] * z[2] + z[2] - z[0] - 1;
  }
};

// atan(z0 - 1) = 0 and 0 <= z1 _|_ z1 - z0 + 2 >= 0: solution (1, 0). Far from z0 = 1 the full Newton step on the
// arctangent overshoots (to z0 - 1 - (1 + (z0 - 1)^2) atan(z0 - 1)), so the line search has to shorten it.
class ArctanNcp : public RowNcp {
 public:
  ArctanNcp() : RowNcp({0.0, 1.0}) {}
  static Eigen::VectorXd Solution() { return Eigen::Vector2d(1, 0); }

 protected:
  double Row(int i, const Eigen::VectorXd& z, std::vector<Entry>* gradient) const override {
    if (i == 0) {
      const double x = z[0] - 1;
      *gradient = {{0, 1.0 / (1.0 + x * x)}};
      return std::atan(x);
    }
    *gradient = {{0, -1.0}, {1, 1.0}};
    return z[1] - z[0] + 2;
  }
};

// Forwards to a problem and records |Phi|_2 at every evaluation with a Jacobian (one per Newton iterate) and the
// number of evaluations without one (line-search trials).
class RecordingNcp : public NcpProblem {
 public:
  explicit RecordingNcp(const NcpProblem& inner) : inner_(inner) {}
  int size() const override { return inner_.size(); }
  bool IsComplementarityRow(int row, double* scale) const override { return inner_.IsComplementarityRow(row, scale); }
  int pattern_version() const override { return inner_.pattern_version(); }
  void Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                Eigen::MatrixXd* J) const override {
    inner_.Evaluate(z, mode, Phi, J);
    Record(*Phi, J != nullptr);
  }
  void EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                      SparseJacobian* J) const override {
    inner_.EvaluateSparse(z, mode, Phi, J);
    Record(*Phi, true);
  }
  const std::vector<double>& iterate_residuals() const { return iterate_residuals_; }
  int trial_evaluations() const { return trial_evaluations_; }

 private:
  void Record(const Eigen::VectorXd& Phi, bool jacobian) const {
    if (jacobian) {
      iterate_residuals_.push_back(Phi.norm());
    } else {
      ++trial_evaluations_;
    }
  }
  const NcpProblem& inner_;
  mutable std::vector<double> iterate_residuals_;
  mutable int trial_evaluations_ = 0;
};

// Forwards to a problem but returns NaN in every row of Phi at any z other than `finite_at` (everywhere if empty).
class PoisonedNcp : public NcpProblem {
 public:
  PoisonedNcp(const NcpProblem& inner, Eigen::VectorXd finite_at) : inner_(inner), finite_at_(std::move(finite_at)) {}
  int size() const override { return inner_.size(); }
  bool IsComplementarityRow(int row, double* scale) const override { return inner_.IsComplementarityRow(row, scale); }
  int pattern_version() const override { return inner_.pattern_version(); }
  void Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                Eigen::MatrixXd* J) const override {
    inner_.Evaluate(z, mode, Phi, J);
    Poison(z, Phi);
  }
  void EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                      SparseJacobian* J) const override {
    inner_.EvaluateSparse(z, mode, Phi, J);
    Poison(z, Phi);
  }

 private:
  void Poison(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
    if (finite_at_.size() == 0 || z != finite_at_) Phi->setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  const NcpProblem& inner_;
  Eigen::VectorXd finite_at_;
};

}  // namespace ncp_test
}  // namespace implicit_sim
