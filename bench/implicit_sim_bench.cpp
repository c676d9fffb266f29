// implicit_sim_bench: speed and accuracy of the stepper on the paper scenes P1-P3, the S1 pile and the J1 jam (the
// soak bin's gripper pressed into its spheres), one JSON line per run on stdout (see bench/README.md). Speed targets live here, never in timed tests.
//   implicit_sim_bench                                   every case
//   implicit_sim_bench --scenario S1 --shape ellipsoid --n 100 --duration 2 [--dt 0.005] [--seed 42]
//   implicit_sim_bench --scenario P3 [--duration 5] [--dt 0.01] [--scenes-dir DIR]
//   implicit_sim_bench --scenario P1 --variant p1_ngon100         a P case by its variant (AllCases below)
// --max-wall S (default 300 s of solver time per run) stops a run early, within a step (the step is then undone); its
// line then says "completed": false and "stop_reason": "max_wall". SIGINT and SIGTERM stop the current run the same
// way ("stop_reason": "interrupted"), print its line and exit 130 without running the remaining cases.
// --dump-worst K --dump-dir DIR writes the K hardest steps of each run as step cases (io/step_case.h) for
// implicit_sim_replay: DIR/<scenario>_<variant>_step<NNNN>.case, NNNN the number of steps before it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/io/run_output.h"
#include "implicit_sim/core/io/step_case.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "scenario_metrics.h"

namespace {
using namespace implicit_sim;

struct Case {
  std::string scenario;  // P1, P2, P3, S1, J1
  std::string variant;   // P: the scene file; S1: <shape>_n<N>, then _er<M> for a torsional lever other than 0.01 m
  double h = 0.01;       // s
  double duration = 1.0; // s
  std::string scene_file;
  PileShape shape = PileShape::kSphere;
  int n = 0;
  unsigned seed = 42;
  double e_r = kPileTorsionLever;  // S1: the torsional lever (m; 0: none)
};

// The paper scenes' sample at a step end (scenario_metrics.h): the first moving body; P3's contacts by pair name.
StepSample SampleOf(const Model& model, const State& state, const Data& data) {
  StepSample s;
  s.t = state.t;
  s.kinetic_energy = KineticEnergy(model, state);
  for (int i = 0; i < 3; ++i) s.v_W[i] = state.v_WB(0)[i], s.w_W[i] = state.w_WB(0)[i];
  for (const ContactResult& contact : data.contacts) {
    const std::string name = model.PairName(contact.pair);
    const int c = name == "ball-sphere_a" ? 0 : name == "ball-sphere_b" ? 1 : -1;
    if (c < 0) continue;
    s.closed[c] = contact.normal_force > 1e-9;
    s.slip_speed[c] = contact.slip_speed;
  }
  return s;
}

double ParseNumber(const std::string& flag, const std::string& text, double low, double high) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !(value >= low && value <= high)) {
    throw std::invalid_argument(flag + " must be a number in [" + FormatNumber(low) + ", " + FormatNumber(high) +
                                "], got '" + text + "'");
  }
  return value;
}

std::string Field(const std::string& key, const std::string& value) { return "\"" + key + "\": " + value; }
std::string Quoted(const std::string& s) { return "\"" + s + "\""; }

// --dump-worst K --dump-dir DIR (worst = 0: no dumping).
struct DumpRequest {
  int worst = 0;
  std::string dir;
  std::string command;  // the bench's command line, for the cases' origin
};

// The K hardest steps of a run, hardest first: a step that did not converge ranks before every step that did, then
// more Newton iterations rank first; among equals the earlier step stays (a later one must be strictly harder).
class WorstSteps {
 public:
  struct Entry {
    long index = 0;  // steps before it
    RecordedOutcome outcome;
    StepInputs inputs;
  };
  explicit WorstSteps(int capacity) : capacity_(capacity) {}
  // Keeps the step if it is among the K hardest so far.
  void Offer(long index, const StepReport& report, const StepInputs& inputs) {
    if (capacity_ <= 0) return;
    const RecordedOutcome outcome = RecordOutcome(report);
    const auto position = std::find_if(entries_.begin(), entries_.end(),
                                       [&](const Entry& e) { return Harder(outcome, e.outcome); });
    if (position == entries_.end() && static_cast<int>(entries_.size()) >= capacity_) return;
    entries_.insert(position, Entry{index, outcome, inputs});
    if (static_cast<int>(entries_.size()) > capacity_) entries_.pop_back();
  }
  const std::vector<Entry>& entries() const { return entries_; }

