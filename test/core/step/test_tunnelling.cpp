// Nothing passes through anything silently: a fast ball or ellipsoid shot at a thin fixed wall (a 1 cm box or an
// ellipsoid plate). The end-of-step conditions alone allow an end pose on the wall's FAR side; FindCrossing rejects
// such solutions and the step is solved again from a cold start or split. Every run must either keep the projectile
// on the near side or report the step it could not solve (never a converged step through the wall), and no run may
// gain kinetic energy while its steps converge.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "scenario_runner.h"

namespace implicit_sim {
namespace {

// A wall in the plane x = 0 (1 cm thick, 1 m wide) and a projectile at (x0, y0, 0) flying along +x at `speed` (m/s)
// with a spin; no gravity, so kinetic energy may only fall.
std::string TunnelScene(double speed, double x0, double y0, bool ellipsoid_projectile, bool ellipsoid_wall) {
  const std::string wall = ellipsoid_wall
                               ? R"(<geometry><sphere radius="0.5"/></geometry>
                                    <implicit type="ellipsoid" semi_axes="0.005 0.5 0.5"/>)"
                               : R"(<geometry><box size="0.01 1 1"/></geometry>)";
  const std::string projectile = ellipsoid_projectile
                                     ? R"(<geometry><sphere radius="0.05"/></geometry>
                                          <implicit type="ellipsoid" semi_axes="0.05 0.03 0.02"/>)"
                                     : R"(<geometry><sphere radius="0.05"/></geometry>)";
  return R"(<robot name="tunnel"><implicit_sim gravity="0 0 0"><friction mu="0.3" e_t="1" e_o="1" e_r="0.01"/>
    <body link="ball" velocity=")" + std::to_string(speed) + R"( 0 0" angular_velocity="3 1 2"/></implicit_sim>
    <link name="world"/><link name="wall"><collision>)" + wall + R"(</collision></link>
    <joint name="wall_joint" type="fixed"><parent link="world"/><child link="wall"/></joint>
    <link name="ball"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/>
    </inertial><collision>)" + projectile + R"(</collision></link>
    <joint name="ball_joint" type="floating"><parent link="world"/><child link="ball"/>
    <origin xyz=")" + std::to_string(x0) + " " + std::to_string(y0) + R"( 0"/></joint></robot>)";
}

// Whether the centre's path between two step ends crosses the wall's mid-plane x = 0 inside the wall's outline (the
// ellipse of semi-axes 0.5 m, or the 1 m square): through the wall, rather than around its rim.
bool CrossesInsideTheWall(const Vec3& from, const Vec3& to, bool ellipsoid_wall) {
  if (!(from.x() <= 0.0 && to.x() > 0.0)) return false;
  const Vec3 at = from + (to - from) * (-from.x() / (to.x() - from.x()));
  return ellipsoid_wall ? std::hypot(at.y(), at.z()) < 0.5 : std::max(std::abs(at.y()), std::abs(at.z())) < 0.5;
}

TEST(Tunnelling, NoConvergedStepCarriesABodyThroughAThinWall) {
  int runs = 0, stopped = 0, reported = 0, around = 0;
  for (const bool ellipsoid_wall : {false, true}) {
    for (const bool ellipsoid_projectile : {false, true}) {
      for (const double speed : {25.0, 60.0, 100.0}) {
        for (const double x0 : {-1.0, -1.161}) {
          SCOPED_TRACE("wall " + std::string(ellipsoid_wall ? "ellipsoid" : "box") + ", projectile " +
                       (ellipsoid_projectile ? "ellipsoid" : "sphere") + ", speed " + std::to_string(speed) +
                       " m/s, x0 " + std::to_string(x0) + " m");
          const Model model = LoadSceneFromString(TunnelScene(speed, x0, 0.0, ellipsoid_projectile, ellipsoid_wall));
          StepperOptions options;  // h = 0.01 s
          Data data(model);
          State state = State::Initial(model);
          const double ke0 = KineticEnergy(model, state);
          bool through = false, beyond = false, all_converged = true;
          for (int i = 0; i < 10; ++i) {
            const Vec3 before = state.q.head<3>();  // the start of this step
            const StepReport report = Step(model, options, &state, &data);
            all_converged = all_converged && report.converged;
            if (!report.advanced) break;  // refused (a crossing in the shortest sub-step): the state stays
            // Energy is only asserted while every step so far converged: an accepted non-converged iterate (the
            // ladder's best, reported) may penetrate, and what it injects stays (doc/method.md).
            if (all_converged) EXPECT_LE(KineticEnergy(model, state), ke0 * (1.0 + 1e-9)) << "step " << i;
            through = through || CrossesInsideTheWall(before, state.q.head<3>(), ellipsoid_wall);
            beyond = beyond || state.q[0] > 0.0;  // the centre beyond the wall's mid-plane
          }
          ++runs;
          if (!beyond) ++stopped;
          if (beyond && !through) ++around;  // deflected sideways past the rim
          if (through) {
            ++reported;
            EXPECT_FALSE(all_converged) << "a converged run went through the wall";
          }
        }
      }
    }
  }
  RecordProperty("runs", runs);
  RecordProperty("stopped_at_the_wall", stopped);
  RecordProperty("through_but_reported_not_converged", reported);
  RecordProperty("around_the_rim", around);
  // Before FindCrossing about half the runs went through, silently; with it and the monotone line search 4 of 24 still
  // did (their shortest sub-steps not converged, reported). Today two do, reported: the ellipsoid at 60 and 100 m/s
  // into the box (doc/method.md, "Tunnelling"). A head-on shot never gets a sideways speed that carries it past the
  // rim within 0.1 s.
  EXPECT_EQ(stopped + reported, runs);
  EXPECT_EQ(around, 0);
  EXPECT_LE(reported, 2);
}

}  // namespace
}  // namespace implicit_sim
