// Joints: URDF joints as bilateral constraints inside the step NCP. Physics against closed forms and an
// independent integration, limits, friction through contact, actuation, and the loader's joint model.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/model/joints.h"
#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

using testing_support::RunScene;
using testing_support::ScenePath;


double TotalEnergy(const Model& model, const State& state) {
  double potential = 0.0;
  for (int k = 0; k < model.num_moving(); ++k) {
    potential -= model.bodies[model.moving_bodies[k]].mass * model.gravity_W.dot(state.q.segment<3>(Model::q_offset(k)));
  }
  return KineticEnergy(model, state) + potential;
}

// Arithmetic-geometric mean: the exact pendulum period is T0 / AGM(1, cos(theta0 / 2)).
double Agm(double a, double b) {
  for (int i = 0; i < 40; ++i) {
    const double m = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = m;
  }
  return a;
}

// Times of the downward zero crossings of joint 0 (linear interpolation between step ends).
struct Crossings {
  std::vector<double> times;
  double max_position_error = 0.0, max_angle_error = 0.0, energy_spread = 0.0;
  int nonconverged = 0;
};

Crossings RunPendulum(const Model& model, const StepperOptions& options, double duration) {
  const double h = options.h;
  Crossings out;
  State state0 = State::Initial(model);
  const double energy0 = TotalEnergy(model, state0);
  double previous = JointPosition(model, state0, 0);
  RunScene(model, options, duration, [&](const Model& m, const State& s, const Data&, const StepReport& r) {
    out.nonconverged += !r.converged;
    out.max_position_error = std::max(out.max_position_error, r.joint_position_error);
    out.max_angle_error = std::max(out.max_angle_error, r.joint_angle_error);
    out.energy_spread = std::max(out.energy_spread, std::abs(TotalEnergy(m, s) - energy0));
    const double q = JointPosition(m, s, 0);
    if (previous > 0.0 && q <= 0.0) out.times.push_back(s.t - h + h * previous / (previous - q));
    previous = q;
  });
  return out;
}

TEST(Joints, PendulumPeriodMatchesTheExactFiniteAmplitudePeriodAndTheJointDoesNotDrift) {
  const Model model = LoadSceneFromFile(ScenePath("pendulum.urdf"));
  ASSERT_EQ(model.joints.size(), 1u);
  const double m = 1.0, r = 0.05, L = 1.0, g = 9.81, theta0 = 5.0 * kPi / 180.0;
  const double I_pivot = 0.4 * m * r * r + m * L * L;
  const double T_exact = 2.0 * kPi * std::sqrt(I_pivot / (m * g * L)) / Agm(1.0, std::cos(theta0 / 2.0));
  StepperOptions options;
  options.h = 0.001;
  const Crossings run = RunPendulum(model, options, 10.0);
  ASSERT_GE(run.times.size(), 4u);
  const double period = (run.times.back() - run.times.front()) / (run.times.size() - 1);
  std::printf("[ joints ] pendulum period %.7f s, exact %.7f s (relative error %.2e); drift %.2e m, %.2e rad; "
              "energy spread %.2e J\n", period, T_exact, period / T_exact - 1.0, run.max_position_error,
              run.max_angle_error, run.energy_spread);
  EXPECT_EQ(run.nonconverged, 0);
  EXPECT_LT(std::abs(period / T_exact - 1.0), 0.005);  // the bar of doc/scenes.md's joint table
  EXPECT_LT(std::abs(period / T_exact - 1.0), 1e-4);   // what the method achieves at h = 0.001
  EXPECT_LE(run.max_position_error, 1e-8);
  EXPECT_LE(run.max_angle_error, 1e-8);
  // Symplectic (SHAKE) forces: the energy oscillates by O(h) and does not decay; m g L (1 - cos theta0) = 0.0373 J.
  EXPECT_LT(run.energy_spread, 1e-3);
}

