// Stage 1 of the RATTLE step (StepperOptions::Scheme::kRattle; doc/method.md, "The second-order step"): the unknowns
// of the paper's step, with rows at half impulses, m (v_half - v0) / h = f / 2 + ..., the Lie-group variational
// rotation row (rows/body_rows.h), half the joints' constant effort, friction bound, damping and drive effort, and
// the contact impulse along the START-of-step frame of each pair closed at the start (the slip on the average of the
// start and end frames; rows/contact_rows.h). The closest points and the gap stay at the END of the step.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/problems/step_problem.h"

namespace implicit_sim {

// The feature of a body's shape at a contact point.
struct ContactFeature {
  int dimension = 0;    // of the set of surface points sharing the normal there, up to flat curvature: 0 at a
                        // strictly curved patch or a vertex; 1 on an edge or a cylinder's side; 2 on a (nearly) flat face
  double radius = 0.0;  // m: the largest radius of curvature of its curved surface (0 for planes alone), at most
                        // 10 bounding radii (flatter counts as flat)
};

class RattlePositionProblem final : public StepProblem {
 public:
  RattlePositionProblem(const StepLayout& layout, const StepKinematics& kinematics,
                        const std::vector<JointDrive>& drives, bool regular_separated_friction)
      : StepProblem(layout, kinematics), drives_(drives), regular_separated_friction_(regular_separated_friction) {}

  // The start-of-step frames from z_start, a solution at the start of the step (the previous step's stage 1): per
  // block whose entry of `known` is nonzero, that is closed in z_start (touching or pushing) and whose closest points
  // are fixed by the geometry (not a face or edge against a face, where they may lie anywhere on a patch), its normal
  // and closest points. Any other block (a new pair, an impact, a box flat on the ground) uses the end-of-step frame
  // like the paper's step. Call after the kinematics' BeginStep.
  void SetStartFrames(const Eigen::VectorXd& z_start, const std::vector<char>& known);
  bool uses_start_frame(int block) const { return use_start_frame_[block] != 0; }
  const Eigen::VectorXd& start_frames() const { return frame_z_; }
  // After a solution z: the pairs with a start frame whose active inequalities (alpha, beta > 0) differ from the
  // start's (a vertex or face switch of a polytope), or whose contact point moved on a body by more than its drift
  // limit (LeverStayed), fall back to the end-of-step frame; returns how many.
  int FallBackWhereFramesMoved(const Eigen::VectorXd& z);
  // The frames as they were before the last FallBackWhereFramesMoved (the ones its solution was found on).
  void UndoFramesMovedFallback() { use_start_frame_ = frames_before_fallback_; }
  // Every pair on the end-of-step frame (rung 1a); returns how many had a start frame.
  int UseFallbackFrames() override;
  bool HasFallbackFrames() const override;
  int RestoreFrames() override;
  // The state's velocities; without pairs or joints (a body in free flight) v_half = v0 + h f / (2 m), the solution of
  // its linear rows, so that a falling body's stage 1 needs no Newton iteration for them.
  void SeedVelocities(const State& state, Eigen::VectorXd* z) const override;

 private:
  void AddRows(const RowContext& ctx) const override;
  // The start-of-step closest point frame_z_[point..+3) in the frame of body `local` (into layout().bodies()) (m).
  Vec3 StartPointInBody(int local, int point) const;
  // The feature of `shape` on body `local` (into layout().bodies()) at its start-of-step closest point
  // frame_z_[point..+3), with the multipliers from frame_z_[multipliers].
  ContactFeature StartFeature(const ConvexShape& shape, int local, int point, int multipliers) const;
  // How far (m) a contact point may move on `shape` within the step, in its body's frame, and keep the start frame:
  // kLeverDriftShare of the larger of its bounding radius and the feature's radius of curvature (the contact rolling
  // through kLeverDriftShare rad); infinite for a half-space.
  double DriftLimit(const ConvexShape& shape, const ContactFeature& feature) const;
  // Whether block c's contact point stayed within its drift limit on both bodies between frame_z_ and z.
  bool LeverStayed(const Eigen::VectorXd& z, int block) const;
  const std::vector<JointDrive>& drives_;
  const bool regular_separated_friction_;
  std::vector<char> use_start_frame_;  // per block: stage 1 acts along the start frame
  std::vector<char> chosen_start_frame_;  // per block: use_start_frame_ as SetStartFrames chose it
  std::vector<char> frames_before_fallback_;  // per block: use_start_frame_ before FallBackWhereFramesMoved
  std::vector<std::array<double, 2>> drift_limit_;  // per block with a start frame, per body: DriftLimit (m)
  Eigen::VectorXd frame_z_;            // the start-of-step solution the start frames come from
};

// A pair's contact point may move on a body within the step (in the body's frame) by this share of the larger of the
// body's bounding radius and its radius of curvature there and keep its start frame: the rolling of a round part
// through 0.1 rad a step. A point that moves farther (a jump to another root or feature) makes the start lever stale.
constexpr double kLeverDriftShare = 0.1;
// A pair counts as closed (for the start frames and for stage 2) within this gap (m) or with a force.
constexpr double kClosedGap = 1e-9;
inline bool IsClosed(double gap, double normal_force, double force_scale) {
  return gap <= kClosedGap || normal_force > 1e-12 * force_scale;
}

}  // namespace implicit_sim
