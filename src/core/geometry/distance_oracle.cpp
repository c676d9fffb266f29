// Distance oracle: paper eq. 7 and support values, each solved by Ipopt with exact first and second derivatives.
//
// Closest points (paper eq. 7), with x1, x2 in the world frame W:
//     min_{x1, x2}  |x1 - x2|^2
//     s.t.          f_k(X_WS1^-1 x1) <= 0   for every inequality k of shape 1,
//                   f_l(X_WS2^-1 x2) <= 0   for every inequality l of shape 2.
// A shape inequality is evaluated in its shape frame S at x_S = R_WS^T (x_W - p_WS); by the chain rule its world
// gradient is R_WS grad_S and its world Hessian R_WS H_S R_WS^T. Every f_k is convex, so the problem is convex and
// any KKT point Ipopt finds is a global minimiser; distance = |x1 - x2| (0 when the bodies touch or overlap).
//
// Support value of a posed shape for a direction u:
//     h(u) = max u.x  s.t.  f_k(X_WS^-1 x) <= 0,  |x_i - c_i| <= 1e4 (c: shape origin in W),
// solved as min -u.x. The box keeps an unbounded intersection (an infinite cylinder without caps, ...) bounded.
#include "implicit_sim/core/geometry/distance_oracle.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <vector>

#include "base/ipopt_app.h"

namespace implicit_sim {
namespace {

using Ipopt::Index;
using Ipopt::Number;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kIpoptInf = 2e19;     // Ipopt treats |bound| >= 1e19 as no bound
constexpr double kSupportBox = 1e4;    // half side of the clipping cube of SupportValue (m)

// One inequality of a posed shape, acting on the 3 variables of block `block` (x1: 0, x2: 1).
struct PosedInequality {
  const Inequality* inequality;
  Pose X_WS;
  int block;
};

// The 3 coordinates starting at x (an Ipopt array).
Vec3 V3(const Number* x) { return Eigen::Map<const Vec3>(x); }

Pose ShapePose(const ConvexShape& shape, const Pose& X_WB) { return X_WB * shape.X_BS; }

// The plane of a single half-space in W: outward unit normal n_W and a point q_W on the plane.
void HalfSpacePlane(const ConvexShape& shape, const Pose& X_WB, Vec3* n_W, Vec3* q_W) {
  const Inequality& q = shape.inequalities.front();
  const Pose X_WP = ShapePose(shape, X_WB) * q.X_SP;
  *n_W = X_WP.linear() * q.normal;
  *q_W = X_WP * (q.offset * q.normal);  // f = n.x - offset = 0 at x_P = offset n
}

// Both problems in one TNLP. kClosest: 6 variables (x1, x2), objective |x1 - x2|^2. kSupport: 3 variables,
// objective -u.x, box bounds around `center`.
class ShapeNlp : public CapturingTnlp {
 public:
  enum class Mode { kClosest, kSupport };

  ShapeNlp(Mode mode, std::vector<PosedInequality> rows, const Eigen::VectorXd& x0)
      : CapturingTnlp(x0), mode_(mode), rows_(std::move(rows)), x0_(x0) {}

  void SetSupport(const Vec3& u_W, const Vec3& center_W) {
    u_W_ = u_W;
    center_W_ = center_W;
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& index_style) override {
    n = num_vars();
    m = static_cast<Index>(rows_.size());
    nnz_jac_g = 3 * m;              // each row depends on the 3 coordinates of its block
    nnz_h_lag = n * (n + 1) / 2;    // dense lower triangle (21 or 6 entries)
    index_style = TNLP::C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    for (Index i = 0; i < n; ++i) {
      const bool box = mode_ == Mode::kSupport;
      x_l[i] = box ? center_W_[i] - kSupportBox : -kIpoptInf;
      x_u[i] = box ? center_W_[i] + kSupportBox : kIpoptInf;
    }
    for (Index k = 0; k < m; ++k) {  // f_k <= 0
      g_l[k] = -kIpoptInf;
      g_u[k] = 0.0;
    }
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number*, Number*, Index, bool init_lambda,
                          Number*) override {
    if (!init_x || init_z || init_lambda) return false;
    for (Index i = 0; i < n; ++i) x[i] = x0_[i];
    return true;
  }

  bool eval_f(Index, const Number* x, bool, Number& obj_value) override {
    if (mode_ == Mode::kClosest) {
      obj_value = (V3(x) - V3(x + 3)).squaredNorm();  // eq. 7: |x1 - x2|^2
    } else {
      obj_value = -u_W_.dot(V3(x));
    }
    return true;
  }

