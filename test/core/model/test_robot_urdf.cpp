// Real robot URDFs: a root link other than 'world' (fixed by default, free on request), links without collision or
// inertial, frame links, <transmission> and <gazebo> elements, and <mesh> collisions replaced by their convex hulls
// (binary and ASCII STL and OBJ written here into a temp dir; package:// through ROS_PACKAGE_PATH and a resolver).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "geometry/convex_hull.h"
#include "implicit_sim/core/geometry/support.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

namespace fs = std::filesystem;
// Half extents of the test box (m), exact in single precision (binary STL stores floats).
const Vec3 kHalf(0.125, 0.0625, 0.25);
// The box's centre in its mesh frame (m): the mesh is not centred on its frame's origin.
const Vec3 kCentre(0.25, 0.0, -0.125);

std::string Scientific(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3e", value);
  return text;
}

std::vector<Vec3> BoxCorners(const Vec3& half, const Vec3& centre) {
  std::vector<Vec3> corners;
  for (int i = 0; i < 8; ++i) {
    corners.push_back(centre + Vec3(i & 1 ? half.x() : -half.x(), i & 2 ? half.y() : -half.y(),
                                    i & 4 ? half.z() : -half.z()));
  }
  return corners;
}

// The 12 triangles of a box as corner indices (BoxCorners numbering).
const int kBoxTriangles[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                  {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};

void WriteBinaryStl(const std::string& path, const std::vector<Vec3>& corners) {
  std::ofstream out(path, std::ios::binary);
  const std::string header(80, ' ');
  out.write(header.data(), 80);
  const uint32_t count = 12;
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const auto& triangle : kBoxTriangles) {
    float values[12] = {0, 0, 0};
    for (int v = 0; v < 3; ++v) {
      for (int c = 0; c < 3; ++c) values[3 + 3 * v + c] = static_cast<float>(corners[triangle[v]][c]);
    }
    out.write(reinterpret_cast<const char*>(values), sizeof(values));
    const uint16_t attribute = 0;
    out.write(reinterpret_cast<const char*>(&attribute), 2);
  }
}

void WriteAsciiStl(const std::string& path, const std::vector<Vec3>& corners) {
  std::ofstream out(path);
  out.precision(17);
  out << "solid box\n";
  for (const auto& triangle : kBoxTriangles) {
    out << "facet normal 0 0 0\nouter loop\n";
    for (int v = 0; v < 3; ++v) {
      out << "vertex " << corners[triangle[v]].x() << " " << corners[triangle[v]].y() << " "
          << corners[triangle[v]].z() << "\n";
    }
    out << "endloop\nendfacet\n";
  }
  out << "endsolid box\n";
}

// An OBJ of the given vertices, with the faces as 1-based index lists.
void WriteObj(const std::string& path, const std::vector<Vec3>& vertices, const std::vector<std::vector<int>>& faces) {
  std::ofstream out(path);
  out.precision(17);
  for (const Vec3& v : vertices) out << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& face : faces) {
    out << "f";
    for (int i : face) out << " " << i;
    out << "\n";
  }
}

// A Collada box: the corners (given in a z-up frame, m) written in the file's axes and units, under a node that
// translates by `node_offset` (file axes and units). Y_UP files hold (x, z, -y) of a z-up point.
void WriteBoxDae(const std::string& path, const std::vector<Vec3>& corners, const std::string& up_axis,
                 double unit_m, const Vec3& node_offset = Vec3::Zero()) {
  std::ofstream out(path);
  out.precision(17);
  out << "<?xml version='1.0'?>\n<COLLADA xmlns='http://www.collada.org/2005/11/COLLADASchema' version='1.4.1'>"
      << "<asset><unit meter='" << unit_m << "'/><up_axis>" << up_axis << "</up_axis></asset>"
      << "<library_geometries><geometry id='box'><mesh><source id='box-p'><float_array id='box-a' count='24'>";
  for (const Vec3& c : corners) {
    const Vec3 file = (up_axis == "Y_UP" ? Vec3(c.x(), c.z(), -c.y()) : c) / unit_m - node_offset;
    out << file.x() << " " << file.y() << " " << file.z() << " ";
  }
  out << "</float_array><technique_common><accessor source='#box-a' count='8' stride='3'><param name='X' "
      << "type='float'/><param name='Y' type='float'/><param name='Z' type='float'/></accessor></technique_common>"
      << "</source><vertices id='box-v'><input semantic='POSITION' source='#box-p'/></vertices><triangles count='12'>"
      << "<input semantic='VERTEX' source='#box-v' offset='0'/><p>";
  for (const auto& triangle : kBoxTriangles) out << triangle[0] << " " << triangle[1] << " " << triangle[2] << " ";
  out << "</p></triangles></mesh></geometry></library_geometries><library_visual_scenes><visual_scene id='s'>"
      << "<node id='n'><translate>" << node_offset.x() << " " << node_offset.y() << " " << node_offset.z()
      << "</translate><instance_geometry url='#box'/></node></visual_scene></library_visual_scenes>"
      << "<scene><instance_visual_scene url='#s'/></scene></COLLADA>\n";
}

