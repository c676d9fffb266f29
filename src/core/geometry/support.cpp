#include "implicit_sim/core/geometry/support.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace implicit_sim {
namespace {


// Support point in the shape frame S for a direction u_S, for the primitives built by the Make* functions.
bool SupportPointInShapeFrame(const ConvexShape& shape, const Vec3& u, Vec3* p) {
  const Vec3& a = shape.size;
  switch (shape.type) {
    case ShapeType::kSphere:
      *p = a[0] * u;
      return true;
    case ShapeType::kEllipsoid: {  // x = A^2 u / |A u|
      const Vec3 au = a.cwiseProduct(u);
      *p = a.cwiseProduct(au) / au.norm();
      return true;
    }
    case ShapeType::kSuperellipsoid: {  // Hoelder: y_i = sign(w_i) |w_i|^(q-1) / |w|_q^(q-1), w = a u, x = a y
      const double q = shape.exponent / (shape.exponent - 1.0);
      const Vec3 w = a.cwiseProduct(u);
      double norm_q = 0.0;
      for (int i = 0; i < 3; ++i) norm_q += std::pow(std::abs(w[i]), q);
      norm_q = std::pow(norm_q, 1.0 / q);
      for (int i = 0; i < 3; ++i) {
        (*p)[i] = a[i] * std::copysign(std::pow(std::abs(w[i]) / norm_q, q - 1.0), w[i]);
      }
      return true;
    }
    case ShapeType::kBox:
      *p = a.cwiseProduct(u.unaryExpr([](double x) { return x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0; }));
      return true;
    case ShapeType::kCylinder: {  // radius a0, half length a2, axis z
      const double radial = std::hypot(u[0], u[1]);
      const double z = u[2] > 0.0 ? a[2] : u[2] < 0.0 ? -a[2] : 0.0;
      *p = radial > 1e-15 ? Vec3(a[0] * u[0] / radial, a[0] * u[1] / radial, z) : Vec3(0.0, 0.0, z);
      return true;
    }
    case ShapeType::kPrism: {  // the best of the 2N vertices
      double best = -1e300;
      for (int k = 0; k < shape.sides; ++k) {
        const double angle = 2.0 * kPi * k / shape.sides;
        const Vec3 v(a[0] * std::cos(angle), a[0] * std::sin(angle), u[2] >= 0.0 ? a[2] : -a[2]);
        if (u.dot(v) > best) {
          best = u.dot(v);
          *p = v;
        }
      }
      return true;
    }
    case ShapeType::kIntersection: {  // a polytope with known vertices: the best vertex
      if (shape.vertices.empty()) return false;
      double best = -1e300;
      for (const Vec3& v : shape.vertices) {
        if (u.dot(v) > best) {
          best = u.dot(v);
          *p = v;
        }
      }
      return true;
    }
    default:
      return false;
  }
}

// max { u . x : x in the posed shape } (m): the closed-form support point, else the oracle's support value.
double Support(const ConvexShape& shape, const Pose& X_WB, const Vec3& u_W) {
  Vec3 p_W;
  return SupportPoint(shape, X_WB, u_W, &p_W) ? u_W.dot(p_W) : SupportValue(shape, X_WB, u_W);
}

// support1(-n) + support2(n) (m): how far body 1 must move along the unit n (pointing from body 2 towards body 1) to
// clear body 2. Its positive part bounds the penetration depth from above for any n; a negative value is a
// separation along n.
double CrossingAlong(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                     const Vec3& n_W) {
  return Support(shape1, X_WB1, -n_W) + Support(shape2, X_WB2, n_W);
}

// c(n) at the normals of both bodies at the distance oracle's closest points, the smaller (m). The oracle's distance
// alone does not decide: it reports overlapping bodies at about its own tolerance, not 0; for bodies it finds apart
// the normals give about minus their distance.
double OracleCrossing(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2) {
  const ClosestPointsResult cp = ComputeClosestPoints(shape1, X_WB1, shape2, X_WB2);
  Vec3 n1_W = -Vec3::UnitZ(), n2_W = Vec3::UnitZ();
  double grad_norm;
  MostActiveInequality(shape1, X_WB1, cp.p_W1, &n1_W, &grad_norm);
  MostActiveInequality(shape2, X_WB2, cp.p_W2, &n2_W, &grad_norm);
  return std::min(CrossingAlong(shape1, X_WB1, shape2, X_WB2, n2_W),
                  CrossingAlong(shape1, X_WB1, shape2, X_WB2, -n1_W));
}

}  // namespace

bool SupportPoint(const ConvexShape& shape, const Pose& X_WB, const Vec3& u_W, Vec3* p_W) {
  const Pose X_WS = X_WB * shape.X_BS;
  Vec3 p_S;
  if (!SupportPointInShapeFrame(shape, X_WS.linear().transpose() * u_W.normalized(), &p_S)) return false;
  *p_W = X_WS * p_S;
  return true;
}

