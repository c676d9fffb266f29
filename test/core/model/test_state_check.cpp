// CheckState: what it refuses (sizes, non-finite values, quaternions off unit norm), its messages naming the body and
// the entry, and that Step refuses such a state and changes nothing.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

TEST(CheckState, AcceptsTheInitialStateAndAQuaternionWithinTheTolerance) {
  const Model model = test_models::SphereOnTwoSpheres();
  State state = State::Initial(model);
  std::string error = "untouched";
  EXPECT_TRUE(CheckState(model, state, &error));
  EXPECT_EQ(error, "untouched");
  state.q[3] += 0.5 * kUnitQuaternionTolerance;  // w = 1 + 5e-10: norm within 1e-9 of 1
  EXPECT_TRUE(CheckState(model, state, nullptr));
  state.q[3] += kUnitQuaternionTolerance;  // 1.5e-9 off
  EXPECT_FALSE(CheckState(model, state, nullptr));
}

TEST(CheckState, NamesTheBodyAndTheEntryOfWhatItRefuses) {
  const Model model = test_models::SphereOnTwoSpheres();
  const std::string body = model.bodies[model.moving_bodies[0]].name;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    int vector;  // 0: q, 1: v, 2: t
    int index;
    double value;
    std::string message;
  };
  const Case cases[] = {
      {0, 1, nan, "state: body '" + body + "' (q[0:3], its position p_WB in m) must be finite"},
      {0, 4, std::numeric_limits<double>::infinity(),
       "state: body '" + body + "' (q[3:7], its quaternion w, x, y, z) must be finite"},
      {0, 3, 2.0, "state: body '" + body + "' (q[3:7], its quaternion w, x, y, z) must be a unit quaternion (norm "
                  "within 1e-09 of 1), got norm 2: normalize it"},
      {1, 0, nan, "state: body '" + body + "' (v[0:3], its velocity v_WB in m/s) must be finite"},
      {1, 5, nan, "state: body '" + body + "' (v[3:6], its angular velocity w_WB in rad/s) must be finite"},
      {2, 0, nan, "state: t must be finite, got nan"},
  };
  for (const Case& c : cases) {
    State state = State::Initial(model);
    if (c.vector == 0) state.q[c.index] = c.value;
    if (c.vector == 1) state.v[c.index] = c.value;
    if (c.vector == 2) state.t = c.value;
    std::string error;
    EXPECT_FALSE(CheckState(model, state, &error));
    EXPECT_EQ(error, c.message);
  }
  State short_state = State::Initial(model);
  short_state.v.resize(5);
  std::string error;
  EXPECT_FALSE(CheckState(model, short_state, &error));
  EXPECT_EQ(error, "state: size does not match the model: q must hold 7 values (got 7) and v 6 (got 5), 7 and 6 per "
                   "moving body");
}

TEST(CheckState, StepRefusesABadStateAndChangesNothing) {
  const Model model = test_models::SphereOnTwoSpheres();
  StepperOptions options;
  Data data(model);
  State state = State::Initial(model);
  state.q[4] = 0.5;  // quaternion (1, 0.5, 0, 0)
  const State before = state;
  try {
    Step(model, options, &state, &data);
    FAIL() << "Step accepted a quaternion of norm 1.118";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("must be a unit quaternion"), std::string::npos) << e.what();
  }
  EXPECT_EQ(state.q, before.q);
  EXPECT_EQ(state.v, before.v);
  EXPECT_EQ(state.t, before.t);
  EXPECT_FALSE(data.has_warm_start);
}

}  // namespace
}  // namespace implicit_sim
