#include "self_collision.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "implicit_sim/core/geometry/support.h"
#include "loader_util.h"
#include "urdf_joints.h"

namespace implicit_sim {
namespace loader {
namespace {

int Root(std::vector<int>* parent, int i) {
  while ((*parent)[i] != i) i = (*parent)[i] = (*parent)[(*parent)[i]];
  return i;
}

// The body of a link: its own, or for a frame link its nearest ancestor's; -1 for `world` and what hangs on it only
// through frame links.
class LinkBodies {
 public:
  LinkBodies(const urdf::ModelInterface& urdf, const Model& model) : urdf_(urdf) {
    for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) body_of_name_[model.bodies[b].name] = b;
  }
  int Of(const std::string& link) {
    const urdf::LinkConstSharedPtr l = urdf_.getLink(link);
    if (!l) return -1;
    return FirstValueUp(*l, &known_, [&](const urdf::Link& at) -> std::optional<int> {
      if (at.name == "world") return -1;
      const auto it = body_of_name_.find(at.name);
      if (it != body_of_name_.end()) return it->second;
      if (!at.parent_joint) return -1;
      return std::nullopt;
    });
  }

 private:
  const urdf::ModelInterface& urdf_;
  std::unordered_map<std::string, int> body_of_name_;
  std::unordered_map<const urdf::Link*, int> known_;  // answers so far (FirstValueUp)
};

std::string RequireLink(const tinyxml2::XMLElement* e, const char* attribute, const urdf::ModelInterface& urdf,
                        const std::string& where) {
  const char* text = e->Attribute(attribute);
  if (!text || !urdf.getLink(text)) Fail(where + ": attribute '" + attribute + "' must name a link of the scene");
  return text;
}

}  // namespace

void ExcludeSelfCollisions(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf, Model* model) {
  LinkBodies bodies(urdf, *model);
  const int n = static_cast<int>(model->bodies.size());
  std::vector<int> robot(n);
  std::iota(robot.begin(), robot.end(), 0);
  for (const auto& [name, joint] : urdf.joints_) {
    if (joint->type == urdf::Joint::FLOATING || joint->parent_link_name == "world") continue;
    const int a = bodies.Of(joint->parent_link_name), b = bodies.Of(joint->child_link_name);
    if (a >= 0 && b >= 0) robot[Root(&robot, a)] = Root(&robot, b);
  }
  std::set<int> self_colliding;  // robots (their roots) whose bodies collide with each other
  std::vector<std::pair<int, int>>& excluded = model->excluded_pairs;
  excluded.clear();
  for (auto* e = sim ? sim->FirstChildElement() : nullptr; e; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    if (tag == "self_collide") {
      CheckAttributes(e, {"link"}, "<implicit_sim><self_collide>");
      const int b = bodies.Of(RequireLink(e, "link", urdf, "<implicit_sim><self_collide>"));
      if (b >= 0) self_colliding.insert(Root(&robot, b));
    } else if (tag == "disable_collisions") {
      const std::string where = "<implicit_sim><disable_collisions>";
      CheckAttributes(e, {"link1", "link2", "reason"}, where);
      const int a = bodies.Of(RequireLink(e, "link1", urdf, where)), b = bodies.Of(RequireLink(e, "link2", urdf, where));
      if (a >= 0 && b >= 0 && a != b) excluded.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(excluded.begin(), excluded.end());
  excluded.erase(std::unique(excluded.begin(), excluded.end()), excluded.end());
  std::vector<int> robot_size(n, 0);
  for (int b = 0; b < n; ++b) ++robot_size[Root(&robot, b)];
  model->self_collision_group.assign(n, -1);
  for (int b = 0; b < n; ++b) {
    const int root = Root(&robot, b);
    if (robot_size[root] > 1 && !self_colliding.count(root)) model->self_collision_group[b] = root;
  }
}

namespace {

// Pairs SelfOverlapNote examines at most (each a descent of up to 200 iterations): a robot heaped on itself is noted,
// not timed out.
constexpr size_t kMaxOverlapCandidates = 10000;

// The body pairs of one self-collision group whose bounding spheres at the start pose overlap (the first
// kMaxOverlapCandidates), ascending: a sweep along the axis over which the group's centres spread most.
std::vector<std::pair<int, int>> SelfCollisionCandidates(const Model& model) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::map<int, std::vector<int>> members;  // group -> its bodies, ascending
  for (int b = 0; b < static_cast<int>(model.self_collision_group.size()); ++b) {
    if (model.self_collision_group[b] >= 0) members[model.self_collision_group[b]].push_back(b);
  }
  std::vector<std::pair<int, int>> candidates;
  for (const auto& [group, list] : members) {
    Vec3 low = Vec3::Constant(kInf), high = Vec3::Constant(-kInf);
    for (int b : list) {
      low = low.cwiseMin(model.bodies[b].X_WB0.translation());
      high = high.cwiseMax(model.bodies[b].X_WB0.translation());
    }
    int axis = 0;
    (high - low).maxCoeff(&axis);
    struct Interval {
      double lower, upper;
      int body;
    };
    std::vector<Interval> intervals;
    for (int b : list) {
      const double centre = model.bodies[b].X_WB0.translation()[axis], reach = model.BodyReach(b);
      intervals.push_back({centre - reach, centre + reach, b});
    }
    std::sort(intervals.begin(), intervals.end(), [](const Interval& a, const Interval& b) { return a.lower < b.lower; });
    std::vector<Interval> active;
    for (const Interval& next : intervals) {
      active.erase(std::remove_if(active.begin(), active.end(), [&](const Interval& a) { return a.upper < next.lower; }),
                   active.end());
      for (const Interval& a : active) {
        const Body &p = model.bodies[a.body], &q = model.bodies[next.body];
        const double distance = (p.X_WB0.translation() - q.X_WB0.translation()).norm();
        if (distance <= model.BodyReach(a.body) + model.BodyReach(next.body)) {
          candidates.emplace_back(std::min(a.body, next.body), std::max(a.body, next.body));
          if (candidates.size() == kMaxOverlapCandidates) break;
        }
      }
      if (candidates.size() == kMaxOverlapCandidates) break;
      active.push_back(next);
    }
    if (candidates.size() == kMaxOverlapCandidates) break;
  }
  std::sort(candidates.begin(), candidates.end());
  return candidates;
}

}  // namespace

std::string SelfOverlapNote(const Model& model) {
  constexpr double kReportedDepth = 1e-6;  // m: deeper than the round-off of hulls that touch
  constexpr size_t kNamed = 8;             // pairs named in the line; the rest are counted
  // Rigid groups: bodies welded by fixed joints, and every fixed body with the world (entry n; a joint's parent -1).
  // Neighbours are groups that a moving joint joins; they meet at their joint, as MoveIt's "Adjacent" pairs do, and
  // are not reported.
  const int n = static_cast<int>(model.bodies.size());
  std::vector<int> group(n + 1);
  std::iota(group.begin(), group.end(), 0);
  const auto node = [n](int body) { return body < 0 ? n : body; };
  for (int b = 0; b < n; ++b) {
    if (model.bodies[b].is_fixed) group[Root(&group, b)] = Root(&group, n);
  }
  for (const Joint& joint : model.joints) {
    if (joint.type == JointType::kFixed) group[Root(&group, node(joint.parent))] = Root(&group, joint.child);
  }
  std::set<std::pair<int, int>> neighbours;
  for (const Joint& joint : model.joints) {
    const int a = Root(&group, node(joint.parent)), b = Root(&group, joint.child);
    neighbours.emplace(std::min(a, b), std::max(a, b));
  }
  std::vector<std::string> overlapping;
  for (const auto& [i, j] : SelfCollisionCandidates(model)) {
    if (std::binary_search(model.excluded_pairs.begin(), model.excluded_pairs.end(), std::make_pair(i, j))) continue;
    const int gi = Root(&group, i), gj = Root(&group, j);
    if (gi == gj || neighbours.count({std::min(gi, gj), std::max(gi, gj)})) continue;
    const Body &a = model.bodies[i], &b = model.bodies[j];
    double depth = 0.0;
    for (const ConvexShape& shape_a : a.shapes) {
      for (const ConvexShape& shape_b : b.shapes) {
        const Vec3 p_WA = a.X_WB0 * shape_a.X_BS.translation(), p_WB = b.X_WB0 * shape_b.X_BS.translation();
        if ((p_WA - p_WB).norm() > shape_a.BoundingRadius() + shape_b.BoundingRadius()) continue;
        // A stationary least crossing is the depth of a note; the oracle's bound only where the descent stalls.
        const CrossingDescent descent = DescendCrossing(shape_a, a.X_WB0, shape_b, b.X_WB0, -kReportedDepth, 200);
        if (descent.value < -kReportedDepth) continue;  // certified apart
        depth = std::max(depth, descent.stationary && std::isfinite(descent.value)
                                    ? descent.value
                                    : PenetrationBound(shape_a, a.X_WB0, shape_b, b.X_WB0, kReportedDepth));
      }
    }
    if (depth <= kReportedDepth) continue;
    char text[32];
    std::snprintf(text, sizeof(text), "%.3g", depth);
    overlapping.push_back("'" + a.name + "'-'" + b.name + "' (" + text + " m)");
  }
  if (overlapping.empty()) return "";
  std::string line = "implicit_sim: " + std::to_string(overlapping.size()) +
                     " pairs of links that no joint joins overlap at their robot's start pose, by up to (they do not "
                     "collide: the robot's self-collision is off):";
  for (size_t k = 0; k < std::min(kNamed, overlapping.size()); ++k) line += (k ? ", " : " ") + overlapping[k];
  if (overlapping.size() > kNamed) line += " and " + std::to_string(overlapping.size() - kNamed) + " more";
  return line;
}

}  // namespace loader
}  // namespace implicit_sim
