// The model: everything about a scene that does not change while it runs. Const after loading.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/geometry/broad_phase.h"
#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {

// Friction of one contact (paper eq. 4-5): mu (-), e_t and e_o (-), e_r (m: largest torsional moment e_r mu f_n).
struct FrictionParams {
  double mu = 0.5;
  double e_t = 1.0;
  double e_o = 1.0;
  double e_r = 0.1;
  // Rolling resistance (m): the largest rolling moment is e_roll * mu * normal force, as two more components of the
  // friction ellipsoid (about the contact's two tangent axes); 0: none, and the pair has no rolling unknowns.
  double e_roll = 0.0;
};

struct Body {
  std::string name;             // the URDF link name
  bool is_fixed = false;        // fixed to the world (pose X_WB0 forever)
  double mass = 0.0;            // kg (moving bodies)
  Mat3 I_B = Mat3::Zero();      // rotational inertia about the centre of mass, body frame (kg m^2)
  // The collision shapes, in the body frame B (origin at the centre of mass): the body is their union, one per URDF
  // <collision> (each shape of one body meets each shape of another as its own contact pair). Empty: no collision.
  std::vector<ConvexShape> shapes;
  Pose X_BL = Pose::Identity(); // pose of the URDF link frame L in B (non-identity when <inertial> has an origin)
  Pose X_WB0 = Pose::Identity();  // initial pose of B in the world W
  Vec3 v_WB0 = Vec3::Zero();    // initial linear velocity of the centre of mass, world frame (m/s)
  Vec3 w_WB0 = Vec3::Zero();    // initial angular velocity, world frame (rad/s)
  Vec3 f_applied_W = Vec3::Zero();  // constant applied force at the centre of mass, world frame (N)
  Vec3 tau_applied_W = Vec3::Zero();  // constant applied torque, world frame (N m)
  // Locked degrees of freedom in world axes: vx vy vz wx wy wz; a locked velocity stays 0.
  std::array<bool, 6> locked{{false, false, false, false, false, false}};
};

// A URDF joint between two bodies: a bilateral constraint inside the step NCP (joints.h has the rows). The joint frame
// J is the URDF joint frame: the child's link frame coincides with it at joint position 0. A planar joint keeps the
// child's joint origin in the plane through the parent's with normal a and lets it turn about a only: three degrees
// of freedom and no single coordinate (no limits, drives, friction or position of its own).
enum class JointType { kFixed, kRevolute, kContinuous, kPrismatic, kPlanar };
const char* JointTypeName(JointType type);  // "fixed", "revolute", "continuous", "prismatic", "planar"

struct Joint {
  std::string name;
  JointType type = JointType::kRevolute;
  int parent = -1;             // body index of the parent link; -1: the world
  int child = -1;              // body index of the child link (always a moving body)
  Vec3 p_PJ = Vec3::Zero();    // joint origin in the parent's body frame (world frame for the world) (m)
  Vec3 p_CJ = Vec3::Zero();    // joint origin in the child's body frame (m)
  // Columns: the unit axis a, then b1 and b2 = a x b1 normal to it; R_PJ in the parent's body frame, R_CJ in the
  // child's at joint position 0. For a limited revolute joint, b1 and b2 of R_PJ are turned about a by `offset`, so
  // that the angle is measured from the middle of its range (any range shorter than 2 pi then works).
  Mat3 R_PJ = Mat3::Identity();
  Mat3 R_CJ = Mat3::Identity();
  double offset = 0.0;         // rad, see R_PJ
  bool limited = false;        // revolute and prismatic joints (URDF <limit lower upper>)
  double lower = 0.0, upper = 0.0;  // rad (revolute) or m (prismatic)
  double effort_limit = 0.0;   // commanded efforts are clamped to +-effort_limit (N m or N); 0: no clamp
  double velocity_limit = 0.0; // URDF <limit velocity> (rad/s or m/s); 0: none given
  // The step bounds the joint rate: -velocity_limit <= qdot <= velocity_limit at the end of every step, by two
  // complementarity rows (doc/scenes.md#velocity-limits). Off unless asked for: LoaderOptions::enforce_velocity_limits
  // or <implicit_sim><joint enforce_velocity_limit>.
  bool velocity_limited = false;
  double damping = 0.0;        // viscous, N m s/rad or N s/m (URDF <dynamics damping>)
  double friction = 0.0;       // Coulomb, N m or N (URDF <dynamics friction>)
  double initial_position = 0.0;  // rad or m
  double initial_velocity = 0.0;  // rad/s or m/s
  double applied_effort = 0.0;    // constant effort (N m or N), within +-effort_limit when that is > 0
  // URDF <mimic joint multiplier offset>: this joint's position is held at mimic_multiplier q_leader + mimic_offset by
  // one more equality (its multiplier the row's last unknown); -1: none. A follower has no limit rows of its own.
  int mimic_leader = -1;
  double mimic_multiplier = 1.0;  // (-)
  double mimic_offset = 0.0;      // rad or m