std::vector<Vec3> OctahedronVertices() {
  return {Vec3(0.1, 0, 0), Vec3(-0.1, 0, 0), Vec3(0, 0.1, 0), Vec3(0, -0.1, 0), Vec3(0, 0, 0.1), Vec3(0, 0, -0.1)};
}
void WriteOctahedronObj(const std::string& path) {
  WriteObj(path, OctahedronVertices(),
           {{1, 3, 5}, {3, 2, 5}, {2, 4, 5}, {4, 1, 5}, {3, 1, 6}, {2, 3, 6}, {4, 2, 6}, {1, 4, 6}});
}

// Coordinates as assimp holds them: single precision (ai_real is float in Debian's build).
std::vector<Vec3> AsFloats(std::vector<Vec3> points) {
  for (Vec3& p : points) p = p.cast<float>().cast<double>();
  return points;
}

// A hexagonal prism (a cylinder-ish link): 12 vertices, 6 side quads and 2 caps.
std::vector<Vec3> HexagonalPrismVertices() {
  std::vector<Vec3> vertices;
  for (double z : {-0.2, 0.2}) {
    for (int k = 0; k < 6; ++k) vertices.emplace_back(0.05 * std::cos(k * kPi / 3), 0.05 * std::sin(k * kPi / 3), z);
  }
  return vertices;
}
void WriteHexagonalPrismObj(const std::string& path) {
  std::vector<std::vector<int>> faces = {{1, 2, 3, 4, 5, 6}, {12, 11, 10, 9, 8, 7}};
  for (int k = 0; k < 6; ++k) faces.push_back({k + 1, (k + 1) % 6 + 1, (k + 1) % 6 + 7, k + 7});
  WriteObj(path, HexagonalPrismVertices(), faces);
}