bool ClosedFormClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                             const Pose& X_WB2, ClosestPointsResult* result) {
  if (shape1.type == ShapeType::kSphere && shape2.type == ShapeType::kSphere) {
    const Vec3 c1 = X_WB1 * shape1.X_BS.translation(), c2 = X_WB2 * shape2.X_BS.translation();
    const double centre_distance = (c1 - c2).norm();
    if (centre_distance < 1e-12) return false;
    const Vec3 n = (c1 - c2) / centre_distance;
    result->p_W1 = c1 - shape1.size[0] * n;
    result->p_W2 = c2 + shape2.size[0] * n;
    result->distance = centre_distance - shape1.size[0] - shape2.size[0];
    result->solved = true;
    return true;
  }
  const bool first_is_plane = shape1.type == ShapeType::kHalfSpace;
  if (!first_is_plane && shape2.type != ShapeType::kHalfSpace) return false;
  const ConvexShape& plane = first_is_plane ? shape1 : shape2;
  const ConvexShape& other = first_is_plane ? shape2 : shape1;
  const Pose X_WP = (first_is_plane ? X_WB1 : X_WB2) * plane.X_BS * plane.inequalities.front().X_SP;
  const Inequality& q = plane.inequalities.front();
  const Vec3 n_W = X_WP.linear() * q.normal;          // outward normal of the half-space
  const Vec3 q_W = X_WP * (q.offset * q.normal);      // a point of its plane
  Vec3 deepest;
  if (!SupportPoint(other, first_is_plane ? X_WB2 : X_WB1, -n_W, &deepest)) return false;
  const double distance = n_W.dot(deepest - q_W);
  const Vec3 on_plane = deepest - distance * n_W;
  result->p_W1 = first_is_plane ? on_plane : deepest;
  result->p_W2 = first_is_plane ? deepest : on_plane;
  result->distance = distance;
  result->solved = true;
  return true;
}

CrossingDescent DescendCrossing(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                const Pose& X_WB2, double stop_below, int max_steps) {
  CrossingDescent d;
  // c(n) and its gradient in n, p2(n) - p1(-n), into `at`.
  const auto evaluate = [&](const Vec3& n_W, CrossingDescent* at) {
    at->n_W = n_W;
    const bool ok = SupportPoint(shape1, X_WB1, -n_W, &at->p_W1) && SupportPoint(shape2, X_WB2, n_W, &at->p_W2);
    at->value = ok ? n_W.dot(at->p_W2 - at->p_W1) : std::numeric_limits<double>::infinity();
  };
  const Vec3 line_W = X_WB1 * shape1.X_BS.translation() - X_WB2 * shape2.X_BS.translation();
  evaluate(line_W.norm() > 0.0 ? Vec3(line_W.normalized()) : Vec3::UnitZ(), &d);
  const double first_step = 1.0 / (shape1.BoundingRadius() + shape2.BoundingRadius());  // rad per m of gradient
  double step = first_step;
  CrossingDescent trial;
  for (int k = 0; k < max_steps && std::isfinite(d.value) && d.value >= stop_below; ++k) {
    const Vec3 gradient_W = d.p_W2 - d.p_W1;
    const Vec3 tangential_W = gradient_W - gradient_W.dot(d.n_W) * d.n_W;
    // Stationary, or stalled by rounding (c no longer decreases along the gradient) close to it.
    if (tangential_W.norm() <= 1e-9 || (step < 1e-12 * first_step && tangential_W.norm() <= 1e-7)) {
      d.stationary = true;
      break;
    }
    evaluate((d.n_W - step * tangential_W).normalized(), &trial);
    if (trial.value < d.value) {
      d = trial;
      step *= 1.5;  // a step that lowers c is lengthened, one that does not is halved
    } else {
      step *= 0.5;
    }
  }
  return d;
}

bool DescentClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                          bool require_stationary, ClosestPointsResult* result) {
  // Strictly convex with a Lipschitz support map: the descent converges (a superellipsoid's support map is not
  // Lipschitz where a coordinate of A u vanishes, and a box's or a cylinder's is not unique).
  const auto smooth = [](const ConvexShape& shape) {
    return shape.type == ShapeType::kSphere || shape.type == ShapeType::kEllipsoid;
  };
  if (!smooth(shape1) || !smooth(shape2)) return false;
  const CrossingDescent d =
      DescendCrossing(shape1, X_WB1, shape2, X_WB2, -std::numeric_limits<double>::infinity(), 1000);
  if (require_stationary && !d.stationary) return false;
  result->solved = std::isfinite(d.value);
  result->distance = std::max(0.0, -d.value);
  result->p_W1 = d.p_W1;
  result->p_W2 = d.p_W2;
  return true;
}

