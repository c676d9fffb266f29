#include "implicit_sim/core/step/time_stepper.h"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <cmath>
#include <stdexcept>

#include "implicit_sim/core/ncp/ipopt_ncp.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/step/step_health.h"
#include "implicit_sim/core/geometry/support.h"

namespace implicit_sim {
namespace pi = pair_index;

const char* StepFaultName(StepFault fault) {
  switch (fault) {
    case StepFault::kNone: return "none";
    case StepFault::kNotConverged: return "not_converged";
    case StepFault::kNoFiniteSolution: return "no_finite_solution";
    case StepFault::kInitialOverlap: return "initial_overlap";
    case StepFault::kDiverged: return "diverged";
  }
  return "unknown";
}

namespace {

void WriteState(const Model& model, const StepProblem& problem, const Eigen::VectorXd& z, double h, State* state) {
  for (int k = 0; k < model.num_moving(); ++k) {
    const Pose X = problem.EndPose(model.moving_bodies[k], z);
    Eigen::Quaterniond quat(X.linear());
    const Eigen::Vector4d old = state->q.segment<4>(7 * k + 3);
    if (quat.w() * old[0] + quat.x() * old[1] + quat.y() * old[2] + quat.z() * old[3] < 0.0) quat.coeffs() *= -1.0;
    state->q.segment<3>(7 * k) = X.translation();
    state->q.segment<4>(7 * k + 3) << quat.w(), quat.x(), quat.y(), quat.z();
    state->v.segment<6>(6 * k) = z.segment<6>(6 * k);
  }
  state->t += h;
}

// Fills the contact block of pair c in z from closest points at the configuration `state` (closed form, or the
// distance oracle) for a cold start, with multipliers consistent with the normal and a normal force guess.
// Closest points without the oracle, for a pair entering the NCP through the broad phase (apart by about the
// margin): the closed form where there is one, otherwise the support points of both bodies along the line of their
// shape origins (exact for spheres, a fair guess for convex bodies near each other).
ClosestPointsResult QuickClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                       const Pose& X_WB2) {
  ClosestPointsResult cp;
  if (ClosedFormClosestPoints(shape1, X_WB1, shape2, X_WB2, &cp)) return cp;
  const Vec3 u = ((X_WB1 * shape1.X_BS).translation() - (X_WB2 * shape2.X_BS).translation()).normalized();
  cp.solved = u.allFinite() && SupportPoint(shape1, X_WB1, -u, &cp.p_W1) && SupportPoint(shape2, X_WB2, u, &cp.p_W2);
  if (cp.solved) cp.distance = std::max(0.0, u.dot(cp.p_W1 - cp.p_W2));
  return cp;
}

void SeedPair(const Model& model, const State& state, int c, const StepProblem& problem, Eigen::VectorXd* z,
              bool use_oracle = true) {
  const PairBlock& blk = problem.blocks()[c];
  const ContactPair& pair = model.pairs[blk.pair];
  const Body& body1 = model.bodies[pair.body1];
  const Body& body2 = model.bodies[pair.body2];
  const Pose X_WB1 = state.X_WB(model, pair.body1), X_WB2 = state.X_WB(model, pair.body2);
  const ClosestPointsResult cp = use_oracle ? FindClosestPoints(body1.shape, X_WB1, body2.shape, X_WB2)
                                            : QuickClosestPoints(body1.shape, X_WB1, body2.shape, X_WB2);
  Vec3 p1 = cp.p_W1, p2 = cp.p_W2;
  if (!cp.solved || !p1.allFinite() || !p2.allFinite()) {  // fall back to the body origins
    p1 = X_WB1.translation();
    p2 = X_WB2.translation();
  }
  Vec3 n;
  double grad2 = 1.0;
  MostActiveInequality(body2.shape, X_WB2, p2, &n, &grad2);
  if (cp.distance > 1e-9) n = (p1 - p2).normalized();  // separated: along the closest points
  z->segment(blk.offset, blk.size()).setZero();
  z->segment<3>(blk.offset + pi::kA1) = p1;
  z->segment<3>(blk.offset + pi::kA2) = p2;
  z->segment<3>(blk.offset + pi::kN) = n;
  (*z)[blk.offset + pi::kD] = n.dot(p1 - p2);
  // -n = sum alpha grad f(a1), n = sum beta grad g(a2): every active inequality's multiplier (edges, corners, rims).
  SeedNormalConeMultipliers(body1.shape, X_WB1, p1, -n, z->data() + blk.offset + pi::kAlpha);
  SeedNormalConeMultipliers(body2.shape, X_WB2, p2, n, z->data() + blk.beta());
  (*z)[blk.ln()] = cp.distance < 1e-6 ? 0.5 * problem.force_scale() : 0.0;
}

// Lays the problem out for `pairs`, carrying z over; the blocks of new pairs are seeded from `state` like a cold start.
void SetPairs(const Model& model, const State& state, const std::vector<int>& pairs, Data* data) {
  StepProblem& problem = data->problem;
  data->LayOut(pairs, &data->z);
  data->z.swap(data->z_remap);
  for (int c : data->new_blocks) {
    SeedPair(model, state, c, problem, &data->z, /*use_oracle=*/false);
    problem.ResetTangentAxis(c, data->z);
    problem.SeedFriction(c, &data->z);
  }
}

// The pairs of the NCP for a step of length h from `state`: the broad phase over bounding spheres grown by the motion
// possible within the step plus a margin, joined with the pairs the end-of-step check forced in (Data::forced_pairs).
void SelectPairs(const Model& model, const StepperOptions& options, double h, const State& state, Data* data) {
  const double fall = 0.5 * model.gravity_W.norm() * h * h;
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) {
    data->X_WB[b] = state.X_WB(model, b);
    const int k = model.velocity_slot[b];
    const double lever = model.bodies[b].shape.X_BS.translation().norm();  // of the bounding sphere's centre (m)
    data->inflation[b] =
        k < 0 ? 0.0 : h * (state.v_WB(k).norm() + state.w_WB(k).norm() * lever) + fall + options.broad_phase_margin;
  }
  data->broad.FindPairs(data->X_WB, data->inflation, &data->candidates);
  data->merged.clear();
  std::set_union(data->candidates.begin(), data->candidates.end(), data->forced_pairs.begin(),
                 data->forced_pairs.end(), std::back_inserter(data->merged));
  data->problem.ActivePairs(&data->pairs);
  if (data->merged != data->pairs) SetPairs(model, state, data->merged, data);
}

