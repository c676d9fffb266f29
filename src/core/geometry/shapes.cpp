#include "implicit_sim/core/geometry/shapes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace implicit_sim {
namespace {


double SignedPow(double u, double p) { return std::copysign(std::pow(std::abs(u), p), u); }

}  // namespace

Inequality Inequality::HalfSpace(const Vec3& normal, double offset) {
  Inequality q;
  q.kind = Kind::kHalfSpace;
  q.normal = normal.normalized();
  q.offset = offset;
  return q;
}

Inequality Inequality::Sphere(double radius) {
  Inequality q;
  q.kind = Kind::kSphere;
  q.radii = Vec3::Constant(radius);
  return q;
}

Inequality Inequality::Ellipsoid(const Vec3& semi_axes) {
  Inequality q;
  q.kind = Kind::kEllipsoid;
  q.radii = semi_axes;
  return q;
}

Inequality Inequality::Superellipsoid(const Vec3& semi_axes, double exponent) {
  Inequality q;
  q.kind = Kind::kSuperellipsoid;
  q.radii = semi_axes;
  q.exponent = exponent;
  return q;
}

Inequality Inequality::InfiniteCylinder(double radius) {
  Inequality q;
  q.kind = Kind::kInfiniteCylinder;
  q.radii = Vec3::Constant(radius);
  return q;
}

// The scaled forms below all have |grad f| = 1 on the surface for a sphere and about 1 otherwise.
void Inequality::EvaluateLocal(const Vec3& x, double* f, Vec3* g, Mat3* H) const {
  switch (kind) {
    case Kind::kHalfSpace:  // f = n.x - c
      *f = normal.dot(x) - offset;
      if (g) *g = normal;
      if (H) H->setZero();
      return;
    case Kind::kSphere: {  // f = (|x|^2 - r^2) / (2 r)
      const double r = radii[0];
      *f = (x.squaredNorm() - r * r) / (2.0 * r);
      if (g) *g = x / r;
      if (H) *H = Mat3::Identity() / r;
      return;
    }
    case Kind::kEllipsoid: {  // f = s/2 (sum x_i^2 / a_i^2 - 1), s = smallest semi-axis
      const double s = radii.minCoeff();
      const Vec3 inv2 = radii.cwiseProduct(radii).cwiseInverse();
      *f = 0.5 * s * (x.cwiseProduct(x).dot(inv2) - 1.0);
      if (g) *g = s * x.cwiseProduct(inv2);
      if (H) *H = (s * inv2).asDiagonal();
      return;
    }
    case Kind::kSuperellipsoid: {  // f = s/p (sum |x_i / a_i|^p - 1)
      const double s = radii.minCoeff(), p = exponent;
      double sum = 0.0;
      Vec3 grad, hdiag;
      for (int i = 0; i < 3; ++i) {
        const double u = x[i] / radii[i];
        sum += std::pow(std::abs(u), p);
        grad[i] = s * SignedPow(u, p - 1.0) / radii[i];
        hdiag[i] = s * (p - 1.0) * std::pow(std::abs(u), p - 2.0) / (radii[i] * radii[i]);
      }
      *f = s / p * (sum - 1.0);
      if (g) *g = grad;
      if (H) *H = hdiag.asDiagonal();
      return;
    }
    case Kind::kInfiniteCylinder: {  // f = (x^2 + y^2 - r^2) / (2 r), axis z
      const double r = radii[0];
      *f = (x[0] * x[0] + x[1] * x[1] - r * r) / (2.0 * r);
      if (g) *g = Vec3(x[0] / r, x[1] / r, 0.0);
      if (H) *H = Vec3(1.0 / r, 1.0 / r, 0.0).asDiagonal();
      return;
    }
  }
  throw std::logic_error("Inequality: unknown kind");
}

double Inequality::Value(const Vec3& x_S) const {
  double f;
  EvaluateLocal(X_SP.inverse() * x_S, &f, nullptr, nullptr);
  return f;
}

void Inequality::Evaluate(const Vec3& x_S, double* f, Vec3* grad_S, Mat3* hess_S) const {
  const Mat3 R_SP = X_SP.linear();
  Vec3 g_P;
  Mat3 H_P;
  EvaluateLocal(R_SP.transpose() * (x_S - X_SP.translation()), f, grad_S ? &g_P : nullptr, hess_S ? &H_P : nullptr);
  if (grad_S) *grad_S = R_SP * g_P;
  if (hess_S) *hess_S = R_SP * H_P * R_SP.transpose();
}

double ConvexShape::BoundingRadius() const {
  switch (type) {
    case ShapeType::kSphere: return size[0];
    case ShapeType::kEllipsoid: return size.maxCoeff();
    case ShapeType::kSuperellipsoid:
    case ShapeType::kBox: return size.norm();
    case ShapeType::kCylinder:
    case ShapeType::kPrism: return std::hypot(size[0], size[2]);
    case ShapeType::kIntersection: {
      double radius = vertices.empty() ? std::numeric_limits<double>::infinity() : 0.0;
      for (const Vec3& v : vertices) radius = std::max(radius, v.norm());
      return radius;
    }
    default: return std::numeric_limits<double>::infinity();
  }
}

