// Batch studies (doc/batch.md): implicit_sim_batch through GNU parallel on this machine, resume after a
// killed run, the cube's resting faces against 1/6, the Slurm array script, the sweep file's error contract, and the
// runner's --stop-at-rest rule, pile sweeps (pile:) and their reliability fields, implicit_sim_make_pile --orientation
// random. Every check is on outputs (bytes, counts, fields); nothing is timed.
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "batch_test_support.h"

namespace {

using namespace batch_test;  // NOLINT: the shared helpers read as this file's own

const std::string kCylinderSweep = kSource + "/scenes/sweeps/cylinder_drop.yaml";
const std::string kPileSweep = kSource + "/scenes/sweeps/pile_ellipsoid50.yaml";
const std::string kMakePile = kRunner.substr(0, kRunner.rfind('/')) + "/implicit_sim_make_pile";  // built beside it

bool Exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

std::string Field(const std::string& line, const std::string& key) {
  const std::regex re("\"" + key + "\": (\"[^\"]*\"|[^,}]+)");
  std::smatch m;
  return std::regex_search(line, m, re) ? m[1].str() : std::string();
}

// The final height of the body's centre (m) in a results line.
double FinalHeight(const std::string& line) {
  const std::regex re("\"final_pose\": \\{\"position\": \\[([^,]+), ([^,]+), ([^\\]]+)\\]");
  std::smatch m;
  return std::regex_search(line, m, re) ? std::stod(m[3].str()) : -1.0;
}

// The merged file of the first 40 cube samples, run once per test process (through GNU parallel, 2 jobs).
const std::string& FortySampleRun() {
  static const std::string results = [] {
    const std::string out = TempDir("forty_a");
    const int status = Batch(kCubeSweep + " --out " + out + " --jobs 2 --samples 40", out);
    return status == 0 ? Read(out + "/results.jsonl") : std::string("run failed: exit ") + std::to_string(status);
  }();
  return results;
}

::testing::AssertionResult IsPng(const std::string& path) {
  const std::string bytes = Read(path);
  if (bytes.substr(0, 8) != std::string("\x89PNG\r\n\x1a\n", 8)) {
    return ::testing::AssertionFailure() << path << " is no PNG";
  }
  if (bytes.size() < 10000) return ::testing::AssertionFailure() << path << ": only " << bytes.size() << " bytes";
  return ::testing::AssertionSuccess();
}

// log of the binomial probability P(K = k), K ~ B(n, p).
double LogBinomial(int n, int k, double p) {
  return std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) + k * std::log(p) +
         (n - k) * std::log1p(-p);
}

// The central 99.9 % interval [lo, hi] of B(n, p): P(K < lo) <= 0.0005 and P(K > hi) <= 0.0005.
std::pair<int, int> BinomialInterval(int n, double p, double tail = 0.0005) {
  int lo = 0, hi = n;
  double below = 0.0;
  while (below + std::exp(LogBinomial(n, lo, p)) <= tail) below += std::exp(LogBinomial(n, lo++, p));
  double above = 0.0;
  while (above + std::exp(LogBinomial(n, hi, p)) <= tail) above += std::exp(LogBinomial(n, hi--, p));
  return {lo, hi};
}

TEST(BatchStudy, FortyCubeSamplesThroughGnuParallelGiveTheSameJsonlTwice) {
  const std::string& first = FortySampleRun();
  const std::string out = TempDir("forty_b");
  ASSERT_EQ(Batch(kCubeSweep + " --out " + out + " --jobs 2 --samples 40", out), 0) << Read(out + ".err");
  const std::string second = Read(out + "/results.jsonl");
  EXPECT_EQ(first, second);  // byte for byte: the lines hold no wall times
  const std::vector<std::string> lines = Lines(second);
  ASSERT_EQ(lines.size(), 40u);
  std::set<std::string> seeds;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    EXPECT_EQ(Field(line, "id"), std::to_string(i)) << line;  // sorted by id
    seeds.insert(Field(line, "seed"));
    for (const char* key : {"params", "orientation", "position", "velocity", "angular_velocity", "mu", "final_pose",
                            "class", "tilt_deg", "stop_reason", "time_to_rest", "t_end", "max_penetration",
                            "solver_failures", "runner_exit", "nonconverged_steps", "bodies_out_of_box", "nan",
                            "max_penetration_m"}) {
      EXPECT_NE(line.find(std::string("\"") + key + "\": "), std::string::npos) << key << " missing in " << line;
    }
    EXPECT_EQ(Field(line, "stop_reason"), "\"at_rest\"") << line;
    EXPECT_EQ(Field(line, "solver_failures"), "0") << line;
    EXPECT_LT(std::stod(Field(line, "max_penetration")), 1e-6) << line;
    EXPECT_LT(std::stod(Field(line, "tilt_deg")), 1.0) << line;  // flat on a face
    EXPECT_EQ(Field(line, "nonconverged_steps"), "0") << line;
    EXPECT_EQ(Field(line, "bodies_out_of_box"), "null") << line;  // no box around a single cube
    EXPECT_EQ(Field(line, "nan"), "false") << line;
    EXPECT_LT(std::stod(Field(line, "max_penetration_m")), 1e-6) << line;
  }
  EXPECT_EQ(seeds.size(), 40u);
  EXPECT_TRUE(IsPng(out + "/report_faces.png"));
  EXPECT_TRUE(IsPng(out + "/report_time_to_rest.png"));
  EXPECT_TRUE(Exists(out + "/report.json"));
  EXPECT_FALSE(Exists(out + "/runs/0"));  // run directories are removed unless --keep-runs
}

