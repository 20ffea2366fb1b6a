// An independent reference for jerk-limited time-optimal profiles: the problem written in time,
// not in the path parameter, and solved by Ipopt. It shares nothing with DiscretizeJerkLimited: no
// grid in s, no rest cells, no linearized jerk rows, no sequential convex programme.
//
// Along one polynomial piece f(s), s in [0, 1], from rest to rest: the unknowns are the duration T,
// the state (s, sdot, sddot) at N + 1 instants t_n = n T / N and a constant s-jerk u_n on each
// interval, tied by the exact integration of that jerk. Velocity f' sdot, acceleration
// f' sddot + f'' sdot^2 and jerk f' u + 3 f'' sdot sddot + f''' sdot^3 are bounded per axis at every
// instant and in the middle of every interval (the jerk on both sides of each instant). Between
// those samples nothing is bounded, so its T is the continuous optimum from below, to
// O(1 / N^2) (the tests measure how much by halving N). The problem is not convex; Ipopt finds a
// local optimum from a septic smoothstep start, which on the tests' curves is the global one (the
// certified SCP's T, a feasible continuous profile, is never below it).
#ifndef TIMEOPT_TESTS_TEMPORAL_TIME_DOMAIN_REFERENCE_H_
#define TIMEOPT_TESTS_TEMPORAL_TIME_DOMAIN_REFERENCE_H_

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>

#include "timeopt/curve/polynomial_piece.h"

namespace timeopt {
namespace test_support {

struct TimeDomainReference {
  bool solved = false;
  double total_time = 0.0;
  std::vector<double> s, sdot, sddot;  // at the N + 1 instants n total_time / N
  std::string message;
};

namespace time_domain {

// Forward-mode derivative with respect to at most kLocals local unknowns.
constexpr int kLocals = 8;
struct Dual {
  double v = 0.0;
  std::array<double, kLocals> d{};
  Dual() = default;
  Dual(double value) : v(value) {}  // NOLINT: constants promote implicitly
};
inline Dual operator+(const Dual& a, const Dual& b) {
  Dual r(a.v + b.v);
  for (int i = 0; i < kLocals; ++i) r.d[i] = a.d[i] + b.d[i];
  return r;
}
inline Dual operator-(const Dual& a, const Dual& b) {
  Dual r(a.v - b.v);
  for (int i = 0; i < kLocals; ++i) r.d[i] = a.d[i] - b.d[i];
  return r;
}
inline Dual operator*(const Dual& a, const Dual& b) {
  Dual r(a.v * b.v);
  for (int i = 0; i < kLocals; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
  return r;
}

// One constraint row: a function of its local unknowns (indices into the variable vector).
struct Row {
  std::vector<int> locals;
  std::function<Dual(const std::array<Dual, kLocals>&)> f;
  double lower, upper;
};

class Nlp : public Ipopt::TNLP {
 public:
  Nlp(std::vector<Row> rows, std::vector<double> x0, std::vector<double> lo, std::vector<double> hi)
      : rows_(std::move(rows)), x_(std::move(x0)), lo_(std::move(lo)), hi_(std::move(hi)) {}

  const std::vector<double>& x() const { return x_; }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = static_cast<Ipopt::Index>(x_.size());
    m = static_cast<Ipopt::Index>(rows_.size());
    nnz_jac = 0;
    for (const Row& r : rows_) nnz_jac += static_cast<Ipopt::Index>(r.locals.size());
    nnz_h = 0;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* xl, Ipopt::Number* xu, Ipopt::Index m, Ipopt::Number* gl,
                       Ipopt::Number* gu) override {
    for (Ipopt::Index i = 0; i < n; ++i) xl[i] = lo_[i], xu[i] = hi_[i];
    for (Ipopt::Index i = 0; i < m; ++i) gl[i] = rows_[i].lower, gu[i] = rows_[i].upper;
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool, Ipopt::Number* x, bool, Ipopt::Number*, Ipopt::Number*, Ipopt::Index,
                          bool, Ipopt::Number*) override {
    for (Ipopt::Index i = 0; i < n; ++i) x[i] = x_[i];
    return true;
  }
  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    f = x[0];
    return true;
  }
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number*, bool, Ipopt::Number* g) override {
    for (Ipopt::Index i = 0; i < n; ++i) g[i] = 0.0;
    g[0] = 1.0;
    return true;
  }
  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index m, Ipopt::Number* g) override {
    for (Ipopt::Index i = 0; i < m; ++i) g[i] = Evaluate(rows_[i], x).v;
    return true;
  }
  bool eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index m, Ipopt::Index, Ipopt::Index* irow,
                  Ipopt::Index* jcol, Ipopt::Number* values) override {
    Ipopt::Index k = 0;
    for (Ipopt::Index i = 0; i < m; ++i) {
      const Row& r = rows_[i];
      if (values == nullptr) {
        for (int local : r.locals) irow[k] = i, jcol[k] = local, ++k;
      } else {
        const Dual value = Evaluate(r, x);
        for (size_t j = 0; j < r.locals.size(); ++j) values[k++] = value.d[j];
      }
    }
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x, const Ipopt::Number*,
                         const Ipopt::Number*, Ipopt::Index, const Ipopt::Number*, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    x_.assign(x, x + n);
  }

 private:
  static Dual Evaluate(const Row& r, const Ipopt::Number* x) {
    std::array<Dual, kLocals> in;
    for (size_t j = 0; j < r.locals.size(); ++j) {
      in[j] = Dual(x[r.locals[j]]);
      in[j].d[j] = 1.0;
    }
    return r.f(in);
  }

  std::vector<Row> rows_;
  std::vector<double> x_, lo_, hi_;
};

