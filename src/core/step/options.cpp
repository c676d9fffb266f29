#include "implicit_sim/core/step/options.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <string>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr const char* kSolverNames[] = {"newton", "ipopt", nullptr};  // by StepperOptions::Solver
constexpr const char* kSchemeNames[] = {"paper", "rattle", nullptr};  // by StepperOptions::Scheme

using Options = StepperOptions;

// Columns: field, ROS parameter, runner flag, kind, default, lower, upper, lower open, upper open, unit, choices,
// description, get, set.
constexpr std::array<OptionRow, kNumOptionRows> kTable{{
    {"h", "time_step", "--dt", OptionKind::kReal, 0.01, 0.0, 1.0, true, false, "s", nullptr, "time step",
     [](const Options& o) { return o.h; }, [](Options* o, double x) { o->h = x; }},
    {"scheme", "scheme", "--scheme", OptionKind::kChoice, 1.0, 0.0, 1.0, false, false, "", kSchemeNames,
     "the time-stepping scheme: the paper's first-order step, or the second-order two-stage RATTLE step",
     [](const Options& o) { return static_cast<double>(static_cast<int>(o.scheme)); },
     [](Options* o, double x) { o->scheme = x == 1.0 ? Options::Scheme::kRattle : Options::Scheme::kPaper; }},
    {"solver", "solver", "--solver", OptionKind::kChoice, 0.0, 0.0, 1.0, false, false, "", kSolverNames,
     "the primary solver (Newton's retry ladder also tries Ipopt)",
     [](const Options& o) { return static_cast<double>(static_cast<int>(o.solver)); },
     [](Options* o, double x) { o->solver = x == 1.0 ? Options::Solver::kIpopt : Options::Solver::kNewton; }},
    {"newton.tolerance", "tolerance", "--tolerance", OptionKind::kReal, 1e-12, 0.0, 0.1, true, false, "", nullptr,
     "Newton tolerance: converged when |Phi|_2 <= tolerance (1 + |z|_inf) on the scaled residual",
     [](const Options& o) { return o.newton.tolerance; }, [](Options* o, double x) { o->newton.tolerance = x; }},
    {"newton.max_iterations", "max_iterations", "--max-iterations", OptionKind::kInteger, 100.0, 1.0, 1e5, false,
     false, "", nullptr, "Newton iterations per solve",
     [](const Options& o) { return static_cast<double>(o.newton.max_iterations); },
     [](Options* o, double x) { o->newton.max_iterations = static_cast<int>(x); }},
    {"newton.lm_damping", "", "", OptionKind::kReal, 1e-12, 0.0, 1.0, false, true, "", nullptr,
     "Levenberg-Marquardt damping factor: damping = lm_damping max(1, |Phi|^2 / 2)",
     [](const Options& o) { return o.newton.lm_damping; }, [](Options* o, double x) { o->newton.lm_damping = x; }},
    {"newton.armijo", "", "", OptionKind::kReal, 1e-4, 0.0, 1.0, true, true, "", nullptr,
     "sufficient decrease factor of the Newton line search",
     [](const Options& o) { return o.newton.armijo; }, [](Options* o, double x) { o->newton.armijo = x; }},
    {"newton.min_step", "", "", OptionKind::kReal, 1e-10, 0.0, 1.0, true, false, "", nullptr,
     "smallest step length of the Newton line search",
     [](const Options& o) { return o.newton.min_step; }, [](Options* o, double x) { o->newton.min_step = x; }},
    {"newton.sparse_regularization", "", "", OptionKind::kReal, 1e-9, 0.0, 1.0, false, true, "", nullptr,
     "regularization delta of the sparse Newton solve",
     [](const Options& o) { return o.newton.sparse_regularization; },
     [](Options* o, double x) { o->newton.sparse_regularization = x; }},
    {"newton.residual_regularization", "", "", OptionKind::kReal, 0.0, 0.0, 1e3, false, false, "", nullptr,
     "the Newton regularization delta grows by this times |Phi|_2 (vanishes with the residual; 0: constant)",
     [](const Options& o) { return o.newton.residual_regularization; },
     [](Options* o, double x) { o->newton.residual_regularization = x; }},
    {"newton.line_search_memory", "", "", OptionKind::kInteger, 10.0, 1.0, 16.0, false, false, "", nullptr,
     "the Newton line search accepts a decrease of the largest of the last this many merits (1: monotone)",
     [](const Options& o) { return static_cast<double>(o.newton.line_search_memory); },
     [](Options* o, double x) { o->newton.line_search_memory = static_cast<int>(x); }},
    {"newton.stall_window", "", "", OptionKind::kInteger, 0.0, 0.0, 1000.0, false, false, "", nullptr,
     "a Newton solve stops as stalled when its last this many iterations did not get the residual below 0.9 times "
     "its best before them (0: never)",
     [](const Options& o) { return static_cast<double>(o.newton.stall_window); },
     [](Options* o, double x) { o->newton.stall_window = static_cast<int>(x); }},
    {"newton.condense_blocks", "", "", OptionKind::kInteger, 1.0, 0.0, 1.0, false, false, "", nullptr,
     "1: sparse Newton solves condense each pair's closest-point unknowns out of the Newton matrix (Schur complement)",
     [](const Options& o) { return o.newton.condense_blocks ? 1.0 : 0.0; },
     [](Options* o, double x) { o->newton.condense_blocks = x != 0.0; }},
    {"newton.retract_sliding", "", "", OptionKind::kInteger, 1.0, 0.0, 1.0, false, false, "", nullptr,
     "1: sparse Newton solves scale a sliding pair's friction fractions back onto their unit sphere at each trial point",
     [](const Options& o) { return o.newton.retract_sliding ? 1.0 : 0.0; },
     [](Options* o, double x) { o->newton.retract_sliding = x != 0.0; }},
    {"projected_retries", "", "", OptionKind::kInteger, 1.0, 0.0, 1.0, false, false, "", nullptr,
     "1: every rung after the plain warm start uses projected multipliers (friction reads the slip speed max(sigma, 0))",
     [](const Options& o) { return o.projected_retries ? 1.0 : 0.0; },
     [](Options* o, double x) { o->projected_retries = x != 0.0; }},
    {"projected_friction", "", "", OptionKind::kInteger, 1.0, 0.0, 2.0, false, false, "", nullptr,
     "friction rows as projection equations: 0 nowhere (the paper's bilinear rows), 1 on sparse islands, 2 everywhere",
     [](const Options& o) { return static_cast<double>(o.projected_friction); },
     [](Options* o, double x) { o->projected_friction = static_cast<int>(x); }},
    {"friction_projection_scale", "", "", OptionKind::kReal, 1.0, 0.0, 1e6, true, false, "s/m", nullptr,
     "the projected friction rows' scale r: s - P(s - r rate) = 0",
     [](const Options& o) { return o.friction_projection_scale; },
     [](Options* o, double x) { o->friction_projection_scale = x; }},
    {"proximal_weight", "", "", OptionKind::kReal, 1.0, 0.0, 1e3, false, false, "m/s", nullptr,
     "first weight of the proximal-point rung after a failed cold start, divided by 10 each round (0: no such rung)",
     [](const Options& o) { return o.proximal_weight; }, [](Options* o, double x) { o->proximal_weight = x; }},
    {"sparse_warm_iterations", "", "", OptionKind::kInteger, 8.0, 1.0, 1000.0, false, false, "", nullptr,
     "Newton iterations of a sparse island's (several pairs') plain warm start before its projected retry",
     [](const Options& o) { return static_cast<double>(o.sparse_warm_iterations); },
     [](Options* o, double x) { o->sparse_warm_iterations = static_cast<int>(x); }},
    {"path_following", "", "", OptionKind::kInteger, 0.0, 0.0, 1.0, false, false, "", nullptr,
     "1: a sparse island's failed warm start follows the smoothing path before the projected retry (rung 1p)",
     [](const Options& o) { return o.path_following ? 1.0 : 0.0; },
     [](Options* o, double x) { o->path_following = x != 0.0; }},
    {"predictor_sweeps", "", "", OptionKind::kInteger, 0.0, 0.0, 20.0, false, false, "", nullptr,
     "block Gauss-Seidel sweeps over the worst pair blocks before a warm solve that starts far off (0: none)",
     [](const Options& o) { return static_cast<double>(o.predictor_sweeps); },
     [](Options* o, double x) { o->predictor_sweeps = static_cast<int>(x); }},
    {"predictor_residual", "", "", OptionKind::kReal, 1e-2, 0.0, kInf, true, true, "", nullptr,
     "the block predictor runs when the warm start's |Phi|_2 exceeds this",
     [](const Options& o) { return o.predictor_residual; }, [](Options* o, double x) { o->predictor_residual = x; }},
    {"ipopt_max_iterations", "", "", OptionKind::kInteger, 500.0, 1.0, 1e5, false, false, "", nullptr,
     "Ipopt iterations per solve",
     [](const Options& o) { return static_cast<double>(o.ipopt_max_iterations); },
     [](Options* o, double x) { o->ipopt_max_iterations = static_cast<int>(x); }},
    {"contact_threshold", "", "", OptionKind::kReal, 1e-9, 0.0, kInf, false, true, "N", nullptr,
     "a pair is an active contact when its normal force exceeds this",
     [](const Options& o) { return o.contact_threshold; }, [](Options* o, double x) { o->contact_threshold = x; }},
    {"broad_phase_margin", "", "", OptionKind::kReal, 0.005, 0.0, 10.0, false, false, "m", nullptr,
     "margin added to the grown bounding spheres of the broad phase",
     [](const Options& o) { return o.broad_phase_margin; }, [](Options* o, double x) { o->broad_phase_margin = x; }},
    {"max_speed", "", "", OptionKind::kReal, 1e5, 0.0, 1e12, true, false, "m/s", nullptr,
     "a step ending faster than this diverged",
     [](const Options& o) { return o.max_speed; }, [](Options* o, double x) { o->max_speed = x; }},
    {"max_angular_speed", "", "", OptionKind::kReal, 1e6, 0.0, 1e12, true, false, "rad/s", nullptr,
     "a step ending turning faster than this diverged",
     [](const Options& o) { return o.max_angular_speed; }, [](Options* o, double x) { o->max_angular_speed = x; }},
    {"overlap_tolerance", "", "", OptionKind::kReal, 1e-6, 0.0, 1.0, false, false, "m", nullptr,
     "a cold step refuses to start from bodies overlapping by more than this",
     [](const Options& o) { return o.overlap_tolerance; }, [](Options* o, double x) { o->overlap_tolerance = x; }},
    {"threads", "threads", "--threads", OptionKind::kInteger, 0.0, 0.0, 256.0, false, false, "", nullptr,
     "threads that solve the step's islands (0: the hardware's cores); results do not depend on it",
     [](const Options& o) { return static_cast<double>(o.threads); },
     [](Options* o, double x) { o->threads = static_cast<int>(x); }},
}};