// A temporary directory with the test meshes, and a ROS package 'test_robot_meshes' under it for package:// URIs.
class RobotUrdf : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/implicit_sim_robot_urdf_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
    fs::create_directories(dir_ + "/share/test_robot_meshes/meshes");
    WriteBinaryStl(dir_ + "/box_binary.stl", BoxCorners(kHalf, kCentre));
    WriteBinaryStl(dir_ + "/share/test_robot_meshes/meshes/box.stl", BoxCorners(kHalf, kCentre));
    fs::create_directories(dir_ + "/share/robots/nested_meshes");  // a package one folder down, as in catkin src/
    std::ofstream(dir_ + "/share/robots/nested_meshes/package.xml") << "<package/>";
    WriteOctahedronObj(dir_ + "/share/robots/nested_meshes/octahedron.obj");
    WriteAsciiStl(dir_ + "/box_ascii.stl", BoxCorners(kHalf, kCentre));
    WriteOctahedronObj(dir_ + "/octahedron.obj");
    WriteHexagonalPrismObj(dir_ + "/prism.obj");
    WriteObj(dir_ + "/planar.obj", {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}, {{1, 2, 3, 4}});
    const char* old = std::getenv("ROS_PACKAGE_PATH");
    had_package_path_ = old != nullptr;
    old_package_path_ = old ? old : "";
    ::setenv("ROS_PACKAGE_PATH", ("/nonexistent_dir:" + dir_ + "/share").c_str(), 1);
  }
  void TearDown() override {
    if (had_package_path_) {
      ::setenv("ROS_PACKAGE_PATH", old_package_path_.c_str(), 1);
    } else {
      ::unsetenv("ROS_PACKAGE_PATH");
    }
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // Writes the URDF into the temp dir and loads it with LoadSceneFromFile (relative meshes against the temp dir).
  Model Load(const std::string& urdf, LoaderOptions options = LoaderOptions()) {
    std::vector<std::string> warnings;
    if (!options.warnings) options.warnings = &warnings;
    const std::string path = dir_ + "/robot.urdf";
    std::ofstream(path) << urdf;
    Model model = LoadSceneFromFile(path, options);
    if (options.warnings == &warnings) warnings_ = warnings;
    return model;
  }
  std::string LoadError(const std::string& urdf) {
    try {
      Load(urdf);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(loaded)";
  }
  std::string dir_;
  std::vector<std::string> warnings_;

 private:
  bool had_package_path_ = false;
  std::string old_package_path_;
};

const char* kArmInertial =
    "<inertial><origin xyz='0.25 0 0'/><mass value='2'/>"
    "<inertia ixx='0.01' iyy='0.05' izz='0.05' ixy='0' ixz='0' iyz='0'/></inertial>";

// A small robot: root 'base_link' (a box), a revolute arm about y with a mesh collision, a visual-only link welded
// to the base, a frame link 'tool0' and a weighted tip welded to the arm, and the usual extra elements.
std::string Robot(const std::string& arm_mesh, const std::string& arm_inertial = kArmInertial,
                  const std::string& base_inertial = "") {
  return "<robot name='arm_robot'>"
         "<material name='grey'><color rgba='0.5 0.5 0.5 1'/></material>"
         "<link name='base_link'>" + base_inertial +
         "<visual><geometry><mesh filename='package://missing_pkg/base.dae'/></geometry>"
         "<material name='grey'/></visual>"
         "<collision><geometry><box size='0.2 0.2 0.1'/></geometry></collision></link>"
         "<link name='camera'><visual><geometry><box size='0.05 0.05 0.05'/></geometry></visual></link>"
         "<joint name='camera_joint' type='fixed'><parent link='base_link'/><child link='camera'/>"
         "<origin xyz='0 0 0.3'/></joint>"
         "<link name='arm'>" + arm_inertial +
         "<visual><geometry><mesh filename='" + arm_mesh + "'/></geometry></visual>"
         "<collision><origin xyz='0 0 0'/><geometry><mesh filename='" + arm_mesh + "'/></geometry></collision>"
         "</link>"
         "<joint name='shoulder' type='revolute'><parent link='base_link'/><child link='arm'/>"
         "<origin xyz='0 0 0.5'/><axis xyz='0 1 0'/><limit lower='-3' upper='3' effort='100' velocity='5'/></joint>"
         "<link name='tool0'/>"
         "<joint name='tool_joint' type='fixed'><parent link='arm'/><child link='tool0'/>"
         "<origin xyz='0.5 0 0'/></joint>"
         "<link name='tip'><inertial><mass value='0.5'/>"
         "<inertia ixx='0.001' iyy='0.001' izz='0.001' ixy='0' ixz='0' iyz='0'/></inertial>"
         "<collision><geometry><sphere radius='0.03'/></geometry></collision></link>"
         "<joint name='tip_joint' type='fixed'><parent link='tool0'/><child link='tip'/>"
         "<origin xyz='0.05 0 0'/></joint>"
         "<transmission name='shoulder_trans'><type>transmission_interface/SimpleTransmission</type>"
         "<joint name='shoulder'><hardwareInterface>EffortJointInterface</hardwareInterface></joint></transmission>"
         "<gazebo reference='arm'><material>Gazebo/Grey</material></gazebo>"
         "</robot>";
}

// Every mesh vertex (given in the link frame: the collision origin is identity) satisfies every inequality of the
// body's shape, and every face plane passes through at least 3 of them. Returns the number of faces.
int ExpectHullOfVertices(const Body& body, const std::vector<Vec3>& vertices_L) {
  const Pose X_SL = body.shapes[0].X_BS.inverse() * body.X_BL;
  std::vector<int> touching(body.shapes[0].inequalities.size(), 0);
  for (const Vec3& v_L : vertices_L) {
    for (size_t i = 0; i < body.shapes[0].inequalities.size(); ++i) {
      const double f = body.shapes[0].inequalities[i].Value(X_SL * v_L);  // m
      EXPECT_LE(f, 1e-9) << "vertex " << v_L.transpose() << " outside face " << i;
      touching[i] += std::abs(f) <= 1e-9;
    }
  }
  for (size_t i = 0; i < touching.size(); ++i) EXPECT_GE(touching[i], 3) << "face " << i;
  return static_cast<int>(body.shapes[0].inequalities.size());
}

TEST_F(RobotUrdf, BinaryStlBoxBecomesSixFacesSpanningItsBoundingBox) {
  const Model model = Load(Robot("box_binary.stl"));
  const Body& arm = model.bodies[model.FindBody("arm")];
  EXPECT_EQ(arm.shapes[0].type, ShapeType::kIntersection);
  EXPECT_EQ(ExpectHullOfVertices(arm, BoxCorners(kHalf, kCentre)), 6);
  EXPECT_EQ(arm.shapes[0].vertices.size(), 8u);
  EXPECT_NEAR(arm.shapes[0].BoundingRadius(), kHalf.norm(), 1e-12);  // S sits at the box's centre
  // Support along the link axes: the bounding box of the mesh (world = link frame at the start: X_WL = X_WB X_BL).
  const Pose X_WL = arm.X_WB0 * arm.X_BL, X_WB = arm.X_WB0;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {1.0, -1.0}) {
      Vec3 p_W;
      ASSERT_TRUE(SupportPoint(arm.shapes[0], X_WB, sign * (X_WL.linear() * Vec3::Unit(axis)), &p_W));
      const Vec3 p_L = X_WL.inverse() * p_W;
      EXPECT_NEAR(p_L[axis], kCentre[axis] + sign * kHalf[axis], 1e-12);
    }
  }
  ASSERT_EQ(warnings_.size(), 1u);
  EXPECT_EQ(warnings_[0],
            "implicit_sim: link 'arm': collision mesh 'box_binary.stl' replaced by its convex hull (6 faces)");
}

TEST_F(RobotUrdf, AsciiStlObjOctahedronAndPrismHullsHaveTheirFaceCounts) {
  const Model ascii = Load(Robot("box_ascii.stl"));
  EXPECT_EQ(ExpectHullOfVertices(ascii.bodies[ascii.FindBody("arm")], BoxCorners(kHalf, kCentre)), 6);
  const Model octahedron = Load(Robot("octahedron.obj"));
  EXPECT_EQ(ExpectHullOfVertices(octahedron.bodies[octahedron.FindBody("arm")], OctahedronVertices()), 8);
  const Model prism = Load(Robot("file://" + dir_ + "/prism.obj"));
  EXPECT_EQ(ExpectHullOfVertices(prism.bodies[prism.FindBody("arm")], AsFloats(HexagonalPrismVertices())), 8);
  ASSERT_EQ(warnings_.size(), 1u);
  EXPECT_NE(warnings_[0].find("link 'arm'"), std::string::npos);
  EXPECT_NE(warnings_[0].find("(8 faces)"), std::string::npos);
}