TEST(BatchStudy, AResumedRunAfterAKilledOneGivesTheSameResult) {
  const std::string& reference = FortySampleRun();
  const std::string out = TempDir("killed");
  const std::string pid_file = out + ".pid";
  // setsid: the batch, GNU parallel and the runs it started form one process group, killed together below.
  ASSERT_EQ(Shell("setsid " + kBatch + " " + kCubeSweep + " --out " + out + " --jobs 2 --samples 40 --runner " +
                  kRunner + " > " + out + ".log 2>&1 & echo $! > " + pid_file),
            0);
  const pid_t group = std::stoi(Read(pid_file));
  auto complete = [&] { return Shell("test $(ls " + out + "/samples 2>/dev/null | grep -c '^[0-9]*\\.json$') -ge 8"); };
  for (int i = 0; i < 6000 && complete() != 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_EQ(::kill(-group, SIGKILL), 0);
  for (int i = 0; i < 500 && ::kill(-group, 0) == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_FALSE(Exists(out + "/results.jsonl")) << "the run ended before it was killed";

  // The lines written before the kill, with their inode and modification time: the resumed run must not redo them.
  std::map<std::string, std::pair<ino_t, long long>> before;
  ASSERT_EQ(Shell("ls " + out + "/samples | grep '^[0-9]*\\.json$' > " + out + ".done"), 0);
  for (const std::string& name : Lines(Read(out + ".done"))) {
    struct stat st;
    ASSERT_EQ(::stat((out + "/samples/" + name).c_str(), &st), 0);
    before[name] = {st.st_ino, static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec};
  }
  ASSERT_GE(before.size(), 8u);
  ASSERT_LT(before.size(), 40u);

  ASSERT_EQ(Batch(kCubeSweep + " --out " + out + " --jobs 2 --samples 40", out + "_resume"), 0)
      << Read(out + "_resume.err");
  EXPECT_NE(Read(out + "_resume.out").find(std::to_string(before.size()) + " of 40 samples complete; running " +
                                           std::to_string(40 - before.size())),
            std::string::npos)
      << Read(out + "_resume.out");
  EXPECT_EQ(Read(out + "/results.jsonl"), reference);
  for (const auto& [name, id] : before) {
    struct stat st;
    ASSERT_EQ(::stat((out + "/samples/" + name).c_str(), &st), 0);
    EXPECT_EQ(st.st_ino, id.first) << name << " was rewritten";
    EXPECT_EQ(static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec, id.second) << name;
  }
  // A third run has nothing left to do and writes the same file.
  ASSERT_EQ(Batch(kCubeSweep + " --out " + out + " --jobs 2 --samples 40", out + "_third"), 0);
  EXPECT_EQ(Read(out + "_third.out").find("GNU parallel"), std::string::npos);
  EXPECT_EQ(Read(out + "/results.jsonl"), reference);
}

// A cube dropped from rest at low height settles on the face most nearly down, so a uniform orientation on SO(3)
// gives each face 1/6 in expectation. The shipped sweep (240 samples): each face's count within the central 99.9 %
// interval of B(240, 1/6), and Pearson's chi-square (5 degrees of freedom) below its 99.9 % quantile 20.515.
TEST(BatchStudy, TheCubesSixFacesEachGetAShareWithinBinomialBoundsOfOneSixth) {
  const std::string out = TempDir("faces");
  ASSERT_EQ(Batch(kCubeSweep + " --out " + out + " --jobs 2", out), 0) << Read(out + ".err");
  const std::vector<std::string> lines = Lines(Read(out + "/results.jsonl"));
  ASSERT_EQ(lines.size(), 240u);
  std::map<std::string, int> counts;
  for (const std::string& line : lines) {
    ++counts[Field(line, "class")];
    EXPECT_EQ(Field(line, "stop_reason"), "\"at_rest\"") << line;
    EXPECT_LT(std::stod(Field(line, "tilt_deg")), 1.0) << line;
  }
  // The first 40 samples are those of the 40-sample run.
  const std::vector<std::string> forty = Lines(FortySampleRun());
  ASSERT_EQ(forty.size(), 40u);
  for (size_t i = 0; i < forty.size(); ++i) EXPECT_EQ(lines[i], forty[i]);

  const auto [lo, hi] = BinomialInterval(240, 1.0 / 6.0);
  EXPECT_EQ(lo, 22);  // 40 +- 18
  EXPECT_EQ(hi, 60);
  double chi2 = 0.0;
  std::ostringstream shares;
  for (const char* face : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    const int k = counts["\"" + std::string(face) + "\""];
    shares << face << ": " << k << "  ";
    EXPECT_GE(k, lo) << face;
    EXPECT_LE(k, hi) << face;
    chi2 += (k - 40.0) * (k - 40.0) / 40.0;
  }
  int total = 0;
  for (const auto& [face, k] : counts) total += k;
  EXPECT_EQ(total, 240);
  EXPECT_EQ(counts.size(), 6u);
  EXPECT_LT(chi2, 20.515) << shares.str();
  std::cout << "[ faces    ] " << shares.str() << "chi2 " << chi2 << ", 99.9 % interval [" << lo << ", " << hi
            << "]\n";
  EXPECT_NE(Read(out + ".out").find("Wilson 95 % interval"), std::string::npos);
  EXPECT_TRUE(IsPng(out + "/report_faces.png"));
}

TEST(BatchStudy, TheSlurmScriptPassesADryCheckAndEachArrayIndexRunsItsSample) {
  const std::vector<std::string> reference = Lines(FortySampleRun());
  ASSERT_EQ(reference.size(), 40u);
  const std::string out = TempDir("slurm");
  const std::string script = out + ".sbatch";
  ASSERT_EQ(Batch(kCubeSweep + " --out " + out + " --samples 40 --slurm-script " + script, out), 0)
      << Read(out + ".err");
  EXPECT_EQ(Shell("bash -n " + script), 0);
  const std::vector<std::string> lines = Lines(Read(script));
  int array_lines = 0;
  for (const std::string& line : lines) array_lines += line == "#SBATCH --array=0-39";
  EXPECT_EQ(array_lines, 1) << Read(script);
  EXPECT_EQ(lines.at(0), "#!/bin/bash");
  EXPECT_TRUE(Exists(out + "/sweep.json"));
  EXPECT_FALSE(Exists(out + "/samples/0.json"));  // written, not run
  // Without Slurm's variable the script refuses to guess.
  EXPECT_EQ(Shell("env -u SLURM_ARRAY_TASK_ID bash " + script + " > /dev/null 2>&1"), 2);
  for (int index : {0, 17, 39}) {
    ASSERT_EQ(Shell("SLURM_ARRAY_TASK_ID=" + std::to_string(index) + " bash " + script + " > " + out + ".task 2>&1"), 0)
        << Read(out + ".task");
    EXPECT_EQ(Read(out + "/samples/" + std::to_string(index) + ".json"), reference[index] + "\n") << index;
  }
  EXPECT_EQ(Shell("ls " + out + "/samples | grep -c 'json$' | grep -qx 3"), 0);
  // The merge step: three lines, the rest reported missing (exit 1).
  EXPECT_EQ(Batch(kCubeSweep + " --out " + out + " --samples 40 --merge-only --no-report", out + "_merge"), 1);
  EXPECT_EQ(Read(out + "/results.jsonl"), reference[0] + "\n" + reference[17] + "\n" + reference[39] + "\n");
  const std::string merge_err = Read(out + "_merge.err");
  EXPECT_NE(merge_err.find("37 samples have no line yet"), std::string::npos) << merge_err;
}

TEST(BatchStudy, TheCylinderSweepClassifiesEverySample) {
  const std::string out = TempDir("cylinder");
  const int status = Batch(kCylinderSweep + " --out " + out + " --jobs 2 --samples 24", out);
  ASSERT_EQ(status, 0) << Read(out + ".err");
  const std::vector<std::string> lines = Lines(Read(out + "/results.jsonl"));
  ASSERT_EQ(lines.size(), 24u);
  std::map<std::string, int> counts;
  for (const std::string& line : lines) {
    const std::string cls = Field(line, "class");
    ++counts[cls];
    EXPECT_TRUE(cls == "\"flat_bottom\"" || cls == "\"flat_top\"" || cls == "\"side\"") << line;
    if (Field(line, "stop_reason") == "\"at_rest\"") {
      // Flat on a cap or on its side; or balanced on the rim, which rolling resistance holds while the centre of mass
      // is within mu e_roll (m) of the vertical through the contact (a rolling moment of up to mu e_roll N).
      if (std::stod(Field(line, "tilt_deg")) >= 1.0) {
        const double half_diagonal = std::hypot(0.05, 0.03), z = FinalHeight(line);
        const double offset = std::sqrt(std::max(0.0, half_diagonal * half_diagonal - z * z));
        EXPECT_LE(offset, std::stod(Field(line, "mu")) * 0.002 * (1.0 + 1e-6)) << line;
      }
      EXPECT_NE(Field(line, "time_to_rest"), "null") << line;
    } else {
      EXPECT_EQ(Field(line, "stop_reason"), "\"duration\"") << line;
      EXPECT_EQ(Field(line, "time_to_rest"), "null") << line;
    }
    EXPECT_LT(std::stod(Field(line, "max_penetration")), 1e-4) << line;
  }
  EXPECT_GE(counts.size(), 2u);  // not all samples in one class
  EXPECT_TRUE(IsPng(out + "/report_faces.png"));
  EXPECT_TRUE(IsPng(out + "/report_time_to_rest.png"));
}

// A bad sweep file or argument: exit 2, one stderr line naming the key (and the allowed range), nothing run.
TEST(BatchStudy, BadSweepsAndArgumentsAreRefusedNamingTheKey) {
  const std::string dir = TempDir("bad");
  Shell("mkdir -p " + dir);
  std::string good = Read(kCubeSweep);
  const std::string relative_scene = "scene: ../cube_drop.urdf";
  good.replace(good.find(relative_scene), relative_scene.size(), "scene: " + kSource + "/scenes/cube_drop.urdf");
  struct Case {
    std::string name, from, to;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"unknown_key", "samples: 240", "samples: 240\nsample_count: 3", {"sample_count", "unknown key", "samples"}},
      {"missing_samples", "samples: 240", "", {"samples", "missing"}},
      {"zero_samples", "samples: 240", "samples: 0", {"samples", "[1, 1000000]"}},
      {"bad_seed", "seed: 1", "seed: -4", {"seed", "[0, "}},
      {"reversed_range", "z: [0.09, 0.1]", "z: [0.1, 0.09]", {"randomize.position.z", "lo <= hi"}},
      {"negative_mu", "mu: [0.3, 0.7]", "mu: [-0.3, 0.7]", {"randomize.mu", "[0, 100]"}},
      {"bad_orientation", "orientation: uniform", "orientation: random", {"randomize.orientation", "uniform"}},
      {"unknown_axis", "y: [-0.05, 0.05]", "w: [-0.05, 0.05]", {"randomize.position.w", "unknown key"}},
      {"bad_duration", "duration: 3", "duration: -3", {"stop.duration", "(0, 1e+06]"}},
      {"bad_energy", "kinetic_energy: 1.0e-5", "kinetic_energy: 0", {"stop.at_rest.kinetic_energy", "J"}},
      {"bad_dt", "dt: 0.005", "dt: 2", {"dt", "(0, 1]"}},
      {"bad_scheme", "dt: 0.005", "dt: 0.005\nscheme: verlet", {"scheme", "paper or rattle", "verlet"}},
      {"negative_e_roll", "e_roll: 0.002", "e_roll: -0.002", {"e_roll", "[0, 1000] m"}},
      {"bad_classifier", "classifier: box_faces", "classifier: corners", {"classifier", "box_faces"}},
      {"no_scene", "/scenes/cube_drop.urdf ", "/scenes/nothing.urdf ", {"scene", "no such file"}},
      {"bad_body", "body: cube", "body: ground", {"body", "floating"}},
  };
  for (const Case& c : cases) {
    std::string text = good;
    const size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    const std::string sweep = dir + "/" + c.name + ".yaml";
    std::ofstream(sweep) << text;
    // --samples 2: a sweep refused by mistake would not run long.
    const int status = Batch(sweep + " --out " + dir + "/" + c.name + " --samples 2", dir + "/" + c.name);
    const std::string err = Read(dir + "/" + c.name + ".err");
    EXPECT_EQ(status, 2) << c.name << ": " << err;
    EXPECT_EQ(Lines(err).size(), 1u) << c.name << ": " << err;
    for (const std::string& word : c.words) EXPECT_NE(err.find(word), std::string::npos) << c.name << ": " << err;
    EXPECT_FALSE(Exists(dir + "/" + c.name + "/results.jsonl")) << c.name;
  }
  // Arguments.
  for (const auto& [args, word] : std::vector<std::pair<std::string, std::string>>{
           {kCubeSweep + " --out " + dir + "/a --jobs 0", "--jobs"},
           {kCubeSweep + " --out " + dir + "/a --samples x", "--samples"},
           {kCubeSweep, "--out"},
           {kCubeSweep + " --out " + dir + "/a --merge-only --run-sample 1", "exclude each other"},
           {kSource + "/scenes/sweeps/nothing.yaml --out " + dir + "/a", "cannot read sweep file"}}) {
    EXPECT_EQ(Batch(args, dir + "/args"), 2) << args;
    EXPECT_NE(Read(dir + "/args.err").find(word), std::string::npos) << args << ": " << Read(dir + "/args.err");
  }
  // An output directory of another sweep is refused: the cylinder sweep cannot resume into the cube's.
  const std::string study = dir + "/study";
  ASSERT_EQ(Batch(kCubeSweep + " --out " + study + " --samples 2", dir + "/study"), 0) << Read(dir + "/study.err");
  EXPECT_EQ(Batch(kCylinderSweep + " --out " + study + " --samples 2", dir + "/other"), 2);
  EXPECT_NE(Read(dir + "/other.err").find("holds samples of another sweep"), std::string::npos);
}

TEST(RunnerStopAtRest, EndsTheRunOnceTheKineticEnergyStaysBelowTheThreshold) {
  const std::string out = TempDir("rest");
  const std::string scene = kSource + "/scenes/cube_drop.urdf";
  ASSERT_EQ(Shell(kRunner + " --scene " + scene + " --duration 3 --dt 0.01 --out " + out +
                  " --stop-at-rest 1e-5:0.2 > /dev/null 2>&1"),
            0);
  const std::string summary = Read(out + "/summary.json");
  EXPECT_NE(summary.find("\"stop_reason\": \"at_rest\""), std::string::npos) << summary;
  // Dropped flat from 5 cm of clearance: lands at sqrt(2 * 0.05 / 9.81) = 0.101 s, then rests.
  const double time_to_rest = std::stod(Field(summary, "time_to_rest"));
  EXPECT_NEAR(time_to_rest, 0.11, 0.0101);
  EXPECT_NEAR(std::stod(Field(summary, "t_end")), time_to_rest + 0.2, 1e-9);
  // header, t = 0 and one row per step
  EXPECT_EQ(Lines(Read(out + "/trajectory.csv")).size(), 2u + std::stoul(Field(summary, "steps")));
  // Without the rule the run goes the full duration and has no time_to_rest.
  ASSERT_EQ(Shell(kRunner + " --scene " + scene + " --duration 0.5 --dt 0.01 --out " + out + " > /dev/null 2>&1"), 0);
  const std::string full = Read(out + "/summary.json");
  EXPECT_NE(full.find("\"stop_reason\": \"duration\""), std::string::npos) << full;
  EXPECT_NE(full.find("\"steps\": 50"), std::string::npos) << full;
  EXPECT_EQ(full.find("time_to_rest"), std::string::npos) << full;
  // Bad values: exit 2, one line naming the flag.
  for (const char* bad : {"0:1", "1e-5", "1e-5:0", "x:1", "1e-5:-1", "1e-5:nan", "2e6:1"}) {
    const std::string err = out + ".err";
    EXPECT_EQ(Shell(kRunner + " --scene " + scene + " --duration 1 --out " + out + "_bad --stop-at-rest " + bad +
                    " > /dev/null 2> " + err),
              2)
        << bad;
    EXPECT_EQ(Lines(Read(err)).size(), 1u) << bad;
    EXPECT_NE(Read(err).find("--stop-at-rest"), std::string::npos) << bad << ": " << Read(err);
    EXPECT_FALSE(Exists(out + "_bad")) << bad;
  }
}

// The pile sweep of the study with everything else kept: n bodies for `duration` seconds.
std::string TinyPileSweep(const std::string& dir, int n, double duration) {
  std::string text = Read(kPileSweep);
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"n: 50", "n: " + std::to_string(n)}, {"duration: 2", "duration: " + std::to_string(duration)}}) {
    const size_t at = text.find(from);
    if (at == std::string::npos) return "";
    text.replace(at, from.size(), to);
  }
  const std::string sweep = dir + "/pile.yaml";
  Shell("mkdir -p " + dir);
  std::ofstream(sweep) << text;
  return sweep;
}

