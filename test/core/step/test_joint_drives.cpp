// Joint drives (joints.h, JointDrive; rows/drive_rows.h): PD drives evaluated implicitly at the end of the step, clamped
// to the effort limit by a box law. The closed-form damped oscillator, stiffness at any gain, saturation, a gripper
// that closes and lifts by position, refused drives, bit-identity without drives, drives turned on and off, and a
// restored warm start with drives.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/step/step_health.h"
#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

using testing_support::HashStep;
using testing_support::ScenePath;
using Scheme = StepperOptions::Scheme;

const char* SchemeName(Scheme scheme) { return scheme == Scheme::kRattle ? "rattle" : "paper"; }

// A rotor: one link on the revolute joint 'hinge' about z through its centre of mass, without gravity, so that
// I th'' = effort with I = kRotorInertia about the axis. Limits +-3 rad.
constexpr double kRotorInertia = 0.02;  // kg m^2
const char* const kRotorUrdf = R"(<?xml version="1.0"?>
<robot name="rotor">
  <implicit_sim gravity="0 0 0"/>
  <link name="world"/>
  <link name="rotor">
    <inertial><mass value="1"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><geometry><sphere radius="0.1"/></geometry></collision>
  </link>
  <joint name="hinge" type="revolute"><parent link="world"/><child link="rotor"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="100"/></joint>
</robot>
)";

// The rotor with Joint::effort_limit = effort_limit (N m; 0: no clamp).
Model Rotor(double effort_limit) {
  Model model = LoadSceneFromString(kRotorUrdf, "rotor");
  model.joints[0].effort_limit = effort_limit;
  return model;
}

StepperOptions Options(Scheme scheme, double h) {
  StepperOptions options;
  options.scheme = scheme;
  options.h = h;
  return options;
}

// I th'' + kd th' + kp (th - target) = 0 from rest at theta0 (rad): target + Re(A e^(r1 t) + B e^(r2 t)) with the
// roots r1, r2 of I r^2 + kd r + kp (distinct: not critically damped).
double DampedOscillator(double t, double theta0, double target, double kp, double kd) {
  using Complex = std::complex<double>;
  const Complex root = std::sqrt(Complex(kd * kd - 4.0 * kp * kRotorInertia));
  const Complex r1 = (-kd + root) / (2.0 * kRotorInertia), r2 = (-kd - root) / (2.0 * kRotorInertia);
  const double e0 = theta0 - target;
  return target + (-e0 * r2 / (r1 - r2) * std::exp(r1 * t) + e0 * r1 / (r1 - r2) * std::exp(r2 * t)).real();
}

// The largest deviation (rad) over `duration` s of the rotor, driven from rest at 0 to 0.5 rad, from the closed form.
double OscillatorError(Scheme scheme, double h, double kp, double kd, double duration) {
  const Model model = Rotor(0.0);
  const StepperOptions options = Options(scheme, h);
  Data data(model);
  data.joint_drives[0] = {0.5, 0.0, kp, kd};
  State state = State::Initial(model);
  double worst = 0.0;
  for (long i = 0; i < std::lround(duration / h); ++i) {
    EXPECT_TRUE(Step(model, options, &state, &data).converged);
    worst = std::max(worst, std::abs(JointPosition(model, state, 0) - DampedOscillator(state.t, 0.0, 0.5, kp, kd)));
  }
  return worst;
}

TEST(JointDrives, RevoluteDriveFollowsTheClosedFormDampedOscillatorToFirstOrder) {
  struct Gains {
    const char* name;
    double kp, kd;  // N m/rad, N m s/rad: omega0 = 10 rad/s, damping ratio 0.2 and 2.5
  };
  for (const Gains& gains : {Gains{"underdamped", 2.0, 0.08}, Gains{"overdamped", 2.0, 1.0}}) {
    for (const Scheme scheme : {Scheme::kPaper, Scheme::kRattle}) {
      SCOPED_TRACE(std::string(gains.name) + ", " + SchemeName(scheme));
      const double hs[3] = {4e-3, 2e-3, 1e-3};
      double errors[3];
      for (int k = 0; k < 3; ++k) errors[k] = OscillatorError(scheme, hs[k], gains.kp, gains.kd, 1.5);
      std::printf("[ drives ] %s oscillator, %s: max error %.3e, %.3e, %.3e rad at h = 4, 2, 1 ms (ratios %.3f, "
                  "%.3f)\n", gains.name, SchemeName(scheme), errors[0], errors[1], errors[2], errors[0] / errors[1],
                  errors[1] / errors[2]);
      for (int k = 0; k < 2; ++k) {  // first order: halving h halves the error
        EXPECT_GT(errors[k] / errors[k + 1], 1.8);
        EXPECT_LT(errors[k] / errors[k + 1], 2.2);
      }
      EXPECT_LT(errors[2], 0.01 * 0.5);  // within 1 % of the 0.5 rad travel at h = 1 ms
    }
  }
}

