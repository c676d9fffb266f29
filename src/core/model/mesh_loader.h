// Collision meshes for the scene loader (internal to the core): a mesh URI resolved to a file, the file's vertices
// read with assimp, and their convex hull as a polytope shape.
#pragma once

#include <string>
#include <vector>

#include "implicit_sim/core/geometry/shapes.h"
#include "implicit_sim/core/model/urdf_loader.h"

namespace implicit_sim {
namespace loader {

// The file a mesh URI names: 'package://pkg/path' through options.resolve_package_uri, then a directory 'pkg' in (or
// up to two levels below) a directory of the ROS_PACKAGE_PATH environment variable; 'file:///abs/path'; an absolute
// path; a relative path against options.mesh_directory (the working directory when that is empty). Throws
// std::invalid_argument (naming the URI) when a package is not found, the file does not exist, lies outside
// options.mesh_roots (when set; one message for every such refusal) or is larger than options.max_mesh_bytes. Returns
// the canonical path when mesh_roots are set.
std::string ResolveMeshUri(const std::string& uri, const LoaderOptions& options);

// Every vertex of every mesh in the file (m, in the file's frame, node transforms applied). STL (binary and ASCII) and
// OBJ, and the other formats assimp reads. Throws std::invalid_argument (naming the file) when assimp cannot read it.
std::vector<Vec3> ReadMeshVertices(const std::string& path);

// The convex hull of a collision mesh scaled by `scale`, as a ShapeType::kIntersection of half-spaces with its
// vertices. The shape frame S sits at the centre of the hull's bounding box: X_BS is its pose in the mesh's frame.
// `warning` gets the one-line note for the user: the link, the file and the face count. Throws
// std::invalid_argument naming the link and the file for a mesh that is missing, unreadable or without volume.
ConvexShape MeshHullShape(const std::string& link, const std::string& uri, const Vec3& scale,
                          const LoaderOptions& options, std::string* warning);

}  // namespace loader
}  // namespace implicit_sim