// Assimp turns a Collada file's up axis into +y and scales it to metres in its root node; URDF links have +z up.
TEST_F(RobotUrdf, ColladaBoxesWithZOrYUpInAnyUnitHullAsTheStlBoxAtTheirCollisionOrigin) {
  WriteBoxDae(dir_ + "/box_z_up.dae", BoxCorners(kHalf, kCentre), "Z_UP", 1.0);
  WriteBoxDae(dir_ + "/box_y_up.dae", BoxCorners(kHalf, kCentre), "Y_UP", 0.25, Vec3(0.5, -1.0, 0.25));
  WriteBoxDae(dir_ + "/box_y_up_mm.dae", BoxCorners(kHalf, kCentre), "Y_UP", 0.001, Vec3(100, 20, -30));
  const Model z_up = Load(Robot("box_z_up.dae"));
  EXPECT_EQ(ExpectHullOfVertices(z_up.bodies[z_up.FindBody("arm")], BoxCorners(kHalf, kCentre)), 6);
  const Model y_up = Load(Robot("box_y_up.dae"));  // a quarter-metre unit: every coordinate stays exact
  EXPECT_EQ(ExpectHullOfVertices(y_up.bodies[y_up.FindBody("arm")], BoxCorners(kHalf, kCentre)), 6);

  // Under a collision origin, each file's hull has the STL hull's support values (mm: float round-off).
  const auto link = [](const std::string& mesh) {
    return "<robot name='r'><link name='base'/><link name='arm'>" + std::string(kArmInertial) +
           "<collision><origin xyz='0.1 -0.2 0.3' rpy='0.4 -0.5 0.6'/><geometry><mesh filename='" + mesh +
           "'/></geometry></collision></link><joint name='j' type='continuous'><parent link='base'/>"
           "<child link='arm'/><axis xyz='0 0 1'/></joint></robot>";
  };
  const Model stl = Load(link("box_binary.stl"));
  const Body& reference = stl.bodies[stl.FindBody("arm")];
  for (const std::string mesh : {"box_z_up.dae", "box_y_up.dae", "box_y_up_mm.dae"}) {
    const Model dae = Load(link(mesh));
    const Body& arm = dae.bodies[dae.FindBody("arm")];
    ASSERT_EQ(arm.shapes.size(), 1u);
    for (int k = 0; k < 27; ++k) {  // the 26 directions to the cells around a cube's centre
      const Vec3 direction(k % 3 - 1.0, (k / 3) % 3 - 1.0, k / 9 - 1.0);
      if (direction.isZero()) continue;
      Vec3 p_expected, p_actual;
      ASSERT_TRUE(SupportPoint(reference.shapes[0], reference.X_WB0, direction, &p_expected));
      ASSERT_TRUE(SupportPoint(arm.shapes[0], arm.X_WB0, direction, &p_actual));
      EXPECT_NEAR(direction.dot(p_actual), direction.dot(p_expected), mesh == "box_y_up_mm.dae" ? 1e-6 : 1e-12)
          << mesh << " along " << direction.transpose();
    }
  }
}

TEST_F(RobotUrdf, ScaleAndPackageUriThroughRosPackagePathAndTheResolver) {
  const Model scaled = Load("<robot name='r'><link name='base'/><link name='arm'>" + std::string(kArmInertial) +
                            "<collision><geometry><mesh filename='package://test_robot_meshes/meshes/box.stl' "
                            "scale='2 1 0.5'/></geometry></collision></link>"
                            "<joint name='j' type='continuous'><parent link='base'/><child link='arm'/>"
                            "<axis xyz='0 0 1'/></joint></robot>");
  std::vector<Vec3> corners = BoxCorners(kHalf, kCentre);
  for (Vec3& c : corners) c = c.cwiseProduct(Vec3(2, 1, 0.5));
  EXPECT_EQ(ExpectHullOfVertices(scaled.bodies[scaled.FindBody("arm")], corners), 6);

  const Model nested = Load(Robot("package://nested_meshes/octahedron.obj"));
  EXPECT_EQ(nested.bodies[nested.FindBody("arm")].shapes[0].inequalities.size(), 8u);

  LoaderOptions options;
  std::vector<std::string> asked;
  options.resolve_package_uri = [&](const std::string& uri) {
    asked.push_back(uri);
    return dir_ + "/octahedron.obj";
  };
  const Model resolved = Load(Robot("package://robot_description/meshes/arm.stl"), options);
  EXPECT_EQ(resolved.bodies[resolved.FindBody("arm")].shapes[0].inequalities.size(), 8u);
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0], "package://robot_description/meshes/arm.stl");
}

