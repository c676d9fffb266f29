// The Python wrappers' own types: a State and a Data that remember the Model they belong to (so that Python can
// check it and keep it alive), and the numpy views and copies they hand out.
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {
namespace python {

namespace py = pybind11;
using ModelPtr = std::shared_ptr<Model>;  // never modified: Python sees only const operations

struct PyState {
  ModelPtr model;
  State state;
};

struct PyData {
  PyData(ModelPtr model_in, Data::PairSelection selection)
      : model(std::move(model_in)), data(*model, selection), wrench_W(Eigen::VectorXd::Zero(model->nv())),
        joint_efforts(Eigen::VectorXd::Zero(model->joints.size())) {}
  ModelPtr model;
  Data data;
  // Step's workspace for the external wrench and the joint efforts of one step: allocated once.
  Eigen::VectorXd wrench_W;
  Eigen::VectorXd joint_efforts;
  // Set while a step runs with the GIL released: a second thread stepping the same Data is refused.
  std::atomic<bool> stepping{false};
  // The step's cooperative stop (Data::interrupt): step's max_wall deadline and, on the main thread, SIGINT.
  StepInterrupt interrupt;
};

// A read-only 1-D numpy view of `values`, kept alive by `owner` (the Python object that holds them).
py::array_t<double> ReadOnlyView(const Eigen::VectorXd& values, py::handle owner);
// Copies: (n,) and (n, 3) arrays.
py::array_t<double> ToArray(const Eigen::VectorXd& values);
py::array_t<double> ToArray(const Vec3& value);
py::array_t<double> ToArray(const Mat3& value);
// A float64 array of exactly `size` values (a 1-D array, or any shape with that many values such as (bodies, 6)),
// copied into *out; ValueError naming `what` otherwise.
void CopyArray(const py::handle& array, Eigen::Index size, const std::string& what, Eigen::VectorXd* out);
// ValueError unless `model` is the very Model `owner_model` (what a State or Data was made from).
void CheckSameModel(const ModelPtr& owner_model, const Model& model, const char* what);
// Returns `index` when it is in [0, count); ValueError naming `what` ("body", "joint", "pair") otherwise.
int CheckIndex(int index, size_t count, const char* what);
inline int CheckBodyIndex(const Model& model, int body) { return CheckIndex(body, model.bodies.size(), "body"); }
inline int CheckJointIndex(const Model& model, int joint) { return CheckIndex(joint, model.joints.size(), "joint"); }

void BindModel(py::module_& m);
void BindOptions(py::module_& m);
void BindState(py::module_& m);
void BindStep(py::module_& m);

}  // namespace python
}  // namespace implicit_sim
