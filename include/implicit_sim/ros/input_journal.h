// The input journal: every command a node applied, with the step before which it took effect, so that a run driven
// live (at real time, commands arriving whenever the network delivers them) can be replayed headless to the same
// state, bit for bit. doc/ros_node.md#the-input-journal gives the contract and the file format.
#pragma once

#include <cstdint>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

#include <ros/serialization.h>

namespace implicit_sim {

// What a record holds: a command topic's message (ROS serialization), or the name of an input the journal cannot
// replay (a service that edits the world, a drag, a change of the solver's parameters).
enum class JournalInput : uint8_t {
  kWrenchCommand = 1,       // implicit_sim/BodyWrench on ~wrench_cmd
  kJointCommand = 2,        // implicit_sim/JointCommand on ~joint_command
  kJointEffortCommand = 3,  // sensor_msgs/JointState on ~joint_effort_cmd
  kJointTrajectory = 4,     // trajectory_msgs/JointTrajectory on ~joint_trajectory
  kUnreplayable = 255,      // bytes: the input's name, e.g. "~set_body_state"
};

struct JournalRecord {
  uint64_t step = 0;  // the input took effect before this step (steps counted from the node's start)
  JournalInput kind = JournalInput::kUnreplayable;
  std::vector<uint8_t> bytes;

  std::string Text() const { return std::string(bytes.begin(), bytes.end()); }
  template <typename Message>
  Message Decode() const {
    Message msg;
    ros::serialization::IStream in(const_cast<uint8_t*>(bytes.data()), static_cast<uint32_t>(bytes.size()));
    ros::serialization::deserialize(in, msg);
    return msg;
  }
};

// Appends records to a file (created or truncated) and flushes each, so a killed node leaves a usable journal.
// Thread-safe.
class InputJournalWriter {
 public:
  // Throws std::invalid_argument naming the path when the file cannot be created.
  explicit InputJournalWriter(const std::string& path);

  template <typename Message>
  void Write(uint64_t step, JournalInput kind, const Message& msg) {
    std::vector<uint8_t> bytes(ros::serialization::serializationLength(msg));
    ros::serialization::OStream out(bytes.data(), static_cast<uint32_t>(bytes.size()));
    ros::serialization::serialize(out, msg);
    WriteRecord(step, kind, bytes);
  }
  void WriteUnreplayable(uint64_t step, const std::string& input) {
    WriteRecord(step, JournalInput::kUnreplayable, std::vector<uint8_t>(input.begin(), input.end()));
  }

 private:
  void WriteRecord(uint64_t step, JournalInput kind, const std::vector<uint8_t>& bytes);

  std::mutex mutex_;
  std::ofstream out_;
};

// Reads a whole journal at construction and hands its records out in order, step by step.
class InputJournalReader {
 public:
  // Throws std::invalid_argument naming the path and the byte offset of a bad header, record kind or length.
  explicit InputJournalReader(const std::string& path);

  // The next record that takes effect before `step`, or nullptr when the next one is for a later step (or none is
  // left). Throws std::logic_error when a record for an earlier step was never taken (the replay skipped a step).
  const JournalRecord* Next(uint64_t step);
  size_t size() const { return records_.size(); }
  size_t remaining() const { return records_.size() - next_; }
  uint64_t last_step() const { return records_.empty() ? 0 : records_.back().step; }

 private:
  std::vector<JournalRecord> records_;
  size_t next_ = 0;
};

}  // namespace implicit_sim