template <typename NameOf>
const OptionRow* FindRow(std::string_view name, NameOf name_of) {
  if (name.empty()) return nullptr;
  for (const OptionRow& row : kTable) {
    if (name == name_of(row)) return &row;
  }
  return nullptr;
}

int NumChoices(const OptionRow& row) {
  int n = 0;
  while (row.choices[n] != nullptr) ++n;
  return n;
}

bool InBounds(const OptionRow& row, double value) {
  return std::isfinite(value) && (row.lower_open ? value > row.lower : value >= row.lower) &&
         (row.upper_open ? value < row.upper : value <= row.upper);
}

std::string ValueText(const OptionRow& row, double value) {
  if (row.kind != OptionKind::kChoice) return FormatNumber(value);
  const bool named = value == std::floor(value) && value >= 0.0 && value < NumChoices(row);
  return named ? std::string("'") + row.choices[static_cast<int>(value)] + "'" : FormatNumber(value);
}

// "<label> must be <what the row allows>"
std::string MustBe(const OptionRow& row, std::string_view label) {
  std::string text = std::string(label) + " must be ";
  if (row.kind == OptionKind::kChoice) return text + OptionRangeText(row);
  text += row.kind == OptionKind::kInteger ? "an integer in " : "in ";
  text += OptionRangeText(row);
  if (*row.unit != '\0') text += std::string(" ") + row.unit;
  return text;
}

}  // namespace

