#include "implicit_sim/core/step/step_health.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "implicit_sim/core/geometry/distance_oracle.h"
#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/step/layout.h"
#include "implicit_sim/core/geometry/support.h"

namespace implicit_sim {
namespace {

// The broad phase's candidate pairs of `state` (bounding volumes without inflation) into data->candidates.
void FindCandidates(const Model& model, const State& state, Data* data) {
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) data->X_WB[b] = state.X_WB(model, b);
  std::fill(data->inflation.begin(), data->inflation.end(), 0.0);
  data->broad.FindPairs(data->X_WB, data->inflation, &data->candidates);
}

// The geometric penetration bound of one pair (see MaxPenetrationBound), m.
double PairPenetrationBound(const Model& model, const State& state, const ContactPair& pair, double tolerance) {
  const ConvexShape& shape1 = model.shape(pair.geom1);
  const ConvexShape& shape2 = model.shape(pair.geom2);
  return PenetrationBound(shape1, state.X_WB(model, pair.body1), shape2, state.X_WB(model, pair.body2), tolerance);
}

}  // namespace

double MaxPenetrationBound(const Model& model, const State& state, double tolerance, Data* data) {
  FindCandidates(model, state, data);
  double deepest = 0.0;
  for (int p : data->candidates) {
    deepest = std::max(deepest, PairPenetrationBound(model, state, model.pairs[p], tolerance));
  }
  return deepest;
}

bool FindInitialOverlap(const Model& model, const State& state, double tolerance, Data* data, std::string* detail) {
  FindCandidates(model, state, data);
  for (int p : data->candidates) {
    const double depth = PairPenetrationBound(model, state, model.pairs[p], tolerance);
    if (depth > tolerance) {
      *detail = "pair '" + model.PairName(p) + "' overlaps by up to " + FormatNumber(depth) + " m at t = " +
                FormatNumber(state.t) + " s (overlap_tolerance " + FormatNumber(tolerance) + " m)";
      return true;
    }
  }
  return false;
}

namespace {

// max { u . x : x in a shape of a body at pose X_WB } for a unit u_W (m): closed form where the shape has one,
// otherwise its bounding sphere (an upper bound; +inf for an unbounded shape).
double UpperSupport(const ConvexShape& shape, const Pose& X_WB, const Vec3& u_W) {
  Vec3 p_W;
  if (SupportPoint(shape, X_WB, u_W, &p_W)) return u_W.dot(p_W);
  return u_W.dot(X_WB * shape.X_BS.translation()) + shape.BoundingRadius();
}

}  // namespace

int FindCrossing(const Model& model, const State& start, const StepKinematics& kinematics, const Eigen::VectorXd& z,
                 std::string* detail) {
  const std::vector<PairBlock>& blocks = kinematics.layout().blocks();
  for (size_t c = 0; c < blocks.size(); ++c) {
    const PairBlock& blk = blocks[c];
    const ContactPair& pair = model.pairs[blk.pair];
    const Vec3 n_W = z.segment<3>(blk.offset + pair_index::kN).normalized();
    const Vec3 p_WA2 = z.segment<3>(blk.offset + pair_index::kA2);
    if (!n_W.allFinite() || !p_WA2.allFinite()) continue;  // a non-finite solution is rejected elsewhere
    // The plane in body 2's frame at the end of the step, then in the world at the start.
    const Pose X_BW_end = kinematics.EndPose(pair.body2, z).inverse();
    const Pose X_WB2_start = start.X_WB(model, pair.body2);
    const Vec3 n0_W = X_WB2_start.linear() * (X_BW_end.linear() * n_W);
    const Vec3 p0_W = X_WB2_start * (X_BW_end * p_WA2);
    if (UpperSupport(model.shape(pair.geom1), start.X_WB(model, pair.body1), n0_W) >= n0_W.dot(p0_W)) continue;
    if (detail) *detail = "pair '" + model.PairName(blk.pair) + "' crossed within the step from t = " + FormatNumber(start.t) + " s";
    return static_cast<int>(c);
  }
  return -1;
}

bool FindDivergence(const Model& model, const State& state, double max_speed, double max_angular_speed,
                    std::string* detail) {
  for (int k = 0; k < model.num_moving(); ++k) {
    const double speed = state.v_WB(k).norm(), angular = state.w_WB(k).norm();
    if (speed <= max_speed && angular <= max_angular_speed) continue;
    *detail = "body '" + model.bodies[model.moving_bodies[k]].name + "' reaches " + FormatNumber(speed) + " m/s, " +
              FormatNumber(angular) + " rad/s (limits " + FormatNumber(max_speed) + " m/s, " +
              FormatNumber(max_angular_speed) + " rad/s)";
    return true;
  }
  return false;
}

}  // namespace implicit_sim
