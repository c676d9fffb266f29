// Vendor robot descriptions as published (test/data/vendor: the xacro output of ros-industrial/universal_robot's
// ur5.xacro, frankaemika/franka_ros's panda.urdf.xacro and Kinovarobotics/kinova-ros's j2n6s300_standalone.xacro, with
// their collision meshes), loaded unedited: the UR5 (+-2 pi joints, 7 STL hulls), the Panda without <inertial> (several
// collisions per link, mimic fingers, franka's <dynamics D K>), the Panda with gazebo:=true and the Jaco (13 Collada
// hulls, Z_UP). Each is held at a pose by PD drives for 1 s with every step converged; the Panda's second finger is
// the first's mimic follower. Also a robot's configuration set by joint positions (model/joint_configuration.h), the
// hull cache of repeated loads and the mimic fingers grasping a part.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/joint_configuration.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/step_health.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

const std::string kVendorDir = std::string(IMPLICIT_SIM_SOURCE_DIR) + "/test/data/vendor";

// package:// URIs into test/data/vendor, the joints' start positions, the loader's notes into *notes.
LoaderOptions VendorOptions(const std::map<std::string, double>& positions, std::vector<std::string>* notes) {
  LoaderOptions options;
  options.resolve_package_uri = [](const std::string& uri) {
    return kVendorDir + "/" + uri.substr(std::string("package://").size());
  };
  options.joint_positions = positions;
  options.warnings = notes;
  return options;
}

Model LoadVendor(const std::string& relative, const std::map<std::string, double>& positions,
                 std::vector<std::string>* notes) {
  return LoadSceneFromFile(kVendorDir + "/" + relative, VendorOptions(positions, notes));
}

// Holds every driven joint (all with a coordinate but mimic followers) at its start position for `seconds`; returns
// the largest |q - target| at the end (rad or m) and counts non-converged steps.
double Hold(const Model& model, double seconds, int* nonconverged, bool gravity_compensation = false) {
  StepperOptions options;
  options.h = 0.005;
  Data data(model);
  State state = State::Initial(model);
  std::vector<double> target(model.joints.size(), 0.0);
  for (int j = 0; j < static_cast<int>(model.joints.size()); ++j) {
    const Joint& joint = model.joints[j];
    if (!joint.has_coordinate() || joint.mimics()) continue;
    target[j] = JointPosition(model, state, j);
    data.joint_drives[j] = JointDrive{target[j], 0.0, 5000.0, 100.0, gravity_compensation};
  }
  *nonconverged = 0;
  for (int i = 0; i < std::lround(seconds / options.h); ++i) *nonconverged += !Step(model, options, &state, &data).converged;
  double worst = 0.0;
  for (int j = 0; j < static_cast<int>(model.joints.size()); ++j) {
    if (JointDriveActive(data.joint_drives[j])) {
      worst = std::max(worst, std::abs(JointDrivePositionError(model.joints[j], target[j], JointPosition(model, state, j))));
    }
  }
  return worst;
}

TEST(VendorRobots, TheUr5LoadsAsPublishedAndIsHeldByItsDrives) {
  std::vector<std::string> notes;
  const Model model = LoadVendor("ur_description/urdf/ur5.urdf", {{"shoulder_lift_joint", -1.2}, {"elbow_joint", 1.0}},
                                 &notes);
  EXPECT_EQ(model.num_moving(), 6);
  EXPECT_FALSE(model.joints[model.FindJoint("shoulder_pan_joint")].limited);  // +-2 pi: no limit rows
  int nonconverged = 0;
  const double error = Hold(model, 1.0, &nonconverged);
  EXPECT_EQ(nonconverged, 0);
  EXPECT_LT(error, 0.02);  // PD sag: the shoulder's gravity torque over kp = 5000 N m/rad
  const double compensated = Hold(model, 1.0, &nonconverged, true);
  EXPECT_EQ(nonconverged, 0);
  EXPECT_LT(compensated, 1e-6);  // the gravity feed-forward holds it where it starts
  std::printf("[ vendor ] UR5: %zu bodies, %zu pairs, held 1 s with the largest joint error %.2e rad, %.2e rad with "
              "the gravity feed-forward\n", model.bodies.size(), model.pairs.size(), error, compensated);
}

