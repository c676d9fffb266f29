// Batch studies on real engines (doc/batch.md): a one-node Slurm cluster (munge, slurmctld, slurmd) and an OpenSSH
// server, both from Debian's packages, started on this machine by test/batch/local_slurm.sh and local_sshd.sh with
// all their state in a scratch folder and ports of their own. The array job submitted with sbatch and the --sshlogin
// run must give the lines of a GNU parallel run of the same samples on this machine. A daemon that cannot start fails
// the test with its log's tail (never a skip: CI installs the packages). The fixtures stop the daemons (and cancel
// the cluster's jobs) in TearDown, which gtest runs after a failed assertion too.
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "batch_test_support.h"

namespace {

using namespace batch_test;  // NOLINT: the shared helpers read as this file's own

const std::string kLocalSlurm = kSource + "/test/batch/local_slurm.sh";
const std::string kLocalSshd = kSource + "/test/batch/local_sshd.sh";
constexpr int kSamples = 16;  // each cube sample runs in about a second

// The merged file of the first kSamples cube samples through GNU parallel on this machine (once per process).
const std::string& LocalRun() {
  static const std::string results = [] {
    const std::string out = TempDir("local");
    const int status = Batch(kCubeSweep + " --out " + out + " --jobs 2 --no-report --samples " +
                             std::to_string(kSamples), out);
    return status == 0 ? Read(out + "/results.jsonl") : "local run failed: exit " + std::to_string(status);
  }();
  return results;
}

// Polls `done` every 50 ms for at most `seconds`.
template <typename Done>
bool WaitFor(Done done, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

// Names of the complete-looking sample files in OUT/samples ("<id>.json"; temporary files start with '.').
std::vector<std::string> SampleFiles(const std::string& out) {
  const std::string list = out + ".list";
  Shell("ls " + out + "/samples 2>/dev/null | grep '^[0-9]*\\.json$' > " + list);
  return Lines(Read(list));
}

// Inode and modification time (ns): a rewritten file changes one of them.
std::pair<ino_t, long long> Identity(const std::string& path) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) return {0, -1};
  return {st.st_ino, static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec};
}

// Starts a daemon helper (local_slurm.sh / local_sshd.sh) in SetUp and always stops it in TearDown.
class DaemonTest : public ::testing::Test {
 protected:
  DaemonTest(std::string helper, std::string name) : helper_(std::move(helper)), dir_(TempDir(name)) {}

  void SetUp() override {
    ASSERT_EQ(LocalRun().rfind("local run failed", 0), std::string::npos) << LocalRun();
    const int status = Shell("bash " + helper_ + " start " + dir_ + StartArgs() + " > " + dir_ + ".start 2>&1");
    started_ = true;
    ASSERT_EQ(status, 0) << helper_ << " start " << dir_ << " failed:\n" << Read(dir_ + ".start");
  }

  void TearDown() override {
    if (!started_) return;
    EXPECT_EQ(Shell("bash " + helper_ + " stop " + dir_ + " > " + dir_ + ".stop 2>&1"), 0) << Read(dir_ + ".stop");
  }

  virtual std::string StartArgs() const { return ""; }

  const std::string helper_;
  const std::string dir_;  // the daemons' scratch folder

 private:
  bool started_ = false;
};

class SlurmCluster : public DaemonTest {
 protected:
  SlurmCluster() : DaemonTest(kLocalSlurm, "slurm") {}

  // A Slurm client command against this cluster (at most `seconds`, so a stuck daemon fails the test, not hangs it).
  int Slurm(const std::string& command, const std::string& log, int seconds = 300) const {
    return Shell("SLURM_CONF=" + dir_ + "/slurm.conf timeout " + std::to_string(seconds) + " " + command + " > " +
                 log + " 2>&1");
  }

  // Writes the array job script for kSamples samples into OUT.
  void WriteScript(const std::string& out, const std::string& script) const {
    ASSERT_EQ(Batch(kCubeSweep + " --out " + out + " --samples " + std::to_string(kSamples) + " --slurm-script " +
                        script, out + "_script"),
              0)
        << Read(out + "_script.err");
  }

