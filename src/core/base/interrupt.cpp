#include "implicit_sim/core/base/interrupt.h"

#include <csignal>

namespace implicit_sim {
namespace {

std::atomic<StepInterrupt*> g_stop_target{nullptr};

extern "C" void OnStopSignal(int signal_number) {
  if (StepInterrupt* interrupt = g_stop_target.load()) interrupt->Request();
  std::signal(signal_number, SIG_DFL);
}

}  // namespace

void RequestOnStopSignals(StepInterrupt* interrupt) {
  g_stop_target = interrupt;
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
}

}  // namespace implicit_sim
