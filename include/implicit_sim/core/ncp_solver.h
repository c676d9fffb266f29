// Semismooth Newton method on the Fischer-Burmeister reformulation Phi(z) = 0 of the step's mixed NCP
// (DESIGN.md section 2, pitfall 8): exact generalized Jacobian, a Levenberg-Marquardt step with tiny damping scaled by
// the merit (it survives the singular Jacobians of separated contacts and flat faces), Armijo backtracking on
// 0.5 |Phi|^2. The workspace is sized once; Solve does not allocate.
#pragma once

#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "implicit_sim/core/step_problem.h"

namespace implicit_sim {

struct NewtonOptions {
  double tolerance = 1e-12;       // converged when |Phi|_2 <= tolerance (1 + |z|_inf) (rows are scaled to O(1))
  int max_iterations = 100;
  double lm_damping = 1e-12;      // LM damping = lm_damping * max(1, 0.5 |Phi|^2)
  double armijo = 1e-4;           // sufficient decrease factor
  double min_step = 1e-10;        // smallest line-search step length
  bool IsValid(std::string* error) const;
};

struct NewtonResult {
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;          // |Phi|_2 at the returned z
};

class SemismoothNewton {
 public:
  explicit SemismoothNewton(int n);
  // Solves from *z (the initial guess) in place. A non-finite residual is never accepted.
  NewtonResult Solve(StepProblem* problem, const NewtonOptions& options, Eigen::VectorXd* z);

 private:
  Eigen::MatrixXd J_, normal_;
  Eigen::VectorXd Phi_, Phi_trial_, z_trial_, rhs_, dz_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
};

}  // namespace implicit_sim