// sum_j c_j s^j for one axis of a coefficient row, by Horner's rule.
inline Dual Polynomial(const Eigen::RowVectorXd& c, const Dual& s) {
  Dual r(c(c.size() - 1));
  for (Eigen::Index j = c.size() - 2; j >= 0; --j) r = r * s + Dual(c(j));
  return r;
}

}  // namespace time_domain

// The optimum along `piece` with per-axis limits v, a, j on N intervals, to rest at its end, from
// rest or from the state (sdot, sddot) = (start_sdot, start_sddot) at s = 0 (a start in motion).
inline TimeDomainReference SolveTimeDomainReference(const PolynomialPiece& piece, const Eigen::Vector3d& v,
                                                    const Eigen::Vector3d& a, const Eigen::Vector3d& j, int N,
                                                    double start_sdot = 0.0, double start_sddot = 0.0) {
  using time_domain::Dual;
  using time_domain::kLocals;
  using time_domain::Row;
  const PolynomialPiece d1 = piece.Derivative(1), d2 = piece.Derivative(2), d3 = piece.Derivative(3);
  const auto coefficients = [](const PolynomialPiece& p, int axis) -> Eigen::RowVectorXd {
    return p.degree() >= 0 && p.coefficients().cols() > 0 ? Eigen::RowVectorXd(p.coefficients().row(axis))
                                                          : Eigen::RowVectorXd::Zero(1);
  };
  const int nvar = 1 + 3 * (N + 1) + N;
  const auto S = [](int n) { return 1 + 3 * n; };
  const auto U = [N](int n) { return 1 + 3 * (N + 1) + n; };
  std::vector<Row> rows;

  // Exact integration of a constant jerk over one interval: locals T, s, v, a, u, s+, v+, a+.
  for (int n = 0; n < N; ++n) {
    const std::vector<int> locals{0, S(n), S(n) + 1, S(n) + 2, U(n), S(n + 1), S(n + 1) + 1, S(n + 1) + 2};
    const double inv = 1.0 / N;
    rows.push_back({locals,
                    [inv](const std::array<Dual, kLocals>& x) {
                      const Dual h = x[0] * Dual(inv);
                      return x[5] - x[1] - x[2] * h - Dual(0.5) * x[3] * h * h - Dual(1.0 / 6.0) * x[4] * h * h * h;
                    },
                    0.0, 0.0});
    rows.push_back({locals,
                    [inv](const std::array<Dual, kLocals>& x) {
                      const Dual h = x[0] * Dual(inv);
                      return x[6] - x[2] - x[3] * h - Dual(0.5) * x[4] * h * h;
                    },
                    0.0, 0.0});
    rows.push_back({locals,
                    [inv](const std::array<Dual, kLocals>& x) {
                      const Dual h = x[0] * Dual(inv);
                      return x[7] - x[3] - x[4] * h;
                    },
                    0.0, 0.0});
  }
  // The limits at a state (s, sdot, sddot) reached `tau` (in units of T / N) after instant n with
  // jerk u_n; tau = 0 is the instant itself. Locals T, s, v, a, u.
  const auto state = [N](const std::array<Dual, kLocals>& x, double tau, Dual* s, Dual* sd, Dual* sdd) {
    const Dual h = x[0] * Dual(tau / N);
    *s = x[1] + x[2] * h + Dual(0.5) * x[3] * h * h + Dual(1.0 / 6.0) * x[4] * h * h * h;
    *sd = x[2] + x[3] * h + Dual(0.5) * x[4] * h * h;
    *sdd = x[3] + x[4] * h;
  };
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::RowVectorXd c1 = coefficients(d1, axis), c2 = coefficients(d2, axis), c3 = coefficients(d3, axis);
    const auto add = [&](const std::vector<int>& locals, double tau, bool speed_and_acceleration) {
      if (speed_and_acceleration) {
        rows.push_back({locals,
                        [=](const std::array<Dual, kLocals>& x) {
                          Dual s, sd, sdd;
                          state(x, tau, &s, &sd, &sdd);
                          return time_domain::Polynomial(c1, s) * sd;
                        },
                        -v(axis), v(axis)});
        rows.push_back({locals,
                        [=](const std::array<Dual, kLocals>& x) {
                          Dual s, sd, sdd;
                          state(x, tau, &s, &sd, &sdd);
                          return time_domain::Polynomial(c1, s) * sdd + time_domain::Polynomial(c2, s) * sd * sd;
                        },
                        -a(axis), a(axis)});
      }
      rows.push_back({locals,
                      [=](const std::array<Dual, kLocals>& x) {
                        Dual s, sd, sdd;
                        state(x, tau, &s, &sd, &sdd);
                        return time_domain::Polynomial(c1, s) * x[4] +
                               Dual(3.0) * time_domain::Polynomial(c2, s) * sd * sdd +
                               time_domain::Polynomial(c3, s) * sd * sd * sd;
                      },
                      -j(axis), j(axis)});
    };
    for (int n = 0; n < N; ++n) {
      const std::vector<int> locals{0, S(n), S(n) + 1, S(n) + 2, U(n)};
      add(locals, 0.0, true);        // instant n, and the jerk just after it
      add(locals, 0.5, true);        // the middle of the interval
      add(locals, 1.0, n == N - 1);  // the jerk just before instant n + 1 (the last instant's v and a too)
    }
  }

  // Bounds: rest at the end (and the start unless given), s in [0, 1], sdot >= 0, T > 0.
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> lo(nvar, -inf), hi(nvar, inf);
  lo[0] = 1e-6;
  for (int n = 0; n <= N; ++n) lo[S(n)] = 0.0, hi[S(n)] = 1.0, lo[S(n) + 1] = 0.0;
  lo[S(0)] = hi[S(0)] = 0.0;
  lo[S(0) + 1] = hi[S(0) + 1] = start_sdot;
  lo[S(0) + 2] = hi[S(0) + 2] = start_sddot;
  lo[S(N)] = hi[S(N)] = 1.0;
  lo[S(N) + 1] = hi[S(N) + 1] = lo[S(N) + 2] = hi[S(N) + 2] = 0.0;

  // Start: the septic smoothstep (zero speed, acceleration and jerk at both ends) over a duration
  // at which it is well inside the limits along the chord.
  double length = 0.0;
  for (int k = 0; k < 64; ++k) length += piece.Evaluate((k + 0.5) / 64.0, 1).norm() / 64.0;
  const double T0 = 2.0 * (length / v.minCoeff() + std::sqrt(length / a.minCoeff()) + std::cbrt(length / j.minCoeff()));
  std::vector<double> x0(nvar, 0.0);
  x0[0] = T0;
  for (int n = 0; n <= N; ++n) {
    const double q = static_cast<double>(n) / N;
    const double q3 = q * q * q;
    x0[S(n)] = q3 * q * (35.0 - 84.0 * q + 70.0 * q * q - 20.0 * q3);
    x0[S(n) + 1] = 140.0 * q3 * (1.0 - q) * (1.0 - q) * (1.0 - q) / T0;
    x0[S(n) + 2] = 420.0 * q * q * (1.0 - q) * (1.0 - q) * (1.0 - 2.0 * q) / (T0 * T0);
  }
  x0[S(0) + 1] = start_sdot;
  x0[S(0) + 2] = start_sddot;
  for (int n = 0; n < N; ++n) x0[U(n)] = (x0[S(n + 1) + 2] - x0[S(n) + 2]) / (T0 / N);

  Ipopt::SmartPtr<time_domain::Nlp> nlp =
      new time_domain::Nlp(std::move(rows), std::move(x0), std::move(lo), std::move(hi));
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = new Ipopt::IpoptApplication(false);
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetNumericValue("tol", 1e-10);
  app->Options()->SetNumericValue("constr_viol_tol", 1e-10);
  app->Options()->SetIntegerValue("max_iter", 5000);
  TimeDomainReference result;
  if (app->Initialize() != Ipopt::Solve_Succeeded) {
    result.message = "Ipopt did not initialize";
    return result;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(Ipopt::GetRawPtr(nlp)));
  result.solved = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  result.total_time = nlp->x()[0];
  for (int n = 0; n <= N; ++n) {
    result.s.push_back(nlp->x()[S(n)]);
    result.sdot.push_back(nlp->x()[S(n) + 1]);
    result.sddot.push_back(nlp->x()[S(n) + 2]);
  }
  result.message = "Ipopt status " + std::to_string(static_cast<int>(status));
  return result;
}

}  // namespace test_support
}  // namespace timeopt

#endif  // TIMEOPT_TESTS_TEMPORAL_TIME_DOMAIN_REFERENCE_H_
