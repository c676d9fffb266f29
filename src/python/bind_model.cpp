// Model: loading a scene, and read-only access to its bodies, joints and pairs; surface meshes for drawing.
#include <functional>

#include <pybind11/stl.h>

#include "implicit_sim/core/geometry/surface_mesh.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "py_types.h"
#include "sigint_during_call.h"

namespace implicit_sim {
namespace python {
namespace {

// A load with the GIL released (a mesh collision's hull can take a while) that Ctrl-C stops between two links: the
// loader's LoadInterrupted becomes Python's KeyboardInterrupt.
ModelPtr LoadInterruptibly(const std::function<Model(const LoaderOptions&)>& load, LoaderOptions options) {
  StepInterrupt interrupt;
  options.interrupt = &interrupt;
  ModelPtr model;
  std::string interrupted;
  {
    SigintDuringCall sigint(&interrupt);
    py::gil_scoped_release release;
    try {
      model = std::make_shared<Model>(load(options));
    } catch (const LoadInterrupted& e) {
      interrupted = e.what();
    }
  }
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // KeyboardInterrupt
  if (!model) throw std::runtime_error(interrupted);              // SIGINT with Python's handler ignoring it
  return model;
}

ModelPtr LoadFile(const std::string& path) {
  return LoadInterruptibly([&](const LoaderOptions& options) { return LoadSceneFromFile(path, options); },
                           LoaderOptions());
}

ModelPtr LoadString(const std::string& xml, const std::string& name, const std::string& mesh_directory) {
  LoaderOptions options;
  options.mesh_directory = mesh_directory;
  return LoadInterruptibly([&](const LoaderOptions& o) { return LoadSceneFromString(xml, name, o); }, options);
}

const Body& BodyAt(const Model& model, int body) { return model.bodies[CheckBodyIndex(model, body)]; }

// The boundary of a body's shapes in its body frame B: vertices (n, 3) in m and triangles (m, 3), one closed surface
// per shape.
py::tuple SurfaceMeshOfBody(const Model& model, int body, int resolution, double plane_half_size) {
  CheckBodyIndex(model, body);
  SurfaceMesh mesh;
  for (const ConvexShape& shape : model.bodies[body].shapes) {
    const SurfaceMesh part = MakeSurfaceMesh(shape, resolution, plane_half_size);
    const int first = static_cast<int>(mesh.vertices.size());
    for (const Vec3& p_S : part.vertices) mesh.vertices.push_back(shape.X_BS * p_S);
    for (const auto& t : part.triangles) mesh.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
  }
  py::array_t<double> vertices({static_cast<py::ssize_t>(mesh.vertices.size()), py::ssize_t{3}});
  py::array_t<int> triangles({static_cast<py::ssize_t>(mesh.triangles.size()), py::ssize_t{3}});
  auto v = vertices.mutable_unchecked<2>();
  auto t = triangles.mutable_unchecked<2>();
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) v(i, k) = mesh.vertices[i][k];
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) t(i, k) = mesh.triangles[i][k];
  }
  return py::make_tuple(vertices, triangles);
}

}  // namespace

