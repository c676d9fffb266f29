#include "implicit_sim/core/ncp/ncp_problem.h"

#include <algorithm>

namespace implicit_sim {

void SparseJacobian::Begin(int pattern_version) {
  pending_version_ = pattern_version;
  recording_ = pattern_version_ != pattern_version;
  recorded_.clear();
  cursor_ = 0;
  if (!recording_) std::fill(matrix.valuePtr(), matrix.valuePtr() + matrix.nonZeros(), 0.0);
}

void SparseJacobian::Finish(int n) {
  if (!recording_) return;
  // First evaluation for this pattern: build it (duplicates summed) and each emitted entry's slot in it.
  matrix.resize(n, n);
  matrix.setFromTriplets(recorded_.begin(), recorded_.end());
  matrix.makeCompressed();
  slot_.resize(recorded_.size());
  for (size_t k = 0; k < recorded_.size(); ++k) {
    const int col = recorded_[k].col();
    const int* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[col];
    const int* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[col + 1];
    slot_[k] = static_cast<int>(std::lower_bound(begin, end, recorded_[k].row()) - matrix.innerIndexPtr());
  }
  pattern_version_ = pending_version_;
  recording_ = false;
}

}  // namespace implicit_sim