  int Merge(const std::string& out) const {
    return Batch(kCubeSweep + " --out " + out + " --samples " + std::to_string(kSamples) +
                     " --merge-only --no-report", out + "_merge");
  }

  // Submits SCRIPT with sbatch (extra options before it); the job id, or "" when sbatch failed.
  std::string Submit(const std::string& options, const std::string& script, const std::string& log) const {
    if (Slurm("sbatch --parsable " + options + " " + script, log, 30) != 0) return "";
    const std::vector<std::string> lines = Lines(Read(log));
    return lines.empty() ? "" : lines.back();
  }

  bool JobListed(const std::string& job) const {
    return Slurm("squeue -h -j " + job + " -o %i | grep -q .", dir_ + ".squeue", 30) == 0;
  }

  // Polls squeue (sbatch --wait polls only every few seconds) until the job has left the queue.
  bool WaitUntilEnded(const std::string& job, double seconds) const {
    return WaitFor([&] { return !JobListed(job); }, seconds);
  }

  // Array tasks of the job in state COMPLETED (exit 0), from scontrol (which keeps ended jobs for MinJobAge, 300 s).
  int CompletedTasks(const std::string& job) const {
    Slurm("scontrol -o show job " + job + " | grep -c JobState=COMPLETED", dir_ + ".completed", 30);
    const std::vector<std::string> lines = Lines(Read(dir_ + ".completed"));
    return lines.empty() ? -1 : std::stoi(lines[0]);
  }

  // The daemons' log tails, for a failure message.
  std::string Logs() const {
    return "\n--- slurmctld.log:\n" + Tail(dir_ + "/slurmctld.log") + "--- slurmd.log:\n" + Tail(dir_ + "/slurmd.log");
  }

  static std::string Tail(const std::string& path) {
    Shell("tail -n 15 " + path + " > " + path + ".tail 2>&1");
    return Read(path + ".tail");
  }
};

// sbatch on the script implicit_sim_batch writes, then --merge-only: the GNU parallel run's lines.
TEST_F(SlurmCluster, TheArrayJobGivesTheLocalRunsLines) {
  const std::string out = TempDir("slurm_study"), script = out + ".sbatch";
  WriteScript(out, script);
  const std::string job = Submit("", script, out + ".sbatch.log");
  ASSERT_NE(job, "") << Read(out + ".sbatch.log") << Logs();
  ASSERT_TRUE(WaitUntilEnded(job, 300)) << "job " << job << " still queued after 300 s" << Logs();
  EXPECT_EQ(CompletedTasks(job), kSamples) << Logs();
  // One log per array task under DIR/slurm: Slurm ran every sample.
  for (int i = 0; i < kSamples; ++i) {
    EXPECT_EQ(Shell("test -f " + out + "/slurm/" + job + "_" + std::to_string(i) + ".log"), 0) << "task " << i;
  }
  ASSERT_EQ(Merge(out), 0) << Read(out + "_merge.err");
  EXPECT_EQ(Read(out + "/results.jsonl"), LocalRun());
}

// A throttled array (one task at a time) cancelled with scancel after a few samples, then the script resubmitted:
// the samples done before are not run again (same inode and mtime), and the merged file is the local run's.
TEST_F(SlurmCluster, AnArrayJobCancelledMidwayAndResubmittedResumes) {
  const std::string out = TempDir("slurm_resume"), script = out + ".sbatch";
  WriteScript(out, script);
  // sbatch's --array overrides the script's #SBATCH --array line.
  const std::string first = Submit("--array=0-" + std::to_string(kSamples - 1) + "%1", script, out + ".first.log");
  ASSERT_NE(first, "") << Read(out + ".first.log") << Logs();
  ASSERT_TRUE(WaitFor([&] { return SampleFiles(out).size() >= 3; }, 120)) << "no 3 samples in 120 s" << Logs();
  ASSERT_EQ(Slurm("scancel " + first, out + ".scancel.log", 30), 0) << Read(out + ".scancel.log");
  ASSERT_TRUE(WaitUntilEnded(first, 60)) << "job " << first << " still listed 60 s after scancel" << Logs();

  std::map<std::string, std::pair<ino_t, long long>> before;
  for (const std::string& name : SampleFiles(out)) before[name] = Identity(out + "/samples/" + name);
  ASSERT_GE(before.size(), 3u);
  ASSERT_LT(before.size(), static_cast<size_t>(kSamples)) << "the array ended before scancel";
  EXPECT_EQ(Merge(out), 1);  // the cancelled tasks' samples are missing

  const std::string second = Submit("", script, out + ".second.log");
  ASSERT_NE(second, "") << Read(out + ".second.log") << Logs();
  ASSERT_TRUE(WaitUntilEnded(second, 300)) << "job " << second << " still queued after 300 s" << Logs();
  EXPECT_EQ(CompletedTasks(second), kSamples) << Logs();  // the done samples' tasks exit 0 at once
  for (const auto& [name, identity] : before) {
    EXPECT_EQ(Identity(out + "/samples/" + name), identity) << name << " was run again";
  }
  ASSERT_EQ(Merge(out), 0) << Read(out + "_merge.err");
  EXPECT_EQ(Read(out + "/results.jsonl"), LocalRun());
}