TEST_F(RobotUrdf, TheRootIsFixedByDefaultAndFreeWhenFloating) {
  const Model fixed = Load(Robot("box_binary.stl"));
  // base_link, camera (visual only, welded), arm, tip; tool0 is a frame link on the moving arm: no body.
  ASSERT_EQ(fixed.bodies.size(), 4u);
  EXPECT_TRUE(fixed.bodies[fixed.FindBody("base_link")].is_fixed);
  EXPECT_TRUE(fixed.bodies[fixed.FindBody("camera")].is_fixed);
  EXPECT_TRUE(fixed.bodies[fixed.FindBody("camera")].shapes.empty());
  EXPECT_EQ(fixed.FindBody("tool0"), -1);
  ASSERT_EQ(fixed.frames.size(), 1u);  // for tf: 0.5 m along the arm's link frame
  EXPECT_EQ(fixed.frames[0].name, "tool0");
  EXPECT_EQ(fixed.frames[0].body, fixed.FindBody("arm"));
  EXPECT_TRUE(fixed.frames[0].X_LF.isApprox(Pose(Eigen::Translation3d(0.5, 0, 0)), 1e-12));
  EXPECT_EQ(fixed.num_moving(), 2);
  ASSERT_EQ(fixed.joints.size(), 2u);
  const Joint& shoulder = fixed.joints[fixed.FindJoint("shoulder")];
  EXPECT_EQ(shoulder.parent, fixed.FindBody("base_link"));
  const Joint& tip = fixed.joints[fixed.FindJoint("tip_joint")];
  EXPECT_EQ(tip.type, JointType::kFixed);
  EXPECT_EQ(tip.parent, fixed.FindBody("arm"));  // through tool0: the origins 0.5 and 0.05 m compose
  const Pose X_WL_tip = fixed.bodies[fixed.FindBody("tip")].X_WB0;
  EXPECT_TRUE(X_WL_tip.translation().isApprox(Vec3(0.55, 0, 0.5), 1e-12));
  double drift_m = 1.0, drift_rad = 1.0;
  JointDrift(fixed, State::Initial(fixed), &drift_m, &drift_rad);
  EXPECT_LT(drift_m, 1e-12);
  EXPECT_LT(drift_rad, 1e-12);

  LoaderOptions placed;  // the fixed root at a given pose: a quarter turn about z, 1 m up
  placed.X_W_root.linear() = Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ()).toRotationMatrix();
  placed.X_W_root.translation() = Vec3(0, 0, 1);
  const Model turned = Load(Robot("box_binary.stl"), placed);
  EXPECT_TRUE(turned.bodies[turned.FindBody("base_link")].is_fixed);
  EXPECT_TRUE(turned.bodies[turned.FindBody("base_link")].X_WB0.isApprox(placed.X_W_root));
  const Body& turned_arm = turned.bodies[turned.FindBody("arm")];
  EXPECT_TRUE(turned_arm.X_WB0.translation().isApprox(Vec3(0, 0.25, 1.5), 1e-12));  // its centre of mass on +y

  LoaderOptions floating;
  floating.floating_root = true;
  floating.X_W_root.translation() = Vec3(1, 2, 3);
  const Model free = Load(Robot("box_binary.stl", kArmInertial, kArmInertial), floating);
  const Body& base = free.bodies[free.FindBody("base_link")];
  EXPECT_FALSE(base.is_fixed);
  EXPECT_TRUE(base.X_WB0.translation().isApprox(Vec3(1.25, 2, 3)));  // its <inertial> origin is 0.25 m along x
  // The massless visual-only camera now hangs on a moving link: a frame link, no body, like tool0.
  EXPECT_EQ(free.FindBody("camera"), -1);
  ASSERT_EQ(free.frames.size(), 2u);  // in URDF order; the camera 0.3 m above the base's link frame
  EXPECT_EQ(free.frames[0].name, "camera");
  EXPECT_EQ(free.frames[0].body, free.FindBody("base_link"));
  EXPECT_TRUE(free.frames[0].X_LF.isApprox(Pose(Eigen::Translation3d(0, 0, 0.3)), 1e-12));
  EXPECT_EQ(free.num_moving(), 3);
  ASSERT_EQ(free.joints.size(), 2u);  // shoulder (parent: the free base) and tip_joint
  EXPECT_EQ(free.joints[free.FindJoint("shoulder")].parent, free.FindBody("base_link"));
  const Body& arm = free.bodies[free.FindBody("arm")];
  EXPECT_TRUE((arm.X_WB0 * arm.X_BL).translation().isApprox(Vec3(1, 2, 3.5)));
}

TEST_F(RobotUrdf, TheArmSwingsDownUnderGravityFromTheFixedBase) {
  const Model model = Load(Robot("box_binary.stl"));
  StepperOptions options;
  options.h = 0.005;
  Data data(model);
  State state = State::Initial(model);
  const int shoulder = model.FindJoint("shoulder");
  double worst_m = 0.0, worst_rad = 0.0, angle = 0.0;  // the largest shoulder angle (rad)
  for (int i = 0; i < 300; ++i) {
    ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
    angle = std::max(angle, JointPosition(model, state, shoulder));
    double drift_m, drift_rad;
    JointDrift(model, state, &drift_m, &drift_rad);
    worst_m = std::max(worst_m, drift_m);
    worst_rad = std::max(worst_rad, drift_rad);
  }
  // Horizontal at the start; about +y a downward swing of the +x arm is a positive angle (the arm swings past its
  // base: one robot's links do not collide by default).
  RecordProperty("shoulder_angle_rad", Scientific(angle));
  RecordProperty("joint_drift_m", Scientific(worst_m));
  RecordProperty("joint_drift_rad", Scientific(worst_rad));
  EXPECT_GT(angle, 0.5);
  EXPECT_LT(worst_m, 1e-6);
  EXPECT_LT(worst_rad, 1e-6);
  EXPECT_TRUE(state.X_WB(model, model.FindBody("base_link")).isApprox(model.bodies[0].X_WB0));
}

