// Malformed and physically invalid scenes (corpus test/data/malformed/, manifest EXPECTED.txt): every file is refused
// by the loader with a message naming the link and attribute, and by the runner with exit 2, one line on stderr and
// nothing written. The 50 MB case is generated here, in a temp dir. How long a refusal takes is recorded
// (RecordProperty), not bounded: the 2 s target is measured by bench/refusal_bench.py.
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <dirent.h>
#include <gtest/gtest.h>

#include "implicit_sim/core/model/urdf_loader.h"
#include "scenario_runner.h"
#include "test_files.h"

namespace implicit_sim {
namespace {


const std::string kCorpusDir = std::string(IMPLICIT_SIM_SOURCE_DIR) + "/test/data/malformed";

struct MalformedCase {
  std::string file;                   // name in kCorpusDir
  std::vector<std::string> mentions;  // substrings the error message must contain
};

std::string Trim(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t") + 1 - begin);
}

// EXPECTED.txt: "FILE | SUBSTRING [| SUBSTRING ...]" per line; '#' starts a comment line.
std::vector<MalformedCase> ReadManifest() {
  std::ifstream in(kCorpusDir + "/EXPECTED.txt");
  std::vector<MalformedCase> cases;
  std::string line;
  while (std::getline(in, line)) {
    if (Trim(line).empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string field;
    MalformedCase c;
    while (std::getline(fields, field, '|')) {
      if (c.file.empty()) {
        c.file = Trim(field);
      } else {
        c.mentions.push_back(Trim(field));
      }
    }
    cases.push_back(c);
  }
  return cases;
}

std::set<std::string> CorpusFiles() {
  std::set<std::string> files;
  if (DIR* dir = ::opendir(kCorpusDir.c_str())) {
    while (const dirent* entry = ::readdir(dir)) {
      const std::string name = entry->d_name;
      if (name.size() > 5 && name.substr(name.size() - 5) == ".urdf") files.insert(name);
    }
    ::closedir(dir);
  }
  return files;
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

using test_files::Exists;
using test_files::ReadText;

std::string FreshTempDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "implicit_sim_malformed_" + name;
  std::system(("rm -rf '" + dir + "' && mkdir -p '" + dir + "'").c_str());
  return dir;
}

// Loads `path`; passes when the loader throws std::invalid_argument naming every entry of `mentions`; *seconds: how long it took.
::testing::AssertionResult LoaderRefuses(const std::string& path, const std::vector<std::string>& mentions,
                                         double* seconds) {
  const auto start = std::chrono::steady_clock::now();
  std::string message;
  try {
    LoadSceneFromFile(path);
    *seconds = SecondsSince(start);
    return ::testing::AssertionFailure() << path << ": accepted";
  } catch (const std::invalid_argument& e) {
    message = e.what();
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << path << ": threw something else than std::invalid_argument: " << e.what();
  }
  *seconds = SecondsSince(start);
  for (const std::string& m : mentions) {
    if (message.find(m) == std::string::npos) {
      return ::testing::AssertionFailure() << path << ": message '" << message << "' does not mention '" << m << "'";
    }
  }
  return ::testing::AssertionSuccess() << message;
}

struct RunnerResult {
  int exit_code = -1;
  std::string out, err;
  double seconds = 0.0;
};

RunnerResult RunRunnerOn(const std::string& scene, const std::string& out_dir, const std::string& log_dir) {
  const std::string command = std::string(IMPLICIT_SIM_RUNNER) + " --scene '" + scene + "' --duration 0.01 --out '" +
                              out_dir + "' > '" + log_dir + "/stdout' 2> '" + log_dir + "/stderr'";
  RunnerResult result;
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  result.seconds = SecondsSince(start);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = ReadText(log_dir + "/stdout");
  result.err = ReadText(log_dir + "/stderr");
  return result;
}

// Exit 2, nothing on stdout, exactly one line on stderr naming every mention, no output directory.
::testing::AssertionResult RunnerRefuses(const std::string& scene, const std::vector<std::string>& mentions,
                                         const std::string& work_dir) {
  const std::string out_dir = work_dir + "/out";
  const RunnerResult r = RunRunnerOn(scene, out_dir, work_dir);
  auto failure = [&]() {
    return ::testing::AssertionFailure() << scene << " (exit " << r.exit_code << ", " << r.seconds << " s, stderr '"
                                         << r.err << "'): ";
  };
  if (r.exit_code != 2) return failure() << "exit code is not 2";
  if (!r.out.empty()) return failure() << "wrote to stdout: " << r.out;
  if (r.err.empty() || r.err.back() != '\n' || r.err.find('\n') != r.err.size() - 1) {
    return failure() << "stderr is not exactly one line";
  }
  for (const std::string& m : mentions) {
    if (r.err.find(m) == std::string::npos) return failure() << "does not mention '" << m << "'";
  }
  if (Exists(out_dir)) return failure() << "created the output directory";
  return ::testing::AssertionSuccess();
}

// A valid scene padded with a comment to 50 MB (52428800 bytes).
std::string WriteFiftyMegabyteScene(const std::string& dir) {
  const std::string path = dir + "/fifty_megabytes.urdf";
  const std::string head =
      "<robot name='t'><link name='world'/><link name='ball'><inertial><mass value='1'/><inertia ixx='0.4' "
      "iyy='0.4' izz='0.4' ixy='0' ixz='0' iyz='0'/></inertial><collision><geometry><sphere radius='1'/>"
      "</geometry></collision></link><joint name='b' type='floating'><parent link='world'/><child link='ball'/>"
      "</joint><!-- ";
  const std::string tail = " --></robot>\n";
  const size_t total = size_t{50} << 20;
  std::ofstream out(path, std::ios::binary);
  out << head << std::string(total - head.size() - tail.size(), 'x') << tail;
  return path;
}

TEST(MalformedScenes, ManifestListsEveryCorpusFileAndEnoughCases) {
  const std::vector<MalformedCase> cases = ReadManifest();
  std::set<std::string> listed;
  for (const MalformedCase& c : cases) {
    EXPECT_TRUE(listed.insert(c.file).second) << c.file << " is listed twice";
    EXPECT_FALSE(c.mentions.empty()) << c.file << " has no expected substring";
  }
  EXPECT_EQ(listed, CorpusFiles());
  EXPECT_GE(cases.size(), 60u);
}

TEST(MalformedScenes, LoaderRefusesEveryCorpusFileNamingTheCulprit) {
  double slowest = 0.0;
  std::string slowest_file;
  for (const MalformedCase& c : ReadManifest()) {
    double seconds = 0.0;
    EXPECT_TRUE(LoaderRefuses(kCorpusDir + "/" + c.file, c.mentions, &seconds));
    if (seconds > slowest) {
      slowest = seconds;
      slowest_file = c.file;
    }
  }
  RecordProperty("slowest_load_s", std::to_string(slowest));
  std::cout << "[ malformed ] slowest refusal: " << slowest_file << " in " << slowest * 1e3 << " ms\n";
}

TEST(MalformedScenes, LoaderRefusesAFiftyMegabyteFile) {
  const std::string dir = FreshTempDir("big_loader");
  const std::string path = WriteFiftyMegabyteScene(dir);
  double seconds = 0.0;
  EXPECT_TRUE(LoaderRefuses(path, {"scene file '" + path + "'", "52428800 bytes exceed the limit"}, &seconds));
  RecordProperty("file_refusal_s", std::to_string(seconds));
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(LoadSceneFromString(ReadText(path), "big"), std::invalid_argument);
  RecordProperty("string_refusal_s", std::to_string(SecondsSince(start)));
  std::system(("rm -rf '" + dir + "'").c_str());
}

TEST(MalformedScenes, RunnerRefusesEveryCorpusFileWithOneLineAndWritesNothing) {
  const std::string dir = FreshTempDir("runner");
  for (const MalformedCase& c : ReadManifest()) {
    EXPECT_TRUE(RunnerRefuses(kCorpusDir + "/" + c.file, c.mentions, dir));
  }
  const std::string big = WriteFiftyMegabyteScene(dir);
  EXPECT_TRUE(RunnerRefuses(big, {"52428800 bytes exceed the limit"}, dir));
  std::system(("rm -rf '" + dir + "'").c_str());
}

// The corpus cases are one change away from this scene, which loads: a refusal comes from the change.
TEST(MalformedScenes, TheUnchangedCorpusSceneAndAVisualOnlyLinkLoad) {
  const std::string inertial =
      "<inertial><mass value='1'/><inertia ixx='0.4' iyy='0.4' izz='0.4' ixy='0' ixz='0' iyz='0'/></inertial>";
  const std::string scene =
      "<robot name='t'><link name='world'/>"
      "<link name='ground'><collision><geometry><box size='1 1 0.01'/></geometry><implicit type='halfspace'/>"
      "</collision></link><joint name='g' type='fixed'><parent link='world'/><child link='ground'/></joint>"
      "<link name='ball'>" + inertial + "<collision><geometry><sphere radius='1'/></geometry></collision></link>"
      "<joint name='b' type='floating'><parent link='world'/><child link='ball'/><origin xyz='0 0 1'/></joint>"
      "<link name='marker'>" + inertial + "<visual><origin xyz='0 0 0.5'/><geometry><box size='1 2 3'/></geometry>"
      "</visual></link><joint name='m' type='floating'><parent link='world'/><child link='marker'/></joint></robot>";
  const Model m = LoadSceneFromString(scene);
  EXPECT_EQ(m.num_moving(), 2);
  ASSERT_EQ(m.pairs.size(), 1u);  // the visual-only link has no shape, hence no pair
  EXPECT_EQ(m.PairName(0), "ball-ground");
}

}  // namespace
}  // namespace implicit_sim