class SshHosts : public DaemonTest {
 protected:
  SshHosts() : DaemonTest(kLocalSshd, "sshd"), island_out_(TempDir("ssh_island")) {}

  // The host `island` sees an empty private folder at island_out_ (a host that does not share that DIR).
  std::string StartArgs() const override { return " " + island_out_; }

  std::string ParallelSsh() const { return "PARALLEL_SSH='ssh -F " + dir_ + "/ssh_config'"; }

  const std::string island_out_;
};

// --sshlogin 1/hostA,1/hostB: both names log in to the test's sshd on 127.0.0.1, so GNU parallel spreads the
// samples over two hosts through real ssh logins; the lines are the local run's.
TEST_F(SshHosts, TwoLoginsSpreadTheSamplesAndGiveTheLocalRunsLines) {
  const std::string out = TempDir("ssh_study");
  ASSERT_EQ(Batch(kCubeSweep + " --out " + out + " --samples " + std::to_string(kSamples) +
                      " --no-report --sshlogin 1/hostA,1/hostB", out, ParallelSsh()),
            0)
      << Read(out + ".err") << Read(out + "/parallel.joblog") << "--- sshd.log:\n" << Read(dir_ + "/sshd.log");
  EXPECT_EQ(Read(out + "/results.jsonl"), LocalRun());
  std::map<std::string, int> per_host;  // the joblog's Host column
  const std::vector<std::string> joblog = Lines(Read(out + "/parallel.joblog"));
  for (size_t i = 1; i < joblog.size(); ++i) ++per_host[joblog[i].substr(joblog[i].find('\t') + 1, 5)];
  EXPECT_GT(per_host["hostA"], 0) << Read(out + "/parallel.joblog");
  EXPECT_GT(per_host["hostB"], 0) << Read(out + "/parallel.joblog");
  EXPECT_EQ(per_host["hostA"] + per_host["hostB"], kSamples) << Read(out + "/parallel.joblog");
  // Every sample came through a real login (GNU parallel may log in more often, e.g. to check the host).
  EXPECT_EQ(Shell("test $(grep -c 'Accepted publickey' " + dir_ + "/sshd.log) -ge " + std::to_string(kSamples)), 0)
      << Read(dir_ + "/sshd.log");
}

// A host that does not share DIR: its samples exit 0 there but their lines never arrive; they are reported missing
// with the host named, and exit 1.
TEST_F(SshHosts, AHostThatDoesNotShareTheStudyFolderIsNamed) {
  EXPECT_EQ(Batch(kCubeSweep + " --out " + island_out_ + " --samples 2 --no-report --sshlogin 1/island",
                  island_out_, ParallelSsh()),
            1)
      << Read(island_out_ + ".err");
  const std::string err = Read(island_out_ + ".err");
  EXPECT_NE(err.find("2 samples (0, 1) exited 0 on host 'island' but left no line"), std::string::npos) << err;
  EXPECT_TRUE(SampleFiles(island_out_).empty());
  EXPECT_EQ(Read(island_out_ + "/results.jsonl"), "");
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
