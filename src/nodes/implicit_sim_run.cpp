// Headless runner: implicit_sim_run --scene FILE --duration T --dt H --out DIR
// Writes DIR/trajectory.csv and DIR/summary.json (see doc/runner.md). No roscore needed. With --stop-at-rest E:S the run
// ends early once the kinetic energy has stayed below E (J) for S (s) of simulated time. With --check-penetration
// every step end is checked for overlaps from the geometry alone (MaxPenetrationBound), not from the step's gaps.
// --max-wall S, SIGINT and SIGTERM stop the run within a step (its solvers stop between factorizations and the step is
// undone); what was written up to the last finished step stays, summary.json included.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/io/run_output.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/step_health.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "implicit_sim/core/model/urdf_loader.h"

namespace {

constexpr const char* kUsage =
    "usage: implicit_sim_run --scene FILE --duration T --dt H --out DIR [--scheme paper|rattle] [--tolerance TOL] "
    "[--max-iterations N] "
    "[--solver newton|ipopt] [--threads N] [--stop-at-rest E:S] [--check-penetration] [--max-wall S]";

struct Args {
  std::string scene, out;
  double duration = 0.0;
  implicit_sim::StepperOptions options;  // --dt, --tolerance, --max-iterations, --solver: rows of the options table
  bool stop_at_rest = false;
  double rest_energy = 0.0;  // J: "at rest" means kinetic energy < rest_energy
  double rest_hold = 0.0;    // s: ... at every step over this much simulated time
  bool check_penetration = false;  // summary.json's max_penetration_oracle: a geometric check of every step end
  double max_wall = 0.0;           // s of wall time for the stepping; 0: no limit
};

// Requested by SIGINT and SIGTERM, due at the --max-wall deadline; every step watches it (Data::interrupt).
implicit_sim::StepInterrupt g_interrupt;

// Pairs closer than this (m) are measured by the separating-plane bound rather than called separated.
constexpr double kPenetrationCheckTolerance = 1e-9;

// A finite number > 0, read with '.' as the decimal point whatever the locale (std::from_chars).
double ParsePositive(const std::string& flag, const std::string& text) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, value);
  if (text.empty() || result.ec != std::errc() || result.ptr != end || !std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument(flag + " must be a finite number > 0, got '" + text + "'");
  }
  return value;
}

// Refuses a value above `max`; the message prints numbers with '.' (FormatNumber), never through the C locale.
void CheckAtMost(const std::string& flag, double value, double max) {
  if (value > max) {
    throw std::invalid_argument(flag + " must be at most " + implicit_sim::FormatNumber(max) + ", got " +
                                implicit_sim::FormatNumber(value));
  }
}

// Error messages are one line: control characters (a newline in a link name, bytes of a binary file) become '?'.
std::string OneLine(const std::string& message) {
  std::string line = message;
  for (char& c : line) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  return line;
}

// The flags of the options table (--dt, --tolerance, ...), each checked against its row's range.
void ParseStepperFlags(const std::map<std::string, std::string>& values, implicit_sim::StepperOptions* options) {
  for (const implicit_sim::OptionRow& row : implicit_sim::OptionTable()) {
    const auto it = values.find(row.runner_flag);
    if (*row.runner_flag == '\0' || it == values.end()) continue;
    double value = 0.0;
    std::string error;
    if (!implicit_sim::ParseOptionValue(row, it->second, row.runner_flag, &value, &error)) {
      throw std::invalid_argument(error);
    }
    row.set(options, value);
  }
}

