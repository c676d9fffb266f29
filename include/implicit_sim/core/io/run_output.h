// Headless outputs of a run: the trajectory CSV (one row per step, t = 0 included) and the summary JSON.
// Column names are a contract (doc/runner.md): t; per moving body B: B.x B.y B.z B.qw B.qx B.qy B.qz B.vx B.vy B.vz
// B.wx B.wy B.wz; per joint J with a coordinate (not fixed): J.q J.qd J.limit (position rad or m, velocity, limit
// effort N m or N); per pair P = <link1>-<link2>: P.gap P.fn P.ft P.mr P.slip (only when every pair is in every NCP, see
// Data::PairSelection); step.iterations step.residual step.converged; energy.kinetic energy.potential (J; potential
// -sum m g . p, zero at the world origin). With the broad phase the contacts go to
// contacts.csv instead, one row per touching pair per step: t,pair,gap,fn,ft,mr,slip. Numbers are written
// locale-independently (shortest round-trip form, '.' as decimal point).
#pragma once

#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {

// Accumulates the figures of summary.json while a run goes on.
struct RunSummary {
  std::string scene;
  double h = 0.0;
  std::string scheme;                  // "paper" or "rattle" (StepperOptions::scheme)
  int steps = 0;
  double wall_s = 0.0;                 // time spent in Step (s)
  double max_penetration = 0.0;        // max over steps and pairs of max(0, -gap) (m)
  int nonconverged_steps = 0;
  // The run's totals of the counters with StepCounter::run_total (step_report.h: cold_restarts, end_frame_retries,
  // proximal_solves, smoothed_solves, ipopt_solves, substeps, crossings, broad_phase_additions); the others stay 0.
  StepReport totals;
  int max_pairs_in_ncp = 0;
  int max_iterations = 0;
  double max_residual = 0.0;
  double kinetic_energy_initial = 0.0; // J
  double kinetic_energy_final = 0.0;   // J
  double max_joint_position_error = 0.0;  // over steps, StepReport::joint_position_error (m)
  double max_joint_angle_error = 0.0;     // StepReport::joint_angle_error (rad)
  // The friction parameters of the pairs with trajectory columns ("pairs" in the JSON; empty: the key is left out).
  std::vector<std::pair<std::string, FrictionParams>> pairs;
  double t_end = 0.0;                  // simulated time at the end of the run (s)
  std::string stop_reason = "duration";  // "duration", "at_rest", "refused", "max_wall" or "interrupted"
  bool at_rest_rule = false;           // the run had a stop-at-rest rule: "time_to_rest" is written
  double time_to_rest = -1.0;          // s; < 0: did not come to rest ("time_to_rest": null)
  bool penetration_checked = false;    // the run checked every step end geometrically: "max_penetration_oracle"
  double max_penetration_oracle = 0.0; // max over step ends of MaxPenetrationBound (step_health.h), m
  void Add(const StepReport& report, const Data& data);
  std::string ToJson() const;
};

class TrajectoryWriter {
 public:
  // Throws std::runtime_error if a file cannot be written. With pair_columns the per-pair columns are in the
  // trajectory; otherwise contacts go to contacts_path.
  TrajectoryWriter(const std::string& path, const Model& model, bool pair_columns, const std::string& contacts_path);
  // The t = 0 row: gaps from FindClosestPoints (closed form, or the distance oracle), forces and slip unknown (nan).
  void WriteInitial(const State& state);
  void WriteStep(const State& state, const Data& data, const StepReport& report);

 private:
  void WriteBodies(const State& state);
  void WriteJoints(const State& state, const Data* data);
  void WriteEnergies(const State& state);  // the two energy columns and the end of the row
  const Model& model_;
  bool pair_columns_;
  std::ofstream out_, contacts_;
};

}  // namespace implicit_sim
