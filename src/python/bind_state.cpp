// State: t, q and v of one Model. q and v are read-only numpy views of the state's own storage (no copy; they show
// the state as it is now, also after later steps); assigning a whole array checks it with the core's CheckState and
// copies it in, or raises ValueError and changes nothing.
#include "implicit_sim/core/model/joints.h"
#include "py_types.h"

namespace implicit_sim {
namespace python {
namespace {

// Checks `candidate` (the current state with one part replaced) and commits it.
void Commit(PyState* self, const State& candidate) {
  std::string error;
  if (!CheckState(*self->model, candidate, &error)) throw py::value_error(error);
  self->state.t = candidate.t;
  self->state.q = candidate.q;  // same sizes: copied into the existing storage, which the views point to
  self->state.v = candidate.v;
}

void SetVector(PyState* self, const py::handle& values, bool is_q) {
  State candidate = self->state;
  CopyArray(values, is_q ? self->model->nq() : self->model->nv(), is_q ? "state: q" : "state: v",
            is_q ? &candidate.q : &candidate.v);
  Commit(self, candidate);
}

}  // namespace

void BindState(py::module_& m) {
  py::class_<PyState>(m, "State", "t (s), q (7 per moving body: p_WB in m, unit quaternion w x y z) and v (6 per "
                                  "moving body: v_WB in m/s, w_WB in rad/s, world frame)")
      .def_static("initial", [](ModelPtr model) { return PyState{model, State::Initial(*model)}; }, py::arg("model"),
                  "the scene's initial state")
      .def_property(
          "t", [](const PyState& s) { return s.state.t; },
          [](PyState& s, double t) {
            State candidate = s.state;
            candidate.t = t;
            Commit(&s, candidate);
          },
          "time (s)")
      .def_property(
          "q", [](py::object self) { return ReadOnlyView(self.cast<PyState&>().state.q, self); },
          [](PyState& s, const py::handle& q) { SetVector(&s, q, true); },
          "positions: a read-only view; assign a whole array to change it")
      .def_property(
          "v", [](py::object self) { return ReadOnlyView(self.cast<PyState&>().state.v, self); },
          [](PyState& s, const py::handle& v) { SetVector(&s, v, false); },
          "velocities: a read-only view; assign a whole array to change it")
      .def("copy", [](const PyState& s) { return PyState(s); }, "an independent copy (same Model)")
      .def("assign", [](PyState& s, const PyState& other) {
             CheckSameModel(s.model, *other.model, "the other State");
             Commit(&s, other.state);
           },
           py::arg("other"), "copies another State of the same Model into this one, in place (views stay valid)")
      .def("pose",
           [](const PyState& s, const Model& model, int body) {
             CheckSameModel(s.model, model, "State");
             CheckBodyIndex(model, body);
             const Pose X_WB = s.state.X_WB(model, body);
             return py::make_tuple(ToArray(Vec3(X_WB.translation())), ToArray(Mat3(X_WB.linear())));
           },
           py::arg("model"), py::arg("body"),
           "(p_WB (3,) in m, R_WB (3, 3)) of a body's centre-of-mass frame B in the world; fixed bodies too")
      .def_property_readonly("model", [](const PyState& s) { return s.model; })
      .def("__repr__", [](const PyState& s) {
        return "<implicit_sim.State t=" + py::repr(py::float_(s.state.t)).cast<std::string>() + " of '" +
               s.model->scene_name + "'>";
      });
  m.def("kinetic_energy", [](const Model& model, const PyState& s) {
        CheckSameModel(s.model, model, "State");
        return KineticEnergy(model, s.state);
      }, py::arg("model"), py::arg("state"), "J");
  m.def("joint_position", [](const Model& model, const PyState& s, int joint) {
        CheckSameModel(s.model, model, "State");
        return JointPosition(model, s.state, CheckJointIndex(model, joint));
      }, py::arg("model"), py::arg("state"), py::arg("joint"), "rad or m");
  m.def("joint_velocity", [](const Model& model, const PyState& s, int joint) {
        CheckSameModel(s.model, model, "State");
        return JointVelocity(model, s.state, CheckJointIndex(model, joint));
      }, py::arg("model"), py::arg("state"), py::arg("joint"), "rad/s or m/s");
}

}  // namespace python
}  // namespace implicit_sim
