#include "implicit_sim/core/model/model.h"

#include <algorithm>
#include <map>


namespace implicit_sim {

namespace {

// A name's index through `index` when it indexes all `items` (names are unique), else by a linear scan.
template <typename Item>
int FindByName(const std::vector<Item>& items, const std::unordered_map<std::string, int>& index,
               const std::string& name) {
  if (index.size() == items.size()) {
    const auto found = index.find(name);
    return found == index.end() ? -1 : found->second;
  }
  for (int i = 0; i < static_cast<int>(items.size()); ++i) {
    if (items[i].name == name) return i;
  }
  return -1;
}

}  // namespace

int Model::FindBody(const std::string& name) const { return FindByName(bodies, body_by_name, name); }

int Model::FindJoint(const std::string& name) const { return FindByName(joints, joint_by_name, name); }

void Model::IndexNames() {
  body_by_name.clear();
  joint_by_name.clear();
  for (int i = 0; i < static_cast<int>(bodies.size()); ++i) body_by_name.emplace(bodies[i].name, i);
  for (int i = 0; i < static_cast<int>(joints.size()); ++i) joint_by_name.emplace(joints[i].name, i);
  // Duplicate names (hand-built models): the maps fall short of the vectors and FindByName scans, first match.
  if (body_by_name.size() != bodies.size()) body_by_name.clear();
  if (joint_by_name.size() != joints.size()) joint_by_name.clear();
}

bool Model::Excluded(int i, int j) const {
  return InOneSelfCollisionGroup(i, j) || std::binary_search(excluded_pairs.begin(), excluded_pairs.end(), std::make_pair(std::min(i, j), std::max(i, j)));
}

const char* SensorTypeName(SensorType type) {
  switch (type) {
    case SensorType::kImu: return "imu";
    case SensorType::kForceTorque: return "force_torque";
    case SensorType::kContact: break;
  }
  return "contact";
}

const char* JointTypeName(JointType type) {
  switch (type) {
    case JointType::kFixed: return "fixed";
    case JointType::kRevolute: return "revolute";
    case JointType::kContinuous: return "continuous";
    case JointType::kPrismatic: return "prismatic";
    case JointType::kPlanar: return "planar";
  }
  return "unknown";
}

int Model::GeomPairIndex(int i, int j) const {
  if (i == j || i < 0 || j < 0 || i >= static_cast<int>(geoms.size()) || j >= static_cast<int>(geoms.size())) {
    return -1;
  }
  const int lo = std::min(i, j), hi = std::max(i, j);
  const auto begin = pairs.begin() + pairs_of_lower[lo], end = pairs.begin() + pairs_of_lower[lo + 1];
  const auto it = std::lower_bound(begin, end, hi, [](const ContactPair& pair, int geom) {
    return std::max(pair.geom1, pair.geom2) < geom;
  });
  return it != end && std::max(it->geom1, it->geom2) == hi ? static_cast<int>(it - pairs.begin()) : -1;
}

int Model::PairIndex(int i, int j) const {
  if (i == j || i < 0 || j < 0 || i >= static_cast<int>(bodies.size()) || j >= static_cast<int>(bodies.size())) {
    return -1;
  }
  const auto first_geom = [this](int body) {  // geoms are ordered by body
    return static_cast<int>(std::lower_bound(geoms.begin(), geoms.end(), body,
                                             [](const Geom& g, int b) { return g.body < b; }) - geoms.begin());
  };
  const int lo = std::min(i, j), hi = std::max(i, j);
  for (int gi = first_geom(lo); gi < first_geom(lo + 1); ++gi) {
    for (int gj = first_geom(hi); gj < first_geom(hi + 1); ++gj) {
      const int pair = GeomPairIndex(gi, gj);
      if (pair >= 0) return pair;
    }
  }
  return -1;
}

std::string Model::GeomName(int geom) const {
  const Body& body = bodies[geoms[geom].body];
  return body.shapes.size() == 1 ? body.name : body.name + "#" + std::to_string(geoms[geom].index);
}

std::string Model::PairName(int pair) const { return GeomName(pairs[pair].geom1) + "-" + GeomName(pairs[pair].geom2); }

double Model::BodyReach(int body) const {
  double reach = 0.0;
  for (const ConvexShape& shape : bodies[body].shapes) {
    reach = std::max(reach, shape.X_BS.translation().norm() + shape.BoundingRadius());
  }
  return reach;
}

int64_t Model::ContactPairBound() const {
  // Shapes with inequalities (others never touch), per body.
  const auto shapes_of = [this](int b) {
    int64_t count = 0;
    for (const ConvexShape& shape : bodies[b].shapes) count += shape.inequalities.empty() ? 0 : 1;
    return count;
  };
  int64_t moving = 0, fixed = 0, within_moving_bodies = 0;
  for (int b = 0; b < static_cast<int>(bodies.size()); ++b) {
    const int64_t k = shapes_of(b);
    (bodies[b].is_fixed ? fixed : moving) += k;
    if (!bodies[b].is_fixed) within_moving_bodies += k * (k - 1) / 2;
  }
  int64_t bound = moving * (moving - 1) / 2 - within_moving_bodies + moving * fixed;
  // Less the pairs inside each self-collision group, counted as the whole scene's are.
  std::map<int, std::array<int64_t, 3>> groups;  // group -> moving shapes, fixed shapes, pairs within moving bodies
  for (int b = 0; b < static_cast<int>(self_collision_group.size()); ++b) {
    if (self_collision_group[b] < 0) continue;
    std::array<int64_t, 3>& g = groups[self_collision_group[b]];
    const int64_t k = shapes_of(b);
    g[bodies[b].is_fixed ? 1 : 0] += k;
    if (!bodies[b].is_fixed) g[2] += k * (k - 1) / 2;
  }
  for (const auto& [group, g] : groups) bound -= g[0] * (g[0] - 1) / 2 - g[2] + g[0] * g[1];
  for (const auto& [i, j] : excluded_pairs) {
    if (!InOneSelfCollisionGroup(i, j) && !(bodies[i].is_fixed && bodies[j].is_fixed)) bound -= shapes_of(i) * shapes_of(j);
  }
  return bound;
}

double Model::ForceScale() const {
  double scale = 1e-3;
  for (int b : moving_bodies) {
    const Body& body = bodies[b];
    scale = std::max(scale, (body.mass * gravity_W + body.f_applied_W).norm());
    scale = std::max(scale, body.mass * std::max(gravity_W.norm(), 1.0));  // at least the weight in 1 m/s^2
  }
  return scale;
}

BroadPhase MakeBroadPhase(const Model& model) {
  std::vector<const ConvexShape*> shapes;
  std::vector<int> body_of;
  for (int g = 0; g < static_cast<int>(model.geoms.size()); ++g) {
    shapes.push_back(&model.shape(g));
    body_of.push_back(model.geoms[g].body);
  }
  return BroadPhase(std::move(shapes), std::move(body_of), [&model](int i, int j) { return model.GeomPairIndex(i, j); });
}

}  // namespace implicit_sim
