// Small models built in code for the core tests (the scenario scenes are read from scenes/ instead).
#pragma once

#include <string>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/urdf_loader.h"

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
  b.shapes = {shape};
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
  b.shapes = {shape};
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

// A robot with every joint type and feature: a base box on a limited revolute joint to the world (damping and
// friction), a slider on a prismatic joint to it (limits, friction, damping), a finger welded to the slider (a 6-D
// fixed joint between moving bodies), and a wheel on a continuous joint whose parent is a fixed post, above a
// ground plane that the swinging arm hits. Axes, origins and inertial frames are all off the principal directions.
inline const char* kJointedRobotUrdf = R"(<?xml version="1.0"?>
<robot name="jointed_robot">
  <implicit_sim gravity="0.3 -0.2 -9.81">
    <joint name="shoulder" position="0.3" velocity="-0.7"/>
    <joint name="slide" position="0.05" velocity="0.2"/>
    <joint name="axle" position="1.0" velocity="3.0"/>
  </implicit_sim>
  <link name="world"/>
  <link name="ground"><collision><geometry><box size="1 1 1"/></geometry><implicit type="halfspace"/></collision></link>
  <joint name="ground_joint" type="fixed"><parent link="world"/><child link="ground"/></joint>
  <link name="base">
    <inertial><origin xyz="0.05 0 0.02" rpy="0.1 0 0.2"/><mass value="2"/>
      <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.03" iyz="0" izz="0.04"/></inertial>
    <collision><origin xyz="0.05 0 0"/><geometry><box size="0.3 0.1 0.1"/></geometry></collision>
  </link>
  <joint name="shoulder" type="revolute"><parent link="world"/><child link="base"/>
    <origin xyz="0 0 0.3" rpy="0.2 0.1 0"/><axis xyz="0.1 1 0.2"/>
    <limit lower="-0.5" upper="1.2" effort="50" velocity="5"/><dynamics damping="0.3" friction="0.4"/></joint>
  <link name="slider">
    <inertial><mass value="0.5"/><inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.003"/></inertial>
    <collision><geometry><sphere radius="0.04"/></geometry></collision>
  </link>
  <joint name="slide" type="prismatic"><parent link="base"/><child link="slider"/>
    <origin xyz="0.2 0 0" rpy="0 0.3 0"/><axis xyz="1 0 0.1"/>
    <limit lower="-0.1" upper="0.15" effort="20" velocity="1"/><dynamics damping="0.5" friction="0.2"/></joint>
  <link name="finger">
    <inertial><origin xyz="0 0 -0.05"/><mass value="0.2"/>
      <inertia ixx="0.0005" ixy="0" ixz="0" iyy="0.0005" iyz="0" izz="0.0002"/></inertial>
    <collision><origin xyz="0 0 -0.05"/><geometry><cylinder radius="0.02" length="0.1"/></geometry></collision>
  </link>
  <joint name="weld" type="fixed"><parent link="slider"/><child link="finger"/><origin xyz="0 0 -0.03" rpy="0.3 0 0"/></joint>
  <link name="post"><collision><geometry><box size="0.05 0.05 0.5"/></geometry></collision></link>
  <joint name="post_joint" type="fixed"><parent link="world"/><child link="post"/><origin xyz="1 1 0.25"/></joint>
  <link name="wheel">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.018"/></inertial>
    <collision><geometry><cylinder radius="0.2" length="0.05"/></geometry></collision>
  </link>
  <joint name="axle" type="continuous"><parent link="post"/><child link="wheel"/>
    <origin xyz="0 0.1 0.3" rpy="1.5707963 0 0"/><axis xyz="0 0 1"/><dynamics damping="0.1"/></joint>
</robot>
)";

inline Model JointedRobot() { return LoadSceneFromString(kJointedRobotUrdf, "jointed_robot"); }

// A puck on a planar joint (normal off the principal directions, origin offset) to an arm that swings on a continuous
// joint from the world: the planar rows with both bodies moving.
inline const char* kPlanarJointRobotUrdf = R"(<?xml version="1.0"?>
<robot name="planar_robot">
  <implicit_sim gravity="0.3 -0.2 -9.81"><joint name="swing" position="0.4" velocity="0.8"/></implicit_sim>
  <link name="world"/>
  <link name="arm">
    <inertial><origin xyz="0.2 0 0" rpy="0.1 0.2 0"/><mass value="1.5"/>
      <inertia ixx="0.01" ixy="0.001" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><origin xyz="0.2 0 0"/><geometry><box size="0.4 0.05 0.05"/></geometry></collision>
  </link>
  <joint name="swing" type="continuous"><parent link="world"/><child link="arm"/>
    <origin xyz="0 0 1" rpy="0.1 0 0.2"/><axis xyz="0.1 1 0.1"/></joint>
  <link name="puck">
    <inertial><origin xyz="0.01 0.02 0" rpy="0 0.1 0.3"/><mass value="0.4"/>
      <inertia ixx="0.001" ixy="0" ixz="0.0001" iyy="0.0012" iyz="0" izz="0.002"/></inertial>
    <collision><geometry><cylinder radius="0.05" length="0.02"/></geometry></collision>
  </link>
  <joint name="glide" type="planar"><parent link="arm"/><child link="puck"/>
    <origin xyz="0.5 0.1 0" rpy="0.3 0 0"/><axis xyz="0.2 0.1 1"/></joint>
</robot>
)";

inline Model PlanarJointRobot() { return LoadSceneFromString(kPlanarJointRobotUrdf, "planar_robot"); }

}  // namespace test_models
}  // namespace implicit_sim