TEST(VendorRobots, ThePandaLoadsAsPublishedWithItsFingersMimicking) {
  // franka's "ready" pose; joint4 has limits [-3.07, -0.07] rad, so the URDF's zero pose is refused.
  const std::map<std::string, double> ready = {{"panda_joint2", -0.785}, {"panda_joint4", -2.356},
                                               {"panda_joint6", 1.571}, {"panda_joint7", 0.785},
                                               {"panda_finger_joint1", 0.02}};
  std::vector<std::string> notes;
  try {
    LoadVendor("franka_description/robots/panda.urdf", {}, &notes);
    ADD_FAILURE() << "the zero pose outside joint4's limits loaded";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'panda_joint4' starts at 0, outside its limits"), std::string::npos)
        << e.what();
  }
  for (const char* file : {"panda.urdf", "panda_gazebo.urdf"}) {
    SCOPED_TRACE(file);
    notes.clear();
    const Model model = LoadVendor(std::string("franka_description/robots/") + file, ready, &notes);
    const int follower = model.FindJoint("panda_finger_joint2"), leader = model.FindJoint("panda_finger_joint1");
    ASSERT_GE(follower, 0);
    EXPECT_EQ(model.joints[follower].mimic_leader, leader);
    const bool published_inertia = std::string(file) == "panda_gazebo.urdf";
    // At the ready pose the hulls are apart; panda.urdf's fat self-collision capsules (*_sc) reach into the links
    // two joints away (4 pairs, 29-49 mm): one note either way, never a refusal.
    int overlap_notes = 0;
    for (const std::string& note : notes) {
      overlap_notes += note.find("overlap at their robot's start pose") != std::string::npos;
    }
    EXPECT_EQ(overlap_notes, published_inertia ? 0 : 1);
    if (!published_inertia) {
      EXPECT_EQ(model.bodies[model.FindBody("panda_link0_sc")].shapes.size(), 3u);
    }
    bool noted_D = false;
    for (const std::string& note : notes) noted_D = noted_D || note.find("'D' of <dynamics>") != std::string::npos;
    EXPECT_TRUE(noted_D);
    int nonconverged = 0;
    const double error = Hold(model, 1.0, &nonconverged);
    EXPECT_EQ(nonconverged, 0);
    // Without <inertial> the links weigh what their fat self-collision capsules hold at 1000 kg/m^3, more than the
    // wrists' 12 N m effort limits carry: only the published inertias are held.
    if (published_inertia) {
      EXPECT_LT(error, 0.02);
    }
    double mass = 0.0;
    for (const Body& body : model.bodies) mass += body.mass;
    std::printf("[ vendor ] Panda (%s): %zu bodies (%.1f kg), %zu joints, held 1 s with the largest joint error "
                "%.2e\n", file, model.bodies.size(), mass, model.joints.size(), error);
  }
  // Near the zero pose (joint4 at its upper limit) the hulls of links 5 and 7, which no joint joins, overlap (the
  // audit's case): one note names them; the robot loads, its self-collision being off.
  notes.clear();
  LoadVendor("franka_description/robots/panda_gazebo.urdf", {{"panda_joint4", -0.0698}}, &notes);
  int zero_pose_notes = 0;
  for (const std::string& note : notes) {
    if (note.find("overlap at their robot's start pose") == std::string::npos) continue;
    ++zero_pose_notes;
    EXPECT_NE(note.find("'panda_link5'-'panda_link7' (0.0064 m)"), std::string::npos) << note;
  }
  EXPECT_EQ(zero_pose_notes, 1);
}

