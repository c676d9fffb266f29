#include "implicit_sim/core/io/run_output.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/geometry/support.h"

namespace implicit_sim {

void RunSummary::Add(const StepReport& report, const Data& data) {
  ++steps;
  wall_s += report.wall_time_s;
  if (!report.converged) ++nonconverged_steps;
  for (const StepCounter& counter : StepCounterTable()) {
    if (counter.run_total) totals.*counter.field += report.*counter.field;
  }
  max_pairs_in_ncp = std::max(max_pairs_in_ncp, report.pairs_in_ncp);
  max_iterations = std::max(max_iterations, report.iterations);
  max_residual = std::max(max_residual, report.residual);
  for (const ContactResult& contact : data.contacts) max_penetration = std::max(max_penetration, -contact.gap);
  max_joint_position_error = std::max(max_joint_position_error, report.joint_position_error);
  max_joint_angle_error = std::max(max_joint_angle_error, report.joint_angle_error);
}

std::string RunSummary::ToJson() const {
  const double us_per_step = steps > 0 ? 1e6 * wall_s / steps : 0.0;
  std::string json = "{\n";
  json += "  \"scene\": \"" + scene + "\",\n";
  json += "  \"h\": " + FormatNumber(h) + ",\n";
  json += "  \"scheme\": \"" + scheme + "\",\n";
  json += "  \"steps\": " + std::to_string(steps) + ",\n";
  json += "  \"wall_s\": " + FormatNumber(wall_s) + ",\n";
  json += "  \"us_per_step\": " + FormatNumber(us_per_step) + ",\n";
  json += "  \"max_penetration\": " + FormatNumber(max_penetration) + ",\n";
  json += "  \"max_joint_position_error\": " + FormatNumber(max_joint_position_error) + ",\n";
  json += "  \"max_joint_angle_error\": " + FormatNumber(max_joint_angle_error) + ",\n";
  json += "  \"nonconverged_steps\": " + std::to_string(nonconverged_steps) + ",\n";
  for (const StepCounter& counter : StepCounterTable()) {
    if (counter.run_total) json += "  \"" + std::string(counter.name) + "\": " + std::to_string(totals.*counter.field) + ",\n";
  }
  json += "  \"max_pairs_in_ncp\": " + std::to_string(max_pairs_in_ncp) + ",\n";
  json += "  \"max_iterations\": " + std::to_string(max_iterations) + ",\n";
  json += "  \"max_residual\": " + FormatNumber(max_residual) + ",\n";
  json += "  \"kinetic_energy_initial\": " + FormatNumber(kinetic_energy_initial) + ",\n";
  json += "  \"kinetic_energy_final\": " + FormatNumber(kinetic_energy_final) + ",\n";
  for (size_t i = 0; i < pairs.size(); ++i) {
    const FrictionParams& f = pairs[i].second;
    json += std::string(i == 0 ? "  \"pairs\": [\n" : "") + "    {\"name\": \"" + pairs[i].first + "\", \"mu\": " +
            FormatNumber(f.mu) + ", \"e_t\": " + FormatNumber(f.e_t) + ", \"e_o\": " + FormatNumber(f.e_o) +
            ", \"e_r\": " + FormatNumber(f.e_r) +
            (f.e_roll > 0.0 ? ", \"e_roll\": " + FormatNumber(f.e_roll) : "") + "}" +
            (i + 1 < pairs.size() ? ",\n" : "\n  ],\n");
  }
  json += "  \"t_end\": " + FormatNumber(t_end) + ",\n";
  json += "  \"stop_reason\": \"" + stop_reason + "\"";
  if (at_rest_rule) json += ",\n  \"time_to_rest\": " + (time_to_rest >= 0.0 ? FormatNumber(time_to_rest) : "null");
  if (penetration_checked) json += ",\n  \"max_penetration_oracle\": " + FormatNumber(max_penetration_oracle);
  return json + "\n}\n";
}

TrajectoryWriter::TrajectoryWriter(const std::string& path, const Model& model, bool pair_columns,
                                   const std::string& contacts_path)
    : model_(model), pair_columns_(pair_columns), out_(path) {
  if (!out_) throw std::runtime_error("cannot write '" + path + "'");
  if (!pair_columns_) {
    contacts_.open(contacts_path);
    if (!contacts_) throw std::runtime_error("cannot write '" + contacts_path + "'");
    contacts_ << "t,pair,gap,fn,ft,mr,slip\n";
  }
  out_ << "t";
  for (int b : model.moving_bodies) {
    for (const char* c : {"x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz"}) {
      out_ << ',' << model.bodies[b].name << '.' << c;
    }
  }
  for (const Joint& joint : model.joints) {
    if (!joint.has_coordinate()) continue;
    for (const char* c : {"q", "qd", "limit"}) out_ << ',' << joint.name << '.' << c;
  }
  for (int pair = 0; pair_columns_ && pair < static_cast<int>(model.pairs.size()); ++pair) {
    for (const char* c : {"gap", "fn", "ft", "mr", "slip"}) out_ << ',' << model.PairName(pair) << '.' << c;
  }
  out_ << ",step.iterations,step.residual,step.converged,energy.kinetic,energy.potential\n";
}

void TrajectoryWriter::WriteBodies(const State& state) {
  out_ << FormatNumber(state.t);
  for (int k = 0; k < model_.num_moving(); ++k) {
    for (int i = 0; i < Model::kBodyNq; ++i) out_ << ',' << FormatNumber(state.q[Model::q_offset(k) + i]);
    for (int i = 0; i < Model::kBodyNv; ++i) out_ << ',' << FormatNumber(state.v[Model::v_offset(k) + i]);
  }
}

void TrajectoryWriter::WriteEnergies(const State& state) {
  double potential = 0.0;
  for (int k = 0; k < model_.num_moving(); ++k) {
    potential -= model_.bodies[model_.moving_bodies[k]].mass * model_.gravity_W.dot(state.q.segment<3>(Model::q_offset(k)));
  }
  out_ << ',' << FormatNumber(KineticEnergy(model_, state)) << ',' << FormatNumber(potential) << '\n';
}

// Position, velocity and limit effort of every joint with a coordinate (limit effort nan: not yet computed).
void TrajectoryWriter::WriteJoints(const State& state, const Data* data) {
  for (int j = 0; j < static_cast<int>(model_.joints.size()); ++j) {
    if (!model_.joints[j].has_coordinate()) continue;
    out_ << ',' << FormatNumber(JointPosition(model_, state, j)) << ',' << FormatNumber(JointVelocity(model_, state, j))
         << ',' << FormatNumber(data ? data->joint_limit_effort[j] : std::nan(""));
  }
}

void TrajectoryWriter::WriteInitial(const State& state) {
  WriteBodies(state);
  WriteJoints(state, nullptr);
  for (size_t c = 0; pair_columns_ && c < model_.pairs.size(); ++c) {
    const ContactPair& pair = model_.pairs[c];
    const ClosestPointsResult cp =
        FindClosestPoints(model_.shape(pair.geom1), state.X_WB(model_, pair.body1), model_.shape(pair.geom2),
                          state.X_WB(model_, pair.body2));
    out_ << ',' << FormatNumber(cp.solved ? cp.distance : std::nan("")) << ",nan,nan,nan,nan";
  }
  out_ << ",0,0,1";
  WriteEnergies(state);
}

void TrajectoryWriter::WriteStep(const State& state, const Data& data, const StepReport& report) {
  WriteBodies(state);
  WriteJoints(state, &data);
  for (const ContactResult& c : data.contacts) {
    std::ostream& out = pair_columns_ ? out_ : contacts_;
    if (!pair_columns_) {
      if (!(c.normal_force > 0.0)) continue;
      out << FormatNumber(state.t) << ',' << model_.PairName(c.pair);
    }
    out << ',' << FormatNumber(c.gap) << ',' << FormatNumber(c.normal_force) << ','
        << FormatNumber(c.friction_force_W.norm()) << ',' << FormatNumber(c.torsional_moment) << ','
        << FormatNumber(c.slip_speed);
    if (!pair_columns_) out << '\n';
  }
  out_ << ',' << report.iterations << ',' << FormatNumber(report.residual) << ',' << (report.converged ? 1 : 0);
  WriteEnergies(state);
}

}  // namespace implicit_sim