// 1/2 I w^2 + 1/2 kp (q - target)^2 of the rotor (J).
double RotorEnergy(const Model& model, const State& state, const JointDrive& drive) {
  const double w = JointVelocity(model, state, 0), e = JointPosition(model, state, 0) - drive.position_target;
  return 0.5 * kRotorInertia * w * w + 0.5 * drive.stiffness * e * e;
}

TEST(JointDrives, AStiffDriveIsStableAtAnyGainAndItsEnergyNeverGrows) {
  const Model model = Rotor(0.0);
  for (const Scheme scheme : {Scheme::kPaper, Scheme::kRattle}) {
    for (const double kd : {0.0, 1e9}) {
      SCOPED_TRACE(std::string(SchemeName(scheme)) + (kd > 0.0 ? ", kd = 1e9" : ", kd = 0"));
      const StepperOptions options = Options(scheme, 0.01);
      Data data(model);
      const JointDrive drive{1.0, 0.0, 1e9, kd};
      data.joint_drives[0] = drive;
      State state = State::Initial(model);
      double energy = RotorEnergy(model, state, drive), previous_q = 0.0;
      double error_after_3 = 0.0, speed_after_3 = 0.0;
      for (int i = 1; i <= 50; ++i) {
        ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
        const double next = RotorEnergy(model, state, drive), q = JointPosition(model, state, 0);
        EXPECT_LE(next, energy * (1.0 + 1e-12) + 1e-9) << "step " << i;
        EXPECT_LE(q, 1.0 + 1e-6) << "step " << i;  // no overshoot (implicit Euler's is about 1 / (h^2 kp / I))
        if (kd > 0.0) {
          EXPECT_GE(q, previous_q) << "step " << i;  // overdamped: a monotone approach
        }
        energy = next;
        previous_q = q;
        if (i == 3) {
          error_after_3 = std::abs(q - 1.0);
          speed_after_3 = std::abs(JointVelocity(model, state, 0));
        }
      }
      std::printf("[ drives ] kp = 1e9, kd = %g, h = 10 ms, %s: after 3 steps |q - target| %.2e rad, |qdot| %.2e "
                  "rad/s; after 50 steps q = %.6f rad, energy %.3e J\n", kd, SchemeName(scheme), error_after_3,
                  speed_after_3, previous_q, energy);
      if (kd == 0.0) {  // at the target and at rest within three steps
        EXPECT_LT(error_after_3, 1e-6);
        EXPECT_LT(speed_after_3, 1e-3);
      } else {  // the overdamped crawl kd q' = kp (target - q): 1 - exp(-0.5) = 0.393 after 0.5 s
        EXPECT_NEAR(previous_q, 1.0 - std::exp(-0.5), 0.01);
      }
    }
  }
}