// Kinova's j2n6s300 (a 6-joint Jaco 2 with three fingers), whose 13 collision meshes are Blender Collada files with
// <up_axis>Z_UP</up_axis>: it loads unedited at Kinova's home pose (joints 2 and 3 have limits that exclude zero) and is
// held by its drives with every step converged, once as published and once spawned with self-collision on (the hulls
// of links no joint joins become contact pairs: the fingers, hand and forearm). The vendor also ships each part as STL in the same frame: the hull of
// finger_distal.dae matches the hull of finger_distal.STL vertex for vertex, so the up axis is honoured as the file
// states it.
TEST(VendorRobots, TheKinovaJacoLoadsItsColladaMeshesAsPublished) {
  const std::map<std::string, double> home = {
      {"j2n6s300_joint_1", 4.80}, {"j2n6s300_joint_2", 2.92}, {"j2n6s300_joint_3", 1.00},
      {"j2n6s300_joint_4", 4.20}, {"j2n6s300_joint_5", 1.44}, {"j2n6s300_joint_6", 1.31}};
  std::vector<std::string> notes;
  const Model model = LoadVendor("kinova_description/urdf/j2n6s300_standalone.urdf", home, &notes);
  EXPECT_EQ(model.num_moving(), 12);  // six links, three fingers of two links each
  int nonconverged = 0;
  const double compensated = Hold(model, 1.0, &nonconverged, true);
  EXPECT_EQ(nonconverged, 0);
  EXPECT_LT(compensated, 1e-6);
  SceneAddition self_colliding;
  std::ifstream in(kVendorDir + "/kinova_description/urdf/j2n6s300_standalone.urdf");
  self_colliding.urdf.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  self_colliding.self_collide = true;
  const Model colliding = LoadSceneFromString(AddToScene("<robot name='w'><link name='world'/></robot>",
                                                         self_colliding, nullptr), "jaco", VendorOptions(home, &notes));
  EXPECT_GT(colliding.pairs.size(), 20u);
  const double colliding_error = Hold(colliding, 1.0, &nonconverged, true);
  EXPECT_EQ(nonconverged, 0);
  EXPECT_LT(colliding_error, 1e-6);
  std::printf("[ vendor ] Jaco j2n6s300: %zu bodies, held 1 s with the largest joint error %.2e rad; with "
              "self-collision (%zu pairs) %.2e rad\n", model.bodies.size(), compensated, colliding.pairs.size(),
              colliding_error);

  auto finger_hull = [&](const std::string& mesh) {
    const std::string urdf =
        "<robot name='f'><link name='world'/><link name='finger'><inertial><mass value='0.01'/><inertia ixx='1e-6' "
        "iyy='1e-6' izz='1e-6' ixy='0' ixz='0' iyz='0'/></inertial><collision><geometry><mesh filename='package://"
        "kinova_description/meshes/" + mesh + "'/></geometry></collision></link><joint name='j' type='floating'>"
        "<parent link='world'/><child link='finger'/></joint></robot>";
    return LoadSceneFromString(urdf, "f", VendorOptions({}, &notes)).bodies[0].shapes[0].vertices;
  };
  // Support functions h(d) = max over the hull of d . v along 400 directions spread over the sphere: the two hulls
  // are simplified separately (to max_hull_faces), so they agree to the simplification's tolerance, not vertex for
  // vertex; a hull turned by 90 deg would differ by centimetres.
  auto support = [](const std::vector<Vec3>& vertices, const Vec3& d) {
    double h = -1e300;
    for (const Vec3& v : vertices) h = std::max(h, d.dot(v));
    return h;
  };
  const std::vector<Vec3> from_collada = finger_hull("finger_distal.dae"), from_stl = finger_hull("finger_distal.STL");
  double largest = 0.0, extent = 0.0;
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = k * 2.399963229728653;
    const Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
    largest = std::max(largest, std::abs(support(from_collada, d) - support(from_stl, d)));
    extent = std::max(extent, support(from_stl, d) + support(from_stl, -d));
  }
  std::printf("[ vendor ] Jaco finger_distal: the Collada and STL hulls' support functions differ by at most %.2e m "
              "over a %.3f m part\n", largest, extent);
  EXPECT_GT(extent, 0.03);  // the distal finger is about 4.5 cm long
  EXPECT_LT(largest, 5e-4);
}