void ConvexShape::UnitDensityMassProperties(double* volume, Mat3* inertia_S) const {
  // Second moments of volume: m2[i] = integral of x_i^2 dV (m^5), so that I_xx = m2[1] + m2[2] (cyclic).
  double V = 0.0;
  Vec3 m2 = Vec3::Zero();
  const Vec3& a = size;
  switch (type) {
    case ShapeType::kSphere:
    case ShapeType::kEllipsoid:  // V = 4/3 pi abc, integral x^2 = V a^2 / 5
      V = 4.0 / 3.0 * kPi * a.prod();
      m2 = V / 5.0 * a.cwiseProduct(a);
      break;
    case ShapeType::kSuperellipsoid: {  // Dirichlet integrals over sum |u_i|^p <= 1, then x = a u
      const double p = exponent, g1 = std::tgamma(1.0 / p);
      const double unit_V = 8.0 * g1 * g1 * g1 / (p * p * p * std::tgamma(1.0 + 3.0 / p));
      const double unit_m2 = 8.0 * std::tgamma(3.0 / p) * g1 * g1 / (p * p * p * std::tgamma(1.0 + 5.0 / p));
      V = unit_V * a.prod();
      m2 = unit_m2 * a.prod() * a.cwiseProduct(a);
      break;
    }
    case ShapeType::kBox:  // V = 8 abc, integral x^2 = V a^2 / 3
      V = 8.0 * a.prod();
      m2 = V / 3.0 * a.cwiseProduct(a);
      break;
    case ShapeType::kCylinder: {  // radius a0, half length a2
      V = kPi * a[0] * a[0] * 2.0 * a[2];
      m2 = Vec3(V * a[0] * a[0] / 4.0, V * a[0] * a[0] / 4.0, V * a[2] * a[2] / 3.0);
      break;
    }
    case ShapeType::kPrism: {  // regular N-gon, circumradius R: area A = N R^2 sin(2 pi/N) / 2,
      const double R = a[0], L = a[2], c = 2.0 * kPi / sides;  // polar moment J = A R^2 (2 + cos c) / 6
      const double A = 0.5 * sides * R * R * std::sin(c);
      const double J = A * R * R * (2.0 + std::cos(c)) / 6.0;
      V = A * 2.0 * L;
      m2 = Vec3(0.5 * J * 2.0 * L, 0.5 * J * 2.0 * L, V * L * L / 3.0);
      break;
    }
    default:
      throw std::invalid_argument("shape '" + TypeName() +
                                  "' has no closed-form inertia: give the link an <inertial> element");
  }
  *volume = V;
  *inertia_S = Vec3(m2[1] + m2[2], m2[0] + m2[2], m2[0] + m2[1]).asDiagonal();
}

namespace {

// Volume, first moment (m^4) and second moment integral of x x^T dV (m^5) of a convex polytope given by half-spaces
// and its corners, about the origin of S: each face is a fan of triangles over its corners (taken in angle order
// about the face's mean corner), and each triangle with the reference point `o` spans a tetrahedron (the divergence
// theorem); for a tetrahedron o, p1, p2, p3 with q_i = p_i - o and signed volume V = det[q1 q2 q3] / 6, the
// second moment about o is V / 20 (sum q_i q_i^T + s s^T), s = q1 + q2 + q3.
void PolytopeMoments(const ConvexShape& shape, double* volume, Vec3* first, Mat3* second) {
  const std::vector<Vec3>& corners = shape.vertices;
  Vec3 o = Vec3::Zero();
  double extent = 0.0;
  for (const Vec3& v : corners) o += v / static_cast<double>(corners.size());
  for (const Vec3& v : corners) extent = std::max(extent, (v - o).norm());
  const double on_face = 1e-9 * extent;  // corners are intersections of the faces' planes: on them to round-off
  *volume = 0.0;
  Vec3 m1 = Vec3::Zero();  // about o
  Mat3 m2 = Mat3::Zero();
  std::vector<std::pair<double, int>> ring;
  for (const Inequality& face : shape.inequalities) {
    const Vec3 n = face.X_SP.linear() * face.normal;  // unit normal and offset in S
    const double offset = face.offset + n.dot(face.X_SP.translation());
    ring.clear();
    Vec3 centre = Vec3::Zero();
    for (int i = 0; i < static_cast<int>(corners.size()); ++i) {
      if (std::abs(n.dot(corners[i]) - offset) <= on_face) {
        ring.emplace_back(0.0, i);
        centre += corners[i];
      }
    }
    if (ring.size() < 3) continue;  // an edge or a corner: no area
    centre /= static_cast<double>(ring.size());
    const Vec3 u = n.unitOrthogonal(), w = n.cross(u);
    for (auto& [angle, i] : ring) angle = std::atan2((corners[i] - centre).dot(w), (corners[i] - centre).dot(u));
    std::sort(ring.begin(), ring.end());  // counter-clockwise seen from outside (along n)
    for (size_t k = 1; k + 1 < ring.size(); ++k) {
      const Vec3 q1 = corners[ring[0].second] - o, q2 = corners[ring[k].second] - o, q3 = corners[ring[k + 1].second] - o;
      const double V = q1.dot(q2.cross(q3)) / 6.0;
      const Vec3 sum = q1 + q2 + q3;
      *volume += V;
      m1 += V * sum / 4.0;
      m2 += V / 20.0 * (q1 * q1.transpose() + q2 * q2.transpose() + q3 * q3.transpose() + sum * sum.transpose());
    }
  }
  // Back to the origin of S: x = o + y.
  *first = m1 + *volume * o;
  *second = m2 + m1 * o.transpose() + o * m1.transpose() + *volume * o * o.transpose();
}

}  // namespace

