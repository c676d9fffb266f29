#include "mesh_loader.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <locale>
#include <sstream>
#include <stdexcept>

#include <assimp/Importer.hpp>
#include <assimp/commonMetaData.h>
#include <assimp/scene.h>

#include "implicit_sim/core/base/file_sandbox.h"
#include "geometry/convex_hull.h"
#include "loader_util.h"

namespace implicit_sim {
namespace loader {
namespace {

namespace fs = std::filesystem;

bool StartsWith(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

// A directory named `package` in `root`, or one with a package.xml up to two levels below it (catkin workspaces nest
// packages in folders).
std::string FindPackageIn(const std::string& root, const std::string& package) {
  std::error_code ec;
  if (fs::is_directory(fs::path(root) / package, ec)) return (fs::path(root) / package).string();
  fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    if (it->is_directory(ec) && it->path().filename() == package && fs::exists(it->path() / "package.xml", ec)) {
      return it->path().string();
    }
    if (it.depth() >= 2) it.disable_recursion_pending();
  }
  return "";
}

std::string ResolvePackageUri(const std::string& uri, const LoaderOptions& options) {
  if (options.resolve_package_uri) {
    const std::string path = options.resolve_package_uri(uri);
    if (!path.empty()) return path;
  }
  const std::string rest = uri.substr(std::string("package://").size());
  const size_t slash = rest.find('/');
  const std::string package = rest.substr(0, slash), inside = slash == std::string::npos ? "" : rest.substr(slash + 1);
  if (package.empty()) Fail("mesh URI '" + uri + "' names no package");
  const char* search_path = std::getenv("ROS_PACKAGE_PATH");
  std::istringstream roots(search_path ? search_path : "");
  std::string root;
  while (std::getline(roots, root, ':')) {
    if (root.empty()) continue;
    const std::string directory = FindPackageIn(root, package);
    if (!directory.empty()) return (fs::path(directory) / inside).string();
  }
  Fail("mesh URI '" + uri + "': package '" + package + "' not found (ROS_PACKAGE_PATH='" +
       (search_path ? search_path : "") + "', and no resolver in LoaderOptions found it)");
}

void CollectVertices(const aiScene& scene, const aiNode& node, const aiMatrix4x4& X_FP, std::vector<Vec3>* out) {
  const aiMatrix4x4 X_FN = X_FP * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = X_FN * mesh.mVertices[v];
      out->emplace_back(p.x, p.y, p.z);
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) CollectVertices(scene, *node.mChildren[c], X_FN, out);
}

std::string FormatLength(double metres) {
  std::ostringstream text;
  text.imbue(std::locale::classic());
  text << std::setprecision(3) << metres;
  return text.str();
}

// The cache key of a mesh file: its bytes' FNV-1a hash and size, the scale and the face cap.
MeshHullCache::Key CacheKey(const std::string& path, const Vec3& scale, int max_faces) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail("mesh file '" + path + "' cannot be opened");
  MeshHullCache::Key key;
  uint64_t hash = 1469598103934665603ull;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof(buffer)) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      hash = (hash ^ static_cast<unsigned char>(buffer[i])) * 1099511628211ull;
    }
    key.size += static_cast<uint64_t>(in.gcount());
  }
  key.content_hash = hash;
  key.scale_x = scale.x();
  key.scale_y = scale.y();
  key.scale_z = scale.z();
  key.max_faces = max_faces;
  return key;
}

}  // namespace

std::string ResolveMeshUri(const std::string& uri, const LoaderOptions& options) {
  std::string path;
  if (StartsWith(uri, "package://")) {
    path = ResolvePackageUri(uri, options);
  } else if (StartsWith(uri, "file://")) {
    path = uri.substr(std::string("file://").size());
  } else if (uri.find("://") != std::string::npos) {
    Fail("mesh URI '" + uri + "': unknown scheme (allowed: package://, file://, a path)");
  } else if (fs::path(uri).is_absolute() || options.mesh_directory.empty()) {
    path = uri;
  } else {
    path = (fs::path(options.mesh_directory) / uri).string();
  }
  std::error_code ec;
  if (!options.mesh_sandbox.Unrestricted()) {
    FileSandbox sandbox = options.mesh_sandbox;
    if (StartsWith(uri, "package://")) {  // a package URI stays inside its package
      sandbox = FileSandbox();
      sandbox.roots = {ResolvePackageUri(uri.substr(0, uri.find('/', std::string("package://").size())), options)};
    }
    path = sandbox.Allowed(path);
    if (path.empty()) {
      Fail("mesh URI '" + uri + "': no readable mesh file there inside what meshes may be read from (" +
           options.mesh_sandbox.Describe() + "; a package:// URI must stay inside its package)");
    }
  } else if (!fs::is_regular_file(path, ec)) {
    Fail("mesh file '" + path + "' (from '" + uri + "') does not exist");
  }
  const uintmax_t bytes = fs::file_size(path, ec);
  if (!ec && bytes > options.max_mesh_bytes) {
    Fail("mesh file '" + path + "' (from '" + uri + "') has " + std::to_string(bytes) + " bytes, over the limit of " +
         std::to_string(options.max_mesh_bytes) + " (LoaderOptions::max_mesh_bytes)");
  }
  return path;
}

