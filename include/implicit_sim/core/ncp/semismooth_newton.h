// Semismooth Newton method on the Fischer-Burmeister reformulation Phi(z) = 0 of a mixed NCP (ncp_problem.h;
// doc/method.md, pitfall 8): exact generalized Jacobian, Armijo backtracking on 0.5 |Phi|^2.
// The Newton system (J + delta P) dz = -Phi is solved by LU: dense with partial pivoting for small NCPs, sparse (KLU,
// see sparse_lu.h, the Jacobian assembled in compressed columns) for large ones. P is the problem's choice of diagonal
// entries (NcpEvalMode::regularization; the step puts it on its normal-force and friction rows): a proximal term that
// keeps the system regular where contact forces are redundant (a body resting on several others) while the residual,
// and so the solution, stays exact. Where a dense J is numerically singular (unknowns that no row determines: the
// closest points along a line contact of a planar body, or across a flat face), the direction is the basic solution of
// J dz = -Phi by a rank-revealing factorization (fully pivoted LU, column-pivoting QR on large islands), without
// squaring J's condition number. If that fails too or its direction does not decrease the merit, the
// Levenberg-Marquardt normal equations (J^T J + lambda I) dz = -J^T Phi are solved instead (dense or sparse LDL^T).
// A sparse solve first condenses the problem's local blocks (the step's closest-point unknowns) out of the Newton
// matrix (condensed_lu.h), and factorizes the whole matrix only when that fails.
// The workspace is sized once per layout; a dense Solve does not allocate.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/ncp/condensed_lu.h"
#include "implicit_sim/core/ncp/dense_lu.h"
#include "implicit_sim/core/ncp/ncp_problem.h"
#include "implicit_sim/core/ncp/ncp_summary.h"
#include "implicit_sim/core/ncp/sparse_lu.h"

namespace implicit_sim {

// A per-iteration trace of Newton solves (NewtonOptions::trace): one row per iteration, for diagnosis only (it
// allocates as it grows, and one trace serves one thread).
struct NewtonTraceRow {
  int solve = 0;             // which solve of the trace (0, 1, ...)
  int iteration = 0;         // within that solve
  double smoothing = 0.0;    // the smoothing mu of its rows (0: the exact problem)
  double residual = 0.0;     // |Phi_mu|_2 at the iterate, before the step
  double step = 0.0;         // the line search's step length (0: no step was accepted)
  bool least_squares = false;  // the step followed the Levenberg-Marquardt direction
  double largest_row = 0.0;    // max_i |Phi_mu,i| at the iterate
  int largest_row_index = -1;  // its row i
  std::string largest_row_name;  // what row i is (StepLayout::RowName), where the caller names rows
  double largest_move = 0.0;     // max_j |dz_j| of the direction taken (the LU's, or the LM one after it)
  int largest_move_index = -1;   // its unknown j
  std::string largest_move_name;  // what unknown j is (the row of the same index), where the caller names rows
  int rows_above_floor = 0;    // how many rows have |Phi_mu,i| > 1e-13 (a round-off floor shows as many small rows)
};
struct NewtonTrace {
  std::vector<NewtonTraceRow> rows;
  int solves = 0;
};

struct NewtonOptions {
  double tolerance = 1e-12;       // converged when |Phi|_2 <= tolerance (1 + |z|_inf) (rows are scaled to O(1))
  int max_iterations = 100;
  double lm_damping = 1e-12;      // LM damping = lm_damping * max(1, 0.5 |Phi|^2)
  double armijo = 1e-4;           // sufficient decrease factor
  double min_step = 1e-10;        // smallest line-search step length
  double sparse_regularization = 1e-9;  // delta (see above)
  // delta grows with the residual: delta_k = sparse_regularization + residual_regularization |Phi(z_k)|_2, so it
  // vanishes at the solution (a regularized semismooth Newton; 0: a constant delta).
  double residual_regularization = 0.0;
  // The line search accepts a step that decreases the largest of the last this many merits (1: monotone), [1, 16].
  int line_search_memory = 10;
  // A solve stops as stalled (NcpTermination::kStalled) when the best residual of its last stall_window iterations
  // is above 0.9 times the best one before them: a line search that keeps accepting short steps along a direction
  // that does not lead to the solution (0: never, the default; doc/method.md, "Stopping stalled solves").
  int stall_window = 0;
  // NcpEvalMode::project_multipliers for this solve (the retry ladder's rung 1b sets it).
  bool project_multipliers = false;
  // NcpEvalMode::proximal_weight and proximal_center for this solve (the retry ladder's proximal rung; 0: off).
  double proximal_weight = 0.0;
  const Eigen::VectorXd* proximal_center = nullptr;
  // Sparse solves condense the problem's local blocks (NcpProblem::CondensableBlocks) out of the Newton matrix by a
  // Schur complement before KLU (condensed_lu.h); the whole matrix is factorized when a block is singular.
  bool condense_blocks = true;
  // Sparse solves of the exact problem move each line-search trial point back onto the problem's curved solution set
  // (NcpProblem::Retract: the step's sliding friction fractions onto their unit sphere).
  bool retract_sliding = true;
  // When set, every iteration appends a row (not an option of the table: the replay tool's --trace).
  NewtonTrace* trace = nullptr;
  // When set and due, a solve stops before its next iteration (NcpTermination::kInterrupted); not an option of the
  // table: the stepper sets it from Data::interrupt.
  const StepInterrupt* interrupt = nullptr;
  // The allowed ranges are those of the step's options table (step/options.h), which validates these fields.
};

// The smoothing path (SemismoothNewton::FollowSmoothingPath): Newton on the Fischer-Burmeister functions smoothed by
// mu, leaving each level as soon as the iterate is in its neighbourhood max_i |Phi_mu,i| <= neighbourhood * mu, with
// the next mu driven by the residual (Qi, Sun and Zhou 2000), then Newton on the exact problem.
struct PathOptions {
  double initial_smoothing = 1.0;   // mu_0 = min(this, max_i |Phi_0,i(z_0)|)
  double final_smoothing = 1e-9;    // the path ends below this mu, or where max_i |Phi_0,i| <= switch_residual
  double switch_residual = 1e-6;
  double neighbourhood = 1.0;       // beta
  double max_reduction = 0.1;       // the next level's mu is at least this share of the last one
  // Newton steps at one mu before it is doubled (once per level); as many again at the doubled mu, and the path ends
  // there (polished from where it got).
  int steps_per_level = 3;
  int max_iterations = 40;          // Newton steps on the path
  int polish_iterations = 6;        // Newton steps on the exact problem after it
};

class SemismoothNewton {
 public:
  SemismoothNewton(int n, bool sparse);
  bool sparse() const { return sparse_; }
  // Solves Phi(z) = 0 from *z (the initial guess) in place, with every Fischer-Burmeister function smoothed by
  // `smoothing` (0: the exact problem). A non-finite residual is never accepted. The workspace follows
  // problem.size() (it is resized, which allocates, only when that changes).
  NcpSummary Solve(const NcpProblem& problem, const NewtonOptions& options, Eigen::VectorXd* z,
                   double smoothing = 0.0);
  // Follows the smoothing path from *z (PathOptions), then polishes on the exact problem; the summary counts both
  // (path_iterations, switch_smoothing and switch_residual describe the path).
  NcpSummary FollowSmoothingPath(const NcpProblem& problem, const NewtonOptions& options, const PathOptions& path,
                                 Eigen::VectorXd* z);
  int lm_fallbacks() const { return lm_fallbacks_; }  // over all solves (NcpSummary::lm_fallbacks: one solve)

