// Every analytic Jacobian block of the step's problems (problems/: the paper's step and RATTLE's two stages) against
// central finite differences (doc/method.md, pitfall 4), at random points away from the Fischer-Burmeister kink, for
// moving-fixed and moving-moving pairs of several shapes; and the rows the layout and the evaluation modes promise.
#include "implicit_sim/core/geometry/support.h"
#include "implicit_sim/core/step/problems/step_problem.h"

#include <random>
#include <string>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "implicit_sim/core/ncp/condensed_lu.h"

#include "ncp/test_ncp_problems.h"

#include "step/step_problems_fixture.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

// A random point z of the problem (normals kept away from zero, multipliers generic) and the start of a step of
// 0.05 s from random velocities with the external wrench `wrench` (may be null); returns z.
using testing_support::StepProblems;

// The problem of each stage (the paper's step; RATTLE's stage 1 and stage 2).
enum class Stage { kPaper, kRattlePosition, kRattleVelocity };

// The model with rolling resistance e_roll (m) on every pair.
Model WithRollingResistance(Model model, double e_roll) {
  for (ContactPair& pair : model.pairs) pair.friction.e_roll = e_roll;
  return model;
}

Eigen::VectorXd BeginAtRandomPoint(const Model& model, unsigned seed, const Eigen::VectorXd* wrench,
                                   StepProblems* problems) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd z(problems->layout.size());
  for (int i = 0; i < z.size(); ++i) z[i] = u(rng);
  for (const PairBlock& blk : problems->layout.blocks()) {
    z.segment<3>(blk.offset + pair_index::kN) += Vec3(0.3, -0.2, 1.0);
  }
  State start = State::Initial(model);
  for (int i = 0; i < start.v.size(); ++i) start.v[i] = 2.0 * u(rng);
  problems->kinematics.BeginStep(start, 0.05, wrench);
  problems->layout.ResetTangentAxes(z);
  return z;
}

