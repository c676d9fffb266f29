// The input journal's file (ros/input_journal.h): records come back in order with their messages bit for bit, the
// reader hands them out step by step, and a damaged file is refused with the path and the byte offset.
#include <fstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <sensor_msgs/JointState.h>

#include "implicit_sim/BodyWrench.h"
#include "implicit_sim/JointCommand.h"
#include "implicit_sim/ros/input_journal.h"

namespace implicit_sim {
namespace {

std::string TempPath(const std::string& name) { return ::testing::TempDir() + "/journal_" + name; }

implicit_sim::BodyWrench Wrench(const std::string& body, double fx) {
  implicit_sim::BodyWrench msg;
  msg.body = body;
  msg.wrench.force.x = fx;
  msg.wrench.torque.z = -1.0 / 3.0;  // not exact in decimal: the round trip must keep every bit
  return msg;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteAll(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

std::string ErrorOf(const std::string& path) {
  try {
    InputJournalReader reader(path);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(InputJournal, RecordsComeBackInOrderWithTheirMessagesAndSteps) {
  const std::string path = TempPath("round_trip");
  {
    InputJournalWriter writer(path);
    writer.Write(0, JournalInput::kWrenchCommand, Wrench("ball_3", 0.1));
    implicit_sim::JointCommand command;
    command.name = {"lift", "wrist"};
    command.position = {-0.2, 1.0 / 7.0};
    writer.Write(0, JournalInput::kJointCommand, command);
    sensor_msgs::JointState efforts;
    efforts.name = {"lift"};
    efforts.effort = {2.5};
    writer.Write(5, JournalInput::kJointEffortCommand, efforts);
    writer.WriteUnreplayable(9, "~set_body_state");
  }
  InputJournalReader reader(path);
  ASSERT_EQ(reader.size(), 4u);
  EXPECT_EQ(reader.last_step(), 9u);
  const JournalRecord* first = reader.Next(0);
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->kind, JournalInput::kWrenchCommand);
  const auto wrench = first->Decode<implicit_sim::BodyWrench>();
  EXPECT_EQ(wrench.body, "ball_3");
  EXPECT_EQ(wrench.wrench.force.x, 0.1);
  EXPECT_EQ(wrench.wrench.torque.z, -1.0 / 3.0);
  const JournalRecord* second = reader.Next(0);
  ASSERT_NE(second, nullptr);
  const auto command = second->Decode<implicit_sim::JointCommand>();
  EXPECT_EQ(command.name, (std::vector<std::string>{"lift", "wrist"}));
  EXPECT_EQ(command.position[1], 1.0 / 7.0);
  EXPECT_EQ(reader.Next(0), nullptr);  // the next record is for step 5
  for (uint64_t step = 1; step < 5; ++step) EXPECT_EQ(reader.Next(step), nullptr) << step;
  const JournalRecord* third = reader.Next(5);
  ASSERT_NE(third, nullptr);
  EXPECT_EQ(third->Decode<sensor_msgs::JointState>().effort, std::vector<double>{2.5});
  for (uint64_t step = 6; step < 9; ++step) EXPECT_EQ(reader.Next(step), nullptr) << step;
  const JournalRecord* fourth = reader.Next(9);
  ASSERT_NE(fourth, nullptr);
  EXPECT_EQ(fourth->kind, JournalInput::kUnreplayable);
  EXPECT_EQ(fourth->Text(), "~set_body_state");
  EXPECT_EQ(reader.remaining(), 0u);
  EXPECT_EQ(reader.Next(10), nullptr);
}

TEST(InputJournal, AReplayThatSkipsAStepIsAnError) {
  const std::string path = TempPath("skipped");
  {
    InputJournalWriter writer(path);
    writer.Write(3, JournalInput::kWrenchCommand, Wrench("ball_0", 1.0));
  }
  InputJournalReader reader(path);
  EXPECT_THROW(reader.Next(4), std::logic_error);
}

TEST(InputJournal, ADamagedFileIsRefusedWithThePathAndTheOffset) {
  const std::string good = TempPath("good");
  {
    InputJournalWriter writer(good);
    writer.Write(1, JournalInput::kWrenchCommand, Wrench("ball_0", 1.0));
    writer.Write(2, JournalInput::kWrenchCommand, Wrench("ball_1", 2.0));
  }
  const std::string bytes = ReadAll(good);
  const size_t header = std::string("implicit_sim input journal 1\n").size();

  const std::string missing = TempPath("missing_file");
  std::remove(missing.c_str());
  EXPECT_NE(ErrorOf(missing).find("cannot read '" + missing + "'"), std::string::npos) << ErrorOf(missing);

  const std::string other = TempPath("other");
  WriteAll(other, "a text file\n");
  EXPECT_NE(ErrorOf(other).find("at byte 0: not an implicit_sim input journal"), std::string::npos);

  const std::string cut = TempPath("cut");
  WriteAll(cut, bytes.substr(0, bytes.size() - 3));
  const std::string cut_error = ErrorOf(cut);
  EXPECT_NE(cut_error.find(cut), std::string::npos) << cut_error;
  EXPECT_NE(cut_error.find("a record is cut short"), std::string::npos) << cut_error;

  std::string bad_kind = bytes;
  bad_kind[header + 8] = 7;
  const std::string kind_path = TempPath("kind");
  WriteAll(kind_path, bad_kind);
  EXPECT_NE(ErrorOf(kind_path).find("at byte " + std::to_string(header) + ": unknown record kind 7"),
            std::string::npos)
      << ErrorOf(kind_path);

  std::string backwards = bytes;
  backwards[header] = 9;  // the first record's step becomes 9, after the second's 2
  const std::string backwards_path = TempPath("backwards");
  WriteAll(backwards_path, backwards);
  EXPECT_NE(ErrorOf(backwards_path).find("steps go backwards"), std::string::npos) << ErrorOf(backwards_path);

  EXPECT_THROW(InputJournalWriter("/nonexistent_dir/journal"), std::invalid_argument);
}

}  // namespace
}  // namespace implicit_sim

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
