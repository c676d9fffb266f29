// Convex shapes as intersections of implicit inequalities f_k(x) <= 0 (paper Section IV and Appendix).
//
// Every inequality is written in its own frame P, posed in the shape (body) frame S by X_SP. Each one is scaled so
// that |grad f| is about 1 on its surface: f is then roughly a signed distance in metres near the surface, which keeps
// the complementarity rows of the step well scaled (doc/method.md, pitfall 8).
#pragma once

#include <string>
#include <vector>

#include "implicit_sim/core/base/types.h"

namespace implicit_sim {

// One convex inequality f(x) <= 0 in its own frame P.
struct Inequality {
  enum class Kind { kHalfSpace, kSphere, kEllipsoid, kSuperellipsoid, kInfiniteCylinder };
  Kind kind = Kind::kHalfSpace;
  Pose X_SP = Pose::Identity();   // pose of the inequality frame P in the shape frame S
  // kHalfSpace: f = normal . x - offset (normal unit, m).
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  // kSphere: radius[0]; kEllipsoid / kSuperellipsoid: semi-axes (m); kInfiniteCylinder: radius[0], axis z.
  Vec3 radii = Vec3::Ones();
  double exponent = 2.0;          // kSuperellipsoid: f ~ sum |x_i / a_i|^exponent - 1, exponent >= 2

  static Inequality HalfSpace(const Vec3& normal, double offset);
  static Inequality Sphere(double radius);
  static Inequality Ellipsoid(const Vec3& semi_axes);
  static Inequality Superellipsoid(const Vec3& semi_axes, double exponent);
  static Inequality InfiniteCylinder(double radius);

  // f, grad f and hess f at a point x_S given in the shape frame S.
  double Value(const Vec3& x_S) const;
  void Evaluate(const Vec3& x_S, double* f, Vec3* grad_S, Mat3* hess_S) const;

 private:
  void EvaluateLocal(const Vec3& x_P, double* f, Vec3* grad_P, Mat3* hess_P) const;
};

// What the user asked for; kept for inertia, rviz markers and bounding radii.
enum class ShapeType { kHalfSpace, kSphere, kEllipsoid, kSuperellipsoid, kBox, kCylinder, kPrism, kIntersection };

// A convex body: the intersection of its inequalities, in the body frame.
struct ConvexShape {
  ShapeType type = ShapeType::kIntersection;
  std::vector<Inequality> inequalities;
  // Parameters of the named primitive (SI): sphere radius; ellipsoid/superellipsoid semi-axes; box half extents;
  // cylinder (radius, radius, half length); prism (circumradius, circumradius, half length) with `sides` sides.
  Vec3 size = Vec3::Zero();
  double exponent = 2.0;
  int sides = 0;
  Pose X_BS = Pose::Identity();   // pose of the shape frame S in the body frame B
  // kIntersection of half-spaces only (a polytope, e.g. a collision mesh's convex hull): its vertices in S (m). When
  // set, they give the exact support point and bounding radius; empty for every other shape.
  std::vector<Vec3> vertices;

  bool IsBounded() const { return type != ShapeType::kHalfSpace; }
  // Largest |x_S| of a point of the shape (m); +inf for a half-space or a general intersection without vertices.
  double BoundingRadius() const;
  // Volume (m^3) and inertia about the shape-frame origin for unit density (m^5), closed forms per primitive.
  // Throws std::invalid_argument for a shape without a closed form (half-space, general intersection).
  void UnitDensityMassProperties(double* volume, Mat3* inertia_S) const;
  // Volume (m^3), centroid in S (m) and inertia about the centroid in S's axes for unit density (m^5): the closed
  // forms above (centroid 0), or for a polytope with vertices (a mesh hull) its faces' divergence sum. Throws
  // std::invalid_argument for a half-space or a general intersection without vertices.
  void UnitDensityMassProperties(double* volume, Vec3* centroid_S, Mat3* inertia_S) const;
  std::string TypeName() const;
};

ConvexShape MakeHalfSpace();                          // z <= 0 in S (a ground plane with normal +z)
ConvexShape MakeSphere(double radius);
ConvexShape MakeEllipsoid(const Vec3& semi_axes);
ConvexShape MakeSuperellipsoid(const Vec3& semi_axes, double exponent);
ConvexShape MakeBox(const Vec3& half_extents);        // 6 half-spaces
ConvexShape MakeCylinder(double radius, double half_length);   // axis z: infinite cylinder and 2 caps
// Regular N-gon prism, axis z, circumradius r, a vertex on +x: N half-spaces and 2 caps.
ConvexShape MakePrism(int sides, double circumradius, double half_length);

}  // namespace implicit_sim
