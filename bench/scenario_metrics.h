// Accuracy figures of the paper scenes, computed the same way for every engine (implicit_sim_bench and the MuJoCo
// driver bench/peers/mujoco_bench.cpp): an engine turns each step end into a StepSample, ScenarioMetrics turns the
// samples into JSON fields (bench/README.md lists them). Header-only; plain numbers, no engine types.
//   P1: energy_drift_max = max over step ends of |KE(t) / KE0 - 1|; energy_ratio_final = KE(T) / KE0.
//   P2: stop_time = first step end with |w_z| < 1e-6 rad/s (null: never); spin_slope = least-squares slope of w_z over
//       [0, 0.9] s, t = 0 included (rad/s^2).
//   P3: per contact A (ball-sphere_a) and B (ball-sphere_b), "closed" = normal force > 1e-9 N, both closed at t = 0:
//       separation_time_a/_b = first step end with the contact open; final_separation_a/_b = first step end after
//       which it stays open to the end (null: closed at the end); toggles_a/_b = open/closed changes;
//       slide_time_b = first step end with B closed and slip speed > 1e-4 m/s; velocity_error_3_5 = |v(3.5 s) -
//       v_ref| / |v_ref| (null when the run stopped earlier).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {

// The state of a paper scene at one step end, as an engine reports it.
struct StepSample {
  double t = 0.0;                            // s
  double kinetic_energy = 0.0;               // J
  std::array<double, 3> v_W{{0.0, 0.0, 0.0}};  // the moving body's centre velocity, world frame (m/s)
  std::array<double, 3> w_W{{0.0, 0.0, 0.0}};  // its angular velocity, world frame (rad/s)
  bool closed[2] = {false, false};           // P3: contacts A, B carry a normal force > 1e-9 N
  double slip_speed[2] = {0.0, 0.0};         // P3: tangential relative speed at A, B (m/s)
};

class ScenarioMetrics {
 public:
  ScenarioMetrics(const std::string& scenario, double kinetic_energy_initial)
      : scenario_(scenario), kinetic_energy_initial_(kinetic_energy_initial) {
    AddSpinPoint(0.0, kP2InitialSpin);
  }

  // Whether the scenario has figures that need a sample at every step end.
  bool NeedsSamples() const { return scenario_ == "P1" || scenario_ == "P2" || scenario_ == "P3"; }

  void Observe(const StepSample& s) {
    if (kinetic_energy_initial_ > 0.0) {
      energy_drift_max_ = std::max(energy_drift_max_, std::abs(s.kinetic_energy / kinetic_energy_initial_ - 1.0));
    }
    energy_ratio_final_ = kinetic_energy_initial_ > 0.0 ? s.kinetic_energy / kinetic_energy_initial_ : 0.0;
    if (stop_time_ < 0.0 && std::abs(s.w_W[2]) < 1e-6) stop_time_ = s.t;
    if (s.t <= 0.9 + 1e-9) AddSpinPoint(s.t, s.w_W[2]);
    for (int c = 0; c < 2; ++c) {
      if (s.closed[c] != closed_[c]) ++toggles_[c];
      if (!s.closed[c] && separation_time_[c] < 0.0) separation_time_[c] = s.t;
      if (!s.closed[c] && closed_[c]) final_separation_[c] = s.t;
      if (s.closed[c]) final_separation_[c] = -1.0;
      closed_[c] = s.closed[c];
    }
    if (slide_time_b_ < 0.0 && s.closed[1] && s.slip_speed[1] > 1e-4) slide_time_b_ = s.t;
    if (std::abs(s.t - 3.5) < 1e-9) {
      double error2 = 0.0, ref2 = 0.0;
      for (int i = 0; i < 3; ++i) {
        error2 += (s.v_W[i] - kP3VelocityAt3_5[i]) * (s.v_W[i] - kP3VelocityAt3_5[i]);
        ref2 += kP3VelocityAt3_5[i] * kP3VelocityAt3_5[i];
      }
      velocity_error_3_5_ = std::sqrt(error2 / ref2);
    }
  }

  // The scenario's fields as "key": value strings (none for S1).
  std::vector<std::string> JsonFields() const {
    if (scenario_ == "P1") {
      return {Field("energy_drift_max", Number(energy_drift_max_)),
              Field("energy_ratio_final", Number(energy_ratio_final_))};
    }
    if (scenario_ == "P2") return {Field("stop_time", Optional(stop_time_)), Field("spin_slope", Number(SpinSlope()))};
    if (scenario_ == "P3") {
      return {Field("separation_time_a", Optional(separation_time_[0])),
              Field("separation_time_b", Optional(separation_time_[1])),
              Field("final_separation_a", Optional(final_separation_[0])),
              Field("final_separation_b", Optional(final_separation_[1])),
              Field("toggles_a", std::to_string(toggles_[0])),
              Field("toggles_b", std::to_string(toggles_[1])),
              Field("slide_time_b", Optional(slide_time_b_)),
              Field("velocity_error_3_5", Optional(velocity_error_3_5_))};
    }
    return {};
  }

 private:
  static constexpr double kP2InitialSpin = 1.962;  // rad/s
  static constexpr double kP3VelocityAt3_5[3] = {4.852055739686922, 0.14948342010862542, -4.083242953676649};  // m/s

  static std::string Field(const std::string& key, const std::string& value) { return "\"" + key + "\": " + value; }
  static std::string Number(double value) { return std::isfinite(value) ? FormatNumber(value) : "null"; }
  static std::string Optional(double value) { return value >= 0.0 ? FormatNumber(value) : "null"; }  // < 0: never

  void AddSpinPoint(double t, double w_z) {
    ++spin_n_;
    spin_st_ += t;
    spin_sw_ += w_z;
    spin_stt_ += t * t;
    spin_stw_ += t * w_z;
  }
  double SpinSlope() const {
    const double denominator = spin_n_ * spin_stt_ - spin_st_ * spin_st_;
    return denominator > 0.0 ? (spin_n_ * spin_stw_ - spin_st_ * spin_sw_) / denominator : NAN;
  }

  std::string scenario_;
  double kinetic_energy_initial_;  // J
  double energy_drift_max_ = 0.0, energy_ratio_final_ = 1.0;
  double stop_time_ = -1.0;  // s
  double spin_n_ = 0.0, spin_st_ = 0.0, spin_sw_ = 0.0, spin_stt_ = 0.0, spin_stw_ = 0.0;
  bool closed_[2] = {true, true};  // P3: both contacts touch at t = 0
  int toggles_[2] = {0, 0};
  double separation_time_[2] = {-1.0, -1.0}, final_separation_[2] = {-1.0, -1.0};  // s
  double slide_time_b_ = -1.0, velocity_error_3_5_ = -1.0;
};

}  // namespace implicit_sim