// The end-of-step check of the pairs left out of the NCP: bounding spheres (no growth) at the end poses of z. Pairs
// that overlap are added to Data::forced_pairs; returns how many.
int CheckLeftOutPairs(const Model& model, Data* data) {
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) {
    data->X_WB[b] = data->problem.EndPose(b, data->z);
    data->inflation[b] = 0.0;
  }
  data->broad.FindPairs(data->X_WB, data->inflation, &data->candidates);
  data->problem.ActivePairs(&data->pairs);
  int missing = 0;
  for (int pair : data->candidates) {
    if (std::binary_search(data->pairs.begin(), data->pairs.end(), pair)) continue;
    data->forced_pairs.push_back(pair);
    ++missing;
  }
  std::sort(data->forced_pairs.begin(), data->forced_pairs.end());
  return missing;
}

// One solve of the step NCP of length h from `state`, climbing the ladder while it fails: warm start, cold start
// (closed-form or oracle closest points), smoothing continuation, Ipopt then a Newton polish. Leaves the best
// solution in data->z; does not touch the state. With the Ipopt solver: warm start, then cold start, both by Ipopt.
NewtonResult SolveStep(const Model& model, const StepperOptions& options, double h, const State& state,
                       const Eigen::VectorXd* wrench, Data* data, StepReport* report) {
  StepProblem& problem = data->problem;
  problem.BeginStep(model, state, h, wrench);
  if (data->broad_phase) SelectPairs(model, options, h, state, data);
  auto cold_guess = [&]() {
    data->z_start.head(6 * model.num_moving()) = state.v;
    problem.SeedJoints(&data->z_start);
    for (int c = 0; c < static_cast<int>(problem.blocks().size()); ++c) SeedPair(model, state, c, problem, &data->z_start);
    problem.ResetTangentAxes(data->z_start);
    problem.SeedFriction(&data->z_start);
  };
  auto solve_from_start = [&]() {
    data->z = data->z_start;
    if (options.solver == StepperOptions::Solver::kIpopt) {
      report->ipopt_solves++;
      const IpoptNcpResult r = SolveStepWithIpopt(&problem, options.ipopt_max_iterations, &data->z);
      report->iterations += r.iterations;
      NewtonResult result;
      result.iterations = r.iterations;
      result.residual = std::max(r.equation_residual, r.complementarity);
      result.converged = r.solved && result.residual <= StepperOptions::kIpoptTolerance;
      return result;
    }
    const NewtonResult result = data->solver.Solve(&problem, options.newton, &data->z);
    report->iterations += result.iterations;
    return result;
  };
  if (!data->has_warm_start) {
    cold_guess();
    return solve_from_start();
  }
  data->z_start = data->z;  // the previous step's solution; its velocities are the state's
  data->z_start.head(6 * model.num_moving()) = state.v;
  problem.UpdateTangentAxes(&data->z_start);
  problem.PredictClosestPoints(&data->z_start);
  const NewtonResult warm = solve_from_start();
  if (warm.converged) return warm;
  report->cold_restarts++;
  data->z_best = data->z;
  data->axes_warm_failed = problem.tangent_axes();
  cold_guess();
  const NewtonResult cold = solve_from_start();
  if (cold.converged || options.solver == StepperOptions::Solver::kIpopt) return cold;
  // Keep the better attempt in z_best (and its tangent axes); the next rungs start from it.
  NewtonResult best = cold;
  if (!(cold.residual < warm.residual) && std::isfinite(warm.residual)) {
    best = warm;
    problem.set_tangent_axes(data->axes_warm_failed);
  } else {
    data->z_best = data->z;
  }
  data->z_start = data->z_best;
  auto keep_if_better = [&](const NewtonResult& r) {
    if (r.residual < best.residual || !std::isfinite(best.residual)) {
      best = r;
      data->z_best = data->z;
    }
  };
  // Smoothing continuation: solve with FB smoothed by mu = 1e-2, 1e-3, ... and then exactly, each from the last.
  report->smoothed_solves++;
  NewtonResult result;
  for (double mu = 1e-2; mu > 1e-9 && data->z.allFinite(); mu *= 0.1) {
    problem.set_smoothing(mu);
    result = data->solver.Solve(&problem, options.newton, &data->z);
    report->iterations += result.iterations;
  }
  problem.set_smoothing(0.0);
  if (data->z.allFinite()) {
    result = data->solver.Solve(&problem, options.newton, &data->z);
    report->iterations += result.iterations;
    if (result.converged) return result;
    keep_if_better(result);
  }
  // The other solver: Ipopt on the complementarity-penalty NLP from the same start, polished by Newton.
  report->ipopt_solves++;
  data->z = data->z_start;
  const IpoptNcpResult ipopt = SolveStepWithIpopt(&problem, options.ipopt_max_iterations, &data->z);
  report->iterations += ipopt.iterations;
  if (data->z.allFinite()) {
    result = data->solver.Solve(&problem, options.newton, &data->z);
    report->iterations += result.iterations;
    if (result.converged) return result;
    keep_if_better(result);
  }
  data->z = data->z_best;
  return best;
}