// Compares J with central differences of Phi column by column; reports the worst block by name. In sparse mode the
// Jacobian comes from the sparse assembly (second evaluation: the recorded pattern replayed) with the friction rows
// of the sparse solver (regular_separated_friction), and the dense Jacobian must equal it entry for entry.
// With a RATTLE stage: stage 1 with start frames from another random point for every other pair (the rest on the end
// frame); stage 2 after RattleVelocityProblem::Begin from the random point, at a point near its initial guess.
// With drives (one per model joint), the joints whose drive is active carry a drive row.
void ExpectJacobianMatchesFiniteDifferences(const Model& model, unsigned seed, bool sparse = false,
                                            bool projected = false, double proximal_weight = 0.0,
                                            Stage stage = Stage::kPaper,
                                            const std::vector<JointDrive>* drives = nullptr,
                                            const FrictionForm& form = FrictionForm()) {
  NcpEvalMode mode;
  mode.project_multipliers = projected;
  Eigen::VectorXd center;
  StepProblems problems(model, sparse);
  problems.SetFrictionForm(form);
  const std::vector<PairBlock>& blocks = problems.layout.blocks();
  if (drives) {
    problems.drives = *drives;
    std::vector<char> driven(model.joints.size());
    for (size_t j = 0; j < driven.size(); ++j) driven[j] = JointDriveActive((*drives)[j]);
    Eigen::VectorXd unused;
    problems.layout.SetDrivenJoints(driven, nullptr, &unused);
  }
  const Eigen::VectorXd wrench = Eigen::VectorXd::Constant(model.nv(), 0.3);
  Eigen::VectorXd z = BeginAtRandomPoint(model, seed, &wrench, &problems);
  if (stage != Stage::kPaper) {
    std::mt19937 rng(seed + 100);
    Eigen::VectorXd frame = z + 0.1 * ncp_test::RandomVector(z.size(), &rng);
    std::vector<char> known(blocks.size());
    for (size_t c = 0; c < known.size(); ++c) {
      known[c] = c % 2 == 0;
      frame.segment<3>(blocks[c].offset + pair_index::kN).normalize();
      frame[blocks[c].offset + pair_index::kD] = 0.0;  // touching at the start
      // Every inequality active (a vertex of a polytope) and each closest point of a bounded shape on its surface,
      // where it is curved: the start frame is kept (RattlePositionProblem::SetStartFrames).
      frame.segment(blocks[c].offset + pair_index::kAlpha, blocks[c].k1 + blocks[c].k2).setOnes();
      const Vec3 n0 = frame.segment<3>(blocks[c].offset + pair_index::kN);
      const int locals[2] = {blocks[c].body1, blocks[c].body2};
      for (int side = 0; side < 2; ++side) {
        const Body& body = model.bodies[problems.layout.bodies()[locals[side]]];
        if (!body.shapes[0].IsBounded()) continue;
        const BodyStart& start = problems.kinematics.start(locals[side]);
        Vec3 point;
        SupportPoint(body.shapes[0], test_models::MakePose(start.p0, start.R0), side == 0 ? Vec3(-n0) : n0, &point);
        frame.segment<3>(blocks[c].offset + (side == 0 ? pair_index::kA1 : pair_index::kA2)) = point;
      }
    }
    problems.position.SetStartFrames(frame, known);
    for (size_t c = 0; c < known.size(); ++c) {
      EXPECT_EQ(problems.position.uses_start_frame(static_cast<int>(c)), c % 2 == 0);
    }
  }
  if (stage == Stage::kRattleVelocity) {
    Eigen::VectorXd z2;
    for (size_t c = 0; c < blocks.size(); ++c) {  // every other pair closed (touching), the rest open
      z[blocks[c].offset + pair_index::kD] = c % 2 == 0 ? 0.0 : 0.05;
      z[blocks[c].normal_force()] = c % 2 == 0 ? 0.7 : 0.0;
    }
    Eigen::VectorXd raw_rows;
    NcpEvalMode raw;
    raw.raw = true;
    problems.position.Evaluate(z, raw, &raw_rows, nullptr);
    problems.velocity.Begin(problems.position, z, raw_rows, &z2);
    std::mt19937 rng(seed + 200);
    z = z2 + 0.2 * ncp_test::RandomVector(z.size(), &rng);
  }
  const StepProblem& problem = stage == Stage::kPaper            ? static_cast<const StepProblem&>(problems.paper)
                               : stage == Stage::kRattlePosition ? static_cast<const StepProblem&>(problems.position)
                                                                 : static_cast<const StepProblem&>(problems.velocity);
  if (proximal_weight > 0.0) {  // a centre away from z
    center = z + Eigen::VectorXd::Constant(z.size(), 0.2);
    mode.proximal_weight = proximal_weight;
    mode.proximal_center = &center;
  }

  Eigen::VectorXd Phi, Phi_plus, Phi_minus;
  Eigen::MatrixXd J;
  problem.Evaluate(z, mode, &Phi, &J);
  if (sparse) {
    SparseJacobian J_sparse;
    Eigen::VectorXd Phi_sparse;
    problem.EvaluateSparse(z + Eigen::VectorXd::Constant(z.size(), 0.01), mode, &Phi_sparse, &J_sparse);  // records
    problem.EvaluateSparse(z, mode, &Phi_sparse, &J_sparse);                                              // replays
    EXPECT_EQ((Phi_sparse - Phi).lpNorm<Eigen::Infinity>(), 0.0);
    EXPECT_EQ((Eigen::MatrixXd(J_sparse.matrix) - J).lpNorm<Eigen::Infinity>(), 0.0);
    J = Eigen::MatrixXd(J_sparse.matrix);
  }
  double worst = 0.0;
  int worst_row = -1, worst_col = -1;
  for (int col = 0; col < z.size(); ++col) {
    const double eps = 1e-6;
    Eigen::VectorXd zp = z, zm = z;
    zp[col] += eps;
    zm[col] -= eps;
    problem.Evaluate(zp, mode, &Phi_plus, nullptr);
    problem.Evaluate(zm, mode, &Phi_minus, nullptr);
    const Eigen::VectorXd fd = (Phi_plus - Phi_minus) / (2.0 * eps);
    for (int row = 0; row < z.size(); ++row) {
      const double err = std::abs(fd[row] - J(row, col)) / std::max(1.0, std::abs(fd[row]));
      if (err > worst) {
        worst = err;
        worst_row = row;
        worst_col = col;
      }
    }
  }
  EXPECT_LT(worst, 2e-6) << "worst mismatch at row " << worst_row << ", column " << worst_col
                         << " (body velocities first, then joint blocks, then pair blocks: a1 a2 n d s_t s_o s_r alpha beta ln sigma)";
}