 private:
  static bool Harder(const RecordedOutcome& a, const RecordedOutcome& b) {
    if (a.converged != b.converged) return !a.converged;
    return a.iterations > b.iterations;
  }
  int capacity_;
  std::vector<Entry> entries_;
};

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error("cannot read scene file '" + path + "'");
  return text.str();
}

// Writes the kept steps as DIR/<scenario>_<variant>_step<NNNN>.case and names each file on stderr.
void DumpWorstSteps(const Case& c, const std::string& urdf, const std::string& scene_name, bool broad_phase,
                    const StepperOptions& options, const DumpRequest& dump, const WorstSteps& worst) {
  for (const WorstSteps::Entry& entry : worst.entries()) {
    char number[32];
    std::snprintf(number, sizeof(number), "%04ld", entry.index);
    StepCase step_case;
    step_case.name = c.scenario + "_" + c.variant + "_step" + number;
    step_case.origin = dump.command + ": step " + std::to_string(entry.index + 1) + " of the run, from t = " +
                       FormatNumber(entry.inputs.state.t) + " s";
    step_case.scene_name = scene_name;
    step_case.urdf = urdf;
    step_case.broad_phase = broad_phase;
    step_case.options = options;
    step_case.inputs = entry.inputs;
    step_case.recorded = entry.outcome;
    const std::string path = dump.dir + "/" + step_case.name + ".case";
    WriteStepCase(step_case, path);
    std::cerr << "implicit_sim_bench: wrote " << path << " (" << entry.outcome.iterations << " iterations, "
              << (entry.outcome.converged ? "converged" : "not converged") << ")\n";
  }
}

// Requested by SIGINT and SIGTERM; due at the --max-wall deadline of the current step.
implicit_sim::StepInterrupt g_interrupt;