// Advances the state by h; when the solve fails, by two halves instead, down to h / 2^kMaxSubstepDepth, where the
// best finite iterate is accepted and reported as not converged. Returns false if the state could not be advanced.
bool Advance(const Model& model, const StepperOptions& options, double h, int depth, const Eigen::VectorXd* wrench,
             State* state, Data* data, StepReport* report) {
  Eigen::VectorXd& backup = data->z_backup[depth];
  backup = data->z;
  if (data->broad_phase) data->problem.ActivePairs(&data->pairs_backup[depth]);
  const bool had_warm_start = data->has_warm_start;
  data->forced_pairs.clear();
  NewtonResult result;
  for (int round = 1;; ++round) {
    result = SolveStep(model, options, h, *state, wrench, data, report);
    if (!data->broad_phase || !data->z.allFinite()) break;
    // No pair may interpenetrate at the step end, in or out of the NCP: re-solve with the ones found overlapping.
    const int missing = CheckLeftOutPairs(model, data);
    if (missing == 0) break;
    report->broad_phase_additions += missing;
    if (round == Data::kMaxBroadPhaseRounds) {
      result.converged = false;
      break;
    }
  }
  report->pairs_in_ncp = static_cast<int>(data->problem.blocks().size());
  if (!result.converged && depth < Data::kMaxSubstepDepth) {
    if (data->broad_phase) data->LayOut(data->pairs_backup[depth], nullptr);  // backup is laid out for these
    data->z = backup;
    data->has_warm_start = had_warm_start;
    report->substeps += 1;
    return Advance(model, options, h / 2, depth + 1, wrench, state, data, report) &&
           Advance(model, options, h / 2, depth + 1, wrench, state, data, report);
  }
  if (!std::isfinite(result.residual) || !data->z.allFinite()) {
    data->has_warm_start = false;  // the state is left as it was; the next step starts cold
    report->converged = false;
    return false;
  }
  StepProblem& problem = data->problem;
  report->converged = report->converged && result.converged;
  report->residual = std::max(report->residual, result.residual);
  report->complementarity_error = std::max(report->complementarity_error, problem.ComplementarityError(data->z));
  problem.Contacts(data->z, &data->contacts);
  WriteState(model, problem, data->z, h, state);
  data->has_warm_start = true;
  return true;
}

}  // namespace

