// implicit_sim_replay: replays step cases (io/step_case.h, written by implicit_sim_bench --dump-worst) through the
// stepper alone, one JSON line per case and a summary line (see bench/README.md).
//   implicit_sim_replay [--repeat R] [--set FIELD=VALUE]... [--trace FILE] FILE_OR_DIR...
// A directory stands for its *.case files, in name order. --repeat R runs each case R times from the same inputs and
// reports the median wall time. --set overrides an option of every case (a field of the options table,
// step/options.h, e.g. newton.line_search_memory=10): the ablations of bench/README.md. --trace FILE writes one JSON
// line per Newton iteration of each case's first replay (solved on one thread). Bad arguments: exit 2 and a one-line message; a case that cannot be read or replayed:
// exit 1 and a one-line message naming it.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/io/step_case.h"
#include "implicit_sim/core/step/options.h"

namespace {
using namespace implicit_sim;

constexpr const char* kUsage =
    "usage: implicit_sim_replay [--repeat R] [--set FIELD=VALUE]... [--trace FILE] FILE_OR_DIR...";

struct Arguments {
  int repeat = 1;
  std::vector<std::pair<const OptionRow*, double>> overrides;  // --set
  std::string trace_path;                                      // --trace
  std::vector<std::string> files;  // the cases, in the order given (a directory's in name order)
};

// The *.case files of a directory, sorted by name.
std::vector<std::string> CasesIn(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".case") files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::invalid_argument("directory '" + dir + "' holds no .case file");
  return files;
}

Arguments ParseArguments(int argc, char** argv) {
  Arguments arguments;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeat") {
      const std::string text = i + 1 < argc ? argv[++i] : "";
      int value = 0;
      try {
        value = std::stoi(text);
      } catch (const std::exception&) {
        value = 0;
      }
      if (std::to_string(value) != text || value < 1 || value > 1000) {
        throw std::invalid_argument("--repeat must be an integer in [1, 1000], got '" + text + "'");
      }
      arguments.repeat = value;
    } else if (arg == "--set") {
      const std::string text = i + 1 < argc ? argv[++i] : "";
      const size_t eq = text.find('=');
      const OptionRow* row = eq == std::string::npos ? nullptr : FindOptionByField(text.substr(0, eq));
      if (!row) throw std::invalid_argument("--set takes FIELD=VALUE with a field of the options table, got '" + text + "'");
      double value = 0.0;
      std::string error;
      if (!ParseOptionValue(*row, text.substr(eq + 1), "--set " + text.substr(0, eq), &value, &error)) {
        throw std::invalid_argument(error);
      }
      arguments.overrides.emplace_back(row, value);
    } else if (arg == "--trace") {
      arguments.trace_path = i + 1 < argc ? argv[++i] : "";
      if (arguments.trace_path.empty()) throw std::invalid_argument("--trace takes a file name");
    } else if (arg.rfind("--", 0) == 0) {
      throw std::invalid_argument("unknown flag '" + arg + "'");
    } else if (std::filesystem::is_directory(arg)) {
      for (const std::string& file : CasesIn(arg)) arguments.files.push_back(file);
    } else if (std::filesystem::is_regular_file(arg)) {
      arguments.files.push_back(arg);
    } else {
      throw std::invalid_argument("'" + arg + "' is neither a file nor a directory");
    }
  }
  if (arguments.files.empty()) throw std::invalid_argument("no step case given");
  return arguments;
}

std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string Json(double value) { return std::isfinite(value) ? FormatNumber(value) : "null"; }
std::string Json(bool value) { return value ? "true" : "false"; }

struct Totals {
  int cases = 0, failures = 0, not_same = 0;
  long iterations = 0, residual_evaluations = 0, factorizations = 0, solves = 0, path_iterations = 0;
  double wall_us = 0.0;
};

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// The trace's rows, one JSON line each, for the case `name`.
void WriteTrace(const std::string& name, const NewtonTrace& trace, std::ostream* out) {
  for (const NewtonTraceRow& row : trace.rows) {
    *out << "{\"case\": " << Quoted(name) << ", \"solve\": " << row.solve << ", \"iteration\": " << row.iteration
         << ", \"smoothing\": " << Json(row.smoothing) << ", \"residual\": " << Json(row.residual)
         << ", \"step\": " << Json(row.step) << ", \"least_squares\": " << Json(row.least_squares)
         << ", \"largest_row\": " << Json(row.largest_row) << ", \"largest_row_index\": " << row.largest_row_index
         << ", \"largest_row_name\": " << Quoted(row.largest_row_name)
         << ", \"rows_above_floor\": " << row.rows_above_floor << ", \"largest_move\": " << Json(row.largest_move)
         << ", \"largest_move_index\": " << row.largest_move_index
         << ", \"largest_move_name\": " << Quoted(row.largest_move_name) << "}\n";
  }
}