// Runs one case and prints its JSON line.
void Run(const Case& c, const std::string& scenes_dir, double max_wall_s, const DumpRequest& dump,
         const std::vector<std::pair<const OptionRow*, double>>& overrides) {
  const std::string scene_path = scenes_dir + "/" + c.scene_file;
  const std::string scene_name =  // as LoadSceneFromFile names it: the file name without ".urdf"
      c.scenario == "S1" ? "s1_" + c.variant : c.scene_file.substr(0, c.scene_file.size() - 5);
  const std::string urdf = c.scenario == "S1" ? MakePileUrdf(c.n, c.shape, c.seed, true, PileOrientation::kAligned,
                                                             0.0, c.e_r)
                           : dump.worst > 0   ? ReadText(scene_path)
                                              : std::string();
  const Model model = c.scenario == "S1" ? LoadSceneFromString(urdf, scene_name) : LoadSceneFromFile(scene_path);
  StepperOptions options;
  options.h = c.h;
  for (const auto& [row, value] : overrides) row->set(&options, value);
  Data data(model);
  State state = State::Initial(model);
  ScenarioMetrics metrics(c.scenario, KineticEnergy(model, state));  // accuracy of the paper scenes
  RunSummary summary;
  summary.h = c.h;
  summary.kinetic_energy_initial = KineticEnergy(model, state);
  const long steps = std::lround(c.duration / c.h);
  double iterations = 0.0, residual_evaluations = 0.0, factorizations = 0.0, solves = 0.0;
  int max_factorizations = 0;
  double slowest_step_s = 0.0;  // the longest wall time of one step
  WorstSteps worst(dump.worst);
  StepInputs inputs;  // of the current step, when dumping
  std::string stop_reason = "duration";
  data.interrupt = &g_interrupt;
  for (long i = 0; i < steps; ++i) {
    if (dump.worst > 0) CaptureStepInputs(state, data, nullptr, &inputs);
    // The solver time left (max_wall_s less the steps so far) is the deadline of this step.
    g_interrupt.SetDeadlineIn(std::max(0.0, max_wall_s - summary.wall_s));
    const StepReport report = Step(model, options, &state, &data);
    if (report.fault == StepFault::kInterrupted) {
      stop_reason = g_interrupt.requested() ? "interrupted" : "max_wall";
      break;
    }
    worst.Offer(i, report, inputs);
    if (!report.advanced) {
      stop_reason = "refused";
      break;
    }
    summary.Add(report, data);
    if (metrics.NeedsSamples()) metrics.Observe(SampleOf(model, state, data));
    iterations += report.iterations;
    residual_evaluations += report.residual_evaluations;
    factorizations += report.factorizations;
    solves += report.solves;
    max_factorizations = std::max(max_factorizations, report.factorizations);
    slowest_step_s = std::max(slowest_step_s, report.wall_time_s);
    if (summary.wall_s > max_wall_s) {
      stop_reason = i + 1 < steps ? "max_wall" : stop_reason;
      break;
    }
  }
  g_interrupt.ClearDeadline();
  DumpWorstSteps(c, urdf, scene_name, data.broad_phase, options, dump, worst);
  summary.kinetic_energy_final = KineticEnergy(model, state);
  const double us = summary.steps > 0 ? 1e6 * summary.wall_s / summary.steps : 0.0;
  const std::vector<std::string> fields = {
      Field("scenario", Quoted(c.scenario)),
      Field("variant", Quoted(c.variant)),
      Field("bodies", std::to_string(model.num_moving())),
      Field("h", FormatNumber(c.h)),
      Field("scheme", Quoted(OptionChoiceName(*FindOptionByField("scheme"), options))),
      Field("steps", std::to_string(summary.steps)),
      Field("completed", summary.steps == steps ? "true" : "false"),
      Field("stop_reason", Quoted(stop_reason)),
      Field("simulated_s", FormatNumber(summary.steps * c.h)),
      Field("wall_s", FormatNumber(summary.wall_s)),
      Field("us_per_step", FormatNumber(us)),
      Field("slowest_step_s", FormatNumber(slowest_step_s)),
      Field("real_time_factor", FormatNumber(summary.wall_s > 0 ? summary.steps * c.h / summary.wall_s : 0.0)),
      Field("max_penetration", FormatNumber(summary.max_penetration)),
      Field("nonconverged_steps", std::to_string(summary.nonconverged_steps)),
      Field("cold_restarts", std::to_string(summary.totals.cold_restarts)),
      Field("smoothed_solves", std::to_string(summary.totals.smoothed_solves)),
      Field("proximal_solves", std::to_string(summary.totals.proximal_solves)),
      Field("ipopt_solves", std::to_string(summary.totals.ipopt_solves)),
      Field("substeps", std::to_string(summary.totals.substeps)),
      Field("crossings", std::to_string(summary.totals.crossings)),
      Field("broad_phase_additions", std::to_string(summary.totals.broad_phase_additions)),
      Field("lm_fallbacks", std::to_string(data.lm_fallbacks())),
      Field("max_pairs_in_ncp", std::to_string(summary.max_pairs_in_ncp)),
      Field("mean_iterations", FormatNumber(summary.steps > 0 ? iterations / summary.steps : 0.0)),
      Field("mean_residual_evaluations", FormatNumber(summary.steps > 0 ? residual_evaluations / summary.steps : 0.0)),
      Field("mean_factorizations", FormatNumber(summary.steps > 0 ? factorizations / summary.steps : 0.0)),
      Field("max_factorizations", std::to_string(max_factorizations)),
      Field("mean_solves", FormatNumber(summary.steps > 0 ? solves / summary.steps : 0.0)),
      Field("path_solves", std::to_string(summary.totals.path_solves)),
      Field("kinetic_energy_initial", FormatNumber(summary.kinetic_energy_initial)),
      Field("kinetic_energy_final", FormatNumber(summary.kinetic_energy_final)),
  };
  std::vector<std::string> all_fields = fields;  // then the engine and the scenario's accuracy (scenario_metrics.h)
  all_fields.push_back(Field("engine", Quoted("implicit_sim")));
  for (const std::string& field : metrics.JsonFields()) all_fields.push_back(field);
  std::string line = "{";
  for (size_t i = 0; i < all_fields.size(); ++i) line += (i ? ", " : "") + all_fields[i];
  std::cout << line << "}" << std::endl;
}

