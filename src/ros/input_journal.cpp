// The input journal's file: a header line, then records of
//   uint64 step | uint8 kind | uint32 size | size bytes        (little-endian, as the ROS serialization itself)
#include "implicit_sim/ros/input_journal.h"

#include <cstring>
#include <iterator>
#include <stdexcept>

namespace implicit_sim {
namespace {

const char kHeader[] = "implicit_sim input journal 1\n";
constexpr size_t kHeaderSize = sizeof(kHeader) - 1;
constexpr size_t kRecordHead = 8 + 1 + 4;  // step, kind, size (bytes)
constexpr uint32_t kMaxRecord = 64u << 20;  // a command message is far smaller; larger means a corrupt file

bool KnownKind(uint8_t kind) {
  switch (static_cast<JournalInput>(kind)) {
    case JournalInput::kWrenchCommand:
    case JournalInput::kJointCommand:
    case JournalInput::kJointEffortCommand:
    case JournalInput::kJointTrajectory:
    case JournalInput::kUnreplayable:
      return true;
  }
  return false;
}

}  // namespace

InputJournalWriter::InputJournalWriter(const std::string& path)
    : out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw std::invalid_argument("~input_journal: cannot create '" + path + "'");
  out_.write(kHeader, kHeaderSize);
  out_.flush();
}

void InputJournalWriter::WriteRecord(uint64_t step, JournalInput kind, const std::vector<uint8_t>& bytes) {
  char head[kRecordHead];
  const uint8_t kind_byte = static_cast<uint8_t>(kind);
  const uint32_t size = static_cast<uint32_t>(bytes.size());
  std::memcpy(head, &step, 8);
  std::memcpy(head + 8, &kind_byte, 1);
  std::memcpy(head + 9, &size, 4);
  std::lock_guard<std::mutex> lock(mutex_);
  out_.write(head, kRecordHead);
  out_.write(reinterpret_cast<const char*>(bytes.data()), size);
  out_.flush();
}

InputJournalReader::InputJournalReader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("~replay_journal: cannot read '" + path + "'");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto refuse = [&path](size_t offset, const std::string& what) {
    return std::invalid_argument("~replay_journal: '" + path + "' at byte " + std::to_string(offset) + ": " + what);
  };
  if (text.compare(0, kHeaderSize, kHeader) != 0) throw refuse(0, "not an implicit_sim input journal (version 1)");
  size_t at = kHeaderSize;
  uint64_t previous_step = 0;
  while (at < text.size()) {
    if (text.size() - at < kRecordHead) throw refuse(at, "a record is cut short");
    JournalRecord record;
    uint8_t kind;
    uint32_t size;
    std::memcpy(&record.step, text.data() + at, 8);
    std::memcpy(&kind, text.data() + at + 8, 1);
    std::memcpy(&size, text.data() + at + 9, 4);
    if (!KnownKind(kind)) throw refuse(at, "unknown record kind " + std::to_string(kind));
    if (record.step < previous_step) throw refuse(at, "steps go backwards");
    if (size > kMaxRecord || text.size() - at - kRecordHead < size) throw refuse(at, "a record is cut short");
    record.kind = static_cast<JournalInput>(kind);
    record.bytes.assign(text.begin() + at + kRecordHead, text.begin() + at + kRecordHead + size);
    previous_step = record.step;
    records_.push_back(std::move(record));
    at += kRecordHead + size;
  }
}

const JournalRecord* InputJournalReader::Next(uint64_t step) {
  if (next_ == records_.size() || records_[next_].step > step) return nullptr;
  if (records_[next_].step < step) {
    throw std::logic_error("the journal's input for step " + std::to_string(records_[next_].step) +
                           " was not replayed before step " + std::to_string(step));
  }
  return &records_[next_++];
}

}  // namespace implicit_sim
