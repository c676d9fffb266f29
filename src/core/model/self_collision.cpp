#include "self_collision.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "loader_util.h"

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
    for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) index_[model.bodies[b].name] = b;
  }
  int Of(std::string link) const {
    while (link != "world") {
      const auto it = index_.find(link);
      if (it != index_.end()) return it->second;
      const urdf::LinkConstSharedPtr l = urdf_.getLink(link);
      if (!l || !l->parent_joint) return -1;
      link = l->parent_joint->parent_link_name;
    }
    return -1;
  }

 private:
  const urdf::ModelInterface& urdf_;
  std::unordered_map<std::string, int> index_;
};

std::string RequireLink(const tinyxml2::XMLElement* e, const char* attribute, const urdf::ModelInterface& urdf,
                        const std::string& where) {
  const char* text = e->Attribute(attribute);
  if (!text || !urdf.getLink(text)) Fail(where + ": attribute '" + attribute + "' must name a link of the scene");
  return text;
}

}  // namespace

void ExcludeSelfCollisions(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf, Model* model) {
  const LinkBodies bodies(urdf, *model);
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
  std::map<int, std::vector<int>> members;  // robot root -> its bodies, ascending
  for (int b = 0; b < n; ++b) members[Root(&robot, b)].push_back(b);
  for (const auto& [root, list] : members) {
    if (list.size() < 2 || self_colliding.count(root)) continue;
    for (size_t i = 0; i < list.size(); ++i) {
      for (size_t j = i + 1; j < list.size(); ++j) excluded.emplace_back(list[i], list[j]);
    }
  }
  std::sort(excluded.begin(), excluded.end());
  excluded.erase(std::unique(excluded.begin(), excluded.end()), excluded.end());
}

}  // namespace loader
}  // namespace implicit_sim
