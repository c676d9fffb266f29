#include "implicit_sim/ros/node_journal.h"

#include <stdexcept>

#include <ros/console.h>

namespace implicit_sim {

NodeJournal::NodeJournal(const std::string& input_journal, const std::string& replay_journal) {
  if (!replay_journal.empty()) {
    reader_ = std::make_unique<InputJournalReader>(replay_journal);
    ROS_INFO("implicit_sim: replaying %zu inputs of '%s' (the last before step %lu)", reader_->size(),
             replay_journal.c_str(), static_cast<unsigned long>(reader_->last_step()));
  }
  if (!input_journal.empty()) writer_ = std::make_unique<InputJournalWriter>(input_journal);
}

bool NodeJournal::Replay(uint64_t step, const std::function<bool(const JournalRecord&, std::string*)>& apply,
                         std::string* refusal) {
  try {
    while (const JournalRecord* record = reader_->Next(step)) {
      if (!apply(*record, refusal)) return false;
    }
  } catch (const std::exception& e) {  // a skipped step, or a record whose bytes are no message of its kind
    *refusal = e.what();
    return false;
  }
  return true;
}

}  // namespace implicit_sim