StepReport Step(const Model& model, const StepperOptions& options, State* state, Data* data,
                const Eigen::VectorXd* external_wrench_W) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument(error);
  if (!data->BelongsTo(model)) {
    throw std::invalid_argument("Data was built from another Model: build it as Data(model) from the Model given to Step");
  }
  if (state->q.size() != 7 * model.num_moving() || state->v.size() != 6 * model.num_moving()) {
    throw std::invalid_argument("state size does not match the model: expected q of " +
                                std::to_string(7 * model.num_moving()) + " and v of " +
                                std::to_string(6 * model.num_moving()) + " values");
  }
  if (external_wrench_W && (external_wrench_W->size() != 6 * model.num_moving() || !external_wrench_W->allFinite())) {
    throw std::invalid_argument("external wrench vector must hold " + std::to_string(6 * model.num_moving()) +
                                " finite values (force, torque per moving body)");
  }
  const auto wall_start = std::chrono::steady_clock::now();
  StepReport report;
  report.converged = true;
  if (!data->has_warm_start && FindInitialOverlap(model, *state, options.overlap_tolerance, &data->broad,
                                                  &data->X_WB, &data->inflation, &data->candidates,
                                                  &report.fault_detail)) {
    report.converged = false;
    report.fault = StepFault::kInitialOverlap;
    return report;
  }
  data->state_backup = *state;
  const double t_end = state->t + options.h;
  report.advanced = Advance(model, options, options.h, 0, external_wrench_W, state, data, &report);
  if (report.advanced && FindDivergence(model, *state, options.max_speed, options.max_angular_speed,
                                        &report.fault_detail)) {
    report.advanced = report.converged = false;
    report.fault = StepFault::kDiverged;
  }
  if (!report.advanced) {
    *state = data->state_backup;  // also undoes a first half-step whose second half failed
    data->has_warm_start = false;
    if (report.fault == StepFault::kNone) report.fault = StepFault::kNoFiniteSolution;
  } else {
    state->t = t_end;  // exactly t + h, whatever the sub-steps summed to
    if (!report.converged) report.fault = StepFault::kNotConverged;
  }
  for (const ContactResult& contact : data->contacts) {
    if (contact.normal_force > options.contact_threshold) ++report.active_contacts;
  }
  JointDrift(model, *state, &report.joint_position_error, &report.joint_angle_error);
  report.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return report;
}

}  // namespace implicit_sim