// A pile sample (3 ellipsoids, 0.3 s): its scene comes from implicit_sim_make_pile with the sample's seed, and its
// line holds the reliability fields with sane values; the report prints them.
TEST(PileStudy, ATinyPileSampleRunsAndItsLineHasTheReliabilityFields) {
  const std::string dir = TempDir("pile");
  const std::string sweep = TinyPileSweep(dir, 3, 0.3);
  ASSERT_FALSE(sweep.empty());
  const std::string out = dir + "/study";
  ASSERT_EQ(Batch(sweep + " --out " + out + " --samples 1 --jobs 1 --keep-runs", out), 0) << Read(out + ".err");
  const std::vector<std::string> lines = Lines(Read(out + "/results.jsonl"));
  ASSERT_EQ(lines.size(), 1u);
  const std::string& line = lines[0];
  EXPECT_EQ(Field(line, "nonconverged_steps"), "0") << line;
  EXPECT_EQ(Field(line, "bodies_out_of_box"), "0") << line;
  EXPECT_EQ(Field(line, "nan"), "false") << line;
  const double depth = std::stod(Field(line, "max_penetration_m"));
  EXPECT_GE(depth, 0.0) << line;
  EXPECT_LT(depth, 1e-6) << line;
  EXPECT_EQ(Field(line, "class"), "null") << line;
  EXPECT_EQ(Field(line, "final_pose"), "null") << line;
  EXPECT_NE(line.find("\"pile\": {\"n\": 3, \"shape\": \"ellipsoid\", \"orientation\": \"random\", \"seed\": "),
            std::string::npos)
      << line;
  const std::string stop = Field(line, "stop_reason");
  EXPECT_TRUE(stop == "\"duration\"" || stop == "\"at_rest\"") << line;
  // The run's scene is the generator's for the sample's seed modulo 2^32.
  const std::string seed = Field(line.substr(line.find("\"pile\"")), "seed");
  ASSERT_EQ(Shell(kMakePile + " --n 3 --shape ellipsoid --orientation random --seed " + seed + " --out " + dir +
                  "/again.urdf"),
            0);
  EXPECT_EQ(Read(out + "/runs/0/scene.urdf"), Read(dir + "/again.urdf"));
  EXPECT_NE(Read(out + "/runs/0/summary.json").find("\"max_penetration_oracle\": "), std::string::npos);
  const std::string report = Read(out + ".out");
  EXPECT_NE(report.find("non-converged steps: 0 (in 0 samples); bodies out of the box: 0 (in 0 samples); samples "
                        "with NaN: 0"),
            std::string::npos)
      << report;
  EXPECT_TRUE(IsPng(out + "/report_time_to_rest.png"));
  EXPECT_FALSE(Exists(out + "/report_faces.png"));  // a pile has no classes
}

