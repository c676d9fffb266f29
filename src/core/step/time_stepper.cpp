// The step as a pipeline (paper Sections III-IV):
//   1. check the inputs, and on a cold step that no two bodies overlap (step_health.h);
//   2. start-of-step kinematics: poses, velocities and world inertia at t (StepKinematics::BeginStep);
//   3. candidate pairs: all of them, or the broad phase over bounding spheres grown by the motion within the step;
//   4. islands: the moving bodies joined by those pairs or by joints (islands.h), each stepped on a thread pool by its
//      scheme (schemes/island_scheme.h: the paper's step, one NCP of paper eq. 10-11 with the kinematic map eq. 2 and
//      the closest-point conditions eq. 19-22; or RATTLE's two stages, one NCP each), every NCP through a retry ladder
//      (retry_ladder.h); a failed island solve splits the island's step into halves, down to
//      h / 2^Data::kMaxSubstepDepth;
//   5. with the broad phase, pairs found overlapping at the step end are added and the step solved again;
//   6. the end-of-step state (paper eq. 2), contact results, health check of the velocities (step_health.h).
#include "implicit_sim/core/step/time_stepper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "implicit_sim/core/geometry/support.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/ncp/ncp_error.h"
#include "implicit_sim/core/step/islands.h"
#include "implicit_sim/core/step/retry_ladder.h"
#include "implicit_sim/core/step/seeding.h"
#include "implicit_sim/core/step/schemes/island_scheme.h"
#include "implicit_sim/core/step/step_health.h"

