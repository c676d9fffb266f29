// Step cases: capture, writing (the format is in bench/README.md), the case's model and its replay. Reading is in
// step_case_reader.cpp.
#include "implicit_sim/core/io/step_case.h"

#include <fstream>
#include <stdexcept>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

const char* BoolText(bool value) { return value ? "true" : "false"; }

void CheckOneLine(const char* key, const std::string& value) {
  if (value.find_first_of("\r\n") != std::string::npos) {
    throw std::invalid_argument(std::string("step case ") + key + " must be one line, got '" + value + "'");
  }
}

void AddLine(std::string* out, const char* key, const std::string& value) {
  *out += key;
  *out += ' ';
  *out += value;
  *out += '\n';
}

// "key count", then one value per line.
void AddVector(std::string* out, const char* key, const Eigen::VectorXd& values) {
  AddLine(out, key, std::to_string(values.size()));
  for (Eigen::Index i = 0; i < values.size(); ++i) *out += FormatNumber(values[i]) + '\n';
}

// "options count", then "field value" per row of the options table; a choice by its name.
void AddOptions(std::string* out, const StepperOptions& options) {
  AddLine(out, "options", std::to_string(OptionTable().size()));
  for (const OptionRow& row : OptionTable()) {
    const double value = row.get(options);
    AddLine(out, row.field,
            row.kind == OptionKind::kChoice ? std::string(row.choices[static_cast<int>(value)]) : FormatNumber(value));
  }
}

void AddWarmStart(std::string* out, const WarmStart& warm) {
  AddLine(out, "warm_start_valid", BoolText(warm.valid));
  AddLine(out, "warm_start_pairs", std::to_string(warm.pairs.size()));
  for (int pair : warm.pairs) *out += std::to_string(pair) + '\n';
  AddVector(out, "warm_start_z", warm.z);
  AddLine(out, "tangent_axes", std::to_string(warm.tangent_axes.size()));
  for (const Vec3& axis : warm.tangent_axes) {
    *out += FormatNumber(axis.x()) + ' ' + FormatNumber(axis.y()) + ' ' + FormatNumber(axis.z()) + '\n';
  }
  AddLine(out, "velocity_reversals", std::to_string(warm.velocity_reversals.size()));
  for (int count : warm.velocity_reversals) *out += std::to_string(count) + '\n';
}

}  // namespace

void CaptureStepInputs(const State& state, const Data& data, const Eigen::VectorXd* external_wrench_W,
                       StepInputs* out) {
  out->state = state;
  SaveWarmStart(data, &out->warm_start);
  if (external_wrench_W) {
    out->external_wrench_W = *external_wrench_W;
  } else {
    out->external_wrench_W.resize(0);
  }
}

RecordedOutcome RecordOutcome(const StepReport& report) {
  RecordedOutcome recorded;
  recorded.converged = report.converged;
  recorded.iterations = report.iterations;
  recorded.residual_evaluations = report.residual_evaluations;
  recorded.fault = StepFaultName(report.fault);
  return recorded;
}

std::string StepCaseToText(const StepCase& step_case) {
  CheckOneLine("name", step_case.name);
  CheckOneLine("origin", step_case.origin);
  CheckOneLine("scene_name", step_case.scene_name);
  const StepInputs& inputs = step_case.inputs;
  std::string out = "implicit_sim_step_case " + std::to_string(kStepCaseVersion) + '\n';
  AddLine(&out, "name", step_case.name);
  AddLine(&out, "origin", step_case.origin);
  AddLine(&out, "scene_name", step_case.scene_name);
  AddLine(&out, "recorded_converged", BoolText(step_case.recorded.converged));
  AddLine(&out, "recorded_iterations", std::to_string(step_case.recorded.iterations));
  AddLine(&out, "recorded_residual_evaluations", std::to_string(step_case.recorded.residual_evaluations));
  AddLine(&out, "recorded_fault", step_case.recorded.fault);
  AddLine(&out, "pair_selection", step_case.broad_phase ? "broad_phase" : "all_pairs");
  AddOptions(&out, step_case.options);
  AddLine(&out, "t", FormatNumber(inputs.state.t));
  AddVector(&out, "q", inputs.state.q);
  AddVector(&out, "v", inputs.state.v);
  AddWarmStart(&out, inputs.warm_start);
  AddVector(&out, "external_wrench", inputs.external_wrench_W);
  AddLine(&out, "urdf_bytes", std::to_string(step_case.urdf.size()));
  out += step_case.urdf;
  out += "\nend\n";
  return out;
}

void WriteStepCase(const StepCase& step_case, const std::string& path) {
  const std::string text = StepCaseToText(step_case);
  std::ofstream out(path, std::ios::binary);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) throw std::runtime_error("cannot write step case '" + path + "'");
}

Model LoadStepCaseModel(const StepCase& step_case) {
  Model model = LoadSceneFromString(step_case.urdf, step_case.scene_name);
  const StepInputs& inputs = step_case.inputs;
  auto check = [&](const char* what, Eigen::Index size, int expected, const char* size_name) {
    if (size == expected) return;
    throw std::invalid_argument("step case '" + step_case.name + "': " + what + " has " + std::to_string(size) +
                                " values, its scene needs " + std::to_string(expected) + " (" + size_name + ")");
  };
  check("q", inputs.state.q.size(), model.nq(), "nq");
  check("v", inputs.state.v.size(), model.nv(), "nv");
  if (inputs.external_wrench_W.size() != 0) check("external_wrench", inputs.external_wrench_W.size(), model.nv(), "nv");
  return model;
}

StepReport ReplayStepCase(const Model& model, const StepCase& step_case, State* end_state,
                          const StepInterrupt* interrupt) {
  Data data(model, step_case.broad_phase ? Data::PairSelection::kBroadPhase : Data::PairSelection::kAllPairs);
  data.interrupt = interrupt;
  try {
    RestoreWarmStart(model, step_case.inputs.warm_start, &data);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("step case '" + step_case.name + "': " + e.what());
  }
  *end_state = step_case.inputs.state;
  const Eigen::VectorXd& wrench = step_case.inputs.external_wrench_W;
  return Step(model, step_case.options, end_state, &data, wrench.size() != 0 ? &wrench : nullptr);
}

std::string HighestRung(const StepReport& report, bool had_warm_start) {
  if (report.substeps > 0) return "substeps";
  if (report.ipopt_solves > 0) return "ipopt";
  if (report.smoothed_solves > 0) return "smoothing";
  if (report.proximal_solves > 0) return "proximal";
  if (report.cold_restarts > 0 || !had_warm_start) return "cold";
  if (report.projected_solves > 0) return "projected";
  if (report.path_solves > 0) return "path";
  return "warm";
}

}  // namespace implicit_sim