// stop.max_wall: a sample over its wall budget is stopped inside its run and still gets its line (stop_reason
// max_wall, the runner's exit 3, the simulated time it reached); the report counts it.
TEST(PileStudy, ASampleOverItsWallBudgetStopsAndItsLineSaysSo) {
  const std::string dir = TempDir("pile_wall");
  std::string sweep = TinyPileSweep(dir, 30, 2.0);
  ASSERT_FALSE(sweep.empty());
  std::string text = Read(sweep);
  const size_t hold = text.find("    hold: 0.2\n");
  ASSERT_NE(hold, std::string::npos);
  text.insert(hold + std::string("    hold: 0.2\n").size(), "  max_wall: 0.3\n");
  std::ofstream(sweep) << text;
  const std::string out = dir + "/study";
  ASSERT_EQ(Batch(sweep + " --out " + out + " --samples 1 --jobs 1", out), 0) << Read(out + ".err");
  const std::vector<std::string> lines = Lines(Read(out + "/results.jsonl"));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(Field(lines[0], "stop_reason"), "\"max_wall\"") << lines[0];
  EXPECT_EQ(Field(lines[0], "runner_exit"), "3") << lines[0];
  const double t_end = std::stod(Field(lines[0], "t_end"));
  EXPECT_GT(t_end, 0.0) << lines[0];
  EXPECT_LT(t_end, 2.0) << lines[0];  // 30 ellipsoids cannot land in 0.3 s of wall time
  EXPECT_EQ(Field(lines[0], "nan"), "false") << lines[0];
  EXPECT_NE(Read(out + ".out").find("stopped by max_wall: 1;"), std::string::npos) << Read(out + ".out");
}