namespace implicit_sim {
namespace {

// The state of the island's bodies at the end of the step: the poses of paper eq. 2 from the velocities of z_pose,
// the velocities of z_velocity (the same solution in the paper's step; stage 1 and stage 2 in the RATTLE step).
// Quaternion signs follow the previous ones, so q is continuous in time. (state->t is Step's.)
void WriteState(const Model& model, const StepKinematics& kinematics, const Eigen::VectorXd& z_pose,
                const Eigen::VectorXd& z_velocity, State* state) {
  const std::vector<int>& slots = kinematics.layout().slots();
  for (size_t i = 0; i < slots.size(); ++i) {
    const Pose X = kinematics.EndPose(model.moving_bodies[slots[i]], z_pose);
    Eigen::Quaterniond quat(X.linear());
    const int iq = Model::q_offset(slots[i]), iv = Model::v_offset(slots[i]);
    const Eigen::Vector4d old = state->q.segment<4>(iq + 3);
    if (quat.w() * old[0] + quat.x() * old[1] + quat.y() * old[2] + quat.z() * old[3] < 0.0) quat.coeffs() *= -1.0;
    state->q.segment<3>(iq) = X.translation();
    state->q.segment<4>(iq + 3) << quat.w(), quat.x(), quat.y(), quat.z();
    state->v.segment<6>(iv) = z_velocity.segment<6>(6 * i);
  }
}

// Lays z out for `pairs`, carrying it over; the blocks of new pairs are seeded from `state` like a cold start.
void SetPairs(const Model& model, const State& state, const std::vector<int>& pairs, Data* data) {
  StepLayout& layout = data->layout;
  data->LayOut(pairs, &data->z);
  data->z.swap(data->z_remap);
  data->frame_known.assign(layout.blocks().size(), 1);
  for (int c : data->new_blocks) data->frame_known[c] = 0;
  for (int c : data->new_blocks) {
    SeedPair(model, state, c, layout, data->kinematics.force_scale(), &data->z, /*use_oracle=*/false);
    layout.ResetTangentAxis(c, data->z);
    SeedFriction(layout, data->kinematics, c, &data->z);
  }
}

// Whether two posed shapes are certified apart by more than `clearance` (m): some unit n along which the lowest point
// of body 1 lies more than `clearance` above the highest point of body 2 (their support points; any n bounds the
// distance from below). Found by the support-function descent, for shapes with closed-form support points; two
// spheres are left to their bounding spheres, which are exact.
bool CertifiedApart(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                    double clearance) {
  if (shape1.type == ShapeType::kSphere && shape2.type == ShapeType::kSphere) return false;
  // A half-space (z <= 0 in its frame S) has one such n, its outward normal: exact, and the descent's start along the
  // line between the frames would see an infinite support.
  const bool plane1 = shape1.type == ShapeType::kHalfSpace, plane2 = shape2.type == ShapeType::kHalfSpace;
  if (plane1 != plane2) {
    const Pose X_WS = (plane1 ? X_WB1 : X_WB2) * (plane1 ? shape1 : shape2).X_BS;
    const Vec3 n_W = X_WS.linear().col(2);
    Vec3 p_W;  // the other shape's point deepest along -n
    if (!SupportPoint(plane1 ? shape2 : shape1, plane1 ? X_WB2 : X_WB1, -n_W, &p_W)) return false;
    return n_W.dot(p_W - X_WS.translation()) > clearance;
  }
  constexpr int kMaxDescentSteps = 30;
  return DescendCrossing(shape1, X_WB1, shape2, X_WB2, -clearance, kMaxDescentSteps).value < -clearance;
}

// Whether a candidate pair can touch within the step by the relative motion of its bodies (for two moving bodies a
// common velocity and gravity cancel; a fixed half-space does not move, and a moving body falls by g h^2 / 2 towards it):
// not if their bounding spheres at the start are apart by more than the relative motion of their centres within the
// step (h |v1 - v2| + h |w_i| lever_i) plus the margin, nor if the shapes themselves are certified apart by more than
// the relative motion of any of their points (h |v1 - v2| + h |w_i| (lever_i + R_i)) plus the margin. A layer of
// parts falling side by side then forms one island per part instead of one for the layer, packed ellipsoids whose
// bounding spheres overlap stay apart, and a long flat part above the floor (whose bounding sphere reaches it) is no
// pair of the NCP. (The end-of-step check still catches what this misses.) X_WB: every body's pose at the start.
bool CanTouchWithinStep(const Model& model, const StepperOptions& options, double h, const State& state,
                        const std::vector<Pose>& X_WB, int pair) {
  const ContactPair& p = model.pairs[pair];
  const int k1 = model.velocity_slot[p.body1], k2 = model.velocity_slot[p.body2];
  // A fixed body other than a half-space (a table, a robot's welded base link of mesh hulls) stays a pair: the
  // support-function descent on each of them every step made two vendor arms held by drives fall behind real time.
  if ((k1 < 0 && model.shape(p.geom1).type != ShapeType::kHalfSpace) ||
      (k2 < 0 && model.shape(p.geom2).type != ShapeType::kHalfSpace)) {
    return true;
  }
  const ConvexShape& s1 = model.shape(p.geom1);
  const ConvexShape& s2 = model.shape(p.geom2);
  const Vec3 zero = Vec3::Zero();
  const Vec3& v1 = k1 < 0 ? zero : state.v_WB(k1);
  const Vec3& v2 = k2 < 0 ? zero : state.v_WB(k2);
  const double w1 = k1 < 0 ? 0.0 : state.w_WB(k1).norm(), w2 = k2 < 0 ? 0.0 : state.w_WB(k2).norm();
  const double fall = k1 < 0 || k2 < 0 ? 0.5 * model.gravity_W.norm() * h * h : 0.0;
  const double dv = (v1 - v2).norm();
  const double R1 = s1.BoundingRadius(), R2 = s2.BoundingRadius();
  const double lever1 = s1.X_BS.translation().norm(), lever2 = s2.X_BS.translation().norm();
  // A fixed body's shape moves not at all, whatever its size (a half-space's bounding radius is infinite).
  const double motion1 = k1 < 0 ? 0.0 : w1 * (lever1 + R1), motion2 = k2 < 0 ? 0.0 : w2 * (lever2 + R2);
  if (std::isfinite(R1) && std::isfinite(R2)) {
    const Vec3 c1 = X_WB[p.body1] * s1.X_BS.translation();
    const Vec3 c2 = X_WB[p.body2] * s2.X_BS.translation();
    const double gap = (c1 - c2).norm() - R1 - R2;
    const double reach = h * (dv + w1 * lever1 + w2 * lever2) + fall + options.broad_phase_margin;
    if (gap > reach) return false;
  } else if (!std::isfinite(motion1) || !std::isfinite(motion2)) {
    return true;  // an unbounded moving shape
  }
  const double sweep = h * (dv + motion1 + motion2) + fall + options.broad_phase_margin;
  return !CertifiedApart(s1, X_WB[p.body1], s2, X_WB[p.body2], sweep);
}

// The pairs of the NCP for a step of length h from `state`: the broad phase over bounding spheres grown by the motion
// possible within the step plus a margin, less the pairs of moving bodies that cannot touch by their relative motion,
// joined with the pairs the end-of-step check forced in (Data::forced_pairs).
void SelectPairs(const Model& model, const StepperOptions& options, double h, const State& state, Data* data) {
  const double fall = 0.5 * model.gravity_W.norm() * h * h;
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) data->X_WB[b] = state.X_WB(model, b);
  for (int g = 0; g < static_cast<int>(model.geoms.size()); ++g) {
    const int k = model.velocity_slot[model.geoms[g].body];
    const double lever = model.shape(g).X_BS.translation().norm();  // of the bounding sphere's centre (m)
    data->inflation[g] =
        k < 0 ? 0.0 : h * (state.v_WB(k).norm() + state.w_WB(k).norm() * lever) + fall + options.broad_phase_margin;
  }
  data->broad.FindPairs(data->X_WB, data->inflation, &data->candidates);
  const auto cannot_touch = [&](int pair) { return !CanTouchWithinStep(model, options, h, state, data->X_WB, pair); };
  data->candidates.erase(std::remove_if(data->candidates.begin(), data->candidates.end(), cannot_touch),
                         data->candidates.end());
  data->merged.clear();
  std::set_union(data->candidates.begin(), data->candidates.end(), data->forced_pairs.begin(),
                 data->forced_pairs.end(), std::back_inserter(data->merged));
  data->layout.ActivePairs(&data->pairs);
  if (data->merged != data->pairs) SetPairs(model, state, data->merged, data);
}

// The end-of-step check of the pairs left out of the NCP: bounding spheres (no growth) at the end poses in `end`.
// Pairs whose spheres overlap, unless the shapes are certified apart (CertifiedApart), are added to
// Data::forced_pairs; returns how many.
int CheckLeftOutPairs(const Model& model, const State& end, Data* data) {
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) data->X_WB[b] = end.X_WB(model, b);
  std::fill(data->inflation.begin(), data->inflation.end(), 0.0);
  data->broad.FindPairs(data->X_WB, data->inflation, &data->candidates);
  data->layout.ActivePairs(&data->pairs);
  int missing = 0;
  for (int pair : data->candidates) {
    if (std::binary_search(data->pairs.begin(), data->pairs.end(), pair)) continue;
    const ContactPair& p = model.pairs[pair];
    if (CertifiedApart(model.shape(p.geom1), data->X_WB[p.body1], model.shape(p.geom2), data->X_WB[p.body2], 0.0)) {
      continue;
    }
    data->forced_pairs.push_back(pair);
    ++missing;
  }
  std::sort(data->forced_pairs.begin(), data->forced_pairs.end());
  return missing;
}

