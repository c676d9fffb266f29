// The node's input journal (doc/ros_node.md#the-input-journal): ~input_journal records the command topics' messages
// as the physics thread applies them, with the step they precede; ~replay_journal applies a recorded journal's
// messages before the same steps, so a replaying node reaches the recorded run's state bit for bit.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <stdexcept>

namespace implicit_sim {

void SimNode::OpenJournals() {
  if (!params_.replay_journal.empty()) {
    replay_ = std::make_unique<InputJournalReader>(params_.replay_journal);
    ROS_INFO("implicit_sim: replaying %zu inputs of '%s' (the last before step %lu)", replay_->size(),
             params_.replay_journal.c_str(), static_cast<unsigned long>(replay_->last_step()));
  }
  if (!params_.input_journal.empty()) journal_ = std::make_unique<InputJournalWriter>(params_.input_journal);
}

bool SimNode::ReplayJournalInputs(std::string* refusal) {
  try {
    while (const JournalRecord* record = replay_->Next(step_count_)) {
      if (!ApplyJournalRecord(*record, refusal)) return false;
    }
  } catch (const std::exception& e) {  // a skipped step, or a record whose bytes are no message of its kind
    *refusal = e.what();
    return false;
  }
  return true;
}

bool SimNode::ApplyJournalRecord(const JournalRecord& record, std::string* refusal) {
  switch (record.kind) {
    case JournalInput::kWrenchCommand:
      ApplyCommand(record.Decode<implicit_sim::BodyWrench>(), kWrenchInput);
      return true;
    case JournalInput::kJointCommand:
      ApplyCommand(record.Decode<implicit_sim::JointCommand>(), kJointCommandInput);
      return true;
    case JournalInput::kJointEffortCommand:
      ApplyCommand(record.Decode<sensor_msgs::JointState>(), kJointEffortInput);
      return true;
    case JournalInput::kJointTrajectory:
      ApplyCommand(record.Decode<trajectory_msgs::JointTrajectory>(), kJointTrajectoryInput);
      return true;
    case JournalInput::kUnreplayable:
      break;
  }
  *refusal = "the journal's input " + record.Text() + " before step " + std::to_string(record.step) +
             " cannot be replayed";
  return false;
}

}  // namespace implicit_sim