// The checks of a run's trajectory can fail: a body through a wall, one below the floor and a NaN are counted.
TEST(PileStudy, TheTrajectoryChecksCountBodiesOutOfTheBoxAndNaN) {
  const std::string dir = TempDir("checks");
  Shell("mkdir -p " + dir);
  std::string header = "t";
  for (const char* body : {"a", "b", "c"}) {
    for (const char* c : {"x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz"}) {
      header += std::string(",") + body + "." + c;
    }
  }
  const std::string rest = ",1,0,0,0,0,0,0,0,0,0";
  // a: ends beyond the wall x = 0.5; b: dips below the floor at t = 0.005, back inside at the end; c: inside.
  std::ofstream(dir + "/trajectory.csv") << header << ",energy.kinetic\n"
                                         << "0,0,0,0.1" << rest << ",0.2,0,0.1" << rest << ",0,0.2,0.1" << rest
                                         << ",nan\n"
                                         << "0.005,0.3,0,0.1" << rest << ",0.2,0,-0.01" << rest << ",0,0.2,0.1" << rest
                                         << ",0\n"
                                         << "0.01,0.6,0,0.1" << rest << ",0.2,0,0.04" << rest << ",0,0.2,0.1" << rest
                                         << ",0\n";
  const std::string check = "import importlib.machinery as m; b = m.SourceFileLoader('b', '" + kSource +
                            "/scripts/implicit_sim_batch').load_module(); print(b.trajectory_checks('" + dir +
                            "/trajectory.csv', BOX))";
  ASSERT_EQ(Shell("/usr/bin/python3 -c \"" + std::regex_replace(check, std::regex("BOX"), "True") + "\" > " + dir +
                  "/box.txt"),
            0);
  EXPECT_EQ(Read(dir + "/box.txt"), "{'nan': False, 'bodies_out_of_box': 2}\n");  // energy's nan is no state
  ASSERT_EQ(Shell("/usr/bin/python3 -c \"" + std::regex_replace(check, std::regex("BOX"), "False") + "\" > " + dir +
                  "/nobox.txt"),
            0);
  EXPECT_EQ(Read(dir + "/nobox.txt"), "{'nan': False, 'bodies_out_of_box': None}\n");
  Shell("sed -i '3s/^0.005,0.3,/0.005,nan,/' " + dir + "/trajectory.csv");
  ASSERT_EQ(Shell("/usr/bin/python3 -c \"" + std::regex_replace(check, std::regex("BOX"), "True") + "\" > " + dir +
                  "/nan.txt"),
            0);
  EXPECT_EQ(Read(dir + "/nan.txt"), "{'nan': True, 'bodies_out_of_box': 2}\n");
}

