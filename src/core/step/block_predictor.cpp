#include "implicit_sim/core/step/block_predictor.h"

#include <algorithm>

namespace implicit_sim {
namespace {

// One pair block of a step problem as an NCP of its own: z_block scattered into the full z, the full problem
// evaluated (its sparse Jacobian), the block's rows and columns gathered. local[i] is the block row of full row i
// (-1 outside the block).
class BlockView final : public NcpProblem {
 public:
  BlockView(const StepProblem& problem, const std::vector<int>& index, const std::vector<int>& local,
            Eigen::VectorXd* z_full, SparseJacobian* J_full)
      : problem_(problem), index_(index), local_(local), z_full_(*z_full), J_full_(*J_full) {}
  int size() const override { return static_cast<int>(index_.size()); }
  bool IsComplementarityRow(int row, double* scale) const override {
    return problem_.IsComplementarityRow(index_[row], scale);
  }
  int pattern_version() const override { return 0; }
  void Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                Eigen::MatrixXd* J) const override {
    ++evaluations_;
    for (int i = 0; i < size(); ++i) z_full_[index_[i]] = z[i];
    if (J) {
      problem_.EvaluateSparse(z_full_, mode, &Phi_full_, &J_full_);
    } else {
      problem_.Evaluate(z_full_, mode, &Phi_full_, nullptr);
    }
    Phi->resize(size());
    for (int i = 0; i < size(); ++i) (*Phi)[i] = Phi_full_[index_[i]];
    if (!J) return;
    J->setZero(size(), size());
    const Eigen::SparseMatrix<double>& full = J_full_.matrix;
    for (int c = 0; c < size(); ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(full, index_[c]); it; ++it) {
        if (local_[it.row()] >= 0) (*J)(local_[it.row()], c) = it.value();
      }
    }
  }
  void EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                      SparseJacobian* J) const override {  // every entry of the dense block, zeros included
    Eigen::MatrixXd dense;
    Evaluate(z, mode, Phi, &dense);
    J->Begin(pattern_version());
    for (int c = 0; c < size(); ++c) {
      for (int r = 0; r < size(); ++r) J->Add(r, c, dense(r, c));
    }
    J->Finish(size());
  }
  int evaluations() const { return evaluations_; }

 private:
  const StepProblem& problem_;
  const std::vector<int>& index_;
  const std::vector<int>& local_;
  Eigen::VectorXd& z_full_;  // the caller's z: the block's entries are written back when the view is done
  SparseJacobian& J_full_;
  mutable Eigen::VectorXd Phi_full_;
  mutable int evaluations_ = 0;
};

}  // namespace

BlockPredictor::BlockPredictor() : solver_(0, /*sparse=*/false) {}

void BlockPredictor::CollectBlock(const StepProblem& problem, const PairBlock& block) {
  index_.clear();
  for (int body : {block.body1, block.body2}) {
    const int column = problem.layout().column(body);
    for (int k = 0; column >= 0 && k < 6; ++k) index_.push_back(column + k);
  }
  for (int k = 0; k < block.size(); ++k) index_.push_back(block.offset + k);
  std::sort(index_.begin(), index_.end());
  index_.erase(std::unique(index_.begin(), index_.end()), index_.end());
}

int BlockPredictor::Run(const StepProblem& problem, const NewtonOptions& options, int sweeps, double fraction,
                        Eigen::VectorXd* z) {
  int evaluations = 1;
  problem.Evaluate(*z, NcpEvalMode(), &Phi_, nullptr);
  const std::vector<PairBlock>& blocks = problem.layout().blocks();
  const double start_residual = Phi_.norm();
  z_saved_ = *z;
  double largest = 0.0;
  for (const PairBlock& b : blocks) largest = std::max(largest, Phi_.segment(b.offset, b.size()).norm());
  selected_.clear();
  local_.assign(problem.size(), -1);
  for (size_t c = 0; c < blocks.size(); ++c) {
    if (Phi_.segment(blocks[c].offset, blocks[c].size()).norm() >= fraction * largest) {
      selected_.push_back(static_cast<int>(c));
    }
  }
  NewtonOptions block_options = options;
  block_options.max_iterations = std::min(options.max_iterations, 20);
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    for (int c : selected_) {
      CollectBlock(problem, blocks[c]);
      z_block_.resize(static_cast<int>(index_.size()));
      for (size_t i = 0; i < index_.size(); ++i) {
        z_block_[i] = (*z)[index_[i]];
        local_[index_[i]] = static_cast<int>(i);
      }
      const BlockView view(problem, index_, local_, z, &J_full_);
      z_block_start_ = z_block_;
      solver_.Solve(view, block_options, &z_block_);
      evaluations += view.evaluations();
      const bool finite = z_block_.allFinite();  // a non-finite block solve keeps its start
      for (size_t i = 0; i < index_.size(); ++i) {
        (*z)[index_[i]] = finite ? z_block_[i] : z_block_start_[i];
        local_[index_[i]] = -1;
      }
    }
  }
  // Blocks share bodies, so one block's solve can undo another's: the sweeps are kept only if they lowered the
  // residual of the whole problem.
  problem.Evaluate(*z, NcpEvalMode(), &Phi_, nullptr);
  ++evaluations;
  if (!(Phi_.norm() < start_residual)) z->swap(z_saved_);
  return evaluations;
}

}  // namespace implicit_sim
