// Reading step cases (the format is in bench/README.md): line by line, every error naming the source, the line and
// what was expected there.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "implicit_sim/core/io/step_case.h"

namespace implicit_sim {
namespace {

class CaseReader {
 public:
  CaseReader(const std::string& text, const std::string& source) : text_(text), source_(source) {}

  [[noreturn]] void Fail(const std::string& what) const {
    throw std::invalid_argument(source_ + ":" + std::to_string(line_) + ": " + what);
  }

  // The next line (without its '\n'); fails at the end of the text, saying what was expected.
  std::string NextLine(const std::string& expected) {
    if (pos_ >= text_.size()) {
      ++line_;
      Fail("unexpected end of file, expected " + expected);
    }
    const size_t end = std::min(text_.find('\n', pos_), text_.size());
    std::string line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++line_;
    return line;
  }

  // The value of the next line, which must be "<key> <value>".
  std::string Value(const std::string& key, const std::string& what) {
    const std::string line = NextLine("'" + key + " " + what + "'");
    if (line.compare(0, key.size() + 1, key + " ") != 0) {
      Fail("expected '" + key + " " + what + "', got '" + line.substr(0, 80) + "'");
    }
    return line.substr(key.size() + 1);
  }

  bool Bool(const std::string& key) {
    const std::string value = Value(key, "true|false");
    if (value != "true" && value != "false") Fail(key + " must be true or false, got '" + value + "'");
    return value == "true";
  }

  long Integer(const std::string& text, const std::string& what) {
    long value = 0;
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    if (text.empty() || result.ec != std::errc() || result.ptr != end) {
      Fail(what + " must be an integer, got '" + text + "'");
    }
    return value;
  }

  // Whether the next line starts with "<key> " (without reading it).
  bool NextKeyIs(const std::string& key) const {
    return pos_ < text_.size() && text_.compare(pos_, key.size() + 1, key + " ") == 0;
  }

  // "<key> <count>": a count of lines that follow, each at least 2 bytes long.
  int Count(const std::string& key) {
    const long count = Integer(Value(key, "<count>"), key + " count");
    if (count < 0 || static_cast<size_t>(count) > (text_.size() - std::min(pos_, text_.size())) / 2) {
      Fail(key + " count " + std::to_string(count) + " is negative or exceeds what is left of the file");
    }
    return static_cast<int>(count);
  }

  double Number(const std::string& text, const std::string& what, bool must_be_finite) {
    double value = 0.0;
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    if (text.empty() || result.ec != std::errc() || result.ptr != end) {
      Fail(what + " must be a number, got '" + text + "'");
    }
    if (must_be_finite && !std::isfinite(value)) Fail(what + " must be a finite number, got '" + text + "'");
    return value;
  }

  // "<key> <count>", then one number per line.
  Eigen::VectorXd Vector(const std::string& key, bool must_be_finite) {
    Eigen::VectorXd values(Count(key));
    for (Eigen::Index i = 0; i < values.size(); ++i) {
      const std::string what = key + "[" + std::to_string(i) + "]";
      values[i] = Number(NextLine(what), what, must_be_finite);
    }
    return values;
  }

  // `count` bytes verbatim, then a line break.
  std::string Bytes(size_t count, const std::string& what) {
    if (count > text_.size() - std::min(pos_, text_.size()) || text_.compare(pos_ + count, 1, "\n") != 0) {
      Fail(what + ": the file ends before its " + std::to_string(count) + " bytes and their line break");
    }
    std::string bytes = text_.substr(pos_, count);
    for (char c : bytes) line_ += c == '\n';
    pos_ += count + 1;
    return bytes;
  }

  bool AtEnd() const { return pos_ >= text_.size(); }