void ConvexShape::UnitDensityMassProperties(double* volume, Vec3* centroid_S, Mat3* inertia_S) const {
  if (type != ShapeType::kIntersection || vertices.size() < 4) {
    *centroid_S = Vec3::Zero();
    UnitDensityMassProperties(volume, inertia_S);
    return;
  }
  Vec3 first;
  Mat3 second;
  PolytopeMoments(*this, volume, &first, &second);
  if (!(*volume > 0.0)) throw std::invalid_argument("a polytope of zero volume has no inertia");
  *centroid_S = first / *volume;
  const Mat3 about_centroid = second - *volume * *centroid_S * centroid_S->transpose();  // integral y y^T dV
  *inertia_S = about_centroid.trace() * Mat3::Identity() - about_centroid;
}

std::string ConvexShape::TypeName() const {
  switch (type) {
    case ShapeType::kHalfSpace: return "halfspace";
    case ShapeType::kSphere: return "sphere";
    case ShapeType::kEllipsoid: return "ellipsoid";
    case ShapeType::kSuperellipsoid: return "superellipsoid";
    case ShapeType::kBox: return "box";
    case ShapeType::kCylinder: return "cylinder";
    case ShapeType::kPrism: return "prism";
    case ShapeType::kIntersection: return "intersection";
  }
  return "unknown";
}

ConvexShape MakeHalfSpace() {
  ConvexShape s;
  s.type = ShapeType::kHalfSpace;
  s.inequalities = {Inequality::HalfSpace(Vec3::UnitZ(), 0.0)};
  return s;
}

ConvexShape MakeSphere(double radius) {
  ConvexShape s;
  s.type = ShapeType::kSphere;
  s.size = Vec3::Constant(radius);
  s.inequalities = {Inequality::Sphere(radius)};
  return s;
}

ConvexShape MakeEllipsoid(const Vec3& semi_axes) {
  ConvexShape s;
  s.type = ShapeType::kEllipsoid;
  s.size = semi_axes;
  s.inequalities = {Inequality::Ellipsoid(semi_axes)};
  return s;
}

ConvexShape MakeSuperellipsoid(const Vec3& semi_axes, double exponent) {
  ConvexShape s;
  s.type = ShapeType::kSuperellipsoid;
  s.size = semi_axes;
  s.exponent = exponent;
  s.inequalities = {Inequality::Superellipsoid(semi_axes, exponent)};
  return s;
}

ConvexShape MakeBox(const Vec3& half_extents) {
  ConvexShape s;
  s.type = ShapeType::kBox;
  s.size = half_extents;
  for (int i = 0; i < 3; ++i) {
    s.inequalities.push_back(Inequality::HalfSpace(Vec3::Unit(i), half_extents[i]));
    s.inequalities.push_back(Inequality::HalfSpace(-Vec3::Unit(i), half_extents[i]));
  }
  return s;
}

ConvexShape MakeCylinder(double radius, double half_length) {
  ConvexShape s;
  s.type = ShapeType::kCylinder;
  s.size = Vec3(radius, radius, half_length);
  s.inequalities = {Inequality::InfiniteCylinder(radius), Inequality::HalfSpace(Vec3::UnitZ(), half_length),
                    Inequality::HalfSpace(-Vec3::UnitZ(), half_length)};
  return s;
}

ConvexShape MakePrism(int sides, double circumradius, double half_length) {
  ConvexShape s;
  s.type = ShapeType::kPrism;
  s.sides = sides;
  s.size = Vec3(circumradius, circumradius, half_length);
  const double apothem = circumradius * std::cos(kPi / sides);
  for (int k = 0; k < sides; ++k) {  // face normals halfway between vertices at angles 2 pi k / N
    const double angle = (2.0 * k + 1.0) * kPi / sides;
    s.inequalities.push_back(Inequality::HalfSpace(Vec3(std::cos(angle), std::sin(angle), 0.0), apothem));
  }
  s.inequalities.push_back(Inequality::HalfSpace(Vec3::UnitZ(), half_length));
  s.inequalities.push_back(Inequality::HalfSpace(-Vec3::UnitZ(), half_length));
  return s;
}

}  // namespace implicit_sim