  bool has_coordinate() const { return type != JointType::kFixed && type != JointType::kPlanar; }
  bool mimics() const { return mimic_leader >= 0; }
  int num_equalities() const { return type == JointType::kFixed ? 6 : type == JointType::kPlanar ? 3 : 5; }
  // Unknowns of the joint in the step NCP, in this order: one multiplier per equality, two limit multipliers when
  // limited, the friction fraction and slip speed when friction > 0, two velocity-limit multipliers when
  // velocity_limited, and the mimic multiplier last (mimic_column()).
  int friction_column() const { return num_equalities() + (limited ? 2 : 0); }
  int velocity_limit_column() const { return friction_column() + (friction > 0.0 ? 2 : 0); }
  int size() const { return velocity_limit_column() + (velocity_limited ? 2 : 0) + (mimics() ? 1 : 0); }
  int mimic_column() const { return size() - 1; }  // offset of the mimic multiplier in the joint's block
};

// One collision shape of the model: Body::shapes[index] of bodies[body].
struct Geom {
  int body = -1;
  int index = 0;
};

// A candidate contact between shape geom1 of body1 and shape geom2 of body2 (indices into Model::bodies and
// Model::geoms). body1 is always a moving body.
struct ContactPair {
  int body1 = -1;
  int body2 = -1;
  int geom1 = -1;
  int geom2 = -1;
  FrictionParams friction;
};

// A link without a body of its own: no inertia, no collision, fixed joints up to a moving body (an arm's tool0 or a
// camera frame). It moves with that body's link frame L; tf publishes it, the step never sees it.
struct FrameLink {
  std::string name;
  int body = -1;                    // the nearest body above it
  Pose X_LF = Pose::Identity();     // the frame F in the body's link frame L
};

// A sensor declared in the scene (<implicit_sim><sensor name type link|joint rate/>, doc/scenes.md#sensors), read
// after each step (step/sensors.h): a contact sensor reports the contacts touching its link (as Gazebo's bumper), an
// IMU the orientation, angular velocity and specific force of its link's frame, a force-torque sensor the wrench its
// joint carries into its child link.
enum class SensorType { kContact, kImu, kForceTorque };
const char* SensorTypeName(SensorType type);  // "contact", "imu", "force_torque"
struct Sensor {
  std::string name;
  SensorType type = SensorType::kContact;
  std::string link;                 // the URDF link it sits on (a body's, or a frame link's for an IMU; a force-torque
                                    // sensor's joint's child link)
  int body = -1;                    // the body that carries that link
  int joint = -1;                   // a force-torque sensor's joint (index into Model::joints); -1 otherwise
  Pose X_LS = Pose::Identity();     // the sensor frame S (the link's frame) in the body's link frame L
  double rate_hz = 50.0;            // samples per second of simulation time, (0, 1000]
};

