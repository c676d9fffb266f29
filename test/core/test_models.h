// Small models built in code for the core tests (the scenario scenes are read from scenes/ instead).
#pragma once

#include <string>

#include "implicit_sim/core/model.h"

namespace implicit_sim {
namespace test_models {

inline Pose MakePose(const Vec3& p, const Mat3& R = Mat3::Identity()) {
  Pose X = Pose::Identity();
  X.translation() = p;
  X.linear() = R;
  return X;
}

inline Mat3 Rot(double angle, const Vec3& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

inline Body MovingBody(const std::string& name, const ConvexShape& shape, double mass, const Pose& X_WB) {
  Body b;
  b.name = name;
  b.shape = shape;
  b.mass = mass;
  double volume;
  Mat3 I_S;
  shape.UnitDensityMassProperties(&volume, &I_S);
  b.I_B = I_S * mass / volume;
  b.X_WB0 = X_WB;
  return b;
}

inline Body FixedBody(const std::string& name, const ConvexShape& shape, const Pose& X_WB = Pose::Identity()) {
  Body b;
  b.name = name;
  b.is_fixed = true;
  b.shape = shape;
  b.X_WB0 = X_WB;
  return b;
}

inline Model Finish(Model model, const FrictionParams& friction = FrictionParams{0.4, 1.0, 0.8, 0.2}) {
  model.Finalize([&](int, int) { return friction; });
  return model;
}

inline Model EllipsoidOnGround() {
  Model m;
  m.bodies.push_back(FixedBody("ground", MakeHalfSpace()));
  m.bodies.push_back(MovingBody("egg", MakeEllipsoid(Vec3(0.3, 0.2, 0.1)), 1.5,
                                MakePose(Vec3(0.1, -0.2, 0.35), Rot(0.7, Vec3(1, 2, 3)))));
  return Finish(m);
}

inline Model SphereOnTwoSpheres() {
  Model m;
  m.gravity_W = Vec3::Zero();
  m.bodies.push_back(MovingBody("ball", MakeSphere(1.0), 1.0, MakePose(Vec3(0, 6.62105263157895, 8.78417110772903))));
  m.bodies.back().f_applied_W = Vec3(1.0, 2.6, -9.81);
  m.bodies.push_back(FixedBody("sphere_a", MakeSphere(10.0)));
  m.bodies.push_back(FixedBody("sphere_b", MakeSphere(9.0), MakePose(Vec3(0, 11.4, 0))));
  return Finish(m, FrictionParams{0.2, 1.0, 1.0, 0.3});
}

inline Model BoxAndSuperellipsoid() {
  Model m;
  m.bodies.push_back(MovingBody("box", MakeBox(Vec3(0.2, 0.15, 0.1)), 2.0,
                                MakePose(Vec3(0, 0, 0.1), Rot(0.3, Vec3(0, 0, 1)))));
  ConvexShape rounded = MakeSuperellipsoid(Vec3(0.1, 0.12, 0.08), 4.0);
  rounded.X_BS = MakePose(Vec3(0.01, 0.0, -0.02), Rot(0.4, Vec3(1, 0, 1)));
  m.bodies.push_back(MovingBody("rounded", rounded, 0.7, MakePose(Vec3(0.05, 0.02, 0.3), Rot(1.1, Vec3(0, 1, 1)))));
  m.bodies.back().tau_applied_W = Vec3(0.1, -0.2, 0.05);
  m.bodies.push_back(FixedBody("ground", MakeHalfSpace()));
  return Finish(m);
}

inline Model PrismOnGround(int sides) {
  Model m;
  m.bodies.push_back(FixedBody("ground", MakeHalfSpace(), MakePose(Vec3(0, 0, -0.1), Rot(0.05, Vec3(1, 0, 0)))));
  ConvexShape prism = MakePrism(sides, 1.0, 0.05);
  prism.X_BS = MakePose(Vec3::Zero(), Rot(1.5707963267948966, Vec3(1, 0, 0)));
  m.bodies.push_back(MovingBody("disc", prism, 1.0, MakePose(Vec3(0, 0, 1))));
  m.bodies.back().locked = {{false, true, false, true, false, true}};
  return Finish(m);
}

}  // namespace test_models
}  // namespace implicit_sim
