// implicit_sim_describe: prints the robot_description of a scene (core/io/scene_edit.h RobotDescriptionOf): the scene
// without its free bodies and without the simulator's extension, for robot_state_publisher and rviz's RobotModel.
// sim.launch sets robot_description from it when robot_state_publisher:=true (doc/ros_node.md#robot-urdfs).
// Usage: implicit_sim_describe SCENE [--scenes-dir DIR]   (SCENE: a file path, or a name looked up as DIR/SCENE.urdf)
// Exit status 0, or 1 with one line on stderr naming the problem.
#include <iostream>
#include <string>

#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/urdf_loader.h"

int main(int argc, char** argv) {
  std::string scene, scenes_dir = ".";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--scenes-dir" && i + 1 < argc) {
      scenes_dir = argv[++i];
    } else if (scene.empty() && arg.rfind("--", 0) != 0) {
      scene = arg;
    } else {
      std::cerr << "implicit_sim_describe: unexpected argument '" << arg
                << "'; usage: implicit_sim_describe SCENE [--scenes-dir DIR]" << std::endl;
      return 1;
    }
  }
  if (scene.empty()) {
    std::cerr << "implicit_sim_describe: no scene; usage: implicit_sim_describe SCENE [--scenes-dir DIR]" << std::endl;
    return 1;
  }
  const bool is_path = scene.find('/') != std::string::npos ||
                       (scene.size() > 5 && scene.compare(scene.size() - 5, 5, ".urdf") == 0);
  try {
    std::cout << implicit_sim::RobotDescriptionOf(
        implicit_sim::ReadSceneFile(is_path ? scene : scenes_dir + "/" + scene + ".urdf"));
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_describe: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