void BindModel(py::module_& m) {
  py::class_<Model, std::shared_ptr<Model>>(m, "Model",
                                            "A scene: everything that does not change while it runs (const).")
      .def_property_readonly("name", [](const Model& model) { return model.scene_name; })
      .def_property_readonly("num_bodies", [](const Model& model) { return model.bodies.size(); })
      .def_property_readonly("num_moving", &Model::num_moving)
      .def_property_readonly("nq", &Model::nq, "size of State.q: 7 per moving body (p_WB, quaternion w x y z)")
      .def_property_readonly("nv", &Model::nv, "size of State.v: 6 per moving body (v_WB, w_WB)")
      .def_property_readonly("body_names",
                             [](const Model& model) {
                               std::vector<std::string> names;
                               for (const Body& body : model.bodies) names.push_back(body.name);
                               return names;
                             })
      .def_property_readonly("joint_names",
                             [](const Model& model) {
                               std::vector<std::string> names;
                               for (const Joint& joint : model.joints) names.push_back(joint.name);
                               return names;
                             })
      .def_property_readonly("pair_names",
                             [](const Model& model) {
                               std::vector<std::string> names;
                               for (size_t p = 0; p < model.pairs.size(); ++p) names.push_back(model.PairName(p));
                               return names;
                             })
      .def_property_readonly("moving_bodies", [](const Model& model) { return model.moving_bodies; },
                             "body index of each velocity slot")
      .def_property_readonly("gravity", [](const Model& model) { return ToArray(model.gravity_W); }, "m/s^2")
      .def("find_body", &Model::FindBody, py::arg("name"), "body index, -1 if absent")
      .def("find_joint", &Model::FindJoint, py::arg("name"), "joint index, -1 if absent")
      .def("is_fixed", [](const Model& model, int body) { return BodyAt(model, body).is_fixed; }, py::arg("body"))
      .def("velocity_slot",
           [](const Model& model, int body) {
             CheckBodyIndex(model, body);
             return model.velocity_slot[body];
           },
           py::arg("body"), "the body's slot in q (7 per slot) and v (6 per slot); -1 for a fixed body")
      .def("mass", [](const Model& model, int body) { return BodyAt(model, body).mass; }, py::arg("body"),
           "kg (0 for a fixed body)")
      .def("inertia", [](const Model& model, int body) { return ToArray(BodyAt(model, body).I_B); }, py::arg("body"),
           "rotational inertia about the centre of mass in the body frame (kg m^2)")
      .def("shape_type",
           [](const Model& model, int body) {
             const std::vector<ConvexShape>& shapes = BodyAt(model, body).shapes;
             return shapes.empty() ? std::string("none") : shapes.size() == 1 ? shapes[0].TypeName() : "union";
           },
           py::arg("body"), "the body's shape type; 'union' for several <collision>, 'none' for no collision")
      .def("joint_type", [](const Model& model, int joint) {
             return JointTypeName(model.joints[CheckJointIndex(model, joint)].type);
           },
           py::arg("joint"))
      .def("joint_limits",
           [](const Model& model, int joint) {
             const Joint& j = model.joints[CheckJointIndex(model, joint)];
             return j.limited ? py::make_tuple(j.lower, j.upper) : py::make_tuple(py::none(), py::none());
           },
           py::arg("joint"), "(lower, upper) in rad or m, (None, None) when not limited")
      .def("pair_bodies",
           [](const Model& model, int pair) {
             const ContactPair& p = model.pairs[CheckIndex(pair, model.pairs.size(), "pair")];
             return py::make_tuple(p.body1, p.body2);
           },
           py::arg("pair"), "(body1, body2): body1 always moves; normals point from body 2 towards body 1")
      .def("pair_friction",
           [](const Model& model, int pair) {
             const FrictionParams& f = model.pairs[CheckIndex(pair, model.pairs.size(), "pair")].friction;
             return py::dict(py::arg("mu") = f.mu, py::arg("e_t") = f.e_t, py::arg("e_o") = f.e_o,
                             py::arg("e_r") = f.e_r, py::arg("e_roll") = f.e_roll);
           },
           py::arg("pair"), "the pair's friction: mu, e_t, e_o (-), e_r and e_roll (m)")
      .def("pair_index",
           [](const Model& model, int body1, int body2) {
             CheckBodyIndex(model, body1);
             CheckBodyIndex(model, body2);
             return model.PairIndex(body1, body2);
           },
           py::arg("body1"), py::arg("body2"), "the pair of two bodies (either order), -1 if none")
      .def("__repr__", [](const Model& model) {
        return "<implicit_sim.Model '" + model.scene_name + "': " + std::to_string(model.bodies.size()) + " bodies (" +
               std::to_string(model.num_moving()) + " moving), " + std::to_string(model.joints.size()) + " joints, " +
               std::to_string(model.pairs.size()) + " pairs>";
      });

  m.def("load_scene", &LoadFile, py::arg("path"),
        "Loads a scene URDF file (doc/scenes.md). ValueError naming the link, joint or attribute when it is invalid.");
  m.def("load_scene_string", &LoadString, py::arg("xml"), py::arg("name") = "scene", py::arg("mesh_directory") = "",
        "Loads a scene from URDF text; relative mesh paths are resolved from mesh_directory (default: the working "
        "directory).");
  m.def("surface_mesh", &SurfaceMeshOfBody, py::arg("model"), py::arg("body"), py::arg("resolution") = 24,
        py::arg("plane_half_size") = 1.0,
        "(vertices (n, 3) in the body frame B in m, triangles (m, 3)) of the body's shape boundary, for drawing: "
        "rays on a grid of `resolution` latitudes; a half-space is a square of half size plane_half_size (m); a body "
        "without a shape gives empty arrays.");
}

}  // namespace python
}  // namespace implicit_sim