  bool eval_grad_f(Index, const Number* x, bool, Number* grad_f) override {
    if (mode_ == Mode::kClosest) {  // d/dx1 = 2 (x1 - x2), d/dx2 = -2 (x1 - x2)
      const Vec3 d = V3(x) - V3(x + 3);
      for (int i = 0; i < 3; ++i) {
        grad_f[i] = 2.0 * d[i];
        grad_f[i + 3] = -2.0 * d[i];
      }
    } else {
      for (int i = 0; i < 3; ++i) grad_f[i] = -u_W_[i];
    }
    return true;
  }

  bool eval_g(Index, const Number* x, bool, Index m, Number* g) override {
    for (Index k = 0; k < m; ++k) g[k] = Evaluate(k, x, nullptr, nullptr);
    return true;
  }

  bool eval_jac_g(Index, const Number* x, bool, Index m, Index, Index* iRow, Index* jCol, Number* values) override {
    for (Index k = 0; k < m; ++k) {
      if (values == nullptr) {
        for (int i = 0; i < 3; ++i) {
          iRow[3 * k + i] = k;
          jCol[3 * k + i] = 3 * rows_[k].block + i;
        }
      } else {
        Vec3 grad_W;
        Evaluate(k, x, &grad_W, nullptr);
        for (int i = 0; i < 3; ++i) values[3 * k + i] = grad_W[i];
      }
    }
    return true;
  }

  // Hessian of the Lagrangian sigma grad^2 f0 + sum_k lambda_k grad^2 g_k, lower triangle, dense.
  bool eval_h(Index n, const Number* x, bool, Number obj_factor, Index m, const Number* lambda, bool,
              Index nele_hess, Index* iRow, Index* jCol, Number* values) override {
    if (values == nullptr) {
      Index e = 0;
      for (Index r = 0; r < n; ++r) {
        for (Index c = 0; c <= r; ++c, ++e) {
          iRow[e] = r;
          jCol[e] = c;
        }
      }
      return true;
    }
    for (Index e = 0; e < nele_hess; ++e) values[e] = 0.0;
    if (mode_ == Mode::kClosest) {  // grad^2 |x1 - x2|^2 = [2I -2I; -2I 2I]
      for (int i = 0; i < 6; ++i) values[Tri(i, i)] += 2.0 * obj_factor;
      for (int i = 0; i < 3; ++i) values[Tri(i + 3, i)] -= 2.0 * obj_factor;
    }                                // the support objective is linear
    for (Index k = 0; k < m; ++k) {
      if (lambda[k] == 0.0) continue;
      Mat3 hess_W;
      Evaluate(k, x, nullptr, &hess_W);
      const int o = 3 * rows_[k].block;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c <= r; ++c) values[Tri(o + r, o + c)] += lambda[k] * hess_W(r, c);
      }
    }
    return true;
  }

 private:
  Index num_vars() const { return mode_ == Mode::kClosest ? 6 : 3; }
  static Index Tri(Index r, Index c) { return r * (r + 1) / 2 + c; }  // lower-triangle entry (r >= c)

  // g_k = f_k(X_WS^-1 x_b); world gradient R_WS grad_S, world Hessian R_WS H_S R_WS^T.
  double Evaluate(Index k, const Number* x, Vec3* grad_W, Mat3* hess_W) const {
    const PosedInequality& row = rows_[k];
    const Mat3 R_WS = row.X_WS.linear();
    const Vec3 x_S = R_WS.transpose() * (V3(x + 3 * row.block) - row.X_WS.translation());
    double f;
    Vec3 grad_S;
    Mat3 hess_S;
    row.inequality->Evaluate(x_S, &f, grad_W ? &grad_S : nullptr, hess_W ? &hess_S : nullptr);
    if (grad_W) *grad_W = R_WS * grad_S;
    if (hess_W) *hess_W = R_WS * hess_S * R_WS.transpose();
    return f;
  }

  Mode mode_;
  std::vector<PosedInequality> rows_;
  Eigen::VectorXd x0_;
  Vec3 u_W_ = Vec3::Zero();
  Vec3 center_W_ = Vec3::Zero();
};

void AppendRows(const ConvexShape& shape, const Pose& X_WB, int block, std::vector<PosedInequality>* rows) {
  const Pose X_WS = ShapePose(shape, X_WB);
  for (const Inequality& q : shape.inequalities) rows->push_back({&q, X_WS, block});
}