Args ParseArgs(int argc, char** argv) {
  std::map<std::string, std::string> values;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      std::cout << kUsage << "\n";
      std::exit(0);
    }
    if (flag == "--check-penetration") {  // a switch: no value
      values[flag] = "";
      continue;
    }
    if (flag != "--scene" && flag != "--duration" && flag != "--out" && flag != "--stop-at-rest" && flag != "--max-wall" &&
        !implicit_sim::FindOptionByRunnerFlag(flag)) {
      throw std::invalid_argument("unknown flag '" + flag + "' (" + kUsage + ")");
    }
    if (i + 1 >= argc) throw std::invalid_argument(flag + " needs a value");
    values[flag] = argv[++i];
  }
  Args args;
  for (const char* required : {"--scene", "--duration", "--out"}) {
    if (!values.count(required)) throw std::invalid_argument(std::string("missing ") + required + " (" + kUsage + ")");
  }
  args.scene = values["--scene"];
  args.out = values["--out"];
  args.duration = ParsePositive("--duration", values["--duration"]);
  args.check_penetration = values.count("--check-penetration") > 0;
  if (values.count("--max-wall")) {
    args.max_wall = ParsePositive("--max-wall (s)", values["--max-wall"]);
    CheckAtMost("--max-wall (s)", args.max_wall, 1e7);
  }
  ParseStepperFlags(values, &args.options);
  if (values.count("--stop-at-rest")) {
    const std::string& text = values["--stop-at-rest"];
    const size_t colon = text.find(':');
    if (colon == std::string::npos) {
      throw std::invalid_argument("--stop-at-rest must be E:S (kinetic energy threshold in J > 0, hold time in s > 0), "
                                  "got '" + text + "'");
    }
    args.rest_energy = ParsePositive("--stop-at-rest energy E (J, in E:S)", text.substr(0, colon));
    args.rest_hold = ParsePositive("--stop-at-rest hold time S (s, in E:S)", text.substr(colon + 1));
    CheckAtMost("--stop-at-rest energy E (J, in E:S)", args.rest_energy, 1e6);
    CheckAtMost("--stop-at-rest hold time S (s, in E:S)", args.rest_hold, 1e6);
    args.stop_at_rest = true;
  }
  if (args.duration / args.options.h > 1e8) throw std::invalid_argument("--duration / --dt exceeds 1e8 steps");
  return args;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace implicit_sim;
  Args args;
  StepperOptions options;
  Model model;
  try {
    args = ParseArgs(argc, argv);
    options = args.options;
    std::string error;
    if (!options.IsValid(&error)) throw std::invalid_argument(error);
    model = LoadSceneFromFile(args.scene);
    std::error_code ec;
    std::filesystem::create_directories(args.out, ec);
    if (ec || !std::filesystem::is_directory(args.out)) {
      throw std::invalid_argument("--out '" + args.out + "' is not a directory that can be created (" + ec.message() +
                                  ")");
    }
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_run: " << OneLine(e.what()) << "\n";
    return 2;
  }
  try {
    Data data(model);
    TrajectoryWriter writer(args.out + "/trajectory.csv", model, !data.broad_phase, args.out + "/contacts.csv");
    State state = State::Initial(model);
    RunSummary summary;
    summary.scene = model.scene_name;
    summary.h = options.h;
    summary.scheme = OptionChoiceName(*FindOptionByField("scheme"), options);
    summary.kinetic_energy_initial = KineticEnergy(model, state);
    for (int pair = 0; !data.broad_phase && pair < static_cast<int>(model.pairs.size()); ++pair) {
      summary.pairs.emplace_back(model.PairName(pair), model.pairs[pair].friction);
    }
    writer.WriteInitial(state);
    const long steps = std::lround(args.duration / options.h);
    // At-rest detection: rest_since is the time of the first state of the current stretch of states with kinetic
    // energy < rest_energy (t = 0 included); the run stops once the stretch lasts rest_hold (to half a step).
    double rest_since = summary.kinetic_energy_initial < args.rest_energy ? state.t : -1.0;
    summary.at_rest_rule = args.stop_at_rest;
    summary.penetration_checked = args.check_penetration;
    std::unique_ptr<Data> check_data;  // the check's own broad-phase workspace
    if (args.check_penetration) check_data = std::make_unique<Data>(model);
    data.interrupt = &g_interrupt;
    if (args.max_wall > 0.0) g_interrupt.SetDeadlineIn(args.max_wall);
    RequestOnStopSignals(&g_interrupt);
    for (long i = 0; i < steps; ++i) {
      const StepReport report = Step(model, options, &state, &data);
      if (report.fault == StepFault::kInterrupted) {
        summary.stop_reason = g_interrupt.requested() ? "interrupted" : "max_wall";
        std::cerr << "implicit_sim_run: " << (g_interrupt.requested() ? "interrupted by a signal" : "--max-wall reached")
                  << " in step " << i + 1 << "; stopping at t = " << FormatNumber(state.t) << " s\n";
        break;
      }
      if (!report.advanced) {
        std::cerr << "implicit_sim_run: step " << i + 1 << " refused (" << StepFaultName(report.fault)
                  << (report.fault_detail.empty() ? "" : ": " + report.fault_detail) << "); stopping at t = "
                  << FormatNumber(state.t) << " s\n";
        summary.stop_reason = "refused";
        break;
      }
      summary.Add(report, data);
      if (check_data) {
        summary.max_penetration_oracle = std::max(
            summary.max_penetration_oracle, MaxPenetrationBound(model, state, kPenetrationCheckTolerance, check_data.get()));
      }
      writer.WriteStep(state, data, report);
      if (args.stop_at_rest) {
        if (KineticEnergy(model, state) < args.rest_energy) {
          if (rest_since < 0.0) rest_since = state.t;
          if (state.t - rest_since >= args.rest_hold - 0.5 * options.h) {
            summary.stop_reason = "at_rest";
            summary.time_to_rest = rest_since;
            break;
          }
        } else {
          rest_since = -1.0;
        }
      }
    }
    summary.kinetic_energy_final = KineticEnergy(model, state);
    std::ofstream json(args.out + "/summary.json");
    summary.t_end = state.t;
    json << summary.ToJson();
    if (!json) throw std::runtime_error("cannot write '" + args.out + "/summary.json'");
    std::cout << "implicit_sim_run: " << summary.steps << " steps of " << FormatNumber(options.h) << " s, "
              << FormatNumber(1e6 * summary.wall_s / std::max(1, summary.steps)) << " us/step, max penetration "
              << FormatNumber(summary.max_penetration) << " m, non-converged steps " << summary.nonconverged_steps
              << "; wrote " << args.out << "/trajectory.csv and summary.json\n";
    if (summary.stop_reason == "interrupted" || summary.stop_reason == "max_wall") return 3;
    return summary.nonconverged_steps == 0 && summary.stop_reason != "refused" ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_run: " << OneLine(e.what()) << "\n";
    return 1;
  }
}
