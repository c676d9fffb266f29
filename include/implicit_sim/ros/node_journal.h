// The node's input journal (doc/ros_node.md#the-input-journal): ~input_journal records the command topics' messages
// as the physics thread applies them, with the step they precede; ~replay_journal applies a recorded journal's
// messages before the same steps, so a replaying node reaches the recorded run's state bit for bit. Physics thread.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "implicit_sim/ros/input_journal.h"

namespace implicit_sim {

class NodeJournal {
 public:
  // Either path may be "" (no journal of that kind). Throws std::invalid_argument for a file it cannot create or read.
  NodeJournal(const std::string& input_journal, const std::string& replay_journal);

  // Records a command topic's message applied before `step`.
  template <typename Message>
  void Record(uint64_t step, JournalInput kind, const Message& msg) {
    if (writer_) writer_->Write(step, kind, msg);
  }
  // Records an input the journal cannot replay (a service that edits the world, a drag, new solver parameters).
  void RecordUnreplayable(uint64_t step, const char* input) {
    if (writer_) writer_->WriteUnreplayable(step, input);
  }
  bool replaying() const { return reader_ != nullptr; }
  // Hands `apply` the recorded inputs that precede `step`; false with *refusal at one it cannot replay, a skipped
  // step or a record whose bytes are no message of its kind.
  bool Replay(uint64_t step, const std::function<bool(const JournalRecord&, std::string*)>& apply,
              std::string* refusal);

 private:
  std::unique_ptr<InputJournalWriter> writer_;
  std::unique_ptr<InputJournalReader> reader_;
};

}  // namespace implicit_sim
