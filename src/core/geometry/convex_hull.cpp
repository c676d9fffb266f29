#include "convex_hull.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <locale>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <libqhull_r/qhull_ra.h>

namespace implicit_sim {
namespace {

// Thinnest spread (m) of the points across their flattest direction, relative to their extent, below which they are
// taken as coplanar.
constexpr double kFlatRatio = 1e-9;
constexpr int kMaxMergeDoublings = 30;

void CheckSpansAVolume(const std::vector<Vec3>& points) {
  if (points.size() < 4) {
    throw std::invalid_argument("fewer than 4 vertices (" + std::to_string(points.size()) + "): no volume");
  }
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : points) {
    if (!p.allFinite()) throw std::invalid_argument("a vertex is not finite (NaN or infinite coordinate)");
    mean += p;
  }
  mean /= static_cast<double>(points.size());
  Mat3 scatter = Mat3::Zero();  // m^2
  for (const Vec3& p : points) scatter += (p - mean) * (p - mean).transpose();
  const Vec3 spread = Eigen::SelfAdjointEigenSolver<Mat3>(scatter).eigenvalues().cwiseMax(0.0).cwiseSqrt();
  if (!(spread[0] > kFlatRatio * spread[2])) {
    throw std::invalid_argument(
        "the vertices are coplanar or collinear (fewer than 4 non-coplanar vertices): no volume");
  }
}

// Runs qhull with `options` and reads its faces and vertices. Throws std::invalid_argument with qhull's message.
ConvexHull RunQhull(const std::vector<Vec3>& points, const std::string& options) {
  std::vector<coordT> coordinates;
  coordinates.reserve(3 * points.size());
  for (const Vec3& p : points) coordinates.insert(coordinates.end(), {p.x(), p.y(), p.z()});
  char* error_text = nullptr;
  size_t error_size = 0;
  FILE* errors = open_memstream(&error_text, &error_size);
  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, errors);
  std::string command = "qhull " + options;
  const int exit_code = qh_new_qhull(qh, 3, static_cast<int>(points.size()), coordinates.data(), False,
                                     command.data(), nullptr, errors);
  ConvexHull hull;
  if (exit_code == 0) {
    facetT* facet;
    FORALLfacets {
      hull.faces.push_back({Vec3(facet->normal[0], facet->normal[1], facet->normal[2]), -facet->offset});
    }
    vertexT* vertex;
    FORALLvertices { hull.vertices.emplace_back(vertex->point[0], vertex->point[1], vertex->point[2]); }
  }
  qh_freeqhull(qh, !qh_ALL);
  int still_long = 0, total_long = 0;
  qh_memfreeshort(qh, &still_long, &total_long);
  std::fclose(errors);
  std::string message = error_text ? error_text : "";
  std::free(error_text);
  if (exit_code != 0) {
    message = message.substr(0, message.find('\n'));
    throw std::invalid_argument("qhull failed (" + (message.empty() ? "exit " + std::to_string(exit_code) : message) +
                                ")");
  }
  return hull;
}

// Moves every face out to the farthest point, so that the faces contain all points exactly (to rounding).
void TouchFarthestPoints(const std::vector<Vec3>& points, ConvexHull* hull) {
  for (HullFace& face : hull->faces) {
    face.normal.normalize();
    double farthest = -1e300;
    for (const Vec3& p : points) farthest = std::max(farthest, face.normal.dot(p));
    face.offset = farthest;
  }
}

// The corners of the polytope bounded by `faces`: every point where three faces meet that no face excludes (within
// `tolerance`, m), without repeats. O(faces^4), used for at most the capped face count.
std::vector<Vec3> PolytopeVertices(const std::vector<HullFace>& faces, double tolerance) {
  std::vector<Vec3> corners;
  const size_t n = faces.size();
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      for (size_t k = j + 1; k < n; ++k) {
        Mat3 normals;
        normals << faces[i].normal.transpose(), faces[j].normal.transpose(), faces[k].normal.transpose();
        if (std::abs(normals.determinant()) < 1e-9) continue;
        const Vec3 p = normals.inverse() * Vec3(faces[i].offset, faces[j].offset, faces[k].offset);
        bool inside = true;
        for (const HullFace& face : faces) inside = inside && face.normal.dot(p) <= face.offset + tolerance;
        bool repeated = false;
        for (const Vec3& c : corners) repeated = repeated || (c - p).norm() <= tolerance;
        if (inside && !repeated) corners.push_back(p);
      }
    }
  }
  return corners;
}

}  // namespace

ConvexHull ComputeConvexHull(const std::vector<Vec3>& points, int max_faces) {
  CheckSpansAVolume(points);
  ConvexHull hull = RunQhull(points, "C-0");
  hull.coplanar_faces = static_cast<int>(hull.faces.size());
  Vec3 lo = points.front(), hi = points.front();
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  double radius = 1e-4 * (hi - lo).norm();  // m
  for (int k = 0; k < kMaxMergeDoublings && static_cast<int>(hull.faces.size()) > max_faces; ++k, radius *= 2.0) {
    std::ostringstream option;
    option.imbue(std::locale::classic());
    option << "C-" << std::setprecision(17) << radius;
    ConvexHull merged = RunQhull(points, option.str());
    merged.coplanar_faces = hull.coplanar_faces;
    merged.merge_radius = radius;
    hull = merged;
  }
  TouchFarthestPoints(points, &hull);
  // Faces moved out meet at new corners: the polytope's own vertices replace the points' hull vertices.
  if (hull.merge_radius > 0.0) hull.vertices = PolytopeVertices(hull.faces, 1e-9 * (hi - lo).norm());
  return hull;
}

}  // namespace implicit_sim