TEST(JointDrives, TheEffortLimitCapsTheDriveAndTheRotorAcceleratesAtTheLimit) {
  constexpr double kLimit = 0.5;  // N m
  const Model model = Rotor(kLimit);
  for (const Scheme scheme : {Scheme::kPaper, Scheme::kRattle}) {
    SCOPED_TRACE(SchemeName(scheme));
    const StepperOptions options = Options(scheme, 0.001);
    Data data(model);
    data.joint_drives[0] = {2.0, 0.0, 100.0, 1.0};  // 200 N m asked for at the start
    State state = State::Initial(model);
    double worst_effort = 0.0, worst_acceleration = 0.0;
    for (int i = 0; i < 100; ++i) {  // 0.1 s: q <= 0.25 rad, qdot <= 2.5 rad/s, so the law asks for > 100 N m
      const double w0 = JointVelocity(model, state, 0);
      ASSERT_TRUE(Step(model, options, &state, &data).converged);
      const double acceleration = (JointVelocity(model, state, 0) - w0) / options.h;
      worst_effort = std::max(worst_effort, std::abs(data.joint_drive_effort[0] / kLimit - 1.0));
      worst_acceleration = std::max(worst_acceleration, std::abs(acceleration * kRotorInertia / kLimit - 1.0));
    }
    std::printf("[ drives ] saturated, %s: effort %.17g N m (limit 0.5), largest relative error of the effort %.2e "
                "and of the acceleration %.2e\n", SchemeName(scheme), data.joint_drive_effort[0], worst_effort,
                worst_acceleration);
    EXPECT_LT(worst_effort, 1e-9);
    EXPECT_LT(worst_acceleration, 1e-9);
  }
}

// The gripper of scenes/gripper_lift.urdf without its constant efforts, driven by position: the fingers close on the
// ball towards a target 1 cm beyond contact, the squeeze capped at kSqueeze by their effort limit, for 0.3 s; then the
// lift tracks a ramp up by 0.1 m at 0.2 m/s (position and velocity targets), and holds.
// N per finger: 2 mu F = 5 N (mu = 0.5) carries the ball also through the ramp's start, where the velocity target's
// jump through kd = 60 N s/m accelerates the lift at up to 30 m/s^2 (with 3 N the ball slips 6e-5 m there).
constexpr double kSqueeze = 5.0;
struct GripperLift {
  double ball_rise = 0.0, slip = 0.0, penetration = 0.0, lift_error = 0.0, finger_effort = 0.0;
  int nonconverged = 0;
};

GripperLift RunGripperLift(Scheme scheme) {
  Model model = LoadSceneFromFile(ScenePath("gripper_lift.urdf"));
  for (Joint& joint : model.joints) joint.applied_effort = 0.0;
  const int lift = model.FindJoint("lift"), left = model.FindJoint("left_slide"), right = model.FindJoint("right_slide");
  model.joints[left].effort_limit = model.joints[right].effort_limit = kSqueeze;
  const int palm = model.velocity_slot[model.FindBody("palm")], ball = model.velocity_slot[model.FindBody("ball")];
  const StepperOptions options = Options(scheme, 0.001);
  Data data(model), check(model);
  data.joint_drives[left] = {0.01, 0.0, 1e4, 20.0};
  data.joint_drives[right] = {-0.01, 0.0, 1e4, 20.0};
  State state = State::Initial(model);
  GripperLift out;
  auto height = [&](int slot) { return state.q[Model::q_offset(slot) + 2]; };
  double ball0 = 0.0, offset0 = 0.0;
  for (int i = 1; i <= 1000; ++i) {
    const double t = i * options.h;  // the end of this step
    const double ramp = std::clamp(t - 0.3, 0.0, 0.5);
    data.joint_drives[lift] = {0.2 * ramp, ramp > 0.0 && ramp < 0.5 ? 0.2 : 0.0, 2000.0, 60.0};
    const StepReport report = Step(model, options, &state, &data);
    out.nonconverged += !report.converged;
    if (i == 300) {
      ball0 = height(ball);
      offset0 = height(ball) - height(palm);
    }
    if (i > 300) out.slip = std::max(out.slip, std::abs(height(ball) - height(palm) - offset0));
    if (i % 10 == 0) out.penetration = std::max(out.penetration, MaxPenetrationBound(model, state, 1e-9, &check));
  }
  out.ball_rise = height(ball) - ball0;
  out.lift_error = std::abs(JointPosition(model, state, lift) - 0.1);
  out.finger_effort = data.joint_drive_effort[left];
  return out;
}