// A box dropped on a ground plane: as a URDF <box> and as a binary STL mesh of the same size.
std::string DropScene(const std::string& collision_geometry, const std::string& collision_xyz = "0 0 0") {
  return "<robot name='drop'><link name='world'/>"
         "<link name='ground'><collision><geometry><box size='1 1 1'/></geometry><implicit type='halfspace'/>"
         "</collision></link><joint name='g' type='fixed'><parent link='world'/><child link='ground'/></joint>"
         "<link name='box'><inertial><mass value='1'/>"
         "<inertia ixx='0.01' iyy='0.01' izz='0.01' ixy='0' ixz='0' iyz='0'/></inertial>"
         "<collision><origin xyz='" + collision_xyz + "'/><geometry>" + collision_geometry +
         "</geometry></collision></link>"
         "<joint name='b' type='floating'><parent link='world'/><child link='box'/><origin xyz='0.25 0 0.3'/>"
         "</joint></robot>";
}

TEST_F(RobotUrdf, AMeshBoxRestsOnAPlaneAtTheHeightOfTheSameUrdfBox) {
  // The mesh's centre is at kCentre in its frame: its collision origin -kCentre puts it where the URDF box is.
  const Model mesh = Load(DropScene("<mesh filename='box_binary.stl'/>", "-0.25 0 0.125"));
  const Model box = Load(DropScene("<box size='0.25 0.125 0.5'/>"));
  double rest[2];
  for (int m = 0; m < 2; ++m) {
    const Model& model = m == 0 ? mesh : box;
    Data data(model);
    State state = State::Initial(model);
    StepperOptions options;
    for (int i = 0; i < 150; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged);
    const Pose X_WB = state.X_WB(model, model.FindBody("box"));
    Vec3 lowest;
    ASSERT_TRUE(SupportPoint(model.bodies[1].shapes[0], X_WB, -Vec3::UnitZ(), &lowest));
    rest[m] = X_WB.translation().z();
    EXPECT_NEAR(lowest.z(), 0.0, 1e-3);
  }
  RecordProperty("rest_height_m", Scientific(rest[0]));
  RecordProperty("rest_height_difference_m", Scientific(rest[0] - rest[1]));
  EXPECT_NEAR(rest[0], rest[1], 1e-6);
  EXPECT_NEAR(rest[1], 0.25, 1e-3);
}

// A static mesh box 'table' and a mesh box dropped onto it from 2 cm, on a floating joint to `parent`.
std::string StackScene(const std::string& parent) {
  const std::string world = parent == "world" ? "<link name='world'/><joint name='t' type='fixed'>"
                                                "<parent link='world'/><child link='table'/></joint>"
                                              : "";
  return "<robot name='stack'>" + world +
         "<link name='table'><collision><origin xyz='-0.25 0 0.125'/>"
         "<geometry><mesh filename='box_binary.stl'/></geometry></collision></link>"
         "<link name='box'><inertial><mass value='1'/>"
         "<inertia ixx='0.01' iyy='0.01' izz='0.01' ixy='0' ixz='0' iyz='0'/></inertial>"
         "<collision><origin xyz='-0.25 0 0.125'/><geometry><mesh filename='box_ascii.stl'/></geometry></collision>"
         "</link><joint name='drop' type='floating'><parent link='" + parent + "'/><child link='box'/>"
         "<origin xyz='0.02 0.01 0.52'/></joint></robot>";
}

// Two polytopes in contact: the distance oracle over their 12 planes.
TEST_F(RobotUrdf, AMeshBoxRestsOnAStaticMeshBox) {
  // Under a root other than 'world' a floating joint is refused (the root is not the world) ...
  EXPECT_THROW(Load(StackScene("table")), std::invalid_argument);
  // ... under 'world' the top box comes to rest 0.25 + 0.25 m above the table's centre.
  const Model model = Load(StackScene("world"));
  EXPECT_EQ(model.pairs.size(), 1u);
  Data data(model);
  State state = State::Initial(model);
  StepperOptions options;
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
  const Pose X_WB = state.X_WB(model, model.FindBody("box"));
  RecordProperty("stacked_height_m", Scientific(X_WB.translation().z()));
  EXPECT_NEAR(X_WB.translation().z(), 0.5, 1e-4);
  EXPECT_NEAR(X_WB.translation().x(), 0.02, 1e-4);
  EXPECT_LT(state.v.norm(), 1e-3);
}