const std::array<OptionRow, kNumOptionRows>& OptionTable() { return kTable; }

const OptionRow* FindOptionByField(std::string_view field) {
  return FindRow(field, [](const OptionRow& row) { return row.field; });
}

const OptionRow* FindOptionByRosParam(std::string_view name) {
  return FindRow(name, [](const OptionRow& row) { return row.ros_param; });
}

const OptionRow* FindOptionByRunnerFlag(std::string_view flag) {
  return FindRow(flag, [](const OptionRow& row) { return row.runner_flag; });
}

const char* OptionChoiceName(const OptionRow& row, const StepperOptions& options) {
  return row.choices[static_cast<int>(row.get(options))];
}

std::string OptionRangeText(const OptionRow& row) {
  if (row.kind == OptionKind::kChoice) {
    std::string text;
    const int n = NumChoices(row);
    for (int i = 0; i < n; ++i) text += std::string(i == 0 ? "" : i + 1 == n ? " or " : ", ") + row.choices[i];
    return text;
  }
  auto bound = [&row](double x) {  // integers in full: [1, 100000], not [1, 1e+05]
    return row.kind == OptionKind::kInteger ? std::to_string(static_cast<long long>(x)) : FormatNumber(x);
  };
  return std::string(row.lower_open ? "(" : "[") + bound(row.lower) + ", " + bound(row.upper) +
         (row.upper_open ? ")" : "]");
}

bool CheckOptionValue(const OptionRow& row, double value, std::string_view label, std::string* error) {
  const bool whole = row.kind == OptionKind::kReal || value == std::floor(value);
  if (whole && InBounds(row, value)) return true;
  *error = MustBe(row, label) + ", got " + ValueText(row, value);
  return false;
}

bool ParseOptionValue(const OptionRow& row, const std::string& text, std::string_view label, double* value,
                      std::string* error) {
  if (row.kind == OptionKind::kChoice) {
    for (int i = 0; row.choices[i] != nullptr; ++i) {
      if (text == row.choices[i]) {
        *value = i;
        return true;
      }
    }
    *error = MustBe(row, label) + ", got '" + text + "'";
    return false;
  }
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, *value);
  if (text.empty() || result.ec != std::errc() || result.ptr != end) {
    *error = MustBe(row, label) + ", got '" + text + "'";
    return false;
  }
  return CheckOptionValue(row, *value, label, error);
}

bool StepperOptions::IsValid(std::string* error) const {
  for (const OptionRow& row : kTable) {
    if (!CheckOptionValue(row, row.get(*this), row.field, error)) return false;
  }
  return true;
}

}  // namespace implicit_sim
