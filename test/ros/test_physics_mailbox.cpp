// The node's physics mailbox (ros/physics_mailbox.h), without timing: a command queued while a step runs runs right
// after that step and before the next one, commands from several threads each run once in queue order, Stop
// releases every waiter, and a step job counts its steps. The "steps" here are gates the test opens, so every
// assertion is about order, never about how long anything took.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/ros/physics_mailbox.h"

namespace implicit_sim {
namespace {

// A physics thread whose steps last until the test opens them one at a time.
class GatedPhysics {
 public:
  explicit GatedPhysics(PhysicsMailbox* mailbox) : mailbox_(mailbox), thread_([this] { Loop(); }) {}
  ~GatedPhysics() {
    mailbox_->Stop();
    OpenSteps(1 << 20);
    thread_.join();
  }
  void OpenSteps(int n) {
    std::lock_guard<std::mutex> lock(mutex_);
    opened_ += n;
    cv_.notify_all();
  }
  void WaitUntilStepRunning(int step) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return started_ >= step; });
  }
  int started() const { return started_.load(); }
  int done() const { return done_.load(); }

 private:
  void Loop() {
    while (mailbox_->WaitForWork(true) != PhysicsMailbox::Work::kStop) {
      std::unique_lock<std::mutex> lock(mutex_);
      ++started_;
      cv_.notify_all();
      cv_.wait(lock, [&] { return opened_ >= started_; });
      ++done_;
    }
  }
  PhysicsMailbox* mailbox_;
  std::mutex mutex_;
  std::condition_variable cv_;
  int opened_ = 0;
  std::atomic<int> started_{0}, done_{0};
  std::thread thread_;
};

void WaitUntilQueued(const PhysicsMailbox& mailbox, size_t n) {
  while (mailbox.QueuedCommands() < n) std::this_thread::yield();
}

TEST(PhysicsMailbox, ACommandQueuedDuringAStepRunsRightAfterIt) {
  PhysicsMailbox mailbox;
  GatedPhysics physics(&mailbox);
  physics.WaitUntilStepRunning(1);
  int started_when_run = -1, done_when_run = -1;
  std::thread caller([&] {
    EXPECT_TRUE(mailbox.RunBetweenSteps([&] {
      started_when_run = physics.started();
      done_when_run = physics.done();
    }));
  });
  WaitUntilQueued(mailbox, 1);
  physics.OpenSteps(1);  // step 1 ends; the command must run before step 2 starts
  caller.join();
  EXPECT_EQ(done_when_run, 1);
  EXPECT_EQ(started_when_run, 1);
  EXPECT_EQ(mailbox.QueuedCommands(), 0u);
}

// The node's cutter interrupts the step in progress; here it ends the gated step, which the command then follows.
TEST(PhysicsMailbox, ACommandThatWaitsCallsTheStepCutterOnce) {
  PhysicsMailbox mailbox;
  GatedPhysics physics(&mailbox);
  std::atomic<int> cuts{0};
  mailbox.SetStepCutter(std::chrono::milliseconds(1), [&] {
    ++cuts;
    physics.OpenSteps(1);
  });
  physics.WaitUntilStepRunning(1);
  int done_when_run = -1;
  EXPECT_TRUE(mailbox.RunBetweenSteps([&] { done_when_run = physics.done(); }));  // no one else opens the step
  EXPECT_EQ(cuts.load(), 1);
  EXPECT_EQ(done_when_run, 1);
}

TEST(PhysicsMailbox, ACommandServedInTimeDoesNotCallTheStepCutter) {
  PhysicsMailbox mailbox;
  GatedPhysics physics(&mailbox);
  std::atomic<int> cuts{0};
  mailbox.SetStepCutter(std::chrono::seconds(60), [&] { ++cuts; });
  physics.WaitUntilStepRunning(1);
  std::thread caller([&] { EXPECT_TRUE(mailbox.RunBetweenSteps([] {})); });
  WaitUntilQueued(mailbox, 1);
  physics.OpenSteps(1);
  caller.join();
  EXPECT_EQ(cuts.load(), 0);
}

TEST(PhysicsMailbox, CommandsFromSeveralThreadsRunOnceInQueueOrder) {
  PhysicsMailbox mailbox;
  GatedPhysics physics(&mailbox);
  physics.WaitUntilStepRunning(1);
  std::vector<int> order;  // only the physics thread writes it
  std::vector<std::thread> callers;
  for (int i = 0; i < 4; ++i) {
    callers.emplace_back([&, i] { EXPECT_TRUE(mailbox.RunBetweenSteps([&, i] { order.push_back(i); })); });
    WaitUntilQueued(mailbox, static_cast<size_t>(i + 1));
  }
  mailbox.Post([&] { order.push_back(4); });
  physics.OpenSteps(1);
  for (auto& caller : callers) caller.join();
  physics.WaitUntilStepRunning(2);
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4}));
}

TEST(PhysicsMailbox, StopReleasesEveryWaiterAndRefusesLaterCommands) {
  PhysicsMailbox mailbox;
  bool ran = false;
  {
    GatedPhysics physics(&mailbox);
    physics.WaitUntilStepRunning(1);
    bool answered = true;
    std::thread caller([&] { answered = mailbox.RunBetweenSteps([&] { ran = true; }); });
    WaitUntilQueued(mailbox, 1);
    mailbox.Stop();  // the step is still running: the waiter must not wait for it
    caller.join();
    EXPECT_FALSE(answered);
    EXPECT_FALSE(mailbox.RunBetweenSteps([&] { ran = true; }));
  }  // the physics thread ends its step and stops
  EXPECT_FALSE(ran);
}

TEST(PhysicsMailbox, AJobCountsItsStepsAndRefusesASecondJob) {
  PhysicsMailbox mailbox;
  std::string refusal;
  ASSERT_TRUE(mailbox.StartJob(3, 0.0, &refusal));
  EXPECT_FALSE(mailbox.StartJob(1, 0.0, &refusal));
  EXPECT_NE(refusal.find("another ~step or ~run_steps job"), std::string::npos) << refusal;
  std::thread physics([&] {
    for (int k = 1; k <= 3; ++k) {
      ASSERT_EQ(mailbox.WaitForWork(false), PhysicsMailbox::Work::kJobStep);
      mailbox.CountJobStep(0.01 * k);
    }
  });
  const StepJob ended = mailbox.WaitForJob(0.01, [](const StepJob&) {}, [] { return false; });
  physics.join();
  EXPECT_TRUE(ended.success);
  EXPECT_EQ(ended.done, 3u);
  EXPECT_DOUBLE_EQ(ended.sim_time, 0.03);
  EXPECT_EQ(ended.message, "ran 3 steps");
  EXPECT_FALSE(mailbox.JobActive());
}

}  // namespace
}  // namespace implicit_sim

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