// The RATTLE step (the joint rates hold at the end of its velocity stage): the energy spread is O(h^2), 100 times
// smaller at h = 0.001 than at 0.01 (the paper's SHAKE step: O(h), 10 times); the period meets the same bars.
TEST(Joints, RattlePendulumEnergySpreadIsSecondOrderAndItsPeriodExact) {
  const Model model = LoadSceneFromFile(ScenePath("pendulum.urdf"));
  const double m = 1.0, r = 0.05, L = 1.0, g = 9.81, theta0 = 5.0 * kPi / 180.0;
  const double I_pivot = 0.4 * m * r * r + m * L * L;
  const double T_exact = 2.0 * kPi * std::sqrt(I_pivot / (m * g * L)) / Agm(1.0, std::cos(theta0 / 2.0));
  const Crossings coarse = RunPendulum(model, testing_support::RattleOptions(0.01), 10.0);
  const Crossings fine = RunPendulum(model, testing_support::RattleOptions(0.001), 10.0);
  ASSERT_GE(fine.times.size(), 4u);
  const double period = (fine.times.back() - fine.times.front()) / (fine.times.size() - 1);
  std::printf("[ joints ] RATTLE pendulum: energy spread %.2e J at h = 0.01, %.2e J at h = 0.001 (ratio %.2f); period "
              "error %.2e; drift %.2e m\n", coarse.energy_spread, fine.energy_spread,
              coarse.energy_spread / fine.energy_spread, period / T_exact - 1.0, fine.max_position_error);
  EXPECT_EQ(coarse.nonconverged + fine.nonconverged, 0);
  EXPECT_GE(coarse.energy_spread / fine.energy_spread, 99.0);  // the bar: 100x (O(h^2))
  EXPECT_LT(std::abs(period / T_exact - 1.0), 1e-4);
  EXPECT_LE(fine.max_position_error, 1e-8);
  EXPECT_LE(fine.max_angle_error, 1e-8);
}

