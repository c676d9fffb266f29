// The seam between the step and its solvers: a mixed nonlinear complementarity problem in the reformulated form
// Phi(z) = 0, with z in R^n and one row per unknown. Row i is either
//   an equation            E_i(z) = 0, or
//   a complementarity row  0 <= a_i _|_ b_i(z) >= 0 with a_i = scale_i z_i, reformulated as FB(a_i, b_i(z)) = 0
//                          (fischer_burmeister.h).
// The solvers (semismooth_newton.h, ipopt_ncp.h) and the error check (ncp_error.h) see a problem only through this
// interface, so they can be tested on small problems with known solutions and handed any NCP (a whole step or part).
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace implicit_sim {

// How a problem is evaluated; chosen by the solver for each call.
struct NcpEvalMode {
  // Smoothing mu >= 0 of every Fischer-Burmeister function (0: the exact problem); see FischerBurmeister.
  double smoothing = 0.0;
  // Raw rows: each complementarity row returns b_i(z), the function side of its pair, instead of FB(a_i, b_i(z)).
  bool raw = false;
  // A proximal term delta >= 0 that the problem may add to the Jacobian's diagonal entries of rows it chooses
  // (never to Phi), to keep the Newton matrix regular where the problem is degenerate.
  double regularization = 0.0;
  // Projected multipliers: the problem's equation rows may read a complementarity unknown at max(z_i, 0), its value
  // at every solution, so that an iterate with a negative multiplier does not act with the wrong sign (the step's
  // friction rows, step/rows/friction_rows.h). The complementarity rows and the raw rows keep z_i.
  bool project_multipliers = false;
  // A proximal-point term (the retry ladder's proximal rung): the problem may add proximal_weight (z_i - c_i), with c
  // = *proximal_center, to the function side of the rows it chooses (the step: its contact force and friction
  // rows), so that the perturbed problem is better posed and its solution stays near c. 0: off.
  double proximal_weight = 0.0;
  const Eigen::VectorXd* proximal_center = nullptr;
};

// A Jacobian in compressed sparse columns. Its pattern is recorded by the first evaluation after the problem's
// pattern_version changes; later evaluations replay the same entries in the same order into the recorded slots
// (no allocation). A problem's EvaluateSparse calls Begin, then Add for every entry, then Finish.
class SparseJacobian {
 public:
  Eigen::SparseMatrix<double> matrix;
  int pattern_version() const { return pattern_version_; }
  // Starts an evaluation of a problem whose pattern is `pattern_version`.
  void Begin(int pattern_version);
  // Adds `value` at (row, col); duplicates are summed. The same sequence of (row, col) for a given pattern.
  void Add(int row, int col, double value) {
    if (recording_) {
      recorded_.emplace_back(row, col, value);
    } else {
      matrix.valuePtr()[slot_[cursor_++]] += value;
    }
  }
  // Ends the evaluation of an n x n Jacobian (builds the pattern after a recording evaluation).
  void Finish(int n);

 private:
  int pattern_version_ = -1;
  int pending_version_ = -1;
  bool recording_ = false;
  std::vector<Eigen::Triplet<double>> recorded_;  // the entries as emitted, while recording
  std::vector<int> slot_;                         // per emitted entry: its index in matrix.valuePtr()
  int cursor_ = 0;
};

class NcpProblem {
 public:
  virtual ~NcpProblem() = default;
  virtual int size() const = 0;  // n: unknowns and rows
  // Whether row i is a complementarity row, and the scale of its variable side a_i = scale * z_i (scale > 0).
  virtual bool IsComplementarityRow(int row, double* scale) const = 0;
  // Changes whenever the size or the sparsity pattern of the Jacobian changes.
  virtual int pattern_version() const = 0;
  // Phi(z) and, if J is not null, an element of its generalized Jacobian (n x n), dense or sparse. Evaluations are
  // not re-entrant: one problem object serves one solver at a time.
  virtual void Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                        Eigen::MatrixXd* J) const = 0;
  virtual void EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                              SparseJacobian* J) const = 0;
  // Local blocks the sparse solver may condense out of the Newton matrix (condensed_lu.h): block p holds the unknowns
  // indices[starts[p] .. starts[p + 1]), and no row of one block touches an unknown of another. Fixed for a
  // pattern_version. By default none.
  virtual void CondensableBlocks(std::vector<int>* starts, std::vector<int>* indices) const {
    starts->assign(1, 0);
    indices->clear();
  }
  // Moves a line-search trial point back onto a curved set that every solution lies on, for the unknowns that z
  // already lies on (NewtonOptions::retract_sliding). By default nothing.
  virtual void Retract(const Eigen::VectorXd& /*z*/, Eigen::VectorXd* /*trial*/) const {}
};

}  // namespace implicit_sim