// The Panda's mimic gripper grasps a part: a 0.02 x 0.03 x 0.02 m box (50 g) placed between the rubber tips of the
// open fingers (0.04 m apart) at the ready pose, the arm held by drives, finger joint 1 driven closed (its mimic
// follows). The fingers stop on the box's 0.03 m width, hold it (it drops while the fingers close, then stays), and no
// body sinks into another (the penetration bound of every pair after every step).
TEST(VendorRobots, ThePandasMimicFingersGraspAPart) {
  const std::map<std::string, double> ready = {{"panda_joint2", -0.785}, {"panda_joint4", -2.356},
                                               {"panda_joint6", 1.571}, {"panda_joint7", 0.785},
                                               {"panda_finger_joint1", 0.02}};
  std::vector<std::string> notes;
  const std::string path = kVendorDir + "/franka_description/robots/panda_gazebo.urdf";
  const Model arm = LoadVendor("franka_description/robots/panda_gazebo.urdf", ready, &notes);
  const State arm_state = State::Initial(arm);
  SceneAddition part;
  part.urdf =
      "<robot name='part'><link name='world'/><link name='part'><inertial><mass value='0.05'/><inertia "
      "ixx='5.4e-6' iyy='3.3e-6' izz='5.4e-6' ixy='0' ixz='0' iyz='0'/></inertial><collision><geometry>"
      "<box size='0.02 0.03 0.02'/></geometry></collision></link><joint name='part_joint' type='floating'>"
      "<parent link='world'/><child link='part'/></joint></robot>";
  // Between the tips: 0.0584 m to the finger joints, 0.04525 m on to the tips' centres, along the hand's z.
  part.X_WO = arm_state.X_WL(arm, arm.FindBody("panda_hand")) * Eigen::Translation3d(0, 0, 0.0584 + 0.04525);
  std::vector<std::string> added;
  std::ifstream in(path);
  const std::string panda((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const Model model = LoadSceneFromString(AddToScene(panda, part, &added), "grasp", VendorOptions(ready, &notes));
  const int box = model.FindBody("part"), finger = model.FindJoint("panda_finger_joint1");
  const int follower = model.FindJoint("panda_finger_joint2");
  StepperOptions stepper;
  stepper.h = 0.005;
  Data data(model);
  State state = State::Initial(model);
  for (int j = 0; j < static_cast<int>(model.joints.size()); ++j) {
    if (!model.joints[j].has_coordinate() || model.joints[j].mimics()) continue;
    data.joint_drives[j] = JointDrive{JointPosition(model, state, j), 0.0, 5000.0, 100.0, true};
  }
  data.joint_drives[finger] = JointDrive{0.0, 0.0, 1000.0, 10.0, false};  // close: 15 N on the 0.03 m box
  int nonconverged = 0;
  double z_grasped = 0.0, deepest = 0.0;
  for (int i = 0; i < 200; ++i) {  // 1 s
    nonconverged += !Step(model, stepper, &state, &data).converged;
    if (i == 39) z_grasped = state.X_WB(model, box).translation().z();  // 0.2 s: closed
    Data check(model);
    deepest = std::max(deepest, MaxPenetrationBound(model, state, 1e-9, &check));
  }
  const double z_end = state.X_WB(model, box).translation().z();
  const double q = JointPosition(model, state, finger), q_follower = JointPosition(model, state, follower);
  std::printf("[ vendor ] Panda grasp: fingers at %.6f and %.6f m, the part moved %.2e m from 0.2 s to 1 s, "
              "deepest overlap %.2e m, %d steps not converged\n", q, q_follower, z_end - z_grasped, deepest,
              nonconverged);
  EXPECT_EQ(nonconverged, 0);
  // On the box's faces: a tip's inner face is 7.58 - 15.2 / 2 = -0.02 mm from the joint position, so q = 0.015 + 2e-5.
  EXPECT_NEAR(q, 0.015 + 2e-5, 1e-6);
  EXPECT_NEAR(q_follower, q, 1e-9);
  EXPECT_LT(std::abs(z_end - z_grasped), 1e-6);
  EXPECT_LT(deepest, 1e-6);
}

// ~set_joint_positions' core (model/joint_configuration.h) on the Panda: the named joints read back exactly what was
// set, the mimic finger follows, the joints not named keep their positions, every joint equality holds to round-off,
// the links above the first named joint do not move, the moved links are at rest; bad requests change nothing.
TEST(VendorRobots, SetJointPositionsPlacesThePandaExactly) {
  const std::map<std::string, double> ready = {{"panda_joint2", -0.785}, {"panda_joint4", -2.356},
                                               {"panda_joint6", 1.571}, {"panda_joint7", 0.785},
                                               {"panda_finger_joint1", 0.02}};
  std::vector<std::string> notes;
  const Model model = LoadVendor("franka_description/robots/panda_gazebo.urdf", ready, &notes);
  State state = State::Initial(model);
  state.v.setConstant(0.25);  // moving: the re-placed links must end at rest, the others keep their velocities
  const int joint4 = model.FindJoint("panda_joint4"), joint6 = model.FindJoint("panda_joint6");
  const int finger = model.FindJoint("panda_finger_joint1"), follower = model.FindJoint("panda_finger_joint2");
  std::vector<double> before(model.joints.size());
  for (size_t j = 0; j < model.joints.size(); ++j) before[j] = JointPosition(model, state, static_cast<int>(j));
  // Listed child-first on purpose: the order of the request must not matter.
  const std::map<int, double> request = {{finger, 0.035}, {joint6, 2.5}, {joint4, -1.5}};
  const State original = state;
  std::string error;
  ASSERT_TRUE(SetJointPositions(model, request, &state, &error)) << error;
  for (size_t j = 0; j < model.joints.size(); ++j) {
    const double q = JointPosition(model, state, static_cast<int>(j));
    const double expected = request.count(static_cast<int>(j)) ? request.at(static_cast<int>(j))
                            : static_cast<int>(j) == follower ? 0.035
                                                               : before[j];
    EXPECT_NEAR(q, expected, 1e-12) << model.joints[j].name;
  }
  double drift_m = 1.0, drift_rad = 1.0;
  JointDrift(model, state, &drift_m, &drift_rad);
  EXPECT_LT(drift_m, 1e-12);
  EXPECT_LT(drift_rad, 1e-12);
  const int link3 = model.FindBody("panda_link3"), link4 = model.FindBody("panda_link4");
  const int slot3 = model.velocity_slot[link3], slot4 = model.velocity_slot[link4];
  EXPECT_EQ(state.q.segment<7>(Model::q_offset(slot3)), original.q.segment<7>(Model::q_offset(slot3)));
  EXPECT_EQ(state.v.segment<6>(Model::v_offset(slot3)), original.v.segment<6>(Model::v_offset(slot3)));
  EXPECT_TRUE(state.v.segment<6>(Model::v_offset(slot4)).isZero(0.0));
  EXPECT_GT((state.q.segment<3>(Model::q_offset(slot4)) - original.q.segment<3>(Model::q_offset(slot4))).norm(), 0.0);
  // Refused, naming the joint and the range; the state unchanged.
  const State set = state;
  const int fixed = model.FindJoint("panda_joint8");
  const std::vector<std::pair<std::map<int, double>, std::string>> refusals = {
      {{{joint4, 0.5}}, "joint 'panda_joint4': position 0.5 is outside its limits [-3.0718, -0.0698]"},
      {{{follower, 0.01}}, "joint 'panda_finger_joint2' mimics 'panda_finger_joint1': set that joint instead"},
      {{{joint6, std::nan("")}}, "joint 'panda_joint6': position must be finite"},
      {{{joint6, 1.0}, {static_cast<int>(model.joints.size()), 0.0}},
       "joint index " + std::to_string(model.joints.size()) + " out of range [0, " +
           std::to_string(model.joints.size()) + ")"}};
  for (const auto& [bad, message] : refusals) {
    EXPECT_FALSE(SetJointPositions(model, bad, &state, &error));
    EXPECT_EQ(error, message);
    EXPECT_EQ(state.q, set.q);
    EXPECT_EQ(state.v, set.v);
  }
  if (fixed >= 0) {
    EXPECT_FALSE(SetJointPositions(model, {{fixed, 0.0}}, &state, &error));
    EXPECT_EQ(error, "joint 'panda_joint8' is fixed: it has no position to set");
  }
}

// A hull cache (LoaderOptions::hull_cache, what the node's world edits use): the second load of the Panda reads every
// hull from the cache, adds no hull note and gives the same model, shape for shape; an edited mesh file (other bytes
// under the same name) and another scale are hulled again.
TEST(VendorRobots, AHullCacheHullsEachMeshOnceByContent) {
  std::vector<std::string> first_notes, second_notes;
  LoaderOptions options = VendorOptions({{"panda_joint4", -2.356}}, &first_notes);
  options.hull_cache = std::make_shared<MeshHullCache>();
  auto hull_notes = [](const std::vector<std::string>& notes) {
    int n = 0;
    for (const std::string& note : notes) n += note.find("replaced by its convex hull") != std::string::npos;
    return n;
  };
  const std::string file = kVendorDir + "/franka_description/robots/panda_gazebo.urdf";
  options.warnings = &first_notes;
  const auto start = std::chrono::steady_clock::now();
  const Model first = LoadSceneFromFile(file, options);
  const auto middle = std::chrono::steady_clock::now();
  const size_t hulled = options.hull_cache->misses();
  EXPECT_GT(hulled, 5u);
  EXPECT_EQ(hull_notes(first_notes), static_cast<int>(hulled));
  options.warnings = &second_notes;
  const Model second = LoadSceneFromFile(file, options);
  const auto end = std::chrono::steady_clock::now();
  std::printf("[ INFO ] Panda load: %.1f ms hulling %zu meshes, %.1f ms with every hull cached (printed, never "
              "asserted)\n", std::chrono::duration<double, std::milli>(middle - start).count(), hulled,
              std::chrono::duration<double, std::milli>(end - middle).count());
  EXPECT_EQ(options.hull_cache->misses(), hulled);
  EXPECT_GE(options.hull_cache->hits(), hulled);
  EXPECT_EQ(hull_notes(second_notes), 0);
  ASSERT_EQ(first.bodies.size(), second.bodies.size());
  for (size_t b = 0; b < first.bodies.size(); ++b) {
    ASSERT_EQ(first.bodies[b].shapes.size(), second.bodies[b].shapes.size());
    for (size_t k = 0; k < first.bodies[b].shapes.size(); ++k) {
      const ConvexShape &a = first.bodies[b].shapes[k], &c = second.bodies[b].shapes[k];
      EXPECT_EQ(a.vertices, c.vertices) << first.bodies[b].name;
      EXPECT_TRUE(a.X_BS.isApprox(c.X_BS, 0.0)) << first.bodies[b].name;
    }
  }
  // Same name, other bytes; and another scale: both hulled again.
  const std::string dir = ::testing::TempDir() + "/hull_cache";
  std::filesystem::create_directories(dir);
  auto write_box = [&](double half) {
    std::ofstream out(dir + "/part.obj");
    for (int i = 0; i < 8; ++i) {
      out << "v " << (i & 1 ? half : -half) << " " << (i & 2 ? half : -half) << " " << (i & 4 ? half : -half) << "\n";
    }
    out << "f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\nf 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\nf 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n";
  };
  auto box_scene = [&](double scale) {
    return "<robot name='p'><link name='world'/><link name='part'><inertial><mass value='1'/><inertia ixx='0.01' "
           "iyy='0.01' izz='0.01' ixy='0' ixz='0' iyz='0'/></inertial><collision><geometry><mesh filename='" +
           dir + "/part.obj' scale='" + std::to_string(scale) + " 1 1'/></geometry></collision></link><joint name='j' "
           "type='floating'><parent link='world'/><child link='part'/><origin xyz='0 0 1'/></joint></robot>";
  };
  auto half_width = [](const Model& m) {
    double x = 0.0;
    for (const Vec3& v : m.bodies[m.FindBody("part")].shapes[0].vertices) x = std::max(x, v.x());
    return x;
  };
  LoaderOptions small;
  std::vector<std::string> small_notes;
  small.warnings = &small_notes;
  small.hull_cache = std::make_shared<MeshHullCache>();
  write_box(0.1);
  EXPECT_NEAR(half_width(LoadSceneFromString(box_scene(1.0), "p", small)), 0.1, 1e-6);
  write_box(0.2);
  EXPECT_NEAR(half_width(LoadSceneFromString(box_scene(1.0), "p", small)), 0.2, 1e-6);
  EXPECT_NEAR(half_width(LoadSceneFromString(box_scene(2.0), "p", small)), 0.4, 1e-6);
  EXPECT_NEAR(half_width(LoadSceneFromString(box_scene(1.0), "p", small)), 0.2, 1e-6);
  EXPECT_EQ(small.hull_cache->misses(), 3u);
  EXPECT_EQ(small.hull_cache->hits(), 1u);
  EXPECT_EQ(hull_notes(small_notes), 3);
}

}  // namespace
}  // namespace implicit_sim