// Whether the velocities of an island's solution z exceed options.max_speed or max_angular_speed (see FindDivergence).
bool ExceedsSpeedLimits(const StepperOptions& options, const StepLayout& layout, const Eigen::VectorXd& z) {
  for (size_t i = 0; i < layout.slots().size(); ++i) {
    if (z.segment<3>(6 * i).norm() > options.max_speed || z.segment<3>(6 * i + 3).norm() > options.max_angular_speed) {
      return true;
    }
  }
  return false;
}

// What an island's step reads besides its own workspace (shared by the threads, read only).
struct IslandStepInputs {
  const Model* model;
  const StepperOptions* options;
  const Eigen::VectorXd* wrench;
  State* state;  // each island reads and writes only its own bodies' slots
};

// The island's step by `scheme` from the start of the step (BeginStep called on its kinematics): the pose problem's
// retry ladder up to `reach`, a cold re-solve if a body passed through another, then the rest of the scheme's step,
// after a converged solve or after the best one of the shortest sub-step (which is then accepted). Sets *crossed if
// the solution still crosses.
NcpSummary SolveIslandStep(const IslandStepInputs& in, IslandScheme& scheme, bool last_chance, LadderReach reach,
                           IslandSolve* island, bool* crossed) {
  const Model& model = *in.model;
  const StepperOptions& options = *in.options;
  const State& state = *in.state;
  StepReport* report = &island->report;
  scheme.BeginStep(island);
  StepProblem& problem = scheme.pose_problem();
  NcpSummary result =
      SolveWithRetryLadder(model, options, state, problem, &scheme.pose_solvers(), island, last_chance, reach, report);
  // A solution in which a body passed through another is no solution of the step (tunnelling): solve again from a
  // cold start (the start-of-step closest points, on the near side), and if it still crosses, split the step.
  const auto crosses = [&]() {
    return island->z.allFinite() && FindCrossing(model, state, island->kinematics, island->z, nullptr) >= 0;
  };
  *crossed = crosses();
  if (*crossed && island->has_warm_start) {
    island->has_warm_start = false;
    result = SolveWithRetryLadder(model, options, state, problem, &scheme.pose_solvers(), island, last_chance, reach,
                                  report);
    *crossed = crosses();
  }
  if (*crossed) {
    report->crossings++;
    result.converged = false;
  }
  if (island->z.allFinite() && (result.converged || last_chance)) {
    result.converged = scheme.FinishStep(options, result.converged, island, report);
  }
  return result;
}

