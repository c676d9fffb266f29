// Runs a scene from scenes/ headless for the scenario tests and hands every step end to a callback.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "implicit_sim/core/model/urdf_loader.h"

namespace implicit_sim {
namespace testing_support {

// FNV-1a over the bytes of t, q, v and every contact's normal force and gap: equal hashes mean equal bits.
inline uint64_t HashStep(const State& state, const Data& data) {
  uint64_t hash = 1469598103934665603ull;
  auto add = [&hash](const double* values, long count) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(values);
    for (long i = 0; i < count * static_cast<long>(sizeof(double)); ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
  };
  add(&state.t, 1);
  add(state.q.data(), state.q.size());
  add(state.v.data(), state.v.size());
  for (const ContactResult& c : data.contacts) {
    add(&c.normal_force, 1);
    add(&c.gap, 1);
  }
  return hash;
}

inline std::string ScenePath(const std::string& file) {
  return std::string(IMPLICIT_SIM_SOURCE_DIR) + "/scenes/" + file;
}

struct RunStats {
  int steps = 0;
  int nonconverged = 0;
  double max_solver_penetration = 0.0;  // max over steps and pairs of -gap (m), as the solver reports it
  double ke0 = 0.0, ke_final = 0.0;
};

using StepCallback = std::function<void(const Model&, const State&, const Data&, const StepReport&)>;

inline RunStats RunScene(const Model& model, const StepperOptions& options, double duration,
                         const StepCallback& on_step = nullptr,
                         Data::PairSelection selection = Data::PairSelection::kAuto) {
  const double h = options.h;
  Data data(model, selection);
  State state = State::Initial(model);
  RunStats stats;
  stats.ke0 = KineticEnergy(model, state);
  const long steps = std::lround(duration / h);
  for (long i = 0; i < steps; ++i) {
    const StepReport report = Step(model, options, &state, &data);
    ++stats.steps;
    if (!report.converged) ++stats.nonconverged;
    for (const ContactResult& c : data.contacts) {
      stats.max_solver_penetration = std::max(stats.max_solver_penetration, -c.gap);
    }
    if (on_step) on_step(model, state, data, report);
  }
  stats.ke_final = KineticEnergy(model, state);
  return stats;
}

inline RunStats RunScene(const Model& model, double h, double duration, const StepCallback& on_step = nullptr,
                         Data::PairSelection selection = Data::PairSelection::kAuto) {
  StepperOptions options;
  options.h = h;
  return RunScene(model, options, duration, on_step, selection);
}

inline StepperOptions RattleOptions(double h) {
  StepperOptions options;
  options.h = h;
  options.scheme = StepperOptions::Scheme::kRattle;
  return options;
}

// Runs a two-body model (body 1 moving, body 0 fixed, one pair) and, at every step end where the pair is apart
// (gap >= 1e-3 m), compares the stepper's closest points and gap with the distance oracle.
struct OracleComparison {
  double worst = 0.0;    // largest gap difference or closest-point distance to the oracle's (m)
  double min_gap = 1.0;  // smallest gap seen (m)
  int checks = 0;        // step ends compared
  int nonconverged = 0;
};

inline OracleComparison CompareClosestPointsWithOracle(const Model& model, double h, double duration) {
  OracleComparison out;
  RunScene(model, h, duration, [&](const Model& m, const State& s, const Data& d, const StepReport& r) {
    out.nonconverged += !r.converged;
    const ContactResult& c = d.contacts[0];
    out.min_gap = std::min(out.min_gap, c.gap);
    if (c.gap < 1e-3) return;
    const ClosestPointsResult cp =
        ComputeClosestPoints(m.bodies[1].shapes[0], s.X_WB(m, 1), m.bodies[0].shapes[0], s.X_WB(m, 0));
    if (!cp.solved) {
      out.worst = std::numeric_limits<double>::infinity();
      return;
    }
    out.worst = std::max({out.worst, std::abs(cp.distance - c.gap), (cp.p_W1 - c.p_WA1).norm(),
                          (cp.p_W2 - c.p_WA2).norm()});
    ++out.checks;
  });
  return out;
}

}  // namespace testing_support
}  // namespace implicit_sim