TEST_F(RobotUrdf, AMeshAboveTheFaceCapIsSimplifiedAndTheWarningSaysSo) {
  std::vector<Vec3> sphere;
  for (int i = 0; i < 200; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / 200, r = std::sqrt(1.0 - z * z), phi = i * kPi * (3.0 - std::sqrt(5.0));
    sphere.push_back(0.1 * Vec3(r * std::cos(phi), r * std::sin(phi), z));
  }
  std::vector<std::vector<int>> strip;  // assimp keeps only the vertices that faces use
  for (int k = 1; k + 2 <= 200; ++k) strip.push_back({k, k + 1, k + 2});
  WriteObj(dir_ + "/sphere.obj", sphere, strip);
  LoaderOptions options;
  options.max_hull_faces = 20;
  const Model model = Load(Robot("sphere.obj"), options);
  const Body& arm = model.bodies[model.FindBody("arm")];
  EXPECT_LE(arm.shapes[0].inequalities.size(), 20u);
  ASSERT_EQ(warnings_.size(), 1u);
  RecordProperty("warning", warnings_[0]);
  EXPECT_NE(warnings_[0].find("link 'arm': collision mesh 'sphere.obj' replaced by its convex hull (" +
                              std::to_string(arm.shapes[0].inequalities.size()) + " faces; simplified from 396 faces"),
            std::string::npos)
      << warnings_[0];
  const Pose X_SL = arm.shapes[0].X_BS.inverse() * arm.X_BL;
  // Within 1e-8 m: assimp's OBJ number parser is not correctly rounded (about one float ulp at 0.1 m).
  for (const Vec3& p : AsFloats(sphere)) {
    for (const Inequality& q : arm.shapes[0].inequalities) EXPECT_LE(q.Value(X_SL * p), 1e-8);
  }
}

TEST_F(RobotUrdf, AMeshOverTheSizeCapIsRefusedBeforeItIsRead) {
  LoaderOptions options;
  options.max_mesh_bytes = fs::file_size(dir_ + "/octahedron.obj") - 1;
  try {
    Load(Robot("octahedron.obj"), options);
    ADD_FAILURE() << "loaded";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("over the limit of " + std::to_string(options.max_mesh_bytes)),
              std::string::npos) << e.what();
  }
  options.max_mesh_bytes += 1;
  EXPECT_NO_THROW(Load(Robot("octahedron.obj"), options));
}

TEST_F(RobotUrdf, ASandboxedLoaderReadsMeshesInItsRootsAndPackagesOnly) {
  LoaderOptions options;
  options.mesh_sandbox.roots = {dir_ + "/share/test_robot_meshes"};
  options.mesh_sandbox.package_files = true;
  EXPECT_NO_THROW(Load(Robot("share/test_robot_meshes/meshes/box.stl"), options));  // in a root
  EXPECT_NO_THROW(Load(Robot("package://nested_meshes/octahedron.obj"), options));  // in a package
  const auto refusal = [&](const std::string& uri) {
    try {
      Load(Robot(uri), options);
    } catch (const std::invalid_argument& e) {
      std::string message = e.what();
      for (size_t at = message.find(uri); at != std::string::npos; at = message.find(uri)) message.erase(at, uri.size());
      return message;
    }
    return std::string("(loaded)");
  };
  const std::string missing = refusal("no_such_mesh.stl");
  EXPECT_NE(missing.find("no readable mesh file there"), std::string::npos) << missing;
  EXPECT_EQ(refusal("octahedron.obj"), missing);  // exists, outside the roots and any package
  EXPECT_EQ(refusal("package://nested_meshes/../../../octahedron.obj"), missing);  // out of its package
  options.mesh_sandbox = FileSandbox();  // unrestricted (the default): both load
  EXPECT_NO_THROW(Load(Robot("octahedron.obj"), options));
  EXPECT_NO_THROW(Load(Robot("package://nested_meshes/../../../octahedron.obj"), options));
}