// Advances the island's bodies in *state by h with its scheme (schemes/island_scheme.h), or where that does not
// converge within its budget, with the scheme's fallback; when the solve fails, by two halves instead, down to
// h / 2^kMaxSubstepDepth, where the best finite iterate is accepted and reported as not converged. Returns false if
// the island could not be advanced.
bool AdvanceIsland(const IslandStepInputs& in, double h, int depth, IslandSolve* island) {
  const Model& model = *in.model;
  const StepperOptions& options = *in.options;
  State* state = in.state;
  IslandScheme* scheme = &island->SchemeFor(options);
  StepReport* report = &island->report;
  // A due interrupt abandons the island (and with it the step, which Step then undoes), before a solve and after one.
  const auto interrupted = [&]() {
    if (!InterruptDue(options.newton.interrupt)) return false;
    report->converged = false;
    report->fault = StepFault::kInterrupted;
    return true;
  };
  if (interrupted()) return false;
  Eigen::VectorXd& backup = island->z_backup[depth];
  backup = island->z;
  const bool had_warm_start = island->has_warm_start;
  island->kinematics.BeginStep(*state, h, in.wrench);
  const bool last_chance = depth == Data::kMaxSubstepDepth;
  bool crossed = false;
  const auto restart = [&]() {
    island->z = backup;
    island->has_warm_start = had_warm_start;
  };
  NcpSummary result;
  // A damping step (see StepIsland) is the fallback's step within the warm rungs' budget: where that does not
  // converge, the island takes the scheme's own step as if it had not been damped.
  const bool damped = island->damping && scheme->fallback() != nullptr &&
                      (result = SolveIslandStep(in, *scheme->fallback(), /*last_chance=*/false,
                                                LadderReach::kWarmRungs, island, &crossed)).converged;
  if (damped) {
    report->damping_steps++;
    scheme = scheme->fallback();
  } else {
    if (island->damping) restart();
    island->damping = false;
    const LadderReach reach = scheme->fallback() ? LadderReach::kWarmRungs : LadderReach::kAllRungs;
    result = SolveIslandStep(in, *scheme, last_chance, reach, island, &crossed);
  }
  if (!result.converged && scheme->fallback() != nullptr) {
    report->paper_fallbacks++;
    restart();
    scheme = scheme->fallback();
    result = SolveIslandStep(in, *scheme, last_chance, LadderReach::kAllRungs, island, &crossed);
  }
  if (!result.converged && interrupted()) return false;
  const Eigen::VectorXd& z_velocity = scheme->velocity_solution(*island);
  if (!result.converged && depth < Data::kMaxSubstepDepth) {
    island->z = backup;
    island->has_warm_start = had_warm_start && !crossed;
    report->substeps += 1;
    return AdvanceIsland(in, h / 2, depth + 1, island) && AdvanceIsland(in, h / 2, depth + 1, island);
  }
  if (!std::isfinite(result.residual) || !island->z.allFinite()) {
    island->has_warm_start = false;
    report->converged = false;
    return false;
  }
  // Even the shortest sub-step crossed: refuse the step rather than let the body through (unless its velocities are
  // beyond the health limits: Step then refuses it as diverged, the more telling fault).
  if (crossed && !ExceedsSpeedLimits(options, island->layout, z_velocity)) {
    island->has_warm_start = false;
    report->converged = false;
    report->fault = StepFault::kCrossing;
    FindCrossing(model, *state, island->kinematics, island->z, &report->fault_detail);
    return false;
  }
  report->converged = report->converged && result.converged;
  report->residual = std::max(report->residual, result.residual);
  report->complementarity_error = std::max(report->complementarity_error, scheme->ComplementarityError(island));
  // The contact results of the step: the closest points of the pose solution, the forces of the velocity solution.
  scheme->velocity_problem().Contacts(z_velocity, &island->contacts);
  for (size_t i = 0; i < island->joints.size(); ++i) {
    island->joint_limit_effort[i] = island->layout.JointLimitEffort(z_velocity, island->joints[i]);
    island->joint_drive_effort[i] = island->layout.JointDriveEffort(z_velocity, island->joints[i]);
  }
  WriteState(model, island->kinematics, island->z, z_velocity, state);
  island->has_warm_start = true;
  std::fill(island->frame_known.begin(), island->frame_known.end(), 1);  // z is a solution at the new start
  return true;
}

