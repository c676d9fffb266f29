#include "sigint_during_call.h"

#include <signal.h>

#include <atomic>

#include <pybind11/pybind11.h>

namespace implicit_sim {
namespace python {
namespace py = pybind11;
namespace {

std::atomic<StepInterrupt*> g_sigint_interrupt{nullptr};
struct sigaction g_python_sigint;

extern "C" void OnSigintDuringCall(int signal_number) {
  if (StepInterrupt* interrupt = g_sigint_interrupt.load()) interrupt->Request();
  if (g_python_sigint.sa_handler != SIG_DFL && g_python_sigint.sa_handler != SIG_IGN) {
    g_python_sigint.sa_handler(signal_number);
  }
}

}  // namespace

SigintDuringCall::SigintDuringCall(StepInterrupt* interrupt) {
  const py::object threading = py::module_::import("threading");
  if (!threading.attr("current_thread")().is(threading.attr("main_thread")())) return;
  struct sigaction ours = {};
  ours.sa_handler = OnSigintDuringCall;
  sigemptyset(&ours.sa_mask);
  g_sigint_interrupt = interrupt;
  installed_ = sigaction(SIGINT, &ours, &g_python_sigint) == 0;
  if (!installed_) g_sigint_interrupt = nullptr;
}

SigintDuringCall::~SigintDuringCall() {
  if (!installed_) return;
  sigaction(SIGINT, &g_python_sigint, nullptr);
  g_sigint_interrupt = nullptr;
}

}  // namespace python
}  // namespace implicit_sim
