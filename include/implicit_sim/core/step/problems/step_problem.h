// The base of the step's problems: one mixed nonlinear complementarity problem (ncp_problem.h) over a layout
// (layout.h) and a step's kinematics (kinematics.h), reformulated with the Fischer-Burmeister function. Each stage of
// a scheme is a problem of its own (paper_step.h, rattle_position.h, rattle_velocity.h), built once per island and
// never switched to another stage: a subclass only says which bodies' end-of-step state it reads (EndsOf) and which
// rows it emits (AddRows, from the emitters of rows/).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/ncp/ncp_problem.h"
#include "implicit_sim/core/step/contact_result.h"
#include "implicit_sim/core/step/kinematics.h"
#include "implicit_sim/core/step/layout.h"
#include "implicit_sim/core/step/rows/row_context.h"

namespace implicit_sim {

class StepProblem : public NcpProblem {
 public:
  // ends_ holds room for every body of the model, so that an island's first evaluation in a warm step (a fallback's
  // problem) does not allocate.
  StepProblem(const StepLayout& layout, const StepKinematics& kinematics) : layout_(layout), kinematics_(kinematics) {
    ends_.reserve(layout.model().bodies.size());
  }
  const StepLayout& layout() const { return layout_; }
  const StepKinematics& kinematics() const { return kinematics_; }
  // How the friction rows are written (the projected form by default).
  void set_friction_form(const FrictionForm& form) { friction_form_ = form; }

  int size() const override { return layout_.size(); }
  // The friction form's rows have patterns of their own (rows/friction_rows.h).
  int pattern_version() const override { return 2 * layout_.pattern_version() + (friction_form_.projected ? 1 : 0); }
  // Raw rows: each complementarity row returns b(z), the function side of its pair (-f_i(a1), -g_j(a2), d, zeta);
  // the variable side a is the unknown with the row's own index (scaled by 1/Fs for forces).
  bool IsComplementarityRow(int row, double* scale) const override;
  // The FB-reformulated residual Phi(z) (or the raw rows) and, if J is not null, its exact generalized Jacobian,
  // dense or sparse. NcpEvalMode::regularization goes on the Jacobian's diagonal entries of the friction rows and
  // (divided by Fs) of the force rows: a proximal term for the Newton direction (semismooth_newton.h).
  void Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                Eigen::MatrixXd* J) const override;
  void EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                      SparseJacobian* J) const override;
  // A sliding pair's friction fractions lie on the unit sphere at every solution (|s| = 1 where sigma > 0,
  // rows/friction_rows.h). A pair on it at z (to 1e-9) and near it at the trial point (to 1e-3) is scaled back onto
  // it: a Newton step along the sphere leaves it by |ds|^2 / 2, which can exceed the residual where the pair's force
  // is nearly redundant (a part wedged in a corner; bench/README.md, "S1 without torsional friction").
  void Retract(const Eigen::VectorXd& z, Eigen::VectorXd* trial) const override;
  // One block per pair: its closest-point unknowns, whose rows touch only themselves and the pair's velocities.
  void CondensableBlocks(std::vector<int>* starts, std::vector<int>* indices) const override {
    layout_.CondensableBlocks(starts, indices);
  }

  // The velocity part of a cold start: the state's velocities (RattlePositionProblem adds its free-flight half step).
  virtual void SeedVelocities(const State& state, Eigen::VectorXd* z) const;
  // A second formulation worth a second warm attempt when the first failed (the retry ladder's rung 1a): switches to
  // it and returns how many pairs it changed (0: none, the default).
  virtual int UseFallbackFrames() { return 0; }
  // Whether the problem has such a fallback formulation it has not switched to yet.
  virtual bool HasFallbackFrames() const { return false; }
  // Back to the first formulation after UseFallbackFrames; returns how many pairs it changed.
  virtual int RestoreFrames() { return 0; }
  // The contact quantities of every pair for a solution z (one entry per block, in block order).
  void Contacts(const Eigen::VectorXd& z, std::vector<ContactResult>* out) const;

 protected:
  // Per row: how its unknown enters a complementarity condition.
  virtual const std::vector<RowKind>& row_kinds() const { return layout_.row_kinds(); }
  // Every body of the layout at the end of the step for the iterate z (by default paper eq. 2).
  virtual void EndsOf(const Eigen::VectorXd& z, std::vector<BodyEnd>* ends) const { kinematics_.EndOfStep(z, ends); }
  // Every row of the problem into ctx.out (Phi is zero on entry; the locked rows are done after).
  virtual void AddRows(const RowContext& ctx) const = 0;

 private:
  void EvaluateInto(const Eigen::VectorXd& z, const RowWriter& out) const;
  const StepLayout& layout_;
  const StepKinematics& kinematics_;
  FrictionForm friction_form_;
  mutable std::vector<BodyEnd> ends_;  // the current iterate's bodies at the end of the step (a cache)
};

}  // namespace implicit_sim