ClosestPointsResult FindClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                      const Pose& X_WB2) {
  ClosestPointsResult result;
  if (ClosedFormClosestPoints(shape1, X_WB1, shape2, X_WB2, &result)) return result;
  if (DescentClosestPoints(shape1, X_WB1, shape2, X_WB2, /*require_stationary=*/true, &result)) return result;
  return ComputeClosestPoints(shape1, X_WB1, shape2, X_WB2);
}

// See support.h.
int MostActiveInequality(const ConvexShape& shape, const Pose& X_WB, const Vec3& p_W, Vec3* normal_W,
                         double* grad_norm) {
  const Pose X_WS = X_WB * shape.X_BS;
  const Vec3 x_S = X_WS.inverse() * p_W;
  int best = 0;
  double best_f = -1e300;
  for (int k = 0; k < static_cast<int>(shape.inequalities.size()); ++k) {
    double f;
    Vec3 g_S;
    shape.inequalities[k].Evaluate(x_S, &f, &g_S, nullptr);
    if (f > best_f && g_S.norm() > 1e-12) {
      best_f = f;
      best = k;
      *grad_norm = g_S.norm();
      *normal_W = X_WS.linear() * g_S / *grad_norm;
    }
  }
  return best;
}

void SeedNormalConeMultipliers(const ConvexShape& shape, const Pose& X_WB, const Vec3& p_W, const Vec3& direction_W,
                               double* multipliers) {
  constexpr int kMaxActive = 8;
  const Pose X_WS = X_WB * shape.X_BS;
  const Vec3 x_S = X_WS.inverse() * p_W;
  const int count = static_cast<int>(shape.inequalities.size());
  double f_k;
  Vec3 g_W[kMaxActive];
  int index[kMaxActive], active = 0;
  double f_max = -1e300;
  for (int k = 0; k < count; ++k) {
    multipliers[k] = 0.0;
    double value;
    shape.inequalities[k].Evaluate(x_S, &value, nullptr, nullptr);
    f_max = std::max(f_max, value);
  }
  for (int k = 0; k < count && active < kMaxActive; ++k) {
    Vec3 g_S;
    shape.inequalities[k].Evaluate(x_S, &f_k, &g_S, nullptr);
    if (f_k < f_max - 1e-5 || g_S.norm() < 1e-12) continue;
    g_W[active] = X_WS.linear() * g_S;
    index[active++] = k;
  }
  // Every subset of one to three active gradients: least squares, kept if non-negative and the best fit so far.
  double best_residual = INFINITY, best_m[3] = {0.0, 0.0, 0.0};
  int best_set[3] = {-1, -1, -1}, best_size = 0;
  const auto try_subset = [&](const int* members, int size) {
    Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 3> G(3, size);
    for (int i = 0; i < size; ++i) G.col(i) = g_W[members[i]];
    const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> m = G.colPivHouseholderQr().solve(direction_W);
    if (!m.allFinite() || m.minCoeff() < 0.0) return;
    const double residual = (G * m - direction_W).norm();
    if (!(residual < best_residual - 1e-12)) return;
    best_residual = residual;
    best_size = size;
    for (int i = 0; i < size; ++i) {
      best_set[i] = members[i];
      best_m[i] = m[i];
    }
  };
  for (int a = 0; a < active; ++a) {
    const int one[1] = {a};
    try_subset(one, 1);
    for (int b = a + 1; b < active; ++b) {
      const int two[2] = {a, b};
      try_subset(two, 2);
      for (int c = b + 1; c < active; ++c) {
        const int three[3] = {a, b, c};
        try_subset(three, 3);
      }
    }
  }
  if (best_size == 0) {  // no non-negative combination: the most active inequality carries the normal
    Vec3 normal;
    double grad_norm = 1.0;
    multipliers[MostActiveInequality(shape, X_WB, p_W, &normal, &grad_norm)] = direction_W.norm() / grad_norm;
    return;
  }
  for (int i = 0; i < best_size; ++i) multipliers[index[best_set[i]]] = best_m[i];
}

double PenetrationBound(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                        double tolerance) {
  ClosestPointsResult cp;
  if (ClosedFormClosestPoints(shape1, X_WB1, shape2, X_WB2, &cp)) return std::max(0.0, -cp.distance);
  const double descent = DescendCrossing(shape1, X_WB1, shape2, X_WB2, -tolerance, 200).value;
  if (descent <= tolerance) return std::max(0.0, descent);
  return std::max(0.0, std::min(descent, OracleCrossing(shape1, X_WB1, shape2, X_WB2)));
}

}  // namespace implicit_sim