 private:
  const std::string& text_;
  std::string source_;
  size_t pos_ = 0;
  int line_ = 0;  // the line last read (1-based)
};

std::vector<std::string> SplitOnSpaces(const std::string& line) {
  std::vector<std::string> tokens;
  std::istringstream in(line);
  for (std::string token; in >> token;) tokens.push_back(token);
  return tokens;
}

void ReadHeader(CaseReader* in) {
  const std::string expected = "implicit_sim_step_case " + std::to_string(kStepCaseVersion);
  const std::string line = in->NextLine("'" + expected + "'");
  if (line == expected) return;
  if (line.rfind("implicit_sim_step_case ", 0) == 0) {
    in->Fail("unsupported step case version '" + line.substr(23) + "' (this build reads version " +
             std::to_string(kStepCaseVersion) + ")");
  }
  in->Fail("not a step case: expected '" + expected + "', got '" + line.substr(0, 80) + "'");
}

void ReadRecorded(CaseReader* in, RecordedOutcome* recorded) {
  recorded->converged = in->Bool("recorded_converged");
  recorded->iterations = static_cast<int>(in->Integer(in->Value("recorded_iterations", "<n>"), "recorded_iterations"));
  recorded->residual_evaluations = static_cast<int>(
      in->Integer(in->Value("recorded_residual_evaluations", "<n>"), "recorded_residual_evaluations"));
  recorded->fault = in->Value("recorded_fault", "<fault name>");
}

// "options <count>", then "<field> <value>" lines in any order; options not listed keep their defaults, but for the
// scheme: a case that does not name one was captured before the option existed, from the paper's step.
void ReadOptions(CaseReader* in, StepperOptions* options) {
  options->scheme = StepperOptions::Scheme::kPaper;
  const int count = in->Count("options");
  std::set<std::string> seen;
  for (int i = 0; i < count; ++i) {
    const std::vector<std::string> tokens = SplitOnSpaces(in->NextLine("an option line '<field> <value>'"));
    if (tokens.size() != 2) in->Fail("expected an option line '<field> <value>'");
    const OptionRow* row = FindOptionByField(tokens[0]);
    if (!row) in->Fail("unknown option '" + tokens[0] + "' (not in this build's options table)");
    if (!seen.insert(tokens[0]).second) in->Fail("option '" + tokens[0] + "' given twice");
    double value = 0.0;
    std::string error;
    if (!ParseOptionValue(*row, tokens[1], "option " + tokens[0], &value, &error)) in->Fail(error);
    row->set(options, value);
  }
}

// The warm start may hold non-finite values only when it is not valid (a step that found no finite solution).
void ReadWarmStart(CaseReader* in, WarmStart* warm) {
  warm->valid = in->Bool("warm_start_valid");
  const int num_pairs = in->Count("warm_start_pairs");
  warm->pairs.resize(num_pairs);
  for (int i = 0; i < num_pairs; ++i) {
    const std::string what = "warm_start_pairs[" + std::to_string(i) + "]";
    warm->pairs[i] = static_cast<int>(in->Integer(in->NextLine(what), what));
  }
  warm->z = in->Vector("warm_start_z", warm->valid);
  const int num_axes = in->Count("tangent_axes");
  if (num_axes != num_pairs) {
    in->Fail("tangent_axes count " + std::to_string(num_axes) + " differs from warm_start_pairs " +
             std::to_string(num_pairs));
  }
  warm->tangent_axes.resize(num_axes);
  for (int i = 0; i < num_axes; ++i) {
    const std::string what = "tangent_axes[" + std::to_string(i) + "]";
    const std::vector<std::string> tokens = SplitOnSpaces(in->NextLine(what + " 'x y z'"));
    if (tokens.size() != 3) in->Fail("expected " + what + " as 'x y z'");
    for (int k = 0; k < 3; ++k) warm->tangent_axes[i][k] = in->Number(tokens[k], what, warm->valid);
  }
  // Cases captured before the RATTLE damping (Data::velocity_reversals) have none: every count 0.
  warm->velocity_reversals.clear();
  if (!in->NextKeyIs("velocity_reversals")) return;
  const int num_slots = in->Count("velocity_reversals");
  warm->velocity_reversals.resize(num_slots);
  for (int i = 0; i < num_slots; ++i) {
    const std::string what = "velocity_reversals[" + std::to_string(i) + "]";
    const long count = in->Integer(in->NextLine(what), what);
    if (count < 0 || count > 1000000) in->Fail(what + " must be in [0, 1000000], got " + std::to_string(count));
    warm->velocity_reversals[i] = static_cast<int>(count);
  }
}

}  // namespace

StepCase ParseStepCase(const std::string& text, const std::string& source) {
  CaseReader in(text, source);
  StepCase step_case;
  ReadHeader(&in);
  step_case.name = in.Value("name", "<case name>");
  step_case.origin = in.Value("origin", "<how it was made>");
  step_case.scene_name = in.Value("scene_name", "<name>");
  ReadRecorded(&in, &step_case.recorded);
  const std::string selection = in.Value("pair_selection", "broad_phase|all_pairs");
  if (selection != "broad_phase" && selection != "all_pairs") {
    in.Fail("pair_selection must be broad_phase or all_pairs, got '" + selection + "'");
  }
  step_case.broad_phase = selection == "broad_phase";
  ReadOptions(&in, &step_case.options);
  State& state = step_case.inputs.state;
  state.t = in.Number(in.Value("t", "<time>"), "t", true);
  state.q = in.Vector("q", true);
  state.v = in.Vector("v", true);
  ReadWarmStart(&in, &step_case.inputs.warm_start);
  step_case.inputs.external_wrench_W = in.Vector("external_wrench", true);
  const long urdf_bytes = in.Integer(in.Value("urdf_bytes", "<count>"), "urdf_bytes");
  if (urdf_bytes < 0) in.Fail("urdf_bytes must not be negative");
  step_case.urdf = in.Bytes(static_cast<size_t>(urdf_bytes), "urdf");
  const std::string end = in.NextLine("'end'");
  if (end != "end") in.Fail("expected 'end' after the URDF, got '" + end.substr(0, 80) + "'");
  if (!in.AtEnd()) in.Fail("unexpected text after 'end'");
  return step_case;
}

StepCase ReadStepCase(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("cannot read step case '" + path + "'");
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw std::runtime_error("cannot read step case '" + path + "'");
  return ParseStepCase(text.str(), path);
}

}  // namespace implicit_sim
