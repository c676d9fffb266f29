// "No allocation inside the step once warm": counts heap allocations (a replaced global operator new) while a warm
// stepper runs 1000 steps of P3 (contact transitions and separations), a polygon, a spinning sphere, a stack of boxes
// and a resting pile in sparse mode.
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"

#include "scenario_runner.h"
#include "test_models.h"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace implicit_sim {
namespace {

TEST(Allocation, TheCounterSeesAllocations) {
  const long before = g_allocations.load();
  std::string text(100, 'x');  // longer than the small-string buffer
  EXPECT_GE(g_allocations.load() - before, 1);
  EXPECT_EQ(text.size(), 100u);
}

// A stack of three boxes on the ground: four face contacts, each with many active inequalities at once.
Model BoxStack() {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  for (int i = 0; i < 3; ++i) {
    m.bodies.push_back(test_models::MovingBody("box" + std::to_string(i), MakeBox(Vec3(0.1, 0.08, 0.05)), 1.0 + i,
                                               test_models::MakePose(Vec3(0.0, 0.0, 0.05 + 0.1 * i))));
  }
  return test_models::Finish(m);
}

TEST(Allocation, AThousandWarmStepsAllocateNothing) {
  std::vector<std::pair<std::string, Model>> scenes;
  for (const char* scene : {"p3_sphere_on_two_spheres.urdf", "p1_ngon20.urdf", "p2_sphere_spinning.urdf",
                            "gripper_lift.urdf"}) {
    scenes.emplace_back(scene, LoadSceneFromFile(testing_support::ScenePath(scene)));
  }
  scenes.emplace_back("stack of three boxes", BoxStack());
  for (const auto scheme : {StepperOptions::Scheme::kPaper, StepperOptions::Scheme::kRattle})
  for (const auto& [name, model] : scenes) {
    SCOPED_TRACE(name + (scheme == StepperOptions::Scheme::kRattle ? ", rattle" : ", paper"));
    Data data(model);
    State state = State::Initial(model);
    StepperOptions options;
    options.scheme = scheme;
    Step(model, options, &state, &data);  // the first step starts cold (distance oracle)
    // A push on the top body that changes every step, so that every step iterates.
    Eigen::VectorXd wrench = Eigen::VectorXd::Zero(model.nv());
    const long before = g_allocations.load();
    int cold = 0, iterations = 0;
    for (int i = 0; i < 1000; ++i) {
      wrench[Model::v_offset(model.num_moving() - 1) + 2] = -0.5 * (1.0 + std::sin(0.3 * i));
      const StepReport report = Step(model, options, &state, &data, &wrench);
      cold += report.cold_restarts;
      iterations += report.iterations;
    }
    // Cold restarts reseed closest points in closed form for these shapes, so they must not allocate either.
    EXPECT_LE(cold, 1);
    EXPECT_EQ(g_allocations.load() - before, 0);
    EXPECT_GE(iterations, 1000);
  }
}

// Joint drives (rows/drive_rows.h) whose targets change every step, on the gripper: the drive unknowns stay in the
// layout, so a warm step allocates nothing either.
TEST(Allocation, AThousandWarmStepsWithJointDrivesAllocateNothing) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("gripper_lift.urdf"));
  const int lift = model.FindJoint("lift"), left = model.FindJoint("left_slide"), right = model.FindJoint("right_slide");
  for (const auto scheme : {StepperOptions::Scheme::kPaper, StepperOptions::Scheme::kRattle}) {
    SCOPED_TRACE(scheme == StepperOptions::Scheme::kRattle ? "rattle" : "paper");
    Data data(model);
    State state = State::Initial(model);
    StepperOptions options;
    options.scheme = scheme;
    options.h = 0.001;
    auto drive = [&](int i) {
      data.joint_drives[left] = {0.01, 0.0, 1e3, 5.0};
      data.joint_drives[right] = {-0.01, 0.0, 1e3, 5.0};
      data.joint_drives[lift] = {0.01 * std::sin(0.01 * i), 0.01 * std::cos(0.01 * i), 2000.0, 60.0};
    };
    drive(0);
    Step(model, options, &state, &data);  // cold, and lays the drive unknowns out
    const long before = g_allocations.load();
    int iterations = 0;
    for (int i = 1; i <= 1000; ++i) {
      drive(i);
      iterations += Step(model, options, &state, &data).iterations;
    }
    EXPECT_EQ(g_allocations.load() - before, 0);
    EXPECT_GE(iterations, 1000);
    EXPECT_NE(data.joint_drive_effort[lift], 0.0);
  }
}

TEST(Allocation, AWarmSparseStepWithAnUnchangedPairSetAllocatesNothing) {
  // Broad phase, sparse Jacobian and KLU: once the pile rests, the pairs in the NCP stay the same and a step reuses
  // the recorded pattern, the symbolic analysis and every buffer.
  const Model model = LoadSceneFromString(MakePileUrdf(10, PileShape::kSphere), "pile");
  Data data(model);
  ASSERT_TRUE(data.broad_phase);
  State state = State::Initial(model);
  StepperOptions options;
  options.h = 0.005;
  for (int i = 0; i < 200; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged);  // land and settle
  // A downward push that changes every step (a sideways one would roll the spheres), so that every step iterates.
  Eigen::VectorXd wrench = Eigen::VectorXd::Zero(model.nv());
  const long before = g_allocations.load();
  int iterations = 0;
  for (int i = 0; i < 1000; ++i) {
    for (int k = 0; k < model.num_moving(); ++k) wrench[Model::v_offset(k) + 2] = -0.5 * (1.0 + std::sin(0.3 * i + k));
    iterations += Step(model, options, &state, &data, &wrench).iterations;
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GE(iterations, 1000);
  EXPECT_GE(data.layout.blocks().size(), 10u);  // every sphere on the floor, in the NCP
}

}  // namespace
}  // namespace implicit_sim