// Whether body `slot` (in `state`, at the end of the step) moves against its start velocity v0 (6: v_WB, w_WB): a
// negative kinetic-energy product m v0.v1 + w0.I_W w1.
bool VelocityReversed(const Model& model, const State& state, int slot, const Eigen::Ref<const Eigen::VectorXd>& v0) {
  const Body& body = model.bodies[model.moving_bodies[slot]];
  const Mat3 R = state.X_WB(model, model.moving_bodies[slot]).linear();
  const double product =
      body.mass * v0.head<3>().dot(state.v_WB(slot)) + v0.tail<3>().dot(R * body.I_B * R.transpose() * state.w_WB(slot));
  return product < 0.0;
}

// The fastest speed of a point of body `slot` within its bounding sphere, |v_WB| + |w_WB| R (m/s; |v_WB| for a body
// without a bounded shape).
double BodySpeed(const Model& model, const State& state, int slot) {
  const double reach = model.BodyReach(model.moving_bodies[slot]);
  return state.v_WB(slot).norm() + (std::isfinite(reach) ? state.w_WB(slot).norm() * reach : 0.0);
}

// RATTLE (Data::velocity_reversals): a body alone in its island (against fixed bodies only, no joint) whose velocity
// reversed in two steps in a row tries the paper's step. One that such a step leaves slower than kRestSpeedShare |g| h
// (what gravity adds to a speed in a millionth of a step) is held at rest: it keeps taking the paper's step.
constexpr int kReversalsToDamp = 2;
constexpr double kRestSpeedShare = 1e-6;

// The step of island `index` of Data (a ThreadPool task), with the damping above.
void StepIsland(void* context, int index) {
  auto* task = static_cast<std::pair<const IslandStepInputs*, Data*>*>(context);
  const IslandStepInputs& in = *task->first;
  Data* data = task->second;
  IslandSolve* island = data->islands[index].get();
  island->report = StepReport();
  island->report.converged = true;
  // Only a lone body is damped: the ringing is a contact's (a face on its one point), and in piles a damping step
  // changes which landing steps the ladders meet (doc/method.md).
  const int slot = island->slots[0];
  const bool rattle = in.options->scheme == StepperOptions::Scheme::kRattle;
  island->damping = rattle && island->slots.size() == 1 && island->joints.empty() &&
                    data->velocity_reversals[slot] >= kReversalsToDamp;
  island->advanced = AdvanceIsland(in, in.options->h, 0, island);  // clears `damping` if the paper's step failed
  if (!island->advanced || !rattle) return;  // the paper's step damps by itself: no counts to keep
  const double rest_speed = kRestSpeedShare * in.model->gravity_W.norm() * in.options->h;
  const bool held = island->damping && BodySpeed(*in.model, *in.state, slot) <= rest_speed;
  const Eigen::VectorXd& v_start = data->state_backup.v;  // the state at the step start (Step)
  for (int s : island->slots) {
    int& reversals = data->velocity_reversals[s];
    const bool reversed = VelocityReversed(*in.model, *in.state, s, v_start.segment<6>(Model::v_offset(s)));
    reversals = held || reversed ? std::min(reversals + 1, kReversalsToDamp) : 0;
  }
}

// Solves the step's islands from `state` (at the step start) and advances *state; returns false if an island could
// not be advanced (the state is then partly advanced: Step restores it).
bool SolveIslands(const Model& model, const StepperOptions& options, const Eigen::VectorXd* wrench, State* state,
                  Data* data, StepReport* report) {
  PartitionIslands(model, data);
  for (int i = 0; i < data->num_islands; ++i) GatherIsland(*data, data->islands[i].get());
  const IslandStepInputs inputs{&model, &options, wrench, state};
  std::pair<const IslandStepInputs*, Data*> task(&inputs, data);
  const int threads = std::min(ResolveThreadCount(options.threads), data->num_islands);
  if (threads > 1) {
    if (!data->pool || data->pool->threads() != ResolveThreadCount(options.threads)) {
      data->pool = std::make_unique<ThreadPool>(ResolveThreadCount(options.threads));
    }
    data->pool->Run(data->num_islands, StepIsland, &task);
  } else {
    for (int i = 0; i < data->num_islands; ++i) StepIsland(&task, i);
  }
  bool advanced = true;
  report->islands = data->num_islands;
  data->contacts.resize(data->layout.blocks().size());  // one per pair in the NCP, whatever a caller left in it
  for (int i = 0; i < data->num_islands; ++i) {
    const IslandSolve& island = *data->islands[i];
    MergeIslandReport(island.report, report);
    advanced = advanced && island.advanced;
    report->largest_island = std::max(report->largest_island, static_cast<int>(island.slots.size()));
    if (island.advanced) ScatterIsland(island, data);
  }
  data->has_warm_start = advanced;
  return advanced;
}

