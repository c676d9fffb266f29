// Ctrl-C during a long call made with the GIL released (a step, a scene load): SIGINT requests the call's
// StepInterrupt (the call stops cooperatively and changes nothing), then Python's own handler, chained here, raises
// KeyboardInterrupt once the GIL is back (the caller runs PyErr_CheckSignals). Only the main thread installs it (Python
// delivers signals there), one call at a time.
#pragma once

#include "implicit_sim/core/base/interrupt.h"

namespace implicit_sim {
namespace python {

class SigintDuringCall {
 public:
  explicit SigintDuringCall(StepInterrupt* interrupt);  // takes the GIL's holder's thread: call with the GIL held
  ~SigintDuringCall();
  SigintDuringCall(const SigintDuringCall&) = delete;
  SigintDuringCall& operator=(const SigintDuringCall&) = delete;

 private:
  bool installed_ = false;
};

}  // namespace python
}  // namespace implicit_sim