// Replays one case `repeat` times and prints its line; with a trace file, traces the first replay into it.
void ReplayOne(const std::string& path, const Arguments& arguments, std::ostream* trace_out, Totals* totals) {
  const int repeat = arguments.repeat;
  StepCase step_case = ReadStepCase(path);  // its errors name the path
  for (const auto& [row, value] : arguments.overrides) row->set(&step_case.options, value);
  NewtonTrace trace;
  if (trace_out) {
    step_case.options.newton.trace = &trace;
    step_case.options.threads = 1;  // one trace serves one thread
  }
  StepReport report;
  std::vector<double> wall_us;
  bool repeatable = true;  // every repeat did what the first did
  int bodies = 0;
  try {
    const Model model = LoadStepCaseModel(step_case);
    bodies = model.num_moving();
    State end_state;
    for (int r = 0; r < repeat; ++r) {
      const StepReport again = ReplayStepCase(model, step_case, &end_state);
      step_case.options.newton.trace = nullptr;
      if (r == 0) report = again;
      repeatable = repeatable && again.iterations == report.iterations && again.converged == report.converged;
      wall_us.push_back(1e6 * again.wall_time_s);
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  if (trace_out) WriteTrace(step_case.name, trace, trace_out);
  const RecordedOutcome& recorded = step_case.recorded;
  const bool same = report.converged == recorded.converged && report.iterations == recorded.iterations &&
                    report.residual_evaluations == recorded.residual_evaluations;
  const double median_us = Median(wall_us);
  std::cout << "{\"case\": " << Quoted(step_case.name) << ", \"bodies\": " << bodies
            << ", \"pairs_in_ncp\": " << report.pairs_in_ncp << ", \"converged\": " << Json(report.converged)
            << ", \"fault\": " << Quoted(StepFaultName(report.fault)) << ", \"iterations\": " << report.iterations
            << ", \"residual_evaluations\": " << report.residual_evaluations
            << ", \"factorizations\": " << report.factorizations << ", \"solves\": " << report.solves
            << ", \"path_solves\": " << report.path_solves << ", \"path_iterations\": " << report.path_iterations
            << ", \"path_switch_smoothing\": " << Json(report.path_switch_smoothing)
            << ", \"path_switch_residual\": " << Json(report.path_switch_residual) << ", \"rung\": "
            << Quoted(HighestRung(report, step_case.inputs.warm_start.valid))
            << ", \"projected_solves\": " << report.projected_solves
            << ", \"cold_restarts\": " << report.cold_restarts << ", \"proximal_solves\": " << report.proximal_solves
            << ", \"smoothed_solves\": " << report.smoothed_solves
            << ", \"ipopt_solves\": " << report.ipopt_solves << ", \"substeps\": " << report.substeps
            << ", \"crossings\": " << report.crossings << ", \"residual\": " << Json(report.residual)
            << ", \"wall_us\": " << Json(median_us) << ", \"repeats\": " << repeat
            << ", \"repeatable\": " << Json(repeatable) << ", \"recorded_iterations\": " << recorded.iterations
            << ", \"recorded_converged\": " << Json(recorded.converged) << ", \"same_as_recorded\": " << Json(same)
            << "}" << std::endl;
  totals->cases++;
  totals->failures += !report.converged;
  totals->not_same += !same;
  totals->iterations += report.iterations;
  totals->residual_evaluations += report.residual_evaluations;
  totals->factorizations += report.factorizations;
  totals->solves += report.solves;
  totals->path_iterations += report.path_iterations;
  totals->wall_us += median_us;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments arguments;
  try {
    arguments = ParseArguments(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_replay: " << e.what() << "; " << kUsage << "\n";
    return 2;
  }
  std::ofstream trace_file;
  if (!arguments.trace_path.empty()) {
    trace_file.open(arguments.trace_path);
    if (!trace_file) {
      std::cerr << "implicit_sim_replay: cannot write the trace file '" << arguments.trace_path << "'\n";
      return 2;
    }
  }
  Totals totals;
  for (const std::string& path : arguments.files) {
    try {
      ReplayOne(path, arguments, trace_file.is_open() ? &trace_file : nullptr, &totals);
    } catch (const std::exception& e) {
      std::cerr << "implicit_sim_replay: " << e.what() << "\n";
      return 1;
    }
  }
  std::cout << "{\"summary\": true, \"cases\": " << totals.cases << ", \"total_iterations\": " << totals.iterations
            << ", \"total_residual_evaluations\": " << totals.residual_evaluations
            << ", \"total_factorizations\": " << totals.factorizations << ", \"total_solves\": " << totals.solves
            << ", \"total_path_iterations\": " << totals.path_iterations
            << ", \"failures\": " << totals.failures << ", \"total_wall_us\": " << Json(totals.wall_us)
            << ", \"not_same_as_recorded\": " << totals.not_same << "}" << std::endl;
  return 0;
}