 private:
  void Resize(int n);
  // Sets the evaluation mode, the workspace and the factorizations' state for a solve into *summary.
  void BeginSolve(const NcpProblem& problem, const NewtonOptions& options, double smoothing, NcpSummary* summary);
  // One Newton step from *z (Phi_ and the Jacobian evaluated there): the direction, the line search, z moved. False
  // if no step decreased the merit. Traces it with `iteration`.
  bool Step(const NcpProblem& problem, const NewtonOptions& options, double merit, int iteration, Eigen::VectorXd* z);
  void Evaluate(const NcpProblem& problem, const Eigen::VectorXd& z, bool jacobian);
  void RememberMerit(double merit);  // into the line search's memory
  // Whether the residuals of iterations 0..iteration (residuals_) show a stall (NewtonOptions::stall_window).
  bool Stalled(const NewtonOptions& options, int iteration) const;
  // dz_ from Phi_ and the Jacobian: the LU Newton direction, or with least_squares the Levenberg-Marquardt one.
  bool Direction(const NewtonOptions& options, double merit, bool least_squares);
  // dz_ by the condensed LU (factorized), if accurate (see the definition); false: use the whole matrix's LU.
  bool CondensedDirection(const Eigen::SparseMatrix<double>& J);
  // The Armijo step length along dz_ from z (0 if none down to min_step); the new point is left in z_trial_.
  double LineSearch(const NcpProblem& problem, const NewtonOptions& options, const Eigen::VectorXd& z, double merit);
  bool sparse_;
  NcpEvalMode mode_;        // of the current solve
  NcpSummary* summary_ = nullptr;  // of the current solve: evaluation counts
  Eigen::MatrixXd J_, normal_;
  Eigen::VectorXd Phi_, Phi_trial_, z_trial_, rhs_, dz_;
  std::vector<double> residuals_;  // of the current solve, by iteration (the stall test)
  DenseLu lu_dense_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_singular_;  // where lu_dense_ finds J singular (see Direction)
  // A singular dense J's basic direction (free unknowns unmoved): full_lu_ on small islands, column_qr_ on large ones.
  CompletePivotLu full_lu_;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> column_qr_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  SparseJacobian J_sparse_;
  SparseLu lu_;
  CondensedLu condensed_lu_;
  bool condense_ = false;  // this solve condenses blocks
  std::vector<int> block_starts_, block_indices_;
  Eigen::SparseMatrix<double> normal_sparse_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> sparse_ldlt_;
  int lm_fallbacks_ = 0;
  static constexpr int kMaxMemory = 16;
  std::array<double, kMaxMemory> history_{};  // the merits of the last iterates (a ring)
  int history_next_ = 0, history_count_ = 0;
};

}  // namespace implicit_sim