// The double pendulum in absolute angles phi1, phi2 of its two rods (Lagrange's equations, the bobs' own rotational
// inertia included), integrated by RK4 with a small step: the reference for the first second, before chaos grows.
struct DoublePendulum {
  double m = 1.0, L = 0.5, I = 0.001, g = 9.81;
  Eigen::Vector4d Rate(const Eigen::Vector4d& x) const {  // (phi1, phi2, phi1', phi2')
    const double d = x[0] - x[1];
    Eigen::Matrix2d M;
    M << 2 * m * L * L + I, m * L * L * std::cos(d), m * L * L * std::cos(d), m * L * L + I;
    const Eigen::Vector2d Q(-2 * m * g * L * std::sin(x[0]) - m * L * L * std::sin(d) * x[3] * x[3],
                            -m * g * L * std::sin(x[1]) + m * L * L * std::sin(d) * x[2] * x[2]);
    const Eigen::Vector2d acc = M.ldlt().solve(Q);
    return Eigen::Vector4d(x[2], x[3], acc[0], acc[1]);
  }
  Eigen::Vector4d Integrate(Eigen::Vector4d x, double duration, double dt) const {
    for (long i = 0; i < std::lround(duration / dt); ++i) {
      const Eigen::Vector4d k1 = Rate(x), k2 = Rate(x + 0.5 * dt * k1), k3 = Rate(x + 0.5 * dt * k2),
                            k4 = Rate(x + dt * k3);
      x += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    return x;
  }
};

TEST(Joints, DoublePendulumFollowsLagrangesEquationsAndItsJointsDoNotDrift) {
  const Model model = LoadSceneFromFile(ScenePath("double_pendulum.urdf"));
  ASSERT_EQ(model.joints.size(), 2u);
  EXPECT_EQ(model.joints[1].parent, model.joints[0].child);
  EXPECT_TRUE(model.pairs.empty());  // the two bobs are joined: no contact pair between them
  const DoublePendulum reference;
  const double energy0 = TotalEnergy(model, State::Initial(model));
  double worst_angle = 0.0, energy_spread = 0.0, position_error = 0.0, angle_error = 0.0;
  int nonconverged = 0;
  Eigen::Vector4d x(kPi / 2.0, kPi / 2.0, 0.0, 0.0);
  RunScene(model, 0.001, 10.0, [&](const Model& m, const State& s, const Data&, const StepReport& r) {
    nonconverged += !r.converged;
    position_error = std::max(position_error, r.joint_position_error);
    angle_error = std::max(angle_error, r.joint_angle_error);
    energy_spread = std::max(energy_spread, std::abs(TotalEnergy(m, s) - energy0));
    if (s.t > 1.0 + 1e-9) return;
    x = reference.Integrate(x, 0.001, 1e-5);
    const double phi1 = JointPosition(m, s, 0), phi2 = phi1 + JointPosition(m, s, 1);
    worst_angle = std::max({worst_angle, std::abs(std::remainder(phi1 - x[0], 2 * kPi)),
                            std::abs(std::remainder(phi2 - x[1], 2 * kPi))});
  });
  std::printf("[ joints ] double pendulum: largest angle error over the first 1 s %.2e rad; energy spread over 10 s "
              "%.3e J (of m g L = %.3f J); drift %.2e m, %.2e rad\n", worst_angle, energy_spread, 9.81 * 0.5,
              position_error, angle_error);
  EXPECT_EQ(nonconverged, 0);
  EXPECT_LT(worst_angle, 0.02);  // first order in h: about 1e-2 rad at h = 0.001
  EXPECT_LE(position_error, 1e-8);
  EXPECT_LE(angle_error, 1e-8);
  EXPECT_LT(energy_spread, 0.05 * 9.81 * 0.5);  // bounded (symplectic), no decay
}

TEST(Joints, RevoluteLimitStopsTheBarWithoutOvershootAndHoldsItAgainstGravity) {
  const Model model = LoadSceneFromFile(ScenePath("limit_stop.urdf"));
  const Joint& joint = model.joints[0];
  ASSERT_TRUE(joint.limited);
  double highest = -10.0, lowest = 10.0, limit_effort = 0.0;
  int steps_at_limit = 0;
  const auto stats = RunScene(model, 0.001, 1.5, [&](const Model& m, const State& s, const Data& d,
                                                     const StepReport&) {
    const double q = JointPosition(m, s, 0);
    highest = std::max(highest, q);
    lowest = std::min(lowest, q);
    limit_effort = d.joint_limit_effort[0];
    steps_at_limit += q > joint.upper - 1e-9;
  });
  const double expected = -1.0 * 9.81 * 0.3 * std::sin(0.3);  // the bar's weight about the hinge at -0.3 rad
  std::printf("[ joints ] limit stop: highest position %.17g (upper %.17g), resting limit effort %.6f N m "
              "(expected %.6f)\n", highest, joint.upper, limit_effort, expected);
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_LE(highest, joint.upper + 1e-10);  // no step end past the limit (but by the solver tolerance)
  EXPECT_GE(lowest, joint.lower - 1e-10);
  EXPECT_GT(steps_at_limit, 1000);  // it reached the stop and stayed (inelastic limit impulse)
  EXPECT_NEAR(limit_effort, expected, 1e-6);
}

TEST(Joints, TwoLinkArmPushesAnEllipsoidWithoutInterpenetrationCertifiedIndependently) {
  const Model model = LoadSceneFromFile(ScenePath("arm_push.urdf"));
  const int egg = model.velocity_slot[model.FindBody("egg")];
  const int forearm_egg = model.PairIndex(model.FindBody("forearm"), model.FindBody("egg"));
  ASSERT_GE(forearm_egg, 0);
  EXPECT_LT(model.PairIndex(model.FindBody("upper_arm"), model.FindBody("forearm")), 0);  // joined: no pair
  const State start = State::Initial(model);
  double worst_bound = 0.0, max_push = 0.0, position_error = 0.0, angle_error = 0.0;
  int certified = 0, step = 0;
  State end;
  const auto stats = RunScene(model, 0.001, 1.0, [&](const Model& m, const State& s, const Data& d,
                                                     const StepReport& r) {
    position_error = std::max(position_error, r.joint_position_error);
    angle_error = std::max(angle_error, r.joint_angle_error);
    max_push = std::max(max_push, d.contacts[forearm_egg].normal_force);
    end = s;
    if (++step % 5 != 0) return;  // every fifth step end: the oracle's support values are the costly part
    for (const ContactResult& c : d.contacts) {  // near pairs: the plane of the solver's contact certifies them
      if (c.gap > 1e-3) continue;
      const ContactPair& pair = m.pairs[c.pair];
      worst_bound = std::max(worst_bound, PenetrationBound(m.shape(pair.geom1), s.X_WB(m, pair.body1),
                                                           m.shape(pair.geom2), s.X_WB(m, pair.body2),
                                                           c.p_WA2, c.n_W));
      ++certified;
    }
  });
  const double moved = (end.q.segment<3>(Model::q_offset(egg)) - start.q.segment<3>(Model::q_offset(egg))).norm();
  std::printf("[ joints ] arm push: egg moved %.3f m, largest forearm push %.3f N, penetration bound %.2e m over %d "
              "near pairs, drift %.2e m %.2e rad\n", moved, max_push, worst_bound, certified, position_error,
              angle_error);
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_GT(moved, 0.3);
  EXPECT_GT(max_push, 0.1);
  EXPECT_GT(certified, 300);
  EXPECT_LE(worst_bound, 1e-8);
  EXPECT_LE(position_error, 1e-8);
  EXPECT_LE(angle_error, 1e-8);
}

// Lifts for 0.8 s and returns how far the ball dropped relative to the palm (m).
double GripperSlip(const std::string& grip) {
  std::string urdf;
  {
    std::ifstream in(ScenePath("gripper_lift.urdf"));
    urdf.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  for (const auto& [from, to] : {std::make_pair(std::string("effort=\"2.0\""), "effort=\"" + grip + "\""),
                                 std::make_pair(std::string("effort=\"-2.0\""), "effort=\"-" + grip + "\"")}) {
    urdf.replace(urdf.find(from), from.size(), to);
  }
  const Model model = LoadSceneFromString(urdf, "gripper_lift");
  const int palm = model.velocity_slot[model.FindBody("palm")], ball = model.velocity_slot[model.FindBody("ball")];
  State state = State::Initial(model);
  const double offset0 = state.q[Model::q_offset(ball) + 2] - state.q[Model::q_offset(palm) + 2];
  int nonconverged = 0;
  const auto stats = RunScene(model, 0.001, 0.8, [&](const Model&, const State& s, const Data&, const StepReport& r) {
    nonconverged += !r.converged;
    state = s;
  });
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_GT(state.q[Model::q_offset(palm) + 2] - 0.56, 0.5);  // the palm rose (1.2 g - g = 0.2 g upwards: 0.63 m if it holds)
  return offset0 - (state.q[Model::q_offset(ball) + 2] - state.q[Model::q_offset(palm) + 2]);
}

TEST(Joints, PrismaticGripperHoldsTheSphereExactlyWhenFrictionCanCarryIt) {
  // The ball needs m (g + a) = 1.2 m g = 1.177 N of friction from two contacts of mu F each (mu = 0.5).
  const double hold = GripperSlip("2.0");   // 2 mu F = 2.0 N > 1.177 N: sticks
  const double slip = GripperSlip("0.8");   // 2 mu F = 0.8 N < 1.177 N: slides down between the fingers
  std::printf("[ joints ] gripper: the ball dropped %.3e m relative to the palm with 2 N per finger, %.3f m with "
              "0.8 N\n", hold, slip);
  EXPECT_LT(std::abs(hold), 1e-6);
  EXPECT_GT(slip, 0.05);
}

// The pendulum after `steps` steps of 1 ms under a constant commanded hinge effort (N m).
State PendulumUnderEffort(const Model& model, double effort, int steps) {
  StepperOptions options;
  options.h = 0.001;
  Data data(model);
  State state = State::Initial(model);
  Eigen::VectorXd efforts = Eigen::VectorXd::Constant(1, effort), wrench(6);
  for (int i = 0; i < steps; ++i) {
    wrench.setZero();
    AddJointEffortWrench(model, state, efforts, &wrench);
    EXPECT_TRUE(Step(model, options, &state, &data, &wrench).converged);
  }
  return state;
}

TEST(Joints, AJointEffortEqualToTheGravityTorqueHoldsThePendulumAndIsClampedToItsLimit) {
  const Model model = LoadSceneFromFile(ScenePath("pendulum.urdf"));
  // Static: the effort balances the weight's torque m g L sin(theta0) about the hinge.
  const State held = PendulumUnderEffort(model, 9.81 * std::sin(5.0 * kPi / 180.0), 1000);
  EXPECT_NEAR(JointPosition(model, held, 0), 5.0 * kPi / 180.0, 1e-9);
  EXPECT_NEAR(JointVelocity(model, held, 0), 0.0, 1e-9);
  // 1000 N m is clamped to the URDF <limit effort="100">: the same motion as 100 N m, q' ~ 100 / I_pivot t.
  const State clamped = PendulumUnderEffort(model, 1e3, 100), at_limit = PendulumUnderEffort(model, 100.0, 100);
  EXPECT_EQ(clamped.q, at_limit.q);
  EXPECT_EQ(clamped.v, at_limit.v);
  EXPECT_NEAR(JointVelocity(model, clamped, 0), 100.0 / 1.001 * 0.1, 0.5);  // less the weight: 0.24 rad/s
  Eigen::VectorXd wrong(2), wrench(6);
  EXPECT_THROW(AddJointEffortWrench(model, State::Initial(model), wrong, &wrench), std::invalid_argument);
  Eigen::VectorXd nan_effort(1);
  nan_effort[0] = std::nan("");
  EXPECT_THROW(AddJointEffortWrench(model, State::Initial(model), nan_effort, &wrench), std::invalid_argument);
}

TEST(Joints, LoaderBuildsTheJointTreeWithFramesLimitsDynamicsAndStarts) {
  const Model model = test_models::JointedRobot();
  ASSERT_EQ(model.joints.size(), 4u);  // shoulder, slide, weld (between moving bodies) and axle; not the fixed post
  const Joint& shoulder = model.joints[model.FindJoint("shoulder")];
  EXPECT_EQ(shoulder.type, JointType::kRevolute);
  EXPECT_EQ(shoulder.parent, -1);
  EXPECT_TRUE(shoulder.limited);
  EXPECT_DOUBLE_EQ(shoulder.lower, -0.5);
  EXPECT_DOUBLE_EQ(shoulder.offset, 0.35);  // measured from the middle of [-0.5, 1.2]
  EXPECT_DOUBLE_EQ(shoulder.damping, 0.3);
  EXPECT_DOUBLE_EQ(shoulder.friction, 0.4);
  EXPECT_DOUBLE_EQ(shoulder.effort_limit, 50.0);
  const Joint& weld = model.joints[model.FindJoint("weld")];
  EXPECT_EQ(weld.type, JointType::kFixed);
  EXPECT_EQ(weld.parent, model.FindBody("slider"));
  const Joint& axle = model.joints[model.FindJoint("axle")];
  EXPECT_EQ(axle.type, JointType::kContinuous);
  EXPECT_TRUE(model.bodies[axle.parent].is_fixed);
  EXPECT_FALSE(axle.limited);
  // Parents before children.
  EXPECT_LT(model.FindJoint("shoulder"), model.FindJoint("slide"));
  EXPECT_LT(model.FindJoint("slide"), model.FindJoint("weld"));
  // The initial state: the joints hold exactly and have the given positions and velocities.
  const State state = State::Initial(model);
  double position_error, angle_error;
  JointDrift(model, state, &position_error, &angle_error);
  EXPECT_LT(position_error, 1e-14);
  EXPECT_LT(angle_error, 1e-14);
  const std::pair<const char*, std::pair<double, double>> starts[] = {
      {"shoulder", {0.3, -0.7}}, {"slide", {0.05, 0.2}}, {"axle", {1.0, 3.0}}};
  for (const auto& [name, expected] : starts) {
    SCOPED_TRACE(name);
    EXPECT_NEAR(JointPosition(model, state, model.FindJoint(name)), expected.first, 1e-12);
    EXPECT_NEAR(JointVelocity(model, state, model.FindJoint(name)), expected.second, 1e-12);
  }
  EXPECT_NEAR(JointVelocity(model, state, model.FindJoint("weld")), 0.0, 1e-15);
  // Joined bodies form no contact pair; nor, without self-collision (the default, as Gazebo's), do other links of
  // one robot; with it they do. The wheel on its fixed post is another robot and meets the arm.
  EXPECT_LT(model.PairIndex(model.FindBody("base"), model.FindBody("slider")), 0);
  EXPECT_LT(model.PairIndex(model.FindBody("slider"), model.FindBody("finger")), 0);
  EXPECT_LT(model.PairIndex(model.FindBody("base"), model.FindBody("finger")), 0);
  EXPECT_GE(model.PairIndex(model.FindBody("wheel"), model.FindBody("finger")), 0);
  std::string self_colliding = test_models::kJointedRobotUrdf;
  self_colliding.insert(self_colliding.find("</implicit_sim>"), "<self_collide link=\"finger\"/>");
  const Model with_self = LoadSceneFromString(self_colliding, "jointed_robot");
  EXPECT_LT(with_self.PairIndex(with_self.FindBody("base"), with_self.FindBody("slider")), 0);
  EXPECT_GE(with_self.PairIndex(with_self.FindBody("base"), with_self.FindBody("finger")), 0);
}

// Dense with every pair, and with the broad phase and the sparse solve (KLU): the joint blocks stay in every NCP
// while pairs come and go.
TEST(Joints, EveryJointKindHoldsAtTheStepEndThroughContactFrictionAndLimitsDenseAndSparse) {
  const Model model = test_models::JointedRobot();
  for (const auto selection : {Data::PairSelection::kAllPairs, Data::PairSelection::kBroadPhase}) {
    SCOPED_TRACE(selection == Data::PairSelection::kAllPairs ? "all pairs, dense" : "broad phase, sparse");
    double position_error = 0.0, angle_error = 0.0;
    int touching_steps = 0;
    const auto stats = RunScene(
        model, 0.002, 2.0,
        [&](const Model&, const State&, const Data&, const StepReport& r) {
          position_error = std::max(position_error, r.joint_position_error);
          angle_error = std::max(angle_error, r.joint_angle_error);
          touching_steps += r.active_contacts > 0;
        },
        selection);
    std::printf("[ joints ] jointed robot, 2 s: drift %.2e m, %.2e rad; %d non-converged steps, %d steps with "
                "contact\n", position_error, angle_error, stats.nonconverged, touching_steps);
    EXPECT_EQ(stats.nonconverged, 0);
    EXPECT_LE(position_error, 1e-8);
    EXPECT_LE(angle_error, 1e-8);
    EXPECT_GT(touching_steps, 50);
  }
}

TEST(Joints, IpoptAgreesWithNewtonOnTheGripperWithItsJointRowsAndContacts) {
  const Model model = LoadSceneFromFile(ScenePath("gripper_lift.urdf"));
  State newton_state = State::Initial(model), ipopt_state = newton_state;
  Data newton_data(model), ipopt_data(model);
  StepperOptions newton, ipopt;
  newton.h = ipopt.h = 0.001;
  ipopt.solver = StepperOptions::Solver::kIpopt;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(Step(model, newton, &newton_state, &newton_data).converged);
    ASSERT_TRUE(Step(model, ipopt, &ipopt_state, &ipopt_data).converged);
    EXPECT_LT((newton_state.v - ipopt_state.v).lpNorm<Eigen::Infinity>(), 1e-4);
  }
}

}  // namespace
}  // namespace implicit_sim
