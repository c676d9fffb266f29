// Helpers shared by the scene loader's files (urdf_loader.cpp, urdf_joints.cpp): reading numbers and attributes with
// the classic "C" locale and failing with a message that names the element and attribute. Internal to the core.
#pragma once

#include <set>
#include <string>
#include <vector>

#include <tinyxml2.h>
#include <urdf_model/pose.h>

#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {
namespace loader {

[[noreturn]] void Fail(const std::string& message);  // throws std::invalid_argument
// Every whitespace-separated token of `text` as a finite number; `what` names the attribute in the error.
std::vector<double> ParseNumbers(const std::string& text, const std::string& what);
// One number from attribute `name` of `e` in [lo, hi] ((lo, hi] when lo_open); `fallback` when absent and not required.
double ReadScalar(const tinyxml2::XMLElement* e, const char* name, const std::string& where, double lo, double hi,
                  bool lo_open, double fallback, bool required);
Vec3 ReadVec3(const tinyxml2::XMLElement* e, const char* name, const std::string& where, const Vec3& fallback,
              bool positive = false, bool required = false);
// `count` finite numbers (each > 0 when `positive`) in attribute `name` of `e`, which must be present.
void CheckNumbers(const tinyxml2::XMLElement* e, const char* name, const std::string& where, size_t count,
                  bool positive);
// Refuses any attribute of `e` not in `allowed`: a misspelt or misplaced attribute would otherwise be ignored.
void CheckAttributes(const tinyxml2::XMLElement* e, const std::vector<std::string>& allowed, const std::string& where);
Pose ToPose(const urdf::Pose& p);

// What one load tells the user without refusing anything (vendor attributes ignored, mass properties taken from
// geometry, mesh hulls), each note once.
class LoadNotes {
 public:
  void Add(const std::string& key, const std::string& text) {
    if (keys_.insert(key).second) lines_.push_back(text);
  }
  const std::vector<std::string>& lines() const { return lines_; }

 private:
  std::set<std::string> keys_;
  std::vector<std::string> lines_;
};
// Stock URDF elements tolerate attributes of other tools (franka's <dynamics D K ...>), as urdfdom does: each
// attribute of `e` not in `allowed` gets one note per element tag and attribute name, and is ignored.
void NoteUnknownAttributes(const tinyxml2::XMLElement* e, const std::vector<std::string>& allowed, LoadNotes* notes);

}  // namespace loader
}  // namespace implicit_sim