// Runs Ipopt on `nlp`; true when it converged (to tol or to the acceptable level) and reported its solution.
bool RunIpopt(const Ipopt::SmartPtr<ShapeNlp>& nlp) {
  IpoptSettings settings;
  settings.tol = 1e-12;
  settings.acceptable_tol = 1e-9;
  settings.max_iter = 500;
  settings.honor_bounds = true;
  const std::lock_guard<std::mutex> lock(IpoptMutex());
  const Ipopt::SmartPtr<Ipopt::IpoptApplication> app = MakeQuietIpopt(settings);
  if (!IsValid(app)) return false;
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(nlp)));
  return IpoptSolved(status) && nlp->finalized() && nlp->x().allFinite();
}

}  // namespace

ClosestPointsResult ComputeClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                         const Pose& X_WB2) {
  ClosestPointsResult result;
  try {
    if (shape1.inequalities.empty() || shape2.inequalities.empty()) return result;
    std::vector<PosedInequality> rows;
    AppendRows(shape1, X_WB1, 0, &rows);
    AppendRows(shape2, X_WB2, 1, &rows);

    // Start at each shape's origin; an unbounded half-space starts at the other origin projected onto its plane.
    const Vec3 o_W1 = ShapePose(shape1, X_WB1).translation(), o_W2 = ShapePose(shape2, X_WB2).translation();
    auto start = [](const ConvexShape& shape, const Pose& X_WB, const Vec3& own, const Vec3& other) -> Vec3 {
      if (shape.IsBounded() || shape.inequalities.size() != 1) return own;
      Vec3 n_W, q_W;
      HalfSpacePlane(shape, X_WB, &n_W, &q_W);
      return other - n_W.dot(other - q_W) * n_W;
    };
    Eigen::VectorXd x0(6);
    x0 << start(shape1, X_WB1, o_W1, o_W2), start(shape2, X_WB2, o_W2, o_W1);

    Ipopt::SmartPtr<ShapeNlp> nlp = new ShapeNlp(ShapeNlp::Mode::kClosest, std::move(rows), x0);
    if (!RunIpopt(nlp)) return result;
    result.solved = true;
    result.p_W1 = nlp->x().head<3>();
    result.p_W2 = nlp->x().tail<3>();
    result.distance = (result.p_W1 - result.p_W2).norm();
  } catch (const std::exception&) {
    result = ClosestPointsResult();
  } catch (...) {
    result = ClosestPointsResult();
  }
  return result;
}

double SupportValue(const ConvexShape& shape, const Pose& X_WB, const Vec3& u_W) {
  try {
    if (shape.inequalities.empty() || !u_W.allFinite()) return kInf;
    if (shape.type == ShapeType::kHalfSpace) {  // closed form: bounded in u only along its outward normal
      Vec3 n_W, q_W;
      HalfSpacePlane(shape, X_WB, &n_W, &q_W);
      return (u_W - n_W).norm() <= 1e-9 ? n_W.dot(q_W) : kInf;
    }
    std::vector<PosedInequality> rows;
    AppendRows(shape, X_WB, 0, &rows);
    const Vec3 c_W = ShapePose(shape, X_WB).translation();
    Ipopt::SmartPtr<ShapeNlp> nlp = new ShapeNlp(ShapeNlp::Mode::kSupport, std::move(rows), c_W);
    nlp->SetSupport(u_W, c_W);
    if (!RunIpopt(nlp)) return kInf;  // conservative: never a finite wrong value
    return u_W.dot(Vec3(nlp->x().head<3>()));
  } catch (...) {
    return kInf;
  }
}

// The plane n.(x - p) = 0 separates body 2 (n.x <= n.p) from body 1 (n.x >= n.p) once each body's crossing is
// removed: body 2 reaches n.x = h2(n) beyond the plane, body 1 reaches min n.x = -h1(-n) below it.
double PenetrationBound(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2, const Pose& X_WB2,
                        const Vec3& p_W, const Vec3& n_W) {
  const double norm = n_W.norm();
  if (!(norm > 0.0) || !std::isfinite(norm) || !p_W.allFinite()) return kInf;
  const auto support1 = [&](const Vec3& u_W) { return SupportValue(shape1, X_WB1, u_W); };
  const auto support2 = [&](const Vec3& u_W) { return SupportValue(shape2, X_WB2, u_W); };
  return PlaneCrossingBound(support1, support2, p_W, n_W / norm);
}

}  // namespace implicit_sim