// The RATTLE stages of every model above, dense and sparse.
TEST(StepProblemJacobian, RattlePositionStage) {
  for (const bool sparse : {false, true}) {
    ExpectJacobianMatchesFiniteDifferences(test_models::EllipsoidOnGround(), 21, sparse, false, 0.0, Stage::kRattlePosition);
    ExpectJacobianMatchesFiniteDifferences(test_models::SphereOnTwoSpheres(), 22, sparse, false, 0.0,
                                           Stage::kRattlePosition);
    ExpectJacobianMatchesFiniteDifferences(test_models::BoxAndSuperellipsoid(), 23, sparse, false, 0.0,
                                           Stage::kRattlePosition);
    ExpectJacobianMatchesFiniteDifferences(test_models::PrismOnGround(7), 24, sparse, false, 0.0, Stage::kRattlePosition);
    ExpectJacobianMatchesFiniteDifferences(test_models::JointedRobot(), 25, sparse, false, 0.0, Stage::kRattlePosition);
  }
}

TEST(StepProblemJacobian, RattleVelocityProblem) {
  for (const bool sparse : {false, true}) {
    ExpectJacobianMatchesFiniteDifferences(test_models::EllipsoidOnGround(), 31, sparse, false, 0.0, Stage::kRattleVelocity);
    ExpectJacobianMatchesFiniteDifferences(test_models::SphereOnTwoSpheres(), 32, sparse, false, 0.0,
                                           Stage::kRattleVelocity);
    ExpectJacobianMatchesFiniteDifferences(test_models::BoxAndSuperellipsoid(), 33, sparse, true, 0.0,
                                           Stage::kRattleVelocity);
    ExpectJacobianMatchesFiniteDifferences(test_models::PrismOnGround(7), 34, sparse, false, 0.0, Stage::kRattleVelocity);
    ExpectJacobianMatchesFiniteDifferences(test_models::JointedRobot(), 35, sparse, false, 0.0, Stage::kRattleVelocity);
  }
}

// Rolling resistance (two more friction components per pair, FrictionParams::e_roll) in every problem of the step,
// dense and sparse, with projected multipliers and with the proximal term.
TEST(StepProblemJacobian, RollingResistanceInEveryStage) {
  for (const bool sparse : {false, true}) {
    for (const Stage stage : {Stage::kPaper, Stage::kRattlePosition, Stage::kRattleVelocity}) {
      const unsigned seed = 40 + static_cast<unsigned>(stage) * 2 + sparse;
      ExpectJacobianMatchesFiniteDifferences(WithRollingResistance(test_models::EllipsoidOnGround(), 0.02), seed,
                                             sparse, false, 0.0, stage);
      ExpectJacobianMatchesFiniteDifferences(WithRollingResistance(test_models::BoxAndSuperellipsoid(), 0.03), seed,
                                             sparse, true, 0.0, stage);
      ExpectJacobianMatchesFiniteDifferences(WithRollingResistance(test_models::SphereOnTwoSpheres(), 0.01), seed,
                                             sparse, false, stage == Stage::kPaper ? 0.7 : 0.0, stage);
    }
  }
}

TEST(StepProblemJacobian, EllipsoidOnGround) {
  ExpectJacobianMatchesFiniteDifferences(test_models::EllipsoidOnGround(), 1);
}

TEST(StepProblemJacobian, SphereOnTwoFixedSpheres) {
  ExpectJacobianMatchesFiniteDifferences(test_models::SphereOnTwoSpheres(), 2);
}

