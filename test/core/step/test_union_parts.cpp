// scenes/union_parts.urdf: two non-convex parts, each one body of two convex shapes, dropped on a floor with the
// default step. Their mass properties are closed forms of their shapes; at rest the L-bracket lies on its base
// with the contact point below its centre of mass and the T-pipe on its pipe and the rim of its branch, at the tilt and with the load split of the statics below;
// no shape ever dips below the floor (checked from the poses and the parts' dimensions alone, with support
// functions written here, not the library's), and the energy never rises.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/urdf_loader.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

constexpr double kPartMass = 0.1;  // kg, each part
constexpr double kUnionGravity = 9.81;
// Bracket (link frame): base leg centred at z = -0.0225 m (2/3 of the mass), upright at (-0.0325, 0, 0.005) m (1/3).
const Vec3 kBracketBase(0.0, 0.0, -0.0225), kBracketUpright(-0.0325, 0.0, 0.005);
const Vec3 kBracketBaseHalf(0.04, 0.015, 0.0075), kBracketUprightHalf(0.0075, 0.015, 0.02);
constexpr double kBracketExponent = 8.0;
// Tee (link frame): pipe along x at z = -0.01 m (r 0.015, 0.09 m long), branch along z at z = 0.025 m (r 0.012,
// 0.04 m), masses in the ratio of their volumes.
constexpr double kPipeZ = -0.01, kPipeRadius = 0.015, kPipeLength = 0.09;
constexpr double kBranchZ = 0.025, kBranchRadius = 0.012, kBranchLength = 0.04;

double PipeMass() {
  const double pipe = kPipeRadius * kPipeRadius * kPipeLength, branch = kBranchRadius * kBranchRadius * kBranchLength;
  return kPartMass * pipe / (pipe + branch);
}

// Lowest z of a superellipsoid |x/a|^p + ... <= 1 centred at c with axes R: c.z - h(-e_z), where the support function
// is h(u) = (sum |a_i u_i|^q)^(1/q), q = p / (p - 1), with u in the shape's axes.
double SuperellipsoidLowest(const Vec3& c, const Mat3& R, const Vec3& half, double p) {
  const Vec3 u = R.transpose() * Vec3::UnitZ();
  const double q = p / (p - 1.0);
  double sum = 0.0;
  for (int i = 0; i < 3; ++i) sum += std::pow(std::abs(half[i] * u[i]), q);
  return c.z() - std::pow(sum, 1.0 / q);
}

// The point of a superellipsoid centred at 0 farthest along u (its axes): x_i = a_i sign(u_i) |a_i u_i|^(q-1) / h^(q-1).
Vec3 SuperellipsoidSupport(const Vec3& half, double p, const Vec3& u) {
  const double q = p / (p - 1.0);
  double sum = 0.0;
  for (int i = 0; i < 3; ++i) sum += std::pow(std::abs(half[i] * u[i]), q);
  const double h = std::pow(sum, 1.0 / q);
  Vec3 x;
  for (int i = 0; i < 3; ++i) x[i] = half[i] * std::copysign(std::pow(std::abs(half[i] * u[i]) / h, q - 1.0), u[i]);
  return x;
}

// The bracket at rest on its base, turned by phi about y: the base (a superellipsoid, curved everywhere, if only
// slightly near its bottom) touches the floor at the one point whose normal is vertical, and that point must lie
// straight below the centre of mass. With d(phi) = (sin phi, 0, -cos phi), the floor's downward direction in the
// link frame, the contact point is p(phi) = base centre + support(d) and phi solves (p - com) x d = 0 (bisection).
double BracketRestTilt(const Vec3& com) {
  auto f = [&](double phi) {
    const Vec3 d(std::sin(phi), 0.0, -std::cos(phi));
    return (kBracketBase + SuperellipsoidSupport(kBracketBaseHalf, kBracketExponent, d) - com).cross(d).y();
  };
  double lo = -0.01, hi = 0.01;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(lo) * f(mid) <= 0.0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

// Lowest z of a solid cylinder with centre c, unit axis a, radius r and length L.
double CylinderLowest(const Vec3& c, const Vec3& a, double r, double L) {
  return c.z() - r * std::sqrt(std::max(0.0, 1.0 - a.z() * a.z())) - 0.5 * L * std::abs(a.z());
}

// The tee at rest, rotated by theta about x and lying on its pipe and the branch's top rim:
// (kBranchZ + L/2 - kPipeZ) cos(theta) - r_b sin(theta) + r_p = 0, the root in (pi/2, pi) by bisection.
double TeeRestAngle() {
  const double arm = kBranchZ + 0.5 * kBranchLength - kPipeZ;
  auto f = [&](double t) { return arm * std::cos(t) - kBranchRadius * std::sin(t) + kPipeRadius; };
  double lo = 1.0, hi = 3.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(lo) * f(mid) <= 0.0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(UnionParts, MassAndCentreOfMassComeFromTheShapes) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("union_parts.urdf"));
  const Body& bracket = model.bodies[model.FindBody("bracket")];
  const Body& tee = model.bodies[model.FindBody("tee")];
  ASSERT_EQ(bracket.shapes.size(), 2u);
  ASSERT_EQ(tee.shapes.size(), 2u);
  EXPECT_NEAR(bracket.mass, kPartMass, 1e-15);
  EXPECT_NEAR(tee.mass, kPartMass, 1e-15);
  const Vec3 bracket_com = (2.0 * kBracketBase + kBracketUpright) / 3.0;  // link frame (m)
  EXPECT_NEAR((bracket.X_BL.translation() + bracket_com).norm(), 0.0, 1e-15);
  const double tee_com_z = (PipeMass() * kPipeZ + (kPartMass - PipeMass()) * kBranchZ) / kPartMass;
  EXPECT_NEAR((tee.X_BL.translation() + Vec3(0.0, 0.0, tee_com_z)).norm(), 0.0, 1e-15);
}