struct Model {
  std::vector<Body> bodies;
  std::vector<Geom> geoms;         // every body's shapes, body by body, in shape order (Finalize builds it)
  std::vector<ContactPair> pairs;
  std::vector<Joint> joints;       // parents before children
  std::vector<FrameLink> frames;   // links on moving bodies without a body, in URDF order
  std::vector<Sensor> sensors;     // in the order of the scene's <implicit_sim>
  std::vector<int> moving_bodies;  // indices of the moving bodies, in URDF order: velocity slot k -> body index
  std::vector<int> velocity_slot;  // body index -> velocity slot, -1 for fixed bodies
  // Pairs are listed by (lower geom index i, higher index j), i ascending then j ascending; the pairs whose lower
  // geom is i are pairs[pairs_of_lower[i] .. pairs_of_lower[i + 1]). Size geoms + 1.
  std::vector<int> pairs_of_lower;
  Vec3 gravity_W = Vec3(0.0, 0.0, -9.81);  // m/s^2
  std::string scene_name;
  // Body pairs that form no contact pair (doc/scenes.md#self-collision), set before Finalize: the pairs a scene or SRDF
  // disables (lower index, higher index; sorted), and per body its robot's group when that robot does not collide with
  // itself (-1: none; empty: no groups). Two bodies of one group never form a pair.
  std::vector<std::pair<int, int>> excluded_pairs;
  std::vector<int> self_collision_group;
  std::unordered_map<std::string, int> body_by_name, joint_by_name;  // IndexNames

  int num_moving() const { return static_cast<int>(moving_bodies.size()); }
  // Sizes of State::q (position and unit quaternion per moving body) and State::v (linear and angular velocity).
  static constexpr int kBodyNq = 7;
  static constexpr int kBodyNv = 6;
  int nq() const { return kBodyNq * num_moving(); }
  int nv() const { return kBodyNv * num_moving(); }
  // Where moving body slot k starts in q (p_WB at +0, the quaternion w, x, y, z at +3) and in v (v_WB at +0, w_WB
  // at +3); the same offsets index 6-per-body wrench vectors.
  static int q_offset(int slot) { return kBodyNq * slot; }
  static int v_offset(int slot) { return kBodyNv * slot; }
  // -1 if absent. By hash once IndexNames (Finalize) has indexed every body or joint; by a linear scan before.
  int FindBody(const std::string& name) const;
  int FindJoint(const std::string& name) const;
  // Indexes the bodies' and joints' names for FindBody and FindJoint; again after any change of bodies or joints.
  void IndexNames();
  // Whether bodies i and j form no pair by excluded_pairs or self_collision_group (joints aside).
  bool Excluded(int i, int j) const;
  bool InOneSelfCollisionGroup(int i, int j) const {
    return !self_collision_group.empty() && self_collision_group[i] >= 0 &&
           self_collision_group[i] == self_collision_group[j];
  }
  const ConvexShape& shape(int geom) const { return bodies[geoms[geom].body].shapes[geoms[geom].index]; }
  // The pair of geoms i and j (either order), -1 if they form none (one body, both fixed, or joined bodies).
  int GeomPairIndex(int i, int j) const;
  // The first pair of bodies i and j (either order; their only one when each has one shape), -1 if none.
  int PairIndex(int i, int j) const;
  // "<link1>-<link2>", body1 first; a body with several shapes is named "<link>#<k>" for its k-th shape (from 0).
  std::string PairName(int pair) const;
  std::string GeomName(int geom) const;  // "<link>", or "<link>#<k>" on a body with several shapes
  // The largest distance from a body's centre of mass to a point of its shapes (m): 0 without shapes, +inf for a
  // half-space or a general intersection.
  double BodyReach(int body) const;
  // Builds moving_bodies, velocity_slot, geoms, the name index and one pair for every two shapes of two bodies of which
  // at least one moves, that no joint joins directly (adjacent links touch at their joint by design, as in MoveIt's
  // default ACM) and that are not Excluded. `pair_friction(i, j)` gives the friction of bodies i and j; bodies must
  // already be filled in. Watches `interrupt` between geoms (LoadInterrupted).
  template <typename FrictionOf>
  void Finalize(FrictionOf pair_friction, const StepInterrupt* interrupt = nullptr);
  // The most contact pairs Finalize can form from the bodies' shapes (every two shapes of two bodies of which one moves,
  // less the excluded body pairs), counted without forming them.
  int64_t ContactPairBound() const;
  // Finalize refuses a scene whose bound exceeds this (std::invalid_argument, before allocating): every pair is stored,
  // about 80 bytes in the model and the step's workspace, so 2^23 pairs take about 650 MB (a pile of 4000 parts).
  static constexpr int64_t kMaxContactPairs = int64_t{1} << 23;
  // A force scale (N) for the solver's row scaling: over the moving bodies, the largest of |m g + f_applied| and
  // m max(|g|, 1 m/s^2); at least 1e-3 N.
  double ForceScale() const;
};