TEST(StepProblemJacobian, TwoMovingBodiesBoxAndSuperellipsoid) {
  ExpectJacobianMatchesFiniteDifferences(test_models::BoxAndSuperellipsoid(), 3);
}

TEST(StepProblemJacobian, PrismWithOffsetShapeFrameAndLockedAxes) {
  ExpectJacobianMatchesFiniteDifferences(test_models::PrismOnGround(7), 4);
}

TEST(StepProblemJacobian, JointsOfEveryTypeWithLimitsFrictionAndDamping) {
  ExpectJacobianMatchesFiniteDifferences(test_models::JointedRobot(), 8);
  ExpectJacobianMatchesFiniteDifferences(test_models::JointedRobot(), 9, true);
}

// The planar joint's three equalities (joints.h) with both of its bodies moving, in every stage, dense and sparse.
TEST(StepProblemJacobian, PlanarJointInEveryStage) {
  for (const bool sparse : {false, true}) {
    for (const Stage stage : {Stage::kPaper, Stage::kRattlePosition, Stage::kRattleVelocity}) {
      const unsigned seed = 60 + static_cast<unsigned>(stage) * 2 + sparse;
      ExpectJacobianMatchesFiniteDifferences(test_models::PlanarJointRobot(), seed, sparse, false, 0.0, stage);
    }
  }
}

// Projected multipliers (the retry ladder's rung 1b): the friction rows' slip speed max(sigma, 0), whose derivative
// is 0 where the random point has sigma < 0.
// Drive rows (rows/drive_rows.h) on the revolute, prismatic and continuous joints of the jointed robot, in every stage,
// dense and sparse: with no effort limit (the law's slope 1) and with limits the law exceeds at the random point (the
// clamp's slope 0), one joint of each.
TEST(StepProblemJacobian, JointDriveRowsInEveryStage) {
  Model model = test_models::JointedRobot();
  const int shoulder = model.FindJoint("shoulder"), slide = model.FindJoint("slide"), axle = model.FindJoint("axle");
  std::vector<JointDrive> drives(model.joints.size());
  drives[shoulder] = {0.7, 0.3, 40.0, 2.0};
  drives[slide] = {0.05, -0.2, 300.0, 0.0};
  drives[axle] = {2.5, 1.5, 0.0, 4.0};
  unsigned seed = 40;
  for (const double limit : {0.0, 1e-3}) {
    model.joints[shoulder].effort_limit = model.joints[slide].effort_limit = model.joints[axle].effort_limit = limit;
    for (const Stage stage : {Stage::kPaper, Stage::kRattlePosition, Stage::kRattleVelocity}) {
      for (const bool sparse : {false, true}) {
        SCOPED_TRACE("effort limit " + std::to_string(limit) + ", stage " + std::to_string(static_cast<int>(stage)) +
                     (sparse ? ", sparse" : ", dense"));
        ExpectJacobianMatchesFiniteDifferences(model, ++seed, sparse, false, 0.0, stage, &drives);
      }
    }
  }
}

// A mimic row (Joint::mimic_leader) coupling two chains: the continuous axle on its fixed post follows the revolute
// shoulder at -0.5 q + 0.2 rad, in every stage, dense and sparse.
TEST(StepProblemJacobian, MimicRowInEveryStage) {
  Model model = test_models::JointedRobot();
  Joint& axle = model.joints[model.FindJoint("axle")];
  axle.mimic_leader = model.FindJoint("shoulder");
  axle.mimic_multiplier = -0.5;
  axle.mimic_offset = 0.2;
  unsigned seed = 60;
  for (const Stage stage : {Stage::kPaper, Stage::kRattlePosition, Stage::kRattleVelocity}) {
    for (const bool sparse : {false, true}) {
      SCOPED_TRACE("stage " + std::to_string(static_cast<int>(stage)) + (sparse ? ", sparse" : ", dense"));
      ExpectJacobianMatchesFiniteDifferences(model, ++seed, sparse, false, 0.0, stage);
    }
  }
}

