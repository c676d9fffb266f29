// StepperOptions and its NewtonOptions: one Python attribute per row of the core's options table (step/options.h),
// named as the C++ field, checked by the table's own range check. Choices are their names ("rattle", "newton").
#include <pybind11/stl.h>

#include "implicit_sim/core/step/options.h"
#include "py_types.h"

namespace implicit_sim {
namespace python {
namespace {

// The newton member of a StepperOptions, as its own Python object that writes through to its owner.
struct NewtonView {
  StepperOptions* options;
  py::object owner;  // keeps *options alive
};

py::object GetOption(const OptionRow& row, const StepperOptions& options) {
  const double value = row.get(options);
  switch (row.kind) {
    case OptionKind::kReal: return py::float_(value);
    case OptionKind::kInteger: return py::int_(static_cast<long long>(value));
    case OptionKind::kChoice: return py::str(row.choices[static_cast<int>(value)]);
  }
  return py::none();
}

// Checks `value` against the row (the core's message, naming "StepperOptions.<field>") and sets it; on a bad value
// raises ValueError and changes nothing.
void SetOption(const OptionRow& row, StepperOptions* options, const py::object& value) {
  const std::string label = std::string("StepperOptions.") + row.field;
  double number = 0.0;
  std::string error;
  if (row.kind == OptionKind::kChoice) {
    if (!py::isinstance<py::str>(value)) {
      throw py::value_error(label + " must be " + OptionRangeText(row) + ", got " +
                            py::repr(value).cast<std::string>());
    }
    if (!ParseOptionValue(row, value.cast<std::string>(), label, &number, &error)) throw py::value_error(error);
  } else {
    if (!PyNumber_Check(value.ptr())) {  // int, float, numpy scalars; whole numbers are checked by CheckOptionValue
      throw py::value_error(label + " must be a number in " + OptionRangeText(row) +
                            (*row.unit ? std::string(" ") + row.unit : std::string()) + ", got " +
                            py::repr(value).cast<std::string>());
    }
    number = value.cast<double>();
    if (!CheckOptionValue(row, number, label, &error)) throw py::value_error(error);
  }
  row.set(options, number);
}

std::string Describe(const StepperOptions& options, bool newton_only) {
  std::string text;
  for (const OptionRow& row : OptionTable()) {
    const bool is_newton = std::string(row.field).rfind("newton.", 0) == 0;
    if (newton_only && !is_newton) continue;
    const std::string name = newton_only ? std::string(row.field).substr(7) : row.field;
    text += (text.empty() ? "" : ", ") + name + "=" + py::repr(GetOption(row, options)).cast<std::string>();
  }
  return text;
}

py::list TableRows() {
  py::list rows;
  for (const OptionRow& row : OptionTable()) {
    rows.append(py::dict(py::arg("field") = row.field, py::arg("ros_param") = row.ros_param,
                         py::arg("runner_flag") = row.runner_flag, py::arg("range") = OptionRangeText(row),
                         py::arg("unit") = row.unit, py::arg("default") = GetOption(row, StepperOptions()),
                         py::arg("description") = row.description));
  }
  return rows;
}

}  // namespace

void BindOptions(py::module_& m) {
  py::class_<NewtonView> newton(m, "NewtonOptions", "StepperOptions.newton: the semismooth Newton solver's options");
  py::class_<StepperOptions> options(m, "StepperOptions",
                                     "The options of a step (step/options.h); every attribute is checked against the "
                                     "options table when set (ValueError naming the option and its range).");
  options.def(py::init<>())
      .def_property_readonly("newton", [](py::object self) {
        return NewtonView{self.cast<StepperOptions*>(), self};
      })
      .def("copy", [](const StepperOptions& o) { return StepperOptions(o); })
      .def("__repr__", [](const StepperOptions& o) { return "StepperOptions(" + Describe(o, false) + ")"; });
  newton.def("__repr__", [](const NewtonView& view) { return "NewtonOptions(" + Describe(*view.options, true) + ")"; });
  for (const OptionRow& row : OptionTable()) {
    const OptionRow* r = &row;
    const std::string field = row.field;
    const std::string doc = std::string(row.description) + " (" + OptionRangeText(row) +
                            (*row.unit ? std::string(" ") + row.unit : std::string()) + ")";
    if (field.rfind("newton.", 0) == 0) {
      newton.def_property(
          field.substr(7).c_str(), [r](const NewtonView& view) { return GetOption(*r, *view.options); },
          [r](NewtonView& view, const py::object& value) { SetOption(*r, view.options, value); }, doc.c_str());
    } else {
      options.def_property(
          field.c_str(), [r](const StepperOptions& o) { return GetOption(*r, o); },
          [r](StepperOptions& o, const py::object& value) { SetOption(*r, &o, value); }, doc.c_str());
    }
  }
  m.def("option_table", &TableRows,
        "The options table: one dict per option (field, ros_param, runner_flag, range, unit, default, description).");
}

}  // namespace python
}  // namespace implicit_sim
