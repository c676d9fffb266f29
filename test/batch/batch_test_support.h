// What test_batch and test_batch_engines share: the paths the build gives them, running a shell command or the batch
// tool, and reading its files.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace batch_test {

const std::string kSource = IMPLICIT_SIM_SOURCE_DIR;
const std::string kRunner = IMPLICIT_SIM_RUNNER;
const std::string kBatch = "/usr/bin/python3 " + kSource + "/scripts/implicit_sim_batch";
const std::string kCubeSweep = kSource + "/scenes/sweeps/cube_drop.yaml";

// The command's exit status (-1 when it did not exit normally).
inline int Shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline std::string Read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

inline std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// A fresh (removed, not created) scratch path under gtest's temporary folder.
inline std::string TempDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "implicit_sim_batch_" + name;
  Shell("rm -rf '" + dir + "'");
  return dir;
}

// Runs implicit_sim_batch with `args` (the runner given explicitly); stdout and stderr go to LOG.out and LOG.err.
inline int Batch(const std::string& args, const std::string& log, const std::string& env = "") {
  return Shell(env + " " + kBatch + " " + args + " --runner " + kRunner + " > " + log + ".out 2> " + log + ".err");
}

}  // namespace batch_test