TEST(JointDrives, TheGripperClosesOnTheBallByPositionAndLiftsItWithoutSlip) {
  for (const Scheme scheme : {Scheme::kPaper, Scheme::kRattle}) {
    SCOPED_TRACE(SchemeName(scheme));
    const GripperLift run = RunGripperLift(scheme);
    std::printf("[ drives ] gripper, %s: ball rose %.6f m, slip %.2e m, penetration bound %.2e m, lift off its "
                "target by %.2e m, finger squeeze %.6f N, %d non-converged steps\n", SchemeName(scheme),
                run.ball_rise, run.slip, run.penetration, run.lift_error, run.finger_effort, run.nonconverged);
    EXPECT_EQ(run.nonconverged, 0);
    EXPECT_GT(run.ball_rise, 0.095);  // the lift's 0.1 m less the sag m g / kp = 2 mm
    EXPECT_LT(run.slip, 1e-9);  // sticking: the solver's tolerance
    EXPECT_LT(run.penetration, 1e-6);
    EXPECT_NEAR(run.finger_effort, kSqueeze, 1e-9 * kSqueeze);  // saturated: the squeeze is the effort limit
  }
}

TEST(JointDrives, CheckJointDriveRefusesBadDrivesAndStepChangesNothing) {
  const Model model = test_models::JointedRobot();
  const int shoulder = model.FindJoint("shoulder"), weld = model.FindJoint("weld");
  ASSERT_TRUE(model.joints[shoulder].limited);
  ASSERT_FALSE(model.joints[weld].has_coordinate());
  struct Bad {
    const char* what;
    int joint;
    JointDrive drive;
  };
  const Bad bad[] = {{"NaN target", shoulder, {std::nan(""), 0.0, 10.0, 1.0}},
                     {"infinite velocity target", shoulder, {0.1, INFINITY, 10.0, 1.0}},
                     {"negative stiffness", shoulder, {0.1, 0.0, -1.0, 1.0}},
                     {"negative damping", shoulder, {0.1, 0.0, 1.0, -1.0}},
                     {"gain above the maximum", shoulder, {0.1, 0.0, 2.0 * kMaxJointDriveGain, 0.0}},
                     {"NaN gain", shoulder, {0.1, 0.0, std::nan(""), 0.0}},
                     {"drive on a fixed joint", weld, {0.0, 0.0, 10.0, 0.0}},
                     {"target above the upper limit", shoulder, {1.3, 0.0, 10.0, 0.0}},
                     {"target below the lower limit", shoulder, {-0.6, 0.0, 10.0, 0.0}}};
  const StepperOptions options = Options(Scheme::kRattle, 0.002);
  Data data(model);
  State state = State::Initial(model);
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged);
  for (const Bad& b : bad) {
    SCOPED_TRACE(b.what);
    std::string error;
    EXPECT_FALSE(CheckJointDrive(model.joints[b.joint], b.drive, &error));
    EXPECT_NE(error.find("'" + model.joints[b.joint].name + "'"), std::string::npos) << error;
    const State before = state;
    const Eigen::VectorXd z_before = data.z;
    data.joint_drives[b.joint] = b.drive;
    try {
      Step(model, options, &state, &data);
      ADD_FAILURE() << "Step accepted the drive";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + model.joints[b.joint].name + "'"), std::string::npos) << e.what();
    }
    EXPECT_EQ(state.t, before.t);
    EXPECT_EQ(state.q, before.q);
    EXPECT_EQ(state.v, before.v);
    EXPECT_EQ(data.z, z_before);
    EXPECT_TRUE(data.has_warm_start);
    data.joint_drives[b.joint] = JointDrive();
  }
  // Inactive drives are not checked against the limits (Data(model) leaves every target at 0), active ones at the
  // limit are accepted, and a wrongly sized drive vector is refused.
  EXPECT_TRUE(CheckJointDrive(model.joints[weld], JointDrive{0.3, 0.0, 0.0, 0.0}, nullptr));
  EXPECT_TRUE(CheckJointDrive(model.joints[shoulder], JointDrive{1.2, 0.0, kMaxJointDriveGain, 0.0}, nullptr));
  data.joint_drives.pop_back();
  EXPECT_THROW(Step(model, options, &state, &data), std::invalid_argument);
}