// Velocity-limit rows (Joint::velocity_limited) on the revolute shoulder (with limits, friction and damping beside
// them), the prismatic slide and the continuous axle, in every stage, dense and sparse.
TEST(StepProblemJacobian, VelocityLimitRowsInEveryStage) {
  Model model = test_models::JointedRobot();
  for (const char* name : {"shoulder", "slide", "axle"}) {
    Joint& joint = model.joints[model.FindJoint(name)];
    joint.velocity_limited = true;
    joint.velocity_limit = 0.8;
  }
  unsigned seed = 80;
  for (const Stage stage : {Stage::kPaper, Stage::kRattlePosition, Stage::kRattleVelocity}) {
    for (const bool sparse : {false, true}) {
      SCOPED_TRACE("stage " + std::to_string(static_cast<int>(stage)) + (sparse ? ", sparse" : ", dense"));
      ExpectJacobianMatchesFiniteDifferences(model, ++seed, sparse, false, 0.0, stage);
    }
  }
}

// The paper's bilinear friction rows (StepperOptions::projected_friction = 0), with joint friction and rolling
// resistance, in every stage, dense and sparse.
TEST(StepProblemJacobian, BilinearFrictionRowsInEveryStage) {
  const FrictionForm bilinear{/*projected=*/false, 1.0};
  for (const Stage stage : {Stage::kPaper, Stage::kRattlePosition, Stage::kRattleVelocity}) {
    for (const bool sparse : {false, true}) {
      ExpectJacobianMatchesFiniteDifferences(WithRollingResistance(test_models::SphereOnTwoSpheres(), 0.01), 31, sparse,
                                             false, 0.0, stage, nullptr, bilinear);
      ExpectJacobianMatchesFiniteDifferences(test_models::JointedRobot(), 32, sparse, false, 0.0, stage, nullptr,
                                             bilinear);
    }
  }
}

TEST(StepProblemJacobian, ProjectedMultipliers) {
  ExpectJacobianMatchesFiniteDifferences(test_models::SphereOnTwoSpheres(), 14, true, true);
  ExpectJacobianMatchesFiniteDifferences(test_models::BoxAndSuperellipsoid(), 15, false, true);
}

// The proximal rung's perturbed rows: c (s - s_c) on the friction rows, d + c h (ln - ln_c) / Fs in the normal row.
TEST(StepProblemJacobian, ProximalTerm) {
  ExpectJacobianMatchesFiniteDifferences(test_models::SphereOnTwoSpheres(), 16, false, false, 0.7);
  ExpectJacobianMatchesFiniteDifferences(test_models::BoxAndSuperellipsoid(), 17, true, true, 3.0);
}

// The proximal term moves exactly the rows it names, by the closed-form amounts, and vanishes at the centre.
TEST(StepProblem, ProximalTermPerturbsOnlyTheForceAndFrictionRows) {
  const Model model = test_models::SphereOnTwoSpheres();
  StepProblems problems(model);
  const StepProblem& problem = problems.paper;
  problems.kinematics.BeginStep(State::Initial(model), 0.01, nullptr);
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd z(problem.size());
  for (int i = 0; i < z.size(); ++i) z[i] = u(rng);
  problems.layout.ResetTangentAxes(z);
  const PairBlock& blk = problems.layout.blocks()[0];
  const double Fs = problems.kinematics.force_scale();
  z[blk.normal_force()] = 2.0 * Fs;  // a positive normal force and a large gap: FB is b there
  z[blk.offset + pair_index::kD] = -0.5;
  Eigen::VectorXd plain, perturbed, at_center;
  problem.Evaluate(z, NcpEvalMode(), &plain, nullptr);
  NcpEvalMode proximal;
  proximal.proximal_weight = 2.0;
  Eigen::VectorXd center = z;
  proximal.proximal_center = &center;
  problem.Evaluate(z, proximal, &at_center, nullptr);
  EXPECT_EQ((at_center - plain).lpNorm<Eigen::Infinity>(), 0.0);  // no perturbation at the centre
  center[blk.offset + pair_index::kSt] -= 0.1;
  center[blk.normal_force()] -= 0.5 * Fs;
  center[0] -= 1.0;  // a velocity: its row has no proximal term
  problem.Evaluate(z, proximal, &perturbed, nullptr);
  const Eigen::VectorXd change = perturbed - plain;
  EXPECT_NEAR(change[blk.offset + pair_index::kSt], 2.0 * 0.1, 1e-12);
  EXPECT_NE(change[blk.normal_force()], 0.0);
  int changed = 0;
  for (int i = 0; i < change.size(); ++i) changed += change[i] != 0.0;
  EXPECT_EQ(changed, 2);
  NcpEvalMode raw = proximal;  // the raw rows (the independent NCP check) never carry it
  raw.raw = true;
  Eigen::VectorXd raw_plain, raw_perturbed;
  NcpEvalMode raw_only;
  raw_only.raw = true;
  problem.Evaluate(z, raw_only, &raw_plain, nullptr);
  problem.Evaluate(z, raw, &raw_perturbed, nullptr);
  EXPECT_EQ((raw_perturbed - raw_plain).lpNorm<Eigen::Infinity>(), 0.0);
}