std::vector<Vec3> ReadMeshVertices(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, 0);
  if (!scene || !scene->mRootNode || scene->mNumMeshes == 0) {
    Fail("mesh file '" + path + "' cannot be read (" +
         (scene ? std::string("no mesh in it") : std::string(importer.GetErrorString())) + ")");
  }
  // Assimp puts a Collada file's <unit meter> and its <up_axis> into the root node: the file's up axis becomes +y.
  // URDF frames have +z up, so a Collada scene is turned back by +90 deg about x (y up -> z up); a Z_UP file's
  // coordinates then come out as written, a Y_UP (or X_UP) file's up axis becomes +z, and units become metres.
  aiMatrix4x4 X_MR;  // the mesh frame M from assimp's root frame R
  aiString format;
  if (scene->mMetaData && scene->mMetaData->Get(AI_METADATA_SOURCE_FORMAT, format) &&
      std::string(format.C_Str()).rfind("Collada", 0) == 0) {
    X_MR = aiMatrix4x4(1, 0, 0, 0,  0, 0, -1, 0,  0, 1, 0, 0,  0, 0, 0, 1);  // exact: (x, y, z) -> (x, -z, y)
  }
  std::vector<Vec3> vertices;
  CollectVertices(*scene, *scene->mRootNode, X_MR, &vertices);
  return vertices;
}

ConvexShape MeshHullShape(const std::string& link, const std::string& uri, const Vec3& scale,
                          const LoaderOptions& options, std::string* warning) {
  const std::string where = "link '" + link + "': collision mesh '" + uri + "'";
  ConvexHull hull;
  MeshHullCache::Key key;
  try {
    const std::string path = ResolveMeshUri(uri, options);
    if (options.hull_cache) {
      key = CacheKey(path, scale, options.max_hull_faces);
      ConvexShape cached;
      if (options.hull_cache->Find(key, &cached)) {
        warning->clear();
        return cached;
      }
    }
    std::vector<Vec3> vertices = ReadMeshVertices(path);
    for (Vec3& v : vertices) v = v.cwiseProduct(scale);
    hull = ComputeConvexHull(vertices, options.max_hull_faces);
  } catch (const std::invalid_argument& e) {
    Fail(where + ": " + e.what());
  }
  Vec3 lo = hull.vertices.front(), hi = hull.vertices.front();
  for (const Vec3& v : hull.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Vec3 p_MS = 0.5 * (lo + hi);  // the shape frame's origin in the mesh frame M (m)
  ConvexShape shape;
  shape.type = ShapeType::kIntersection;
  shape.X_BS.translation() = p_MS;
  for (const HullFace& face : hull.faces) {
    shape.inequalities.push_back(Inequality::HalfSpace(face.normal, face.offset - face.normal.dot(p_MS)));
  }
  for (const Vec3& v : hull.vertices) shape.vertices.push_back(v - p_MS);
  *warning = "implicit_sim: " + where + " replaced by its convex hull (" + std::to_string(hull.faces.size()) + " faces";
  if (hull.merge_radius > 0.0) {
    *warning += "; simplified from " + std::to_string(hull.coplanar_faces) + " faces by merging facets within " +
                FormatLength(hull.merge_radius) + " m, cap " + std::to_string(options.max_hull_faces);
  }
  *warning += ")";
  if (options.hull_cache) options.hull_cache->Insert(key, shape);
  return shape;
}

}  // namespace loader
}  // namespace implicit_sim