// A joint whose position is an angle without limits (continuous) is driven the shorter way round; a limited or a
// prismatic joint by the plain difference. The law clamps to the effort limit.
TEST(JointDrives, AContinuousJointIsDrivenTheShorterWayRound) {
  const Model model = test_models::JointedRobot();
  const Joint& axle = model.joints[model.FindJoint("axle")];
  const Joint& shoulder = model.joints[model.FindJoint("shoulder")];
  constexpr double kTwoPi = 6.28318530717958647692;
  EXPECT_EQ(axle.type, JointType::kContinuous);
  EXPECT_NEAR(JointDrivePositionError(axle, -3.0, 3.0), kTwoPi - 6.0, 1e-15);
  EXPECT_NEAR(JointDrivePositionError(axle, 3.0, -3.0), 6.0 - kTwoPi, 1e-15);
  EXPECT_EQ(JointDrivePositionError(axle, 0.5, 0.2), 0.5 - 0.2);
  EXPECT_EQ(JointDrivePositionError(shoulder, 1.0, -0.4), 1.0 + 0.4);
  EXPECT_EQ(JointDriveEffortAt(shoulder, JointDrive{1.0, 0.0, 1e3, 0.0}, 0.0, 0.0), shoulder.effort_limit);
  EXPECT_EQ(JointDriveEffortAt(axle, JointDrive{0.0, 2.0, 0.0, 3.0}, 0.0, 1.0), 3.0);  // no limit on the axle
  // The axle, starting at 1 rad, driven to -3 rad by position: the shorter way is forward through pi, by
  // 2 pi - 4 = 2.283 rad (overdamped: kp = 20 N m/rad, kd = 2 N m s/rad, I = 0.018 kg m^2).
  const StepperOptions options = Options(Scheme::kRattle, 0.002);
  Data data(model);
  const int a = model.FindJoint("axle");
  data.joint_drives[a] = {-3.0, 0.0, 20.0, 2.0};
  State state = State::Initial(model);
  double travel = 0.0;  // rad
  for (int i = 0; i < 1000; ++i) {
    const double q0 = JointPosition(model, state, a);
    ASSERT_TRUE(Step(model, options, &state, &data).converged);
    travel += JointDrivePositionError(axle, JointPosition(model, state, a), q0);  // the step's turn, unwrapped
  }
  std::printf("[ drives ] continuous axle: from 1 rad to %.9f rad, turned %.6f rad\n", JointPosition(model, state, a),
              travel);
  EXPECT_NEAR(JointPosition(model, state, a), -3.0, 1e-6);
  EXPECT_NEAR(travel, kTwoPi - 4.0, 1e-6);
}

// Hashes of `steps` steps of `model` from its initial state; with set_drives, every drive set to an inactive one
// (zero gains, nonzero targets) before each step.
std::vector<uint64_t> HashedRun(const Model& model, Scheme scheme, int steps, bool set_drives) {
  const StepperOptions options = Options(scheme, 0.002);
  Data data(model);
  State state = State::Initial(model);
  std::vector<uint64_t> hashes;
  for (int i = 0; i < steps; ++i) {
    if (set_drives) {
      for (JointDrive& drive : data.joint_drives) drive = {0.0, 0.5, 0.0, 0.0};
    }
    EXPECT_TRUE(Step(model, options, &state, &data).converged);
    hashes.push_back(HashStep(state, data));
    for (double effort : data.joint_drive_effort) EXPECT_EQ(effort, 0.0);
  }
  return hashes;
}

TEST(JointDrives, InactiveDrivesLeaveTheRunBitIdentical) {
  for (const char* scene : {"gripper_lift.urdf", "arm_push.urdf"}) {
    const Model model = LoadSceneFromFile(ScenePath(scene));
    for (const Scheme scheme : {Scheme::kPaper, Scheme::kRattle}) {
      SCOPED_TRACE(std::string(scene) + ", " + SchemeName(scheme));
      EXPECT_EQ(HashedRun(model, scheme, 300, false), HashedRun(model, scheme, 300, true));
    }
  }
}