// The broad phase over the model's bodies; its candidates are model pair indices. It refers to the model, which must
// outlive it.
BroadPhase MakeBroadPhase(const Model& model);

template <typename FrictionOf>
void Model::Finalize(FrictionOf pair_friction, const StepInterrupt* interrupt) {
  moving_bodies.clear();
  velocity_slot.assign(bodies.size(), -1);
  for (int i = 0; i < static_cast<int>(bodies.size()); ++i) {
    if (!bodies[i].is_fixed) {
      velocity_slot[i] = static_cast<int>(moving_bodies.size());
      moving_bodies.push_back(i);
    }
  }
  IndexNames();
  geoms.clear();
  for (int b = 0; b < static_cast<int>(bodies.size()); ++b) {
    for (int k = 0; k < static_cast<int>(bodies[b].shapes.size()); ++k) geoms.push_back(Geom{b, k});
  }
  const int64_t bound = ContactPairBound();
  if (bound > kMaxContactPairs) {
    throw std::invalid_argument("scene: " + std::to_string(bodies.size()) + " bodies with " +
                                std::to_string(geoms.size()) + " shapes can form " + std::to_string(bound) +
                                " contact pairs, over the limit of " + std::to_string(kMaxContactPairs) +
                                " (Model::kMaxContactPairs; every pair is stored, about 80 bytes each): fewer moving "
                                "bodies, or fewer shapes on them");
  }
  std::vector<std::pair<int, int>> joined;  // body pairs a joint joins, sorted
  for (const Joint& joint : joints) {
    if (joint.parent >= 0) joined.emplace_back(std::min(joint.parent, joint.child), std::max(joint.parent, joint.child));
  }
  std::sort(joined.begin(), joined.end());
  pairs.clear();
  pairs_of_lower.assign(geoms.size() + 1, 0);
  for (int gi = 0; gi < static_cast<int>(geoms.size()); ++gi) {
    ThrowIfLoadInterrupted(interrupt, scene_name);
    pairs_of_lower[gi] = static_cast<int>(pairs.size());
    const int i = geoms[gi].body;
    for (int gj = gi + 1; gj < static_cast<int>(geoms.size()); ++gj) {
      const int j = geoms[gj].body;
      if (i == j || (bodies[i].is_fixed && bodies[j].is_fixed)) continue;
      if (shape(gi).inequalities.empty() || shape(gj).inequalities.empty()) continue;
      if (Excluded(i, j) || std::binary_search(joined.begin(), joined.end(), std::make_pair(i, j))) continue;
      const bool swap = bodies[i].is_fixed;  // body1 moves
      ContactPair pair;
      pair.body1 = swap ? j : i;
      pair.body2 = swap ? i : j;
      pair.geom1 = swap ? gj : gi;
      pair.geom2 = swap ? gi : gj;
      pair.friction = pair_friction(pair.body1, pair.body2);
      pairs.push_back(pair);
    }
  }
  pairs_of_lower[geoms.size()] = static_cast<int>(pairs.size());
}

}  // namespace implicit_sim
