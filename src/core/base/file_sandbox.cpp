#include "implicit_sim/core/base/file_sandbox.h"

#include <filesystem>

namespace implicit_sim {
namespace {

namespace fs = std::filesystem;

bool IsUnder(const fs::path& canonical_file, const std::string& root) {
  std::error_code ec;
  const fs::path canonical_root = fs::canonical(root, ec);
  if (ec || !fs::is_directory(canonical_root, ec)) return false;
  std::string prefix = canonical_root.string();
  if (prefix.back() != '/') prefix += '/';
  return canonical_file.string().compare(0, prefix.size(), prefix) == 0;
}

// Whether a directory above the file (up to the file system's root) holds a package.xml.
bool InPackage(const fs::path& canonical_file) {
  std::error_code ec;
  for (fs::path dir = canonical_file.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (fs::is_regular_file(dir / "package.xml", ec)) return true;
    if (dir == dir.root_path()) break;
  }
  return false;
}

}  // namespace

std::string FileSandbox::Allowed(const std::string& path) const {
  if (path.empty()) return "";
  std::error_code ec;
  const fs::path canonical = fs::canonical(path, ec);
  if (ec || !fs::is_regular_file(canonical, ec)) return "";
  if (Unrestricted()) return canonical.string();
  for (const std::string& root : roots) {
    if (!root.empty() && IsUnder(canonical, root)) return canonical.string();
  }
  return package_files && InPackage(canonical) ? canonical.string() : "";
}

std::string FileSandbox::Describe() const {
  std::string text;
  for (const std::string& root : roots) {
    if (!root.empty()) text += (text.empty() ? "'" : ", '") + root + "'";
  }
  if (package_files) text += text.empty() ? "ROS packages" : " and ROS packages";
  return text.empty() ? "anywhere" : text;
}

}  // namespace implicit_sim