// The gripper of scenes/gripper_lift.urdf with its constant efforts (a drive adds to them), drives turned on and off
// every 50 steps: none; fingers and lift; lift only; fingers only.
TEST(JointDrives, DrivesTurnOnAndOffBetweenStepsWithTheWarmStartCarriedOver) {
  const Model model = LoadSceneFromFile(ScenePath("gripper_lift.urdf"));
  const int lift = model.FindJoint("lift"), left = model.FindJoint("left_slide"), right = model.FindJoint("right_slide");
  for (const Scheme scheme : {Scheme::kPaper, Scheme::kRattle}) {
    for (const auto selection : {Data::PairSelection::kAllPairs, Data::PairSelection::kBroadPhase}) {
      SCOPED_TRACE(std::string(SchemeName(scheme)) +
                   (selection == Data::PairSelection::kBroadPhase ? ", broad phase" : ", all pairs"));
      const StepperOptions options = Options(scheme, 0.002);
      Data data(model, selection);
      const int undriven_base = data.layout.pair_base();
      State state = State::Initial(model);
      int cold_restarts = 0, toggle_iterations = 0, toggles = 0;
      double lift_speed = 0.0;
      for (int i = 0; i < 400; ++i) {
        const int phase = (i / 50) % 4;
        const bool fingers = phase == 1 || phase == 3, lifting = phase == 1 || phase == 2;
        data.joint_drives[left] = fingers ? JointDrive{0.01, 0.0, 1e3, 5.0} : JointDrive();
        data.joint_drives[right] = fingers ? JointDrive{-0.01, 0.0, 1e3, 5.0} : JointDrive();
        data.joint_drives[lift] = lifting ? JointDrive{0.0, 0.1, 0.0, 50.0} : JointDrive();
        const StepReport report = Step(model, options, &state, &data);
        ASSERT_TRUE(report.converged) << "step " << i;
        cold_restarts += report.cold_restarts;
        if (i % 50 == 0 && i > 0) {
          toggle_iterations = std::max(toggle_iterations, report.iterations);
          ++toggles;
        }
        EXPECT_EQ(data.layout.pair_base(), undriven_base + 2 * fingers + lifting) << "step " << i;
        EXPECT_EQ(data.z.size(), data.layout.size());
        if (!fingers) {
          EXPECT_EQ(data.joint_drive_effort[left], 0.0);
        }
        if (i == 349) lift_speed = JointVelocity(model, state, lift);
      }
      // The lift's velocity drive (50 N s/m) against its constant effort 4.709 N and the weight 0.4 kg g = 3.924 N:
      // 50 (0.1 - v) = -0.785 N at rest in the drive's frame, v = 0.1157 m/s.
      std::printf("[ drives ] on and off, %s: %d cold restarts over 400 steps, at most %d Newton iterations at the "
                  "%d toggles, lift at %.6f m/s (expected %.6f)\n", SchemeName(scheme), cold_restarts,
                  toggle_iterations, toggles, lift_speed, 0.1 + (4.70880 - 0.4 * 9.81) / 50.0);
      EXPECT_EQ(cold_restarts, 0);
      EXPECT_LE(toggle_iterations, 50);  // the squeeze jumps by up to 8 N at a toggle: a few dozen iterations
      EXPECT_NEAR(lift_speed, 0.1 + (4.70880 - 0.4 * 9.81) / 50.0, 1e-3);
    }
  }
}

TEST(JointDrives, ARestoredWarmStartWithDrivesContinuesBitIdenticallyOnAnyThreadCount) {
  const Model model = test_models::JointedRobot();
  const int shoulder = model.FindJoint("shoulder"), slide = model.FindJoint("slide"), axle = model.FindJoint("axle");
  for (const Scheme scheme : {Scheme::kPaper, Scheme::kRattle}) {
    SCOPED_TRACE(SchemeName(scheme));
    auto drive = [&](Data* data) {
      data->joint_drives[shoulder] = {0.8, 0.0, 200.0, 5.0};
      data->joint_drives[slide] = {0.1, 0.0, 500.0, 10.0};
      data->joint_drives[axle] = {0.0, 2.0, 0.0, 3.0};
    };
    auto run = [&](int steps, int threads, State* state, Data* data) {
      StepperOptions options = Options(scheme, 0.002);
      options.threads = threads;
      std::vector<uint64_t> hashes;
      for (int i = 0; i < steps; ++i) {
        EXPECT_TRUE(Step(model, options, state, data).converged);
        hashes.push_back(HashStep(*state, *data));
      }
      return hashes;
    };
    Data data(model);
    drive(&data);
    State state = State::Initial(model);
    run(100, 1, &state, &data);
    const State saved_state = state;
    WarmStart saved;
    SaveWarmStart(data, &saved);
    std::vector<int> driven = {shoulder, slide, axle};
    std::sort(driven.begin(), driven.end());
    EXPECT_EQ(saved.driven_joints, driven);
    const std::vector<uint64_t> continued = run(200, 1, &state, &data);
    // Into a new Data whose drives are off when it is restored (the layout follows the warm start, then the drives).
    Data fresh(model);
    RestoreWarmStart(model, saved, &fresh);
    EXPECT_EQ(fresh.layout.size(), data.layout.size());
    drive(&fresh);
    State fresh_state = saved_state;
    EXPECT_EQ(run(200, 3, &fresh_state, &fresh), continued);
    // A warm start with a joint that cannot be driven is refused and changes nothing.
    WarmStart wrong = saved;
    wrong.driven_joints = {model.FindJoint("weld")};
    const int size = fresh.layout.size();
    EXPECT_THROW(RestoreWarmStart(model, wrong, &fresh), std::invalid_argument);
    EXPECT_EQ(fresh.layout.size(), size);
  }
}

