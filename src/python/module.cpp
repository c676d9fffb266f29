// The Python module implicit_sim._core (doc/python.md): the core library's Model, StepperOptions, State, Data and
// Step, with numpy arrays for vectors. Bad input raises ValueError with the core's own message.
#include "py_types.h"

namespace implicit_sim {
namespace python {

py::array_t<double> ReadOnlyView(const Eigen::VectorXd& values, py::handle owner) {
  py::array_t<double> view({values.size()}, {static_cast<py::ssize_t>(sizeof(double))}, values.data(), owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

py::array_t<double> ToArray(const Eigen::VectorXd& values) {
  py::array_t<double> out(values.size());
  std::copy(values.data(), values.data() + values.size(), out.mutable_data());
  return out;
}

py::array_t<double> ToArray(const Vec3& value) {
  py::array_t<double> out(3);
  for (int i = 0; i < 3; ++i) out.mutable_data()[i] = value[i];
  return out;
}

py::array_t<double> ToArray(const Mat3& value) {
  py::array_t<double> out({3, 3});
  auto r = out.mutable_unchecked<2>();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = value(i, j);
  }
  return out;
}

void CopyArray(const py::handle& array, Eigen::Index size, const std::string& what, Eigen::VectorXd* out) {
  const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values) throw py::value_error(what + " must be an array of numbers");
  if (values.size() != size) {
    throw py::value_error(what + " must hold " + std::to_string(size) + " values, got " +
                          std::to_string(values.size()));
  }
  out->resize(size);
  std::copy(values.data(), values.data() + size, out->data());
}

void CheckSameModel(const ModelPtr& owner_model, const Model& model, const char* what) {
  if (owner_model.get() != &model) {
    throw py::value_error(std::string(what) + " was made for another Model: make it from the Model given here");
  }
}

int CheckIndex(int index, size_t count, const char* what) {
  if (index < 0 || index >= static_cast<int>(count)) {
    throw py::value_error(std::string(what) + " index must be in [0, " + std::to_string(count) + "), got " +
                          std::to_string(index));
  }
  return index;
}

}  // namespace python
}  // namespace implicit_sim

PYBIND11_MODULE(_core, m) {
  m.doc() = "implicit_sim's core: geometrically implicit time stepping of rigid bodies with implicit convex shapes";
  implicit_sim::python::BindModel(m);
  implicit_sim::python::BindOptions(m);
  implicit_sim::python::BindState(m);
  implicit_sim::python::BindStep(m);
}