std::vector<Case> AllCases() {
  std::vector<Case> cases = {
      {"P1", "p1_disc_rolling", 0.01, 5.0, "p1_disc_rolling.urdf"},
      {"P1", "p1_ngon100", 0.01, 5.0, "p1_ngon100.urdf"},
      {"P2", "p2_sphere_spinning", 0.07, 1.4, "p2_sphere_spinning.urdf"},
      {"P2", "p2_sphere_spinning", 0.01, 1.4, "p2_sphere_spinning.urdf"},
      {"P3", "p3_sphere_on_two_spheres", 0.01, 5.0, "p3_sphere_on_two_spheres.urdf"},
      {"J1", "soak_jam", 0.01, 2.0, "soak_jam.urdf"},  // the soak bin's gripper pressed into its spheres
  };
  for (PileShape shape : {PileShape::kSphere, PileShape::kEllipsoid}) {
    for (int n : {10, 100, 1000}) {
      Case c;
      c.scenario = "S1";
      c.shape = shape;
      c.n = n;
      c.h = 0.005;
      c.duration = 2.0;
      c.variant = std::string(shape == PileShape::kSphere ? "sphere" : "ellipsoid") + "_n" + std::to_string(n);
      cases.push_back(c);
    }
  }
  return cases;
}

// --dump-worst K (an integer in [1, 10000]) and --dump-dir DIR (an existing directory) go together.
void ParseDumpRequest(const std::map<std::string, std::string>& values, int argc, char** argv, DumpRequest* dump) {
  const bool worst = values.count("--dump-worst") > 0, dir = values.count("--dump-dir") > 0;
  if (worst != dir) throw std::invalid_argument("--dump-worst and --dump-dir go together");
  if (!worst) return;
  const std::string& text = values.at("--dump-worst");
  dump->worst = static_cast<int>(ParseNumber("--dump-worst", text, 1, 10000));
  if (std::to_string(dump->worst) != text) {
    throw std::invalid_argument("--dump-worst must be an integer in [1, 10000], got '" + text + "'");
  }
  dump->dir = values.at("--dump-dir");
  std::error_code error;
  if (!std::filesystem::is_directory(dump->dir, error)) {
    throw std::invalid_argument("--dump-dir must be an existing directory, got '" + dump->dir + "'");
  }
  dump->command = "implicit_sim_bench";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--dump-worst" || arg == "--dump-dir" || arg == "--scenes-dir") {
      ++i;  // where the files went is no part of how the steps were made
      continue;
    }
    dump->command += " " + arg;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage =
      "usage: implicit_sim_bench [--scenario P1|P2|P3|S1|J1] [--shape sphere|ellipsoid] [--n N] [--seed S] "
      "[--e-r M] [--duration T] [--dt H] [--max-wall S] [--scenes-dir DIR] [--dump-worst K --dump-dir DIR] "
      "[--set FIELD=VALUE]...";
  std::map<std::string, std::string> values;
  std::vector<std::pair<const OptionRow*, double>> overrides;  // --set, in the order given
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--set" && i + 1 < argc) {
      const std::string text = argv[++i];
      const size_t eq = text.find('=');
      const OptionRow* row = eq == std::string::npos ? nullptr : FindOptionByField(text.substr(0, eq));
      double value = 0.0;
      std::string error = "--set takes FIELD=VALUE with a field of the options table other than h (use --dt), got '" +
                          text + "'";
      if (!row || text.substr(0, eq) == "h" ||
          !ParseOptionValue(*row, text.substr(eq + 1), "--set " + text.substr(0, eq), &value, &error)) {
        std::cerr << "implicit_sim_bench: " << error << "\n" << usage << "\n";
        return 2;
      }
      overrides.emplace_back(row, value);
      continue;
    }
    if (std::string(argv[i]) == "--variant" && i + 1 < argc) {  // a P case by its variant (AllCases), e.g. p1_ngon100
      values["--variant"] = argv[++i];
      continue;
    }
    const std::string flag = argv[i];
    const bool known = flag == "--scenario" || flag == "--shape" || flag == "--n" || flag == "--seed" ||
                       flag == "--duration" || flag == "--dt" || flag == "--scenes-dir" || flag == "--max-wall" ||
                       flag == "--dump-worst" || flag == "--dump-dir" || flag == "--e-r";
    if (!known || i + 1 >= argc) {
      std::cerr << "implicit_sim_bench: bad argument '" << flag << "'\n" << usage << "\n";
      return 2;
    }
    values[flag] = argv[++i];
  }
  const std::string scenes_dir = values.count("--scenes-dir") ? values["--scenes-dir"] : IMPLICIT_SIM_SCENES_DIR;
  std::vector<Case> cases;
  double max_wall_s = 300.0;
  DumpRequest dump;
  try {
    if (values.count("--max-wall")) max_wall_s = ParseNumber("--max-wall", values["--max-wall"], 1e-3, 1e7);
    ParseDumpRequest(values, argc, argv, &dump);
    if (!values.count("--scenario")) {
      if (values.size() > values.count("--scenes-dir") + values.count("--max-wall") + values.count("--dump-worst") +
                              values.count("--dump-dir")) {
        throw std::invalid_argument("--shape, --n, --seed, --e-r, --duration and --dt need --scenario");
      }
      cases = AllCases();
    } else {
      const std::string scenario = values["--scenario"];
      Case c;
      c.scenario = scenario;
      if (scenario == "S1") {
        const std::string shape = values.count("--shape") ? values["--shape"] : "sphere";
        if (shape != "sphere" && shape != "ellipsoid") {
          throw std::invalid_argument("--shape must be sphere or ellipsoid, got '" + shape + "'");
        }
        c.shape = shape == "sphere" ? PileShape::kSphere : PileShape::kEllipsoid;
        c.n = values.count("--n") ? static_cast<int>(ParseNumber("--n", values["--n"], 1, 100000)) : 100;
        if (values.count("--n") && std::to_string(c.n) != values["--n"]) {
          throw std::invalid_argument("--n must be an integer in [1, 100000], got '" + values["--n"] + "'");
        }
        c.seed = values.count("--seed") ? static_cast<unsigned>(ParseNumber("--seed", values["--seed"], 0, 4e9)) : 42;
        c.h = 0.005;
        c.duration = 2.0;
        c.variant = shape + "_n" + std::to_string(c.n);
        if (values.count("--e-r")) {
          c.e_r = ParseNumber("--e-r", values["--e-r"], 0.0, 1000.0);
          if (c.e_r != kPileTorsionLever) c.variant += "_er" + FormatNumber(c.e_r);
        }
        if (values.count("--variant")) throw std::invalid_argument("--variant applies to P1, P2 and P3 only");
      } else {
        bool found = false;
        for (const Case& known : AllCases()) {
          const bool variant_ok = !values.count("--variant") || known.variant == values["--variant"];
          if (known.scenario == scenario && variant_ok && !found) {
            c = known;
            found = true;
          }
        }
        if (!found && values.count("--variant")) {
          throw std::invalid_argument("no case " + scenario + " with --variant '" + values["--variant"] + "'");
        }
        if (!found) throw std::invalid_argument("--scenario must be P1, P2, P3, S1 or J1, got '" + scenario + "'");
        if (values.count("--shape") || values.count("--n") || values.count("--seed") || values.count("--e-r")) {
          throw std::invalid_argument("--shape, --n, --seed and --e-r apply to --scenario S1 only");
        }
      }
      if (values.count("--duration")) c.duration = ParseNumber("--duration", values["--duration"], 1e-6, 1e6);
      if (values.count("--dt")) c.h = ParseNumber("--dt", values["--dt"], 1e-6, 1.0);
      cases.push_back(c);
    }
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_bench: " << e.what() << "\n" << usage << "\n";
    return 2;
  }
  RequestOnStopSignals(&g_interrupt);
  try {
    for (const Case& c : cases) {
      Run(c, scenes_dir, max_wall_s, dump, overrides);
      if (g_interrupt.requested()) return 130;
    }
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