// A two-link arm about y, straight out along x: link 1 (1 kg, centre of mass 0.25 m out), link 2 (0.5 kg, 0.25 m past
// the elbow at 0.5 m). Held at 0 by stiff drives it sags by its weight over the stiffness; with the gravity
// feed-forward it holds exactly.
const char* const kHorizontalArmUrdf = R"(<?xml version="1.0"?>
<robot name="horizontal_arm">
  <link name="world"/>
  <link name="upper"><inertial><origin xyz="0.25 0 0"/><mass value="1"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <link name="fore"><inertial><origin xyz="0.25 0 0"/><mass value="0.5"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="world"/><child link="upper"/><origin xyz="0 0 1"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="100" velocity="10"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.5 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="100" velocity="10"/></joint>
</robot>
)";

TEST(JointDrives, GravityFeedForwardHoldsAHorizontalArmWithoutSag) {
  const Model model = LoadSceneFromString(kHorizontalArmUrdf, "horizontal_arm");
  const int shoulder = model.FindJoint("shoulder"), elbow = model.FindJoint("elbow");
  const State start = State::Initial(model);
  // Closed form: the weights' moments about +y through each joint, 9.81 (1 x 0.25 + 0.5 x 0.75) and 9.81 (0.5 x 0.25);
  // the drive pushes back.
  std::vector<double> mass;
  std::vector<Vec3> first_moment_W;
  SubtreeMassMoments(model, start, &mass, &first_moment_W);
  EXPECT_NEAR(JointGravityEffort(model, start, shoulder, mass, first_moment_W), -9.81 * 0.625, 1e-12);
  EXPECT_NEAR(JointGravityEffort(model, start, elbow, mass, first_moment_W), -9.81 * 0.125, 1e-12);
  EXPECT_DOUBLE_EQ(mass[model.FindBody("upper")], 1.5);  // kg: the upper link and the forearm below it
  EXPECT_DOUBLE_EQ(mass[model.FindBody("fore")], 0.5);
  EXPECT_TRUE(first_moment_W[model.FindBody("upper")].isApprox(Vec3(1.0 * 0.25 + 0.5 * 0.75, 0, 1.0 * 1.5)));
  for (Scheme scheme : {Scheme::kRattle, Scheme::kPaper}) {
    for (bool compensate : {false, true}) {
      SCOPED_TRACE(std::string(SchemeName(scheme)) + (compensate ? " with" : " without") + " gravity feed-forward");
      Data data(model);
      State state = start;
      for (int j : {shoulder, elbow}) {
        data.joint_drives[j].stiffness = 200.0;  // N m/rad
        data.joint_drives[j].damping = 20.0;     // N m s/rad
        data.joint_drives[j].gravity_compensation = compensate;
      }
      const StepperOptions options = Options(scheme, 0.01);
      for (int i = 0; i < 300; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
      const double sag = std::max(std::abs(JointPosition(model, state, shoulder)),
                                  std::abs(JointPosition(model, state, elbow)));
      if (compensate) {
        EXPECT_LT(sag, 1e-9);
        EXPECT_NEAR(data.joint_drive_effort[shoulder], -9.81 * 0.625, 1e-6);
      } else {
        EXPECT_GT(sag, 0.9 * 9.81 * 0.625 / 200.0);  // about the static sag of the shoulder, 0.031 rad
      }
    }
  }
}

}  // namespace
}  // namespace implicit_sim