// The shipped study parses (its Slurm script has 200 array tasks); bad pile values are refused with exit 2, one
// line naming the key and its allowed values, and nothing written.
TEST(PileStudy, ThePileKeyParsesAndBadValuesAreRefusedNamingTheKey) {
  const std::string dir = TempDir("pile_keys");
  Shell("mkdir -p " + dir);
  ASSERT_EQ(Batch(kPileSweep + " --out " + dir + "/shipped --slurm-script " + dir + "/pile.sbatch", dir + "/shipped"),
            0)
      << Read(dir + "/shipped.err");
  EXPECT_NE(Read(dir + "/pile.sbatch").find("#SBATCH --array=0-199\n"), std::string::npos);
  const std::string sweep_json = Read(dir + "/shipped/sweep.json");
  for (const char* expected : {"\"n\": 50", "\"shape\": \"ellipsoid\"", "\"orientation\": \"random\"", "\"dt\": 0.005"}) {
    EXPECT_NE(sweep_json.find(expected), std::string::npos) << expected << " in " << sweep_json;
  }
  EXPECT_NE(sweep_json.find("\"scheme\": \"paper\""), std::string::npos);  // the runner gets it as --scheme
  const std::string good = Read(kPileSweep);
  struct Case {
    std::string name, from, to;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"zero_n", "n: 50", "n: 0", {"pile.n", "[1, 4000]"}},
      {"fractional_n", "n: 50", "n: 2.5", {"pile.n", "integer"}},
      {"bad_shape", "shape: ellipsoid", "shape: cube", {"pile.shape", "sphere, ellipsoid"}},
      {"bad_orientation", "orientation: random", "orientation: tilted", {"pile.orientation", "random", "aligned"}},
      {"unknown_key", "shape: ellipsoid", "shape: ellipsoid\n  size: 3", {"pile.size", "unknown key"}},
      {"no_shape", "  shape: ellipsoid\n", "", {"pile.shape", "missing"}},
      {"with_scene", "samples: 200", "samples: 200\nscene: ../cube_drop.urdf", {"scene", "not allowed with pile"}},
      {"not_a_mapping", "pile:\n(  [^\n]*\n)+", "pile: 50\n", {"pile", "mapping"}},
      {"zero_max_wall", "    hold: 0.2", "    hold: 0.2\n  max_wall: 0", {"stop.max_wall", "(0, 1e+07] s"}},
      {"text_max_wall", "    hold: 0.2", "    hold: 0.2\n  max_wall: long", {"stop.max_wall", "number"}},
  };
  for (const Case& c : cases) {
    const std::string text = std::regex_replace(good, std::regex(c.from), c.to, std::regex_constants::format_first_only);
    ASSERT_NE(text, good) << c.name;
    const std::string sweep = dir + "/" + c.name + ".yaml";
    std::ofstream(sweep) << text;
    const int status = Batch(sweep + " --out " + dir + "/" + c.name + " --samples 1", dir + "/" + c.name);
    const std::string err = Read(dir + "/" + c.name + ".err");
    EXPECT_EQ(status, 2) << c.name << ": " << err;
    EXPECT_EQ(Lines(err).size(), 1u) << c.name << ": " << err;
    for (const std::string& word : c.words) EXPECT_NE(err.find(word), std::string::npos) << c.name << ": " << err;
    EXPECT_FALSE(Exists(dir + "/" + c.name)) << c.name << ": the output directory was created";
  }
}

