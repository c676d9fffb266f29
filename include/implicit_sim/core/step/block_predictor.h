// A nonlinear block Gauss-Seidel predictor for a step NCP whose start is far from its solution (a layer of a pile
// landing: a few new contacts carry most of the residual). Each selected pair block is solved on its own by the
// dense semismooth Newton: its unknowns and the velocities of its moving bodies, every other unknown of z frozen, in
// block order, for a number of sweeps. The result is a start for the Newton solve of the whole problem, never a
// solution: the retry ladder (retry_ladder.h) decides what happens next.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/ncp/semismooth_newton.h"
#include "implicit_sim/core/step/problems/step_problem.h"

namespace implicit_sim {

class BlockPredictor {
 public:
  BlockPredictor();
  // Sweeps over the pair blocks whose residual |Phi_block| is at least `fraction` of the largest block's at *z
  // (chosen once, before the first sweep) and updates *z in place if the sweeps lowered the residual of the whole
  // problem (otherwise *z is left as it was). Returns the residual evaluations of the full
  // problem it made (each block evaluation is one).
  int Run(const StepProblem& problem, const NewtonOptions& options, int sweeps, double fraction, Eigen::VectorXd* z);

 private:
  // The block's unknowns (indices into z), ascending; its rows are the same indices.
  void CollectBlock(const StepProblem& problem, const PairBlock& block);
  std::vector<int> index_;          // of the current block
  std::vector<int> selected_;       // the selected blocks (indices into problem.blocks())
  std::vector<int> local_;          // per unknown of the problem: its index in the current block, or -1
  Eigen::VectorXd Phi_, z_block_, z_block_start_, z_saved_;
  SparseJacobian J_full_;
  SemismoothNewton solver_;
};

}  // namespace implicit_sim
