// Where a reader that serves untrusted requests (the node's services) may open files. A file counts only by its
// canonical path (symlinks and '..' resolved), so neither a link nor a '..' leads out, and every refusal carries one
// message whatever the reason (missing, outside, not a regular file): a caller cannot probe which paths exist.
#pragma once

#include <string>
#include <vector>

namespace implicit_sim {

struct FileSandbox {
  std::vector<std::string> roots;  // directories whose files may be read (missing ones are skipped)
  bool package_files = false;      // also files inside a ROS package: below a directory that holds a package.xml
  // Unrestricted (no roots, no packages): any regular file may be read.
  bool Unrestricted() const { return roots.empty() && !package_files; }
  // The canonical path of `path` when it names a regular file this sandbox allows; "" otherwise.
  std::string Allowed(const std::string& path) const;
  // The sandbox for messages: "'a', 'b' and ROS packages".
  std::string Describe() const;
};

}  // namespace implicit_sim
