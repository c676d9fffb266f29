#include "implicit_sim/core/step/problems/rattle_position.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "implicit_sim/core/step/rows/body_rows.h"
#include "implicit_sim/core/step/rows/contact_rows.h"
#include "implicit_sim/core/step/rows/joint_rows.h"

namespace implicit_sim {
namespace pi = pair_index;
namespace {

// An inequality counts as active at a closest point when its multiplier exceeds this share of the largest.
constexpr double kActiveShare = 1e-6;

// Whether the multipliers x[0 .. count) have the same active set as y[0 .. count).
bool SameActiveSet(const double* x, const double* y, int count) {
  double x_max = 0.0, y_max = 0.0;
  for (int k = 0; k < count; ++k) {
    x_max = std::max(x_max, x[k]);
    y_max = std::max(y_max, y[k]);
  }
  for (int k = 0; k < count; ++k) {
    if ((x[k] > kActiveShare * x_max) != (y[k] > kActiveShare * y_max)) return false;
  }
  return true;
}

// Principal curvatures below this share of 1 / (bounding radius) count as flat (a superellipsoid's face).
constexpr double kFlatCurvatureShare = 0.1;

// The principal curvatures (1/m) of the surface f = 0 with gradient g and Hessian H: the eigenvalues of the Hessian
// on the tangent plane over |g|, sorted by magnitude, the normal's zero left out.
Eigen::Vector2d PrincipalCurvatures(const Vec3& g, const Mat3& H) {
  const double g_norm = g.norm();
  if (!(g_norm > 0.0)) return Eigen::Vector2d::Zero();
  const Vec3 n = g / g_norm;
  const Mat3 P = Mat3::Identity() - n * n.transpose();
  const Eigen::SelfAdjointEigenSolver<Mat3> eigen(P * H * P / g_norm, Eigen::EigenvaluesOnly);
  Vec3 k = eigen.eigenvalues().cwiseAbs();
  std::sort(k.data(), k.data() + 3);
  return Eigen::Vector2d(k[1], k[2]);
}

// The feature of `shape` at its point p_B (body frame) with multipliers x (one per inequality).
ContactFeature FeatureAt(const ConvexShape& shape, const Vec3& p_B, const double* x) {
  const int count = static_cast<int>(shape.inequalities.size());
  double x_max = 0.0;
  for (int k = 0; k < count; ++k) x_max = std::max(x_max, x[k]);
  const double bound = shape.BoundingRadius();
  const double flat_curvature = std::isfinite(bound) && bound > 0.0 ? kFlatCurvatureShare / bound : 0.0;
  const Vec3 p_S = shape.X_BS.inverse() * p_B;
  int planes = 0, flat_directions = -1;
  ContactFeature feature;
  for (int k = 0; k < count; ++k) {
    if (x[k] <= kActiveShare * x_max) continue;
    if (shape.inequalities[k].kind == Inequality::Kind::kHalfSpace) {
      ++planes;
      continue;
    }
    double f;
    Vec3 g;
    Mat3 H;
    shape.inequalities[k].Evaluate(p_S, &f, &g, &H);
    const Eigen::Vector2d curvature = PrincipalCurvatures(g, H);
    const int flat = (curvature[0] < flat_curvature) + (curvature[1] < flat_curvature);
    if (shape.inequalities[k].kind == Inequality::Kind::kSuperellipsoid) {
      // Strictly convex: its closest point is unique even on the flat middle of a face, but it travels far for a
      // small tilt there, so a flat patch is allowed only a drift of the body's size (no radius above the bound).
      flat_directions = 0;
      feature.radius = std::max(feature.radius, flat > 0 ? bound : 1.0 / std::max(curvature[0], flat_curvature));
      continue;
    }
    flat_directions = flat_directions < 0 ? flat : std::min(flat_directions, flat);
    if (flat_curvature > 0.0) feature.radius = std::max(feature.radius, 1.0 / std::max(curvature[0], flat_curvature));
  }
  feature.dimension = std::max(0, (flat_directions < 0 ? 3 : flat_directions) - planes);
  return feature;
}

}  // namespace

// Only a pair closed at the start has a start frame worth acting along: for an impact (a pair apart at the start,
// closed at the end) the start-of-step closest points say nothing about where the bodies meet, so the impulse takes
// the end frame, as in the paper's step.
void RattlePositionProblem::SetStartFrames(const Eigen::VectorXd& z_start, const std::vector<char>& known) {
  frame_z_ = z_start;
  const std::vector<PairBlock>& blocks = layout().blocks();
  use_start_frame_.resize(blocks.size());
  drift_limit_.resize(blocks.size());
  for (size_t c = 0; c < blocks.size(); ++c) {
    const PairBlock& blk = blocks[c];
    const bool closed =
        IsClosed(z_start[blk.offset + pi::kD], z_start[blk.normal_force()], kinematics().force_scale());
    use_start_frame_[c] = known[c] && closed;
    if (!use_start_frame_[c]) continue;
    const ContactPair& pair = layout().model().pairs[blk.pair];
    const ConvexShape& shape1 = layout().model().shape(pair.geom1);
    const ConvexShape& shape2 = layout().model().shape(pair.geom2);
    const ContactFeature feature1 = StartFeature(shape1, blk.body1, blk.offset + pi::kA1, blk.offset + pi::kAlpha);
    const ContactFeature feature2 = StartFeature(shape2, blk.body2, blk.offset + pi::kA2, blk.beta());
    // Where the two features could touch along a line or a patch (a box flat on the ground, a cylinder on its side),
    // the closest points are not fixed by the geometry, so the start levers are arbitrary: the end frame is used.
    use_start_frame_[c] = feature1.dimension + feature2.dimension < 3;
    drift_limit_[c] = {DriftLimit(shape1, feature1), DriftLimit(shape2, feature2)};
  }
  chosen_start_frame_ = use_start_frame_;
}

double RattlePositionProblem::DriftLimit(const ConvexShape& shape, const ContactFeature& feature) const {
  const double bound = shape.BoundingRadius();
  // A half-space: its contact point may travel anywhere.
  if (!std::isfinite(bound)) return std::numeric_limits<double>::infinity();
  return kLeverDriftShare * std::max(bound, feature.radius);
}

Vec3 RattlePositionProblem::StartPointInBody(int local, int point) const {
  const BodyStart& start = kinematics().start(local);
  return start.R0.transpose() * (frame_z_.segment<3>(point) - start.p0);
}

ContactFeature RattlePositionProblem::StartFeature(const ConvexShape& shape, int local, int point,
                                                  int multipliers) const {
  return FeatureAt(shape, StartPointInBody(local, point), &frame_z_[multipliers]);
}

bool RattlePositionProblem::LeverStayed(const Eigen::VectorXd& z, int c) const {
  const PairBlock& blk = layout().blocks()[c];
  const int local[2] = {blk.body1, blk.body2};
  const int point[2] = {blk.offset + pi::kA1, blk.offset + pi::kA2};
  for (int i = 0; i < 2; ++i) {
    if (!std::isfinite(drift_limit_[c][i])) continue;
    const Pose X_WB1 = kinematics().EndPose(layout().bodies()[local[i]], z);
    const Vec3 p_B0 = StartPointInBody(local[i], point[i]);
    const Vec3 p_B1 = X_WB1.linear().transpose() * (z.segment<3>(point[i]) - X_WB1.translation());
    if ((p_B1 - p_B0).norm() > drift_limit_[c][i]) return false;
  }
  return true;
}

int RattlePositionProblem::FallBackWhereFramesMoved(const Eigen::VectorXd& z) {
  frames_before_fallback_ = use_start_frame_;
  int count = 0;
  const std::vector<PairBlock>& blocks = layout().blocks();
  for (size_t c = 0; c < blocks.size(); ++c) {
    const PairBlock& blk = blocks[c];
    if (!use_start_frame_[c]) continue;
    const int first = blk.offset + pi::kAlpha;
    if (SameActiveSet(&z[first], &frame_z_[first], blk.k1) &&
        SameActiveSet(&z[blk.beta()], &frame_z_[blk.beta()], blk.k2) &&
        LeverStayed(z, static_cast<int>(c))) {
      continue;
    }
    use_start_frame_[c] = 0;
    ++count;
  }
  return count;
}

int RattlePositionProblem::UseFallbackFrames() {
  int count = 0;
  for (char& use : use_start_frame_) {
    count += use;
    use = 0;
  }
  return count;
}

int RattlePositionProblem::RestoreFrames() {
  int count = 0;
  for (size_t c = 0; c < use_start_frame_.size(); ++c) {
    count += chosen_start_frame_[c] && !use_start_frame_[c];
    use_start_frame_[c] = chosen_start_frame_[c];
  }
  return count;
}

bool RattlePositionProblem::HasFallbackFrames() const {
  return std::find(use_start_frame_.begin(), use_start_frame_.end(), 1) != use_start_frame_.end();
}

void RattlePositionProblem::SeedVelocities(const State& state, Eigen::VectorXd* z) const {
  StepProblem::SeedVelocities(state, z);
  if (!layout().blocks().empty() || !layout().joints().empty()) return;
  const double h = kinematics().h();
  for (size_t i = 0; i < layout().slots().size(); ++i) {
    const Body& body = layout().model().bodies[layout().bodies()[layout().slot_body(static_cast<int>(i))]];
    const int row = static_cast<int>(6 * i);
    const Vec3 f_ext = kinematics().ExternalForce(static_cast<int>(i));
    for (int k = 0; k < 3; ++k) {
      if (!layout().locked_rows()[row + k]) (*z)[row + k] += 0.5 * h * f_ext[k] / body.mass;
    }
  }
}

void RattlePositionProblem::AddRows(const RowContext& ctx) const {
  AddHalfStepMomentumRows(ctx);
  AddJointRows(ctx, 0.5, drives_);
  for (size_t c = 0; c < layout().blocks().size(); ++c) {
    ContactRowOptions options;
    options.regular_separated_friction = regular_separated_friction_;
    if (use_start_frame_[c]) options.start_frame = &frame_z_;
    AddContactRows(ctx, static_cast<int>(c), options);
  }
}

}  // namespace implicit_sim
