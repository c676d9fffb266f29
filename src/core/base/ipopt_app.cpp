#include "base/ipopt_app.h"

#include <sstream>

namespace implicit_sim {

std::mutex& IpoptMutex() {
  static std::mutex mutex;
  return mutex;
}

Ipopt::SmartPtr<Ipopt::IpoptApplication> MakeQuietIpopt(const IpoptSettings& settings) {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");  // no banner
  app->Options()->SetStringValue("mu_strategy", "adaptive");
  app->Options()->SetNumericValue("tol", settings.tol);
  app->Options()->SetNumericValue("acceptable_tol", settings.acceptable_tol);
  app->Options()->SetIntegerValue("max_iter", settings.max_iter);
  if (settings.limited_memory_hessian) app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  if (settings.honor_bounds) {
    app->Options()->SetNumericValue("bound_relax_factor", 0.0);
    app->Options()->SetStringValue("honor_original_bounds", "yes");
  }
  std::istringstream no_option_file;  // do not pick up a stray ipopt.opt from the working directory
  if (app->Initialize(no_option_file) != Ipopt::Solve_Succeeded) return nullptr;
  return app;
}

}  // namespace implicit_sim
