#include "loader_util.h"

#include <algorithm>
#include <cmath>
#include <locale>
#include <sstream>
#include <stdexcept>

namespace implicit_sim {
namespace loader {

void Fail(const std::string& message) { throw std::invalid_argument(message); }

// Numbers are read with the classic "C" locale whatever the process locale is.
std::vector<double> ParseNumbers(const std::string& text, const std::string& what) {
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  std::vector<double> out;
  std::string token;
  while (in >> token) {
    std::istringstream tin(token);
    tin.imbue(std::locale::classic());
    double value;
    if (!(tin >> value) || !tin.eof()) Fail(what + ": '" + token + "' is not a finite number");
    if (!std::isfinite(value)) Fail(what + ": value must be finite, got '" + token + "'");
    out.push_back(value);
  }
  return out;
}

double ReadScalar(const tinyxml2::XMLElement* e, const char* name, const std::string& where, double lo, double hi,
                  bool lo_open, double fallback, bool required) {
  const char* text = e ? e->Attribute(name) : nullptr;
  if (!text) {
    if (required) Fail(where + ": missing attribute '" + name + "'");
    return fallback;
  }
  const std::vector<double> v = ParseNumbers(text, where + " attribute '" + name + "'");
  if (v.size() != 1) Fail(where + " attribute '" + name + "': expected one number");
  const bool low_ok = lo_open ? v[0] > lo : v[0] >= lo;
  if (!low_ok || v[0] > hi) {
    std::ostringstream msg;
    msg.imbue(std::locale::classic());
    msg << where << " attribute '" << name << "' = " << v[0] << " is out of range " << (lo_open ? "(" : "[") << lo
        << ", " << hi << "]";
    Fail(msg.str());
  }
  return v[0];
}

Vec3 ReadVec3(const tinyxml2::XMLElement* e, const char* name, const std::string& where, const Vec3& fallback,
              bool positive, bool required) {
  const char* text = e ? e->Attribute(name) : nullptr;
  if (!text && required) Fail(where + ": missing attribute '" + name + "'");
  if (!text) return fallback;
  const std::vector<double> v = ParseNumbers(text, where + " attribute '" + name + "'");
  if (v.size() != 3) Fail(where + " attribute '" + name + "': expected three numbers");
  const Vec3 out(v[0], v[1], v[2]);
  if (positive && !(out.minCoeff() > 0.0)) Fail(where + " attribute '" + name + "': every value must be > 0");
  return out;
}

Pose ToPose(const urdf::Pose& p) {
  Pose X = Pose::Identity();
  X.translation() = Vec3(p.position.x, p.position.y, p.position.z);
  X.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).toRotationMatrix();
  return X;
}

// Refuses any attribute of `e` not in `allowed`: a misspelt or misplaced attribute would otherwise be ignored.
void CheckAttributes(const tinyxml2::XMLElement* e, const std::vector<std::string>& allowed,
                     const std::string& where) {
  for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
    bool known = false;
    std::string list;
    for (const std::string& name : allowed) {
      known = known || a->Name() == name;
      list += (list.empty() ? "" : ", ") + name;
    }
    if (!known) Fail(where + ": unknown attribute '" + a->Name() + "' (allowed: " + list + ")");
  }
}

void NoteUnknownAttributes(const tinyxml2::XMLElement* e, const std::vector<std::string>& allowed, LoadNotes* notes) {
  for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
    if (std::find(allowed.begin(), allowed.end(), a->Name()) != allowed.end()) continue;
    const std::string tag = e->Name();
    notes->Add(tag + "/" + a->Name(), "implicit_sim: attribute '" + std::string(a->Name()) + "' of <" + tag +
                                          "> is not a URDF attribute the simulator reads; ignored wherever it occurs");
  }
}

// `count` finite numbers (each > 0 when `positive`) in attribute `name` of `e`.
void CheckNumbers(const tinyxml2::XMLElement* e, const char* name, const std::string& where, size_t count,
                  bool positive) {
  const char* text = e->Attribute(name);
  if (!text) Fail(where + ": missing attribute '" + name + "'");
  const std::vector<double> values = ParseNumbers(text, where + " attribute '" + name + "'");
  if (values.size() != count) {
    Fail(where + " attribute '" + name + "': expected " + std::to_string(count) + " number" + (count > 1 ? "s" : ""));
  }
  for (double v : values) {
    if (positive && !(v > 0.0)) Fail(where + " attribute '" + name + "': every value must be > 0");
  }
}

}  // namespace loader
}  // namespace implicit_sim