TEST_F(RobotUrdf, BadMeshesNameTheLinkAndTheFile) {
  const std::string missing = LoadError(Robot("no_such_mesh.stl"));
  EXPECT_NE(missing.find("link 'arm'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("no_such_mesh.stl"), std::string::npos) << missing;
  EXPECT_NE(missing.find("does not exist"), std::string::npos) << missing;
  const std::string planar = LoadError(Robot("planar.obj"));
  EXPECT_NE(planar.find("link 'arm'"), std::string::npos) << planar;
  EXPECT_NE(planar.find("planar.obj"), std::string::npos) << planar;
  EXPECT_NE(planar.find("coplanar"), std::string::npos) << planar;
  const std::string package = LoadError(Robot("package://no_such_package/meshes/arm.stl"));
  EXPECT_NE(package.find("link 'arm'"), std::string::npos) << package;
  EXPECT_NE(package.find("package://no_such_package/meshes/arm.stl"), std::string::npos) << package;
  EXPECT_NE(package.find("not found"), std::string::npos) << package;
  std::ofstream(dir_ + "/garbage.stl") << "not a mesh at all";
  const std::string garbage = LoadError(Robot("garbage.stl"));
  EXPECT_NE(garbage.find("link 'arm'"), std::string::npos) << garbage;
  EXPECT_NE(garbage.find("garbage.stl"), std::string::npos) << garbage;
  // A moving link with neither <inertial> nor <collision> has no mass to take.
  std::string bare = Robot("box_binary.stl", "");
  const std::string arm_collision = "<collision><origin xyz='0 0 0'/><geometry><mesh filename='box_binary.stl'/>"
                                    "</geometry></collision>";
  bare.erase(bare.find(arm_collision), arm_collision.size());
  const std::string massless = LoadError(bare);
  EXPECT_NE(massless.find("link 'arm': a moving link needs <inertial> or a <collision>"), std::string::npos)
      << massless;
  // Nothing is warned about a load that fails.
  EXPECT_TRUE(warnings_.empty());
}

TEST_F(RobotUrdf, TheWarningGoesToStderrWithoutAWarningsVector) {
  const std::string path = dir_ + "/robot.urdf";
  std::ofstream(path) << Robot("octahedron.obj");
  ::testing::internal::CaptureStderr();
  LoadSceneFromFile(path);
  const std::string printed = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "implicit_sim: link 'arm': collision mesh 'octahedron.obj' replaced by its convex hull "
                     "(8 faces)\n");
}

TEST_F(RobotUrdf, RootOptionsAreRefusedForAWorldRootAndOutOfRangeCaps) {
  const std::string world_scene = DropScene("<box size='0.25 0.125 0.5'/>");
  LoaderOptions floating;
  floating.floating_root = true;
  EXPECT_THROW(LoadSceneFromString(world_scene, "s", floating), std::invalid_argument);
  LoaderOptions bad_cap;
  bad_cap.max_hull_faces = 3;
  try {
    LoadSceneFromString(world_scene, "s", bad_cap);
    ADD_FAILURE() << "accepted max_hull_faces = 3";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_hull_faces = 3 is out of range [4, 10000]"), std::string::npos);
  }
  LoaderOptions sheared;
  sheared.X_W_root.linear()(0, 1) = 0.5;
  EXPECT_THROW(Load(Robot("box_binary.stl"), sheared), std::invalid_argument);
  // A floating root without <inertial> takes the mass of its 0.2 x 0.2 x 0.1 m box at 1000 kg/m^3.
  const Model free_base = Load(Robot("box_binary.stl"), floating);
  EXPECT_NEAR(free_base.bodies[free_base.FindBody("base_link")].mass, 4.0, 1e-12);
}

TEST_F(RobotUrdf, AMeshLinkWithoutInertialTakesTheHullsMassAtWatersDensity) {
  const Model model = Load(Robot("box_binary.stl", ""));
  const Body& arm = model.bodies[model.FindBody("arm")];
  const double mass = 1000.0 * 8.0 * kHalf.prod();  // kg: the box at 1000 kg/m^3
  EXPECT_NEAR(arm.mass, mass, 1e-9 * mass);
  EXPECT_NEAR((arm.X_BL.inverse().translation() - kCentre).norm(), 0.0, 1e-12);  // the box's centre, in the link frame
  const Vec3 h2 = kHalf.cwiseProduct(kHalf);
  const Vec3 I(h2.y() + h2.z(), h2.x() + h2.z(), h2.x() + h2.y());  // m/3 (b^2 + c^2) with half extents
  EXPECT_LT((arm.I_B - Mat3(Vec3(mass / 3.0 * I).asDiagonal())).norm(), 1e-9 * arm.I_B.norm()) << arm.I_B;
  int notes = 0;
  for (const std::string& w : warnings_) notes += w.find("'arm'") != std::string::npos && w.find("1000 kg/m^3") != std::string::npos;
  EXPECT_EQ(notes, 1);
}

// Points on a sphere (radius 0.1 m): about 2 N triangles before the cap.
std::vector<Vec3> SpherePoints(int count) {
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / count, r = std::sqrt(1.0 - z * z), phi = i * kPi * (3.0 - std::sqrt(5.0));
    points.push_back(0.1 * Vec3(r * std::cos(phi), r * std::sin(phi), z));
  }
  return points;
}

TEST(ConvexHull, AHullAboveTheCapIsSimplifiedAndStillContainsEveryPoint) {
  const std::vector<Vec3> points = SpherePoints(400);
  const ConvexHull full = ComputeConvexHull(points, 10000);
  EXPECT_EQ(full.merge_radius, 0.0);
  EXPECT_EQ(full.faces.size(), 796u);  // a triangulated sphere: 2 V - 4
  const ConvexHull capped = ComputeConvexHull(points, 64);
  RecordProperty("capped_faces", std::to_string(capped.faces.size()));
  RecordProperty("merge_radius_m", Scientific(capped.merge_radius));
  EXPECT_LE(capped.faces.size(), 64u);
  EXPECT_GE(capped.faces.size(), 8u);
  EXPECT_EQ(capped.coplanar_faces, 796);
  EXPECT_GT(capped.merge_radius, 0.0);
  for (const Vec3& p : points) {
    for (const HullFace& face : capped.faces) EXPECT_LE(face.normal.dot(p) - face.offset, 1e-12);
  }
  // The corners are the polytope's own: on at least 3 faces, inside all, and no farther out than 2 x the radius.
  ASSERT_GE(capped.vertices.size(), 4u);
  for (const Vec3& v : capped.vertices) {
    int on = 0;
    for (const HullFace& face : capped.faces) {
      EXPECT_LE(face.normal.dot(v) - face.offset, 1e-9);
      on += std::abs(face.normal.dot(v) - face.offset) <= 1e-9;
    }
    EXPECT_GE(on, 3);
    EXPECT_LT(v.norm(), 0.2);
  }
}

TEST(ConvexHull, RefusesFlatAndNonFiniteAndTooFewPoints) {
  EXPECT_THROW(ComputeConvexHull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, 64), std::invalid_argument);
  EXPECT_THROW(ComputeConvexHull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)}, 64),
               std::invalid_argument);
  EXPECT_THROW(ComputeConvexHull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, NAN)}, 64),
               std::invalid_argument);
  EXPECT_EQ(ComputeConvexHull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, 64).faces.size(), 4u);
}

}  // namespace
}  // namespace implicit_sim
