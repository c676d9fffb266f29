// The node's path policy (doc/ros_node.md, "Security"): scene files and meshes named in service requests are read
// only inside ~scenes_dir, the package's scenes/, ~read_dirs and ROS packages, by their canonical path, so symlinks and
// '..' do not lead out; every refusal has one message whether the path exists or not.
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "implicit_sim/ros/world.h"

namespace implicit_sim {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScene = R"(<robot name="one"><link name="world"/><link name="ball"><inertial><mass value="1"/>
  <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>
  <sphere radius="0.05"/></geometry></collision></link><joint name="j" type="floating"><parent link="world"/>
  <child link="ball"/></joint></robot>)";

// A scene of one free link whose collision is the mesh `uri`.
std::string MeshScene(const std::string& uri) {
  return R"(<robot name="meshy"><link name="world"/><link name="part"><inertial><mass value="1"/>
  <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>
  <mesh filename=")" + uri + R"("/></geometry></collision></link><joint name="j" type="floating">
  <parent link="world"/><child link="part"/></joint></robot>)";
}

void Write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

// A cube of half-width 0.05 m as an OBJ file.
void WriteCubeObj(const fs::path& path) {
  std::string text;
  for (int i = 0; i < 8; ++i) {
    text += "v " + std::string(i & 1 ? "0.05" : "-0.05") + (i & 2 ? " 0.05" : " -0.05") + (i & 4 ? " 0.05" : " -0.05") +
            "\n";
  }
  text += "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  Write(path, text);
}

class ReadPolicy : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) / ("read_policy_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "scenes" / "sub");
    fs::create_directories(root_ / "outside");
    fs::create_directories(root_ / "extra");
    Write(root_ / "scenes" / "ball.urdf", kScene);
    Write(root_ / "scenes" / "sub" / "ball2.urdf", kScene);
    Write(root_ / "outside" / "secret.urdf", kScene);
    Write(root_ / "extra" / "more.urdf", kScene);
    fs::create_symlink(root_ / "outside" / "secret.urdf", root_ / "scenes" / "link.urdf");
    fs::create_symlink("/etc/passwd", root_ / "scenes" / "shadow_link.urdf");
    params_.scenes_dir = (root_ / "scenes").string();
  }
  void TearDown() override { fs::remove_all(root_); }

  // The refusal of `file` ("" if it was read).
  std::string Refusal(const std::string& file) {
    SceneText scene;
    std::string error;
    return ReadRequestedScene(params_, "", file, &scene, &error) ? "" : error;
  }
  // The refusal of `file` with its own name taken out, to compare two refusals' text.
  std::string Anonymous(const std::string& file) { return Without(Refusal(file), file); }
  // The loader's refusal of a scene whose mesh is `uri`, the URI taken out ("" if it loaded).
  std::string MeshRefusal(const std::string& uri) {
    try {
      BuildWorld(params_, SceneText{MeshScene(uri), "meshy", (root_ / "scenes").string()}, nullptr);
    } catch (const std::invalid_argument& e) {
      return Without(e.what(), uri);
    }
    return "";
  }
  static std::string Without(std::string message, const std::string& name) {
    for (size_t at = message.find(name); at != std::string::npos; at = message.find(name)) message.erase(at, name.size());
    return message;
  }

  fs::path root_;
  NodeParams params_;
};

TEST_F(ReadPolicy, NamesAndPathsInsideTheScenesFolderAreRead) {
  EXPECT_EQ(Refusal("ball"), "");
  EXPECT_EQ(Refusal("ball.urdf"), "");  // a name with its extension: in ~scenes_dir, not the working directory
  EXPECT_EQ(Refusal("sub/ball2.urdf"), "");
  EXPECT_EQ(Refusal((root_ / "scenes" / "sub" / "ball2.urdf").string()), "");
  EXPECT_EQ(Refusal("cube_drop"), "");  // the package's scenes/ after ~scenes_dir
  SceneText scene;
  std::string error;
  ASSERT_TRUE(ReadRequestedScene(params_, "", "sub/ball2", &scene, &error)) << error;
  EXPECT_EQ(scene.name, "ball2");
  EXPECT_EQ(fs::path(scene.dir), fs::canonical(root_ / "scenes" / "sub"));
}

TEST_F(ReadPolicy, EveryWayOutIsRefusedWithOneMessage) {
  const std::string missing = Anonymous("no_such_scene");
  ASSERT_NE(missing, "");
  EXPECT_NE(missing.find("no readable scene file there"), std::string::npos) << missing;
  const std::string outside = (root_ / "outside" / "secret.urdf").string();
  for (const std::string& file : {std::string("link"), std::string("shadow_link"), std::string("shadow_link.urdf"),
                                  std::string("../outside/secret.urdf"), outside, std::string("/etc/passwd"),
                                  std::string("/etc/no_such_file"), std::string("sub/../../outside/secret"),
                                  (root_ / "scenes" / "sub").string()}) {
    EXPECT_EQ(Anonymous(file), missing) << file;
  }
  EXPECT_EQ(Refusal("/etc/passwd").find("root:"), std::string::npos);
}

TEST_F(ReadPolicy, APackageUriStaysInsideItsPackage) {
  EXPECT_EQ(Refusal("package://implicit_sim/scenes/cube_drop.urdf"), "");
  const std::string missing = Anonymous("package://implicit_sim/scenes/no_such_file.urdf");
  EXPECT_NE(missing.find("no readable scene file there"), std::string::npos) << missing;
  EXPECT_EQ(Anonymous("package://implicit_sim/../../../../../../../../../etc/passwd"), missing);
  EXPECT_EQ(Anonymous("package://implicit_sim/../../../../../../../../../etc/no_such_file"), missing);
  EXPECT_NE(Refusal("package://no_such_package_xyz/a.urdf").find("no such package"), std::string::npos);
}

TEST_F(ReadPolicy, ReadDirsWidenTheSandbox) {
  const std::string more = (root_ / "extra" / "more.urdf").string();
  EXPECT_NE(Refusal(more), "");
  params_.read_dirs = {(root_ / "extra").string()};
  EXPECT_EQ(Refusal(more), "");
}

TEST_F(ReadPolicy, MeshesAreReadOnlyInsideTheSandbox) {
  WriteCubeObj(root_ / "scenes" / "cube.obj");
  WriteCubeObj(root_ / "outside" / "cube.obj");
  fs::create_symlink(root_ / "outside" / "cube.obj", root_ / "scenes" / "cube_link.obj");
  EXPECT_EQ(MeshRefusal("cube.obj"), "");  // relative to the scene's folder
  EXPECT_EQ(MeshRefusal((root_ / "scenes" / "cube.obj").string()), "");
  EXPECT_EQ(MeshRefusal("package://implicit_sim/test/data/vendor/ur_description/meshes/ur5/collision/base.stl"), "");
  // Every way out fails with one message (the URI itself taken out).
  const std::string missing = MeshRefusal("/etc/no_such_mesh.stl");
  ASSERT_NE(missing.find("no readable mesh file there"), std::string::npos) << missing;
  for (const std::string& uri :
       {std::string("/etc/passwd"), std::string("file:///proc/self/environ"), std::string("cube_link.obj"),
        std::string("../outside/cube.obj"), (root_ / "outside" / "cube.obj").string(),
        std::string("package://implicit_sim/../../../../../../../../../etc/passwd")}) {
    EXPECT_EQ(MeshRefusal(uri), missing) << uri;
  }
}

}  // namespace
}  // namespace implicit_sim

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
