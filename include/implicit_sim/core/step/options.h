// The options of a step: time step, solver choice, tolerances and health limits. They live outside the Model and
// validate themselves through the options table below, which also gives the ROS node's parameter and the runner's
// flag for each option (one allowed range for all three).
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "implicit_sim/core/ncp/ipopt_ncp.h"
#include "implicit_sim/core/ncp/semismooth_newton.h"

namespace implicit_sim {

struct StepperOptions {
  enum class Solver { kNewton, kIpopt };
  // kPaper: the paper's first-order step (one NCP, everything at the end of the step). kRattle: the two-stage
  // second-order step of doc/method.md ("The second-order step"): the same end-of-step contact, energy-conserving
  // smooth motion.
  enum class Scheme { kPaper, kRattle };
  double h = 0.01;                // time step (s), in (0, 1]
  Scheme scheme = Scheme::kRattle;
  Solver solver = Solver::kNewton;  // the primary solver; Newton's retry ladder also tries Ipopt
  NewtonOptions newton;
  int ipopt_max_iterations = 500; // [1, 100000]
  // Every rung after the plain warm start solves with projected multipliers (retry_ladder.h, rung 1b on), 0 or 1.
  bool projected_retries = true;
  // The proximal-point rung (retry_ladder.h) starts with this weight (m/s per unit multiplier) and divides it by 10
  // each round; 0: no proximal rung. [0, 1000]
  double proximal_weight = 1.0;
  // Newton iterations of the plain warm start of a sparse island of several pairs (retry_ladder.h, rung 1) before the
  // projected one, [1, 1000] (more where its residual is already below 1e-6).
  int sparse_warm_iterations = 8;
  // Where the friction rows take the projected form (rows/friction_rows.h), [0, 2]: 0 nowhere (the paper's bilinear
  // rows), 1 on islands the sparse LU solves (more than NewtonSolvers::kDenseSizeLimit unknowns: piles), 2 on every
  // island; and its projection scale r (s/m, (0, 1e6]). doc/method.md, "The friction rows as projection equations".
  int projected_friction = 1;
  double friction_projection_scale = 1.0;
  // The smoothing-path rung (retry_ladder.h, rung 1p) after it, 0 or 1 (an ablation: measured, not kept).
  bool path_following = false;
  // Block Gauss-Seidel sweeps (block_predictor.h) over the pair blocks with the largest residuals, before the warm
  // solve, when its start's |Phi| exceeds predictor_residual; 0: none. [0, 20], (0, inf)
  int predictor_sweeps = 0;
  double predictor_residual = 1e-2;
  double contact_threshold = 1e-9;  // a pair counts as an active contact when its normal force exceeds this (N)
  // Broad phase (when Data uses one): a pair enters the NCP when the bounding spheres of its bodies, each grown by the
  // motion possible within the step (h |v| + h |w| |offset| + |g| h^2 / 2) plus this margin, overlap. (m, [0, 10])
  double broad_phase_margin = 0.005;
  // Health checks (see StepFault). A step whose end velocities exceed these diverged (m/s, rad/s; (0, 1e12]).
  double max_speed = 1e5;
  double max_angular_speed = 1e6;
  // A cold step (the first, or after a reset or a set state) refuses to start from bodies overlapping by more than
  // this (m, [0, 1]): the step's end-of-step contact would throw them apart with an impulse of overlap / h.
  double overlap_tolerance = 1e-6;
  // Threads that solve the islands of a step (step/islands.h), [0, 256]; 0: the hardware's cores. Results are
  // bit-identical for any value.
  int threads = 0;
  // Checks every row of the options table; on failure sets *error to a message naming the option, its range and
  // unit, and the bad value.
  bool IsValid(std::string* error) const;
  // The Ipopt solver's options (its convergence bar: IpoptNcpOptions::tolerance).
  IpoptNcpOptions IpoptOptions() const {
    IpoptNcpOptions ipopt;
    ipopt.max_iterations = ipopt_max_iterations;
    ipopt.interrupt = newton.interrupt;
    return ipopt;
  }
};

// The options table: one row per field of StepperOptions and its NewtonOptions. Values pass as doubles: integers as
// whole numbers, a choice as the index of its name.
enum class OptionKind { kReal, kInteger, kChoice };

struct OptionRow {
  const char* field;        // the StepperOptions field, e.g. "newton.tolerance"
  const char* ros_param;    // the node's private parameter (~name); "" when the node has none
  const char* runner_flag;  // implicit_sim_run's flag; "" when it has none
  OptionKind kind;
  double default_value;     // equals a default-constructed StepperOptions
  double lower, upper;      // bounds; upper may be infinite (the value must still be finite)
  bool lower_open, upper_open;
  const char* unit;         // "" when dimensionless
  const char* const* choices;  // kChoice: the names by index, ending with nullptr; otherwise nullptr
  const char* description;  // one line
  double (*get)(const StepperOptions& options);
  void (*set)(StepperOptions* options, double value);
};

constexpr int kNumOptionRows = 29;
const std::array<OptionRow, kNumOptionRows>& OptionTable();

// The row with this field, ROS parameter or runner flag; nullptr when none (an empty name finds nothing).
const OptionRow* FindOptionByField(std::string_view field);
const OptionRow* FindOptionByRosParam(std::string_view name);
const OptionRow* FindOptionByRunnerFlag(std::string_view flag);

// The name of a choice row's value in `options`, e.g. "rattle" for the row "scheme" of default options.
const char* OptionChoiceName(const OptionRow& row, const StepperOptions& options);

// "(0, 0.1]", "[1, 100000]", "[0, inf)" or, for a choice, "newton or ipopt".
std::string OptionRangeText(const OptionRow& row);

// Whether `value` is allowed for the row (finite, within the bounds, whole for integers, an index for choices). When
// not, sets *error to "<label> must be ..., got <value>"; label names the option as its user wrote it (the field,
// "parameter ~tolerance", "--tolerance"). Allocates nothing when the value is allowed.
bool CheckOptionValue(const OptionRow& row, double value, std::string_view label, std::string* error);

// Reads `text` for the row: a choice's name, or a number with '.' as the decimal point whatever the locale; then
// checks it as CheckOptionValue does.
bool ParseOptionValue(const OptionRow& row, const std::string& text, std::string_view label, double* value,
                      std::string* error);

}  // namespace implicit_sim
