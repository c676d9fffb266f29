// Data, step and its report, contact results, warm starts, joint drives and applied wrenches.

#include <atomic>
#include <cmath>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/io/step_case.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/wrench.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "py_types.h"
#include "sigint_during_call.h"

namespace implicit_sim {
namespace python {
namespace {

Data::PairSelection ParsePairSelection(const std::string& name) {
  if (name == "auto") return Data::PairSelection::kAuto;
  if (name == "all") return Data::PairSelection::kAllPairs;
  if (name == "broad_phase") return Data::PairSelection::kBroadPhase;
  throw py::value_error("pair_selection must be auto, all or broad_phase, got '" + name + "'");
}

// Data::contacts as arrays, one row per pair in the last step's NCP.
py::dict ContactArrays(const Data& data) {
  const py::ssize_t n = static_cast<py::ssize_t>(data.contacts.size());
  py::array_t<int> pair(n);
  py::array_t<double> gap(n), normal_force(n), torsional_moment(n), slip_speed(n);
  py::array_t<double> p_WA1({n, py::ssize_t{3}}), p_WA2({n, py::ssize_t{3}}), n_W({n, py::ssize_t{3}}),
      friction_force_W({n, py::ssize_t{3}}), rolling_moment_W({n, py::ssize_t{3}});
  auto a1 = p_WA1.mutable_unchecked<2>(), a2 = p_WA2.mutable_unchecked<2>(), nn = n_W.mutable_unchecked<2>(),
       ff = friction_force_W.mutable_unchecked<2>(), rm = rolling_moment_W.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const ContactResult& c = data.contacts[i];
    pair.mutable_data()[i] = c.pair;
    gap.mutable_data()[i] = c.gap;
    normal_force.mutable_data()[i] = c.normal_force;
    torsional_moment.mutable_data()[i] = c.torsional_moment;
    slip_speed.mutable_data()[i] = c.slip_speed;
    for (int k = 0; k < 3; ++k) {
      a1(i, k) = c.p_WA1[k];
      a2(i, k) = c.p_WA2[k];
      nn(i, k) = c.n_W[k];
      ff(i, k) = c.friction_force_W[k];
      rm(i, k) = c.rolling_moment_W[k];
    }
  }
  return py::dict(py::arg("pair") = pair, py::arg("gap") = gap, py::arg("n_W") = n_W, py::arg("p_WA1") = p_WA1,
                  py::arg("p_WA2") = p_WA2, py::arg("normal_force") = normal_force,
                  py::arg("friction_force_W") = friction_force_W, py::arg("torsional_moment") = torsional_moment,
                  py::arg("rolling_moment_W") = rolling_moment_W, py::arg("slip_speed") = slip_speed);
}

constexpr const char* kDataBusy = "this Data is being stepped in another thread: give each thread a Data of its own";

// ValueError while another thread steps this Data (with the GIL released).
void CheckNotStepping(const PyData& data) {
  if (data.stepping) throw py::value_error(kDataBusy);
}

// Step with the external wrench and joint efforts of this step (either may be None), the GIL released while the core
// steps, and max_wall (s, or None) as the step's deadline. The inputs are checked before the state is touched.
StepReport StepOnce(const Model& model, const StepperOptions& options, PyState* state, PyData* data,
                    const py::object& wrench, const py::object& joint_efforts, const py::object& max_wall) {
  CheckSameModel(state->model, model, "State");
  CheckSameModel(data->model, model, "Data");
  if (data->stepping.exchange(true)) throw py::value_error(kDataBusy);
  struct Done {
    std::atomic<bool>* stepping;
    ~Done() { *stepping = false; }
  } done{&data->stepping};
  const Eigen::VectorXd* wrench_W = nullptr;
  if (!wrench.is_none() || !joint_efforts.is_none()) {
    if (!wrench.is_none()) {
      CopyArray(wrench, model.nv(), "wrench (force then torque per moving body: N, N m)", &data->wrench_W);
    } else {
      data->wrench_W.setZero();
    }
    if (!joint_efforts.is_none()) {
      CopyArray(joint_efforts, static_cast<Eigen::Index>(model.joints.size()), "joint_efforts (one per joint)",
                &data->joint_efforts);
      AddJointEffortWrench(model, state->state, data->joint_efforts, &data->wrench_W);
    }
    wrench_W = &data->wrench_W;
  }
  data->interrupt.Clear();
  if (!max_wall.is_none()) {
    const double seconds = max_wall.cast<double>();
    if (!(seconds > 0.0) || !std::isfinite(seconds)) {
      throw py::value_error("max_wall must be a finite number of seconds > 0, got " + FormatNumber(seconds));
    }
    data->interrupt.SetDeadlineIn(seconds);
  }
  data->data.interrupt = &data->interrupt;
  StepReport report;
  {
    SigintDuringCall sigint(&data->interrupt);
    py::gil_scoped_release release;
    report = Step(model, options, &state->state, &data->data, wrench_W);
  }
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // KeyboardInterrupt (the step was undone)
  return report;
}

void SetJointDrive(PyData* self, int joint, double position_target, double velocity_target, double stiffness,
                   double damping) {
  const Model& model = *self->model;
  CheckNotStepping(*self);
  CheckJointIndex(model, joint);
  JointDrive drive;
  drive.position_target = position_target;
  drive.velocity_target = velocity_target;
  drive.stiffness = stiffness;
  drive.damping = damping;
  std::string error;
  if (!CheckJointDrive(model.joints[joint], drive, &error)) throw py::value_error(error);
  self->data.joint_drives[joint] = drive;
}

py::array_t<double> WrenchAtPoint(const Model& model, const PyState& state, int body, const Eigen::Vector3d& p_WP,
                                  const Eigen::Vector3d& f_W, const Eigen::Vector3d& tau_W) {
  CheckSameModel(state.model, model, "State");
  if (!p_WP.allFinite() || !f_W.allFinite() || !tau_W.allFinite()) {
    throw py::value_error("wrench_at_point: the point, force and torque must be finite");
  }
  Eigen::VectorXd wrench = Eigen::VectorXd::Zero(model.nv());
  AddWrenchAtPoint(model, state.state, body, -1, p_WP, f_W, tau_W, &wrench);
  return ToArray(wrench);
}

void BindReport(py::module_& m) {
  py::class_<StepReport> report(m, "StepReport", "What a step did (step/step_report.h)");
  for (const StepCounter& counter : StepCounterTable()) {  // iterations, cold_restarts, ... (the counter table)
    const auto field = counter.field;
    report.def_property_readonly(counter.name, [field](const StepReport& r) { return r.*field; });
  }
  report.def_readonly("converged", &StepReport::converged)
      .def_readonly("advanced", &StepReport::advanced)
      .def_readonly("residual", &StepReport::residual)
      .def_readonly("complementarity_error", &StepReport::complementarity_error)
      .def_readonly("path_switch_smoothing", &StepReport::path_switch_smoothing)
      .def_readonly("path_switch_residual", &StepReport::path_switch_residual)
      .def_readonly("joint_position_error", &StepReport::joint_position_error, "m")
      .def_readonly("joint_angle_error", &StepReport::joint_angle_error, "rad")
      .def_readonly("wall_time_s", &StepReport::wall_time_s)
      .def_property_readonly("fault", [](const StepReport& r) { return StepFaultName(r.fault); })
      .def_readonly("fault_detail", &StepReport::fault_detail)
      .def("__repr__", [](const StepReport& r) {
        return std::string("<StepReport converged=") + (r.converged ? "True" : "False") +
               " iterations=" + std::to_string(r.iterations) + " residual=" +
               py::repr(py::float_(r.residual)).cast<std::string>() + " fault=" + StepFaultName(r.fault) + ">";
      });
}

}  // namespace

void BindStep(py::module_& m) {
  BindReport(m);
  py::class_<PyData>(m, "Data", "The solver workspace and the last step's results of one Model (step/data.h)")
      .def(py::init([](ModelPtr model, const std::string& pair_selection) {
             return std::make_unique<PyData>(model, ParsePairSelection(pair_selection));
           }),
           py::arg("model"), py::arg("pair_selection") = "auto")
      .def_property_readonly("contacts", [](const PyData& d) {
        CheckNotStepping(d);
        return ContactArrays(d.data);
      },
                             "the last step's contact results, one row per pair in its NCP: pair (model pair index), "
                             "gap (m), n_W (unit, body 2 to body 1), p_WA1, p_WA2 (closest points, m), normal_force "
                             "(N), friction_force_W (on body 1, N), torsional_moment (N m), rolling_moment_W "
                             "(on body 1, N m), slip_speed (m/s)")
      .def_property_readonly("has_warm_start", [](const PyData& d) { return d.data.has_warm_start; })
      .def_property_readonly("broad_phase", [](const PyData& d) { return d.data.broad_phase; })
      .def_property_readonly("joint_limit_effort", [](const PyData& d) {
        return ToArray(Eigen::Map<const Eigen::VectorXd>(d.data.joint_limit_effort.data(),
                                                         d.data.joint_limit_effort.size()).eval());
      }, "per joint, the last step's limit effort (N m or N)")
      .def_property_readonly("joint_drive_effort", [](const PyData& d) {
        return ToArray(Eigen::Map<const Eigen::VectorXd>(d.data.joint_drive_effort.data(),
                                                         d.data.joint_drive_effort.size()).eval());
      }, "per joint, the last step's drive effort (N m or N)")
      .def("set_joint_drive", &SetJointDrive, py::arg("joint"), py::arg("position_target") = 0.0,
           py::arg("velocity_target") = 0.0, py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
           "a PD drive evaluated at the end of each step (joints.h, JointDrive); stiffness = damping = 0 turns it off")
      .def_property_readonly("model", [](const PyData& d) { return d.model; });

  py::class_<WarmStart>(m, "WarmStart", "What a step reads besides the State and the drives (step/data.h)")
      .def_readonly("valid", &WarmStart::valid)
      .def_readonly("pairs", &WarmStart::pairs);
  m.def("save_warm_start", [](const PyData& d) {
    CheckNotStepping(d);
    WarmStart saved;
    SaveWarmStart(d.data, &saved);
    return saved;
  }, py::arg("data"));
  m.def("restore_warm_start", [](const Model& model, const WarmStart& saved, PyData* d) {
    CheckSameModel(d->model, model, "Data");
    CheckNotStepping(*d);
    RestoreWarmStart(model, saved, &d->data);
  }, py::arg("model"), py::arg("saved"), py::arg("data"),
        "with the State saved at the same time, the run continues bit-identically");
  m.def("clear_warm_start", [](PyData* d) {
    CheckNotStepping(*d);
    ClearWarmStart(&d->data);
  }, py::arg("data"),
        "the next step starts cold, like the first step of a new Data");
  m.def("write_step_case", [](const std::string& path, const std::string& name, const std::string& origin,
                              const std::string& urdf, const std::string& scene_name, const StepperOptions& options,
                              const PyState& state, const WarmStart& warm_start, const PyData& data,
                              const StepReport& report) {
    CheckSameModel(data.model, *state.model, "State");
    StepCase step_case;
    step_case.name = name;
    step_case.origin = origin;
    step_case.scene_name = scene_name;
    step_case.urdf = urdf;
    step_case.broad_phase = data.data.broad_phase;
    step_case.options = options;
    step_case.inputs.state = state.state;
    step_case.inputs.warm_start = warm_start;
    step_case.recorded = RecordOutcome(report);
    // The case must load back to a scene of the same sizes (the URDF is the one the model was loaded from).
    LoadStepCaseModel(step_case);
    WriteStepCase(step_case, path);
  }, py::arg("path"), py::arg("name"), py::arg("origin"), py::arg("urdf"), py::arg("scene_name"), py::arg("options"),
        py::arg("state"), py::arg("warm_start"), py::arg("data"), py::arg("report"),
        "Writes a step case (bench/README.md, the step case format) for implicit_sim_replay: the step from `state` and "
        "`warm_start` (both saved before the step), with `options`, on the scene of `urdf` loaded as `scene_name`, "
        "that reported `report`; data gives the pair selection. Without external wrench or joint efforts.");
  m.def("step", &StepOnce, py::arg("model"), py::arg("options"), py::arg("state"), py::arg("data"),
        py::arg("wrench") = py::none(), py::arg("joint_efforts") = py::none(), py::arg("max_wall") = py::none(),
        "Advances state by one step of options.h and returns its StepReport. wrench: nv values (force N then torque "
        "N m per moving body, world frame, at the centre of mass) for this step; joint_efforts: one per joint (N m or "
        "N); max_wall: seconds after which the step is interrupted and undone (fault 'interrupted'). Ctrl-C (SIGINT) "
        "on the main thread interrupts the step too, undoes it and raises KeyboardInterrupt. ValueError (nothing "
        "changed) for bad options, state, wrench, drives or max_wall; solver trouble is reported.");
  m.def("wrench_at_point", &WrenchAtPoint, py::arg("model"), py::arg("state"), py::arg("body"), py::arg("p_WP"),
        py::arg("f_W"), py::arg("tau_W") = Eigen::Vector3d::Zero(),
        "the wrench vector (nv,) of a force f_W (N) at the world point p_WP (m) plus a torque tau_W (N m) on a moving "
        "body");
}

}  // namespace python
}  // namespace implicit_sim
