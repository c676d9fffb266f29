#include "mjcf_scene.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {
namespace {

std::string Numbers(std::initializer_list<double> values) {
  std::string text;
  for (double value : values) text += (text.empty() ? "" : " ") + FormatNumber(value);
  return text;
}

// pos="x y z" quat="w x y z" of a pose.
std::string PoseAttributes(const Pose& X) {
  const Eigen::Quaterniond q(X.linear());
  const Vec3 p = X.translation();
  return "pos=\"" + Numbers({p.x(), p.y(), p.z()}) + "\" quat=\"" + Numbers({q.w(), q.x(), q.y(), q.z()}) + "\"";
}

// The 2N vertices of a regular N-gon prism in its shape frame: axis z, circumradius r, a vertex on +x (MakePrism).
std::string PrismVertices(const ConvexShape& shape) {
  const double r = shape.size.x(), half_length = shape.size.z();
  std::string text;
  for (int k = 0; k < shape.sides; ++k) {
    const double angle = 2.0 * M_PI * k / shape.sides;  // rad
    for (double z : {-half_length, half_length}) {
      text += (text.empty() ? "" : " ") + Numbers({r * std::cos(angle), r * std::sin(angle), z});
    }
  }
  return text;
}

// The friction of every pair: MuJoCo combines per-geom values, so the scene must have one friction for all pairs.
FrictionParams SceneFriction(const Model& model) {
  if (model.pairs.empty()) return FrictionParams();
  const FrictionParams f = model.pairs.front().friction;
  for (const ContactPair& pair : model.pairs) {
    const FrictionParams& g = pair.friction;
    if (g.mu != f.mu || g.e_t != f.e_t || g.e_o != f.e_o || g.e_r != f.e_r) {
      throw std::invalid_argument("MJCF: pairs with different friction cannot be mirrored per geom");
    }
  }
  if (f.e_t != 1.0 || f.e_o != 1.0) throw std::invalid_argument("MJCF: only isotropic friction (e_t = e_o = 1)");
  return f;
}

bool IsPlanarXZ(const Body& body) {
  const std::array<bool, 6> planar{{false, true, false, true, false, true}};  // y, rx, rz locked
  bool any_locked = false;
  for (bool locked : body.locked) any_locked = any_locked || locked;
  if (!any_locked) return false;
  if (body.locked != planar) throw std::invalid_argument("MJCF: body '" + body.name + "': only 'y rx rz' locking");
  if (!body.X_WB0.linear().isIdentity(1e-12)) {
    throw std::invalid_argument("MJCF: planar body '" + body.name + "' must start unrotated");
  }
  return true;
}

// One geom for a shape posed by X_PS in its parent frame P; a prism also adds its mesh to `assets`.
std::string GeomXml(const std::string& name, const ConvexShape& shape, const Pose& X_PS, const std::string& contact,
                    std::ostringstream& assets) {
  std::string type_and_size;
  switch (shape.type) {
    case ShapeType::kHalfSpace: type_and_size = "type=\"plane\" size=\"10 10 0.1\""; break;  // infinite for contacts
    case ShapeType::kSphere: type_and_size = "type=\"sphere\" size=\"" + Numbers({shape.size.x()}) + "\""; break;
    case ShapeType::kEllipsoid:
      type_and_size = "type=\"ellipsoid\" size=\"" + Numbers({shape.size.x(), shape.size.y(), shape.size.z()}) + "\"";
      break;
    case ShapeType::kCylinder:
      type_and_size = "type=\"cylinder\" size=\"" + Numbers({shape.size.x(), shape.size.z()}) + "\"";
      break;
    case ShapeType::kPrism:
      assets << "    <mesh name=\"" << name << "_prism\" vertex=\"" << PrismVertices(shape) << "\"/>\n";
      type_and_size = "type=\"mesh\" mesh=\"" + name + "_prism\"";
      break;
    default: throw std::invalid_argument("MJCF: shape '" + shape.TypeName() + "' of '" + name + "' has no MuJoCo twin");
  }
  return "<geom name=\"" + name + "\" " + type_and_size + " " + PoseAttributes(X_PS) + " " + contact + "/>";
}

std::string BodyXml(const Body& body, const std::string& contact, std::ostringstream& assets) {
  const Mat3& I = body.I_B;  // kg m^2, about the centre of mass in the body frame
  std::ostringstream out;
  out << "    <body name=\"" << body.name << "\" " << PoseAttributes(body.X_WB0) << ">\n";
  if (IsPlanarXZ(body)) {
    out << "      <joint name=\"" << body.name << "_x\" type=\"slide\" axis=\"1 0 0\"/>\n"
        << "      <joint name=\"" << body.name << "_z\" type=\"slide\" axis=\"0 0 1\"/>\n"
        << "      <joint name=\"" << body.name << "_ry\" type=\"hinge\" axis=\"0 1 0\"/>\n";
  } else {
    out << "      <freejoint name=\"" << body.name << "_free\"/>\n";
  }
  out << "      <inertial pos=\"0 0 0\" mass=\"" << FormatNumber(body.mass) << "\" fullinertia=\""
      << Numbers({I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)}) << "\"/>\n"
      << "      " << GeomXml(body.name, body.shapes[0], body.shapes[0].X_BS, contact, assets) << "\n"
      << "    </body>\n";
  return out.str();
}

}  // namespace

std::string MjcfFromModel(const Model& model, const MjcfOptions& options) {
  if (!model.joints.empty()) throw std::invalid_argument("MJCF: scenes with joints are not mirrored");
  const FrictionParams friction = SceneFriction(model);
  bool planar = false;
  for (const Body& body : model.bodies) planar = planar || (!body.is_fixed && IsPlanarXZ(body));
  // No torsion (e_r = 0, point contacts) is condim 3, as a planar body's contact (it cannot spin about the normal).
  const bool torsion = !planar && friction.e_r > 0.0;
  const std::string contact = "condim=\"" + std::string(torsion ? "4" : "3") + "\" friction=\"" +
                              Numbers({friction.mu, friction.e_r * friction.mu, 0.0}) + "\"";
  std::ostringstream assets, world;
  for (const Body& body : model.bodies) {
    if (body.shapes.empty()) continue;  // the world link
    if (body.shapes.size() > 1) throw std::invalid_argument("MJCF: body '" + body.name + "' has several shapes");
    if (body.is_fixed) {
      world << "    " << GeomXml(body.name, body.shapes[0], body.X_WB0 * body.shapes[0].X_BS, contact, assets) << "\n";
    } else {
      world << BodyXml(body, contact, assets);
    }
  }
  const Vec3 g = model.gravity_W;  // m/s^2
  std::ostringstream out;
  out << "<mujoco model=\"" << model.scene_name << "\">\n"
      << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
      << "  <option timestep=\"" << FormatNumber(options.h) << "\" gravity=\"" << Numbers({g.x(), g.y(), g.z()})
      << "\" integrator=\"Euler\" cone=\"elliptic\" solver=\"" << options.solver << "\"/>\n";
  if (options.max_contacts > 0 || options.max_constraint_rows > 0) {
    out << "  <size";
    if (options.max_contacts > 0) out << " nconmax=\"" << options.max_contacts << "\"";
    if (options.max_constraint_rows > 0) out << " njmax=\"" << options.max_constraint_rows << "\"";
    out << "/>\n";
  }
  if (!assets.str().empty()) out << "  <asset>\n" << assets.str() << "  </asset>\n";
  out << "  <worldbody>\n" << world.str() << "  </worldbody>\n</mujoco>\n";
  return out.str();
}

}  // namespace implicit_sim