// implicit_sim_make_pile --orientation random: the same bytes for a seed, other bytes for another seed, the default
// layout unchanged by the flag's existence (aligned is the default), and a bad value refused.
TEST(PileStudy, MakePileRandomOrientationsAreDeterministicForASeed) {
  const std::string dir = TempDir("make_pile");
  Shell("mkdir -p " + dir);
  const std::string make = kMakePile + " --n 50 --shape ellipsoid";
  ASSERT_EQ(Shell(make + " --orientation random --seed 11 --out " + dir + "/a.urdf"), 0);
  ASSERT_EQ(Shell(make + " --orientation random --seed 11 --out " + dir + "/b.urdf"), 0);
  ASSERT_EQ(Shell(make + " --orientation random --seed 12 --out " + dir + "/c.urdf"), 0);
  ASSERT_EQ(Shell(make + " --seed 11 --out " + dir + "/default.urdf"), 0);
  ASSERT_EQ(Shell(make + " --orientation aligned --seed 11 --out " + dir + "/aligned.urdf"), 0);
  EXPECT_EQ(Read(dir + "/a.urdf"), Read(dir + "/b.urdf"));
  EXPECT_NE(Read(dir + "/a.urdf"), Read(dir + "/c.urdf"));
  EXPECT_EQ(Read(dir + "/default.urdf"), Read(dir + "/aligned.urdf"));
  EXPECT_NE(Read(dir + "/a.urdf").find("Random orientations"), std::string::npos);
  // Non-overlapping: the runner's first step refuses overlaps (initial_overlap) and its geometric check reports
  // none after one step.
  ASSERT_EQ(Shell(kRunner + " --scene " + dir + "/a.urdf --duration 0.005 --dt 0.005 --threads 1 --check-penetration --out " +
                  dir + "/run > /dev/null 2>&1"),
            0);
  const std::string summary = Read(dir + "/run/summary.json");
  EXPECT_NE(summary.find("\"stop_reason\": \"duration\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"max_penetration_oracle\": 0\n"), std::string::npos) << summary;
  EXPECT_EQ(Shell(make + " --orientation tilted --out " + dir + "/bad.urdf 2> " + dir + "/bad.err"), 2);
  EXPECT_EQ(Read(dir + "/bad.err"), "implicit_sim_make_pile: --orientation must be aligned or random, got 'tilted'\n");
  EXPECT_FALSE(Exists(dir + "/bad.urdf"));
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
