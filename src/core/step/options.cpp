#include "implicit_sim/core/step/options.h"

#include <cmath>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {

bool StepperOptions::IsValid(std::string* error) const {
  if (ipopt_max_iterations < 1 || ipopt_max_iterations > 100000) {
    *error = "ipopt_max_iterations must be in [1, 100000], got " + std::to_string(ipopt_max_iterations);
    return false;
  }
  if (!(h > 0.0 && h <= 1.0)) {
    *error = "time step h must be in (0, 1] s, got " + FormatNumber(h);
    return false;
  }
  if (!(broad_phase_margin >= 0.0 && broad_phase_margin <= 10.0)) {
    *error = "broad_phase_margin must be in [0, 10] m, got " + FormatNumber(broad_phase_margin);
    return false;
  }
  if (!(contact_threshold >= 0.0 && std::isfinite(contact_threshold))) {
    *error = "contact_threshold must be finite and >= 0 N, got " + FormatNumber(contact_threshold);
    return false;
  }
  if (!(max_speed > 0.0 && max_speed <= 1e12) || !(max_angular_speed > 0.0 && max_angular_speed <= 1e12)) {
    *error = "max_speed and max_angular_speed must be in (0, 1e12] (m/s, rad/s)";
    return false;
  }
  if (!(overlap_tolerance >= 0.0 && overlap_tolerance <= 1.0)) {
    *error = "overlap_tolerance must be in [0, 1] m";
    return false;
  }
  return newton.IsValid(error);
}

}  // namespace implicit_sim