// The closest-point blocks the sparse solver condenses (NcpProblem::CondensableBlocks) touch only their own unknowns
// and the velocities of the moving bodies, and the condensed LU of the sparse Jacobian solves like a dense LU of it.
void ExpectCondensableBlocksAreLocal(const Model& model, unsigned seed, const FrictionForm& form) {
  StepProblems problems(model, /*regular_separated_friction=*/true);
  problems.SetFrictionForm(form);
  const StepProblem& problem = problems.paper;
  const Eigen::VectorXd z = BeginAtRandomPoint(model, seed, nullptr, &problems);
  std::vector<int> starts, indices;
  problem.CondensableBlocks(&starts, &indices);
  ASSERT_EQ(starts.size(), problems.layout.blocks().size() + 1);
  std::vector<int> block_of(z.size(), -1);
  for (size_t p = 0; p + 1 < starts.size(); ++p) {
    for (int k = starts[p]; k < starts[p + 1]; ++k) block_of[indices[k]] = static_cast<int>(p);
  }
  SparseJacobian J;
  Eigen::VectorXd Phi;
  problem.EvaluateSparse(z, NcpEvalMode(), &Phi, &J);
  const int num_velocities = 6 * static_cast<int>(problems.layout.slots().size());
  int condensed_rows = 0;
  for (int col = 0; col < z.size(); ++col) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(J.matrix, col); it; ++it) {
      const int row = static_cast<int>(it.row());
      if (block_of[row] < 0 || block_of[row] == block_of[col]) continue;
      EXPECT_LT(col, num_velocities) << "row " << row << " of block " << block_of[row] << " touches column " << col;
    }
  }
  for (int b : block_of) condensed_rows += b >= 0;
  EXPECT_EQ(condensed_rows, static_cast<int>(indices.size()));
  CondensedLu lu;
  lu.SetBlocks(starts, indices);
  ASSERT_TRUE(lu.Factorize(J.matrix, J.pattern_version()));
  EXPECT_EQ(lu.global_size(), z.size() - static_cast<int>(indices.size()));
  Eigen::VectorXd x = Phi;
  ASSERT_TRUE(lu.Solve(&x));
  const Eigen::VectorXd expected = Eigen::MatrixXd(J.matrix).partialPivLu().solve(Phi);
  EXPECT_LT((x - expected).norm() / expected.norm(), 1e-9);
}

TEST(StepProblem, CondensableBlocksTouchOnlyThemselvesAndBodyVelocities) {
  for (const bool projected : {true, false}) {
    SCOPED_TRACE(projected ? "projected friction" : "bilinear friction");
    // The projected rows at a scale that puts every random pair outside the ball (sliding), where they are regular;
    // inside, a sticking pair's rows read only its rates, and the jointed robot's are then redundant (rank 262 of 267).
    const FrictionForm form{projected, 50.0};
    ExpectCondensableBlocksAreLocal(test_models::SphereOnTwoSpheres(), 21, form);
    ExpectCondensableBlocksAreLocal(test_models::BoxAndSuperellipsoid(), 22, form);
    ExpectCondensableBlocksAreLocal(test_models::JointedRobot(), 23, form);
  }
}