// Advances the state by one step: the islands' solves; with the broad phase, solved again from the step start while
// the end-of-step check finds pairs left out of the NCP overlapping (no pair may interpenetrate at the step end, in or
// out of the NCP). Returns false if the state could not be advanced.
bool Advance(const Model& model, const StepperOptions& options, const Eigen::VectorXd* wrench, State* state,
             Data* data, StepReport* report) {
  data->forced_pairs.clear();
  const bool had_warm_start = data->has_warm_start;
  for (int round = 1;; ++round) {
    // The pairs whose closest points in z are at the step's start (RATTLE's start frames): the previous step's, not
    // a new pair's (SetPairs) nor those a repeated round carries from the end of the step.
    data->frame_known.assign(data->layout.blocks().size(), round == 1 ? 1 : 0);
    if (data->broad_phase) {
      data->kinematics.BeginStep(*state, options.h, wrench);  // for the seeds of new pairs
      SelectPairs(model, options, options.h, *state, data);
      if (round > 1) std::fill(data->frame_known.begin(), data->frame_known.end(), 0);
    }
    report->pairs_in_ncp = static_cast<int>(data->layout.blocks().size());
    if (!SolveIslands(model, options, wrench, state, data, report)) return false;
    if (!data->broad_phase) return true;
    const int missing = CheckLeftOutPairs(model, *state, data);
    if (missing == 0) return true;
    report->broad_phase_additions += missing;
    if (round == Data::kMaxBroadPhaseRounds) {
      report->converged = false;
      return true;
    }
    *state = data->state_backup;  // solve the step again with the pairs added
    data->has_warm_start = had_warm_start;
  }
}

// Throws std::invalid_argument naming the joint if Data::joint_drives does not hold a valid drive per model joint.
void CheckJointDrives(const Model& model, const Data& data) {
  if (data.joint_drives.size() != model.joints.size()) {
    throw std::invalid_argument("Data::joint_drives must hold one drive per model joint (" +
                                std::to_string(model.joints.size()) + "), got " +
                                std::to_string(data.joint_drives.size()));
  }
  std::string error;
  for (size_t j = 0; j < model.joints.size(); ++j) {
    if (!CheckJointDrive(model.joints[j], data.joint_drives[j], &error)) throw std::invalid_argument(error);
  }
}

}  // namespace

StepReport Step(const Model& model, const StepperOptions& user_options, State* state, Data* data,
                const Eigen::VectorXd* external_wrench_W) {
  std::string error;
  if (!user_options.IsValid(&error)) throw std::invalid_argument(error);
  StepperOptions options = user_options;  // every solver of the step watches the caller's interrupt
  options.newton.interrupt = data->interrupt;
  if (!data->BelongsTo(model)) {
    throw std::invalid_argument("Data was built from another Model: build it as Data(model) from the Model given to Step");
  }
  if (!CheckState(model, *state, &error)) throw std::invalid_argument(error);
  if (external_wrench_W && (external_wrench_W->size() != model.nv() || !external_wrench_W->allFinite())) {
    throw std::invalid_argument("external wrench vector must hold " + std::to_string(model.nv()) +
                                " finite values (force, torque per moving body)");
  }
  CheckJointDrives(model, *data);
  const auto wall_start = std::chrono::steady_clock::now();
  StepReport report;
  if (InterruptDue(data->interrupt)) {  // nothing done: the warm start stays
    report.fault = StepFault::kInterrupted;
    return report;
  }
  report.converged = true;
  if (!data->has_warm_start &&
      FindInitialOverlap(model, *state, options.overlap_tolerance, data, &report.fault_detail)) {
    report.converged = false;
    report.fault = StepFault::kInitialOverlap;
    return report;
  }
  data->LayOutDrives(*state);
  data->state_backup = *state;
  const double t_end = state->t + options.h;
  report.advanced = Advance(model, options, external_wrench_W, state, data, &report);
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
