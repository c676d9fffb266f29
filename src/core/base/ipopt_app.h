// Private to the core: what the two Ipopt users (the distance oracle and the Ipopt NCP solver) share. A quiet Ipopt
// application, and a TNLP base that keeps the solution Ipopt finalizes.
#pragma once

#include <mutex>

#include <Eigen/Core>
#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>

namespace implicit_sim {

struct IpoptSettings {
  double tol = 1e-8;             // Ipopt's "tol"
  double acceptable_tol = 1e-6;  // "acceptable_tol"
  int max_iter = 3000;           // "max_iter"
  bool limited_memory_hessian = false;  // "hessian_approximation limited-memory" (the TNLP gives no Hessian)
  bool honor_bounds = false;     // "bound_relax_factor 0" and "honor_original_bounds yes"
};

// An initialized application with no output, no banner, adaptive mu, and no option file read from the working
// directory; null if Ipopt fails to initialize.
Ipopt::SmartPtr<Ipopt::IpoptApplication> MakeQuietIpopt(const IpoptSettings& settings);

// Held by every Ipopt solve: Debian's Ipopt factors with the sequential MUMPS, which is not thread-safe, and islands
// are solved on several threads (step/islands.h).
std::mutex& IpoptMutex();

// Whether an Ipopt return status is a solution (to tol, or to the acceptable level).
inline bool IpoptSolved(Ipopt::ApplicationReturnStatus status) {
  return status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
}

// A TNLP that keeps the point Ipopt finalizes (x(), finalized(), status()).
class CapturingTnlp : public Ipopt::TNLP {
 public:
  const Eigen::VectorXd& x() const { return x_; }
  bool finalized() const { return finalized_; }
  Ipopt::SolverReturn status() const { return status_; }

  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x, const Ipopt::Number*,
                         const Ipopt::Number*, Ipopt::Index, const Ipopt::Number*, const Ipopt::Number*,
                         Ipopt::Number, const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    finalized_ = true;
    status_ = status;
    x_ = Eigen::Map<const Eigen::VectorXd>(x, n);
  }

 protected:
  explicit CapturingTnlp(const Eigen::VectorXd& x0) : x_(x0) {}

 private:
  Eigen::VectorXd x_;
  bool finalized_ = false;
  Ipopt::SolverReturn status_ = Ipopt::INTERNAL_ERROR;
};

}  // namespace implicit_sim