int PairNamed(const Model& model, const std::string& name) {
  for (int p = 0; p < static_cast<int>(model.pairs.size()); ++p) {
    if (model.PairName(p) == name) return p;
  }
  return -1;
}

TEST(UnionParts, TheBracketRestsOnItsBaseAndTheTeeOnItsPipeAndBranchRimAsStaticsSays) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("union_parts.urdf"));
  const int bracket = model.FindBody("bracket"), tee = model.FindBody("tee");
  const int pairs[4] = {PairNamed(model, "bracket#0-floor"), PairNamed(model, "bracket#1-floor"),
                        PairNamed(model, "tee#0-floor"), PairNamed(model, "tee#1-floor")};
  for (int p : pairs) ASSERT_GE(p, 0);
  auto energy = [&](const State& s) {  // J: kinetic plus potential of both parts
    return KineticEnergy(model, s) +
           kPartMass * kUnionGravity * (s.X_WB(model, bracket).translation().z() + s.X_WB(model, tee).translation().z());
  };
  const double energy0 = energy(State::Initial(model));
  double lowest = 1.0, energy_rise = -1.0;  // m over every shape and step end; J above the initial energy
  double force[4] = {0, 0, 0, 0}, speed = 1.0;
  Pose X_W_bracket = Pose::Identity(), X_W_tee = Pose::Identity();  // link frames at the last step end
  const auto stats = testing_support::RunScene(model, 0.005, 1.0,
                                               [&](const Model& m, const State& s, const Data& d, const StepReport&) {
    X_W_bracket = s.X_WL(m, bracket);
    X_W_tee = s.X_WL(m, tee);
    const Mat3& Rb = X_W_bracket.linear();
    const Mat3& Rt = X_W_tee.linear();
    lowest = std::min({lowest,
                       SuperellipsoidLowest(X_W_bracket * kBracketBase, Rb, kBracketBaseHalf, kBracketExponent),
                       SuperellipsoidLowest(X_W_bracket * kBracketUpright, Rb, kBracketUprightHalf, kBracketExponent),
                       CylinderLowest(X_W_tee * Vec3(0, 0, kPipeZ), Rt * Vec3::UnitX(), kPipeRadius, kPipeLength),
                       CylinderLowest(X_W_tee * Vec3(0, 0, kBranchZ), Rt * Vec3::UnitZ(), kBranchRadius,
                                      kBranchLength)});
    energy_rise = std::max(energy_rise, energy(s) - energy0);
    for (int k = 0; k < 4; ++k) force[k] = d.contacts[pairs[k]].normal_force;
    speed = s.v.norm();
  });
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_GE(lowest, -1e-9);
  EXPECT_LE(energy_rise, 1e-9);
  EXPECT_LT(speed, 1e-7);  // m/s and rad/s: at rest
  const double weight = kPartMass * kUnionGravity;  // N
  // Bracket: on its base, tilted by the small angle that puts the contact point below the centre of mass (about
  // 2e-5 rad: the base is flat only to 8th order), the whole weight on the base and none on the upright.
  const double phi = BracketRestTilt((2.0 * kBracketBase + kBracketUpright) / 3.0);
  const Vec3 down(std::sin(phi), 0.0, -std::cos(phi));
  const Eigen::AngleAxisd tilt(X_W_bracket.linear());
  EXPECT_GT(std::abs(phi), 1e-5);
  EXPECT_NEAR(tilt.angle(), std::abs(phi), 1e-9);
  EXPECT_NEAR(std::abs(tilt.axis().y()), 1.0, 1e-6);
  EXPECT_NEAR(X_W_bracket.translation().z(),
              down.dot(kBracketBase + SuperellipsoidSupport(kBracketBaseHalf, kBracketExponent, down)), 1e-9);
  EXPECT_NEAR(force[0], weight, 1e-6 * weight);
  EXPECT_NEAR(force[1], 0.0, 1e-9 * weight);
  // Tee: turned by theta about x onto the branch's rim, the pipe's axis r_p above the floor; moments about the
  // pipe's contact line split the weight between the pipe and the rim in the ratio of their lever arms along y.
  const double theta = TeeRestAngle();
  const Eigen::AngleAxisd turn(X_W_tee.linear());
  EXPECT_NEAR(turn.angle(), theta, 1e-9);
  EXPECT_NEAR(std::abs(turn.axis().x()), 1.0, 1e-9);
  EXPECT_NEAR((X_W_tee * Vec3(0, 0, kPipeZ)).z(), kPipeRadius, 1e-9);
  const double tee_com_z = (PipeMass() * kPipeZ + (kPartMass - PipeMass()) * kBranchZ) / kPartMass;
  const double arm_com = (tee_com_z - kPipeZ) * std::sin(theta);
  const double arm_rim = (kBranchZ + 0.5 * kBranchLength - kPipeZ) * std::sin(theta) + kBranchRadius * std::cos(theta);
  EXPECT_NEAR(force[3], weight * arm_com / arm_rim, 1e-6 * weight);
  EXPECT_NEAR(force[2] + force[3], weight, 1e-6 * weight);
}

}  // namespace
}  // namespace implicit_sim