TEST(StepProblemJacobian, SparseAssemblyWithSeparatedFrictionRows) {
  ExpectJacobianMatchesFiniteDifferences(test_models::SphereOnTwoSpheres(), 5, true);
  ExpectJacobianMatchesFiniteDifferences(test_models::BoxAndSuperellipsoid(), 6, true);
  ExpectJacobianMatchesFiniteDifferences(test_models::PrismOnGround(7), 7, true);
}

// With projected multipliers the friction rows take the slip speed as max(sigma, 0) (a negative iterate would make
// friction push along the slip); the plain rows and the raw rows (Ipopt's, the independent NCP check's) keep sigma.
TEST(StepProblem, FrictionRowsClampANegativeSlipSpeedButRawRowsDoNot) {
  const Model model = test_models::SphereOnTwoSpheres();
  StepProblems problems(model);
  problems.SetFrictionForm(FrictionForm{/*projected=*/false, 1.0});  // the rows that read sigma
  const StepProblem& problem = problems.paper;
  problems.kinematics.BeginStep(State::Initial(model), 0.01, nullptr);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd z(problem.size());
  for (int i = 0; i < z.size(); ++i) z[i] = u(rng);
  problems.layout.ResetTangentAxes(z);
  const PairBlock& blk = problems.layout.blocks()[0];
  const int friction_row = blk.offset + pair_index::kSt;
  Eigen::VectorXd at_zero = z, negative = z, Phi_zero, Phi_negative;
  at_zero[blk.sigma()] = 0.0;
  negative[blk.sigma()] = -0.3;
  NcpEvalMode projected;
  projected.project_multipliers = true;
  problem.Evaluate(at_zero, projected, &Phi_zero, nullptr);
  problem.Evaluate(negative, projected, &Phi_negative, nullptr);
  EXPECT_EQ(Phi_zero[friction_row], Phi_negative[friction_row]);
  problem.Evaluate(negative, NcpEvalMode(), &Phi_negative, nullptr);  // plain rows: sigma itself
  EXPECT_NEAR(Phi_negative[friction_row] - Phi_zero[friction_row], -0.3 * z[friction_row], 1e-12);
  NcpEvalMode raw;
  raw.raw = true;
  raw.project_multipliers = true;
  problem.Evaluate(at_zero, raw, &Phi_zero, nullptr);
  problem.Evaluate(negative, raw, &Phi_negative, nullptr);
  EXPECT_NEAR(Phi_negative[friction_row] - Phi_zero[friction_row], -0.3 * z[friction_row], 1e-12);
}

TEST(StepProblem, LayoutCountsUnknownsAndRowsOfEveryPair) {
  const Model model = test_models::BoxAndSuperellipsoid();
  const StepLayout layout(model);
  // 2 moving bodies x 6; pairs: box-super (13 + 6 + 1 + 2), box-ground (13 + 6 + 1 + 2), super-ground (13 + 1 + 1 + 2)
  EXPECT_EQ(layout.size(), 12 + 22 + 22 + 17);
  // Rolling resistance adds its two fractions to a pair, as equations (the slip rows), none without it.
  const StepLayout rolling(WithRollingResistance(model, 0.01));
  EXPECT_EQ(rolling.size(), layout.size() + 3 * 2);
  for (const PairBlock& blk : rolling.blocks()) {
    EXPECT_EQ(blk.rolling, 2);
    EXPECT_EQ(rolling.row_kinds()[blk.roll()], RowKind::kEquation);
    EXPECT_EQ(rolling.row_kinds()[blk.sigma()], RowKind::kComplementarity);
  }
  for (const PairBlock& blk : layout.blocks()) EXPECT_EQ(blk.rolling, 0);
}

}  // namespace
}  // namespace implicit_sim
