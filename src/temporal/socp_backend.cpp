// The paper's SOCP (eqs. 30-38, 50) over the shared discretization, solved by timeopt::conic.
//
// Variables: x (free grid values, b = scale * x), c_v <= sqrt(x_v) per free value, d_k per cell,
// and t when rho > 0. Cones:
//   (x_v, 1/2, c_v) rotated          <=>  c_v^2 <= x_v                       (eqs. 31, 35)
//   (d_k, S_k, sqrt 2) rotated       <=>  d_k S_k >= 1,  S_k = sqrt(b^k) + sqrt(b^{k+1})  (eqs. 30-34)
//   (t/g, g/2, a_0 ... a_{N-1}) rotated <=> t >= sum a_k^2, a_k = (b^{k+1} - b^k) / (2 ds) (eqs. 37-38,
//   50; g > 0 only balances the cone, see below)
// where sqrt(b) = sqrt(scale) c_v for a free value and a constant for a fixed one (presolve: a
// fixed b = 0 would leave the cone c <= sqrt(b) without interior, so c is not a variable there).
// Objective: sum 2 ds d_k + rho ds t (eq. 36). Velocity bounds, acceleration and
// acceleration-change rows are the discretization's linear rows.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <utility>
#include <vector>

#include "banded_ipm.h"
#include "discretization.h"
#include "timeopt/conic/problem_builder.h"
#include "timeopt/conic/solver.h"
#include "timeopt/temporal/temporal_socp.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// An answer of the conic solver can miss a row by about 1e-6 of its bound even when it meets its
// own tolerances: near a minimum-jerk curve's vanishing tangents b spans five orders of magnitude
// and an acceleration row's two terms cancel (1.3e-6 seen). A reduced-accuracy answer, or one that
// misses a row by more than kScaleIntoRowsAbove (the rows' units: 1 is the limit; ten times the
// solver's default tolerance), is scaled into its rows by ScaleIntoRows.
constexpr double kScaleIntoRowsAbove = 1e-7;

// When there are only linear rows and each one's interval contains 0 (x = 0 satisfies it: a
// rest-to-rest problem under the paper's or certified rows), lambda x keeps the rows that x
// satisfies (their values move towards 0) and meets the others for the largest lambda <= 1
// computed here; scaling b by it slows the profile by 1 / sqrt(lambda), about half the violation.
// False, x unchanged, when the problem is not of that kind or no lambda > 0 does it (a row whose
// bound is 0 missed).
bool ScaleIntoRows(const TemporalDiscretization& d, std::vector<double>* x) {
  if (!d.cubic_rows.empty() || !d.cone_rows.empty()) return false;
  for (const LinearRow& r : d.rows) {
    if (r.lower > 0.0 || r.upper < 0.0) return false;
  }
  std::vector<double> v = *x;
  for (double& value : v) value = std::max(value, 0.0);  // b >= 0: its misses are rounding
  double lambda = 1.0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (v[i] > d.var_upper[i]) lambda = std::min(lambda, d.var_upper[i] / v[i]);
  }
  for (const LinearRow& r : d.rows) {
    double value = 0.0;
    for (const auto& t : r.terms) value += t.second * v[static_cast<size_t>(t.first)];
    if (value > r.upper) lambda = std::min(lambda, r.upper / value);
    if (value < r.lower) lambda = std::min(lambda, r.lower / value);
  }
  if (!(lambda > 0.0)) return false;
  for (double& value : v) value *= lambda;
  *x = std::move(v);
  return true;
}

}  // namespace

namespace {

// sqrt(b_g) as terms in the root variables c (c0: the first), a fixed value's in the constant.
void AddRoot(const TemporalDiscretization& d, int c0, int g, conic::AffineExpr& e) {
  const GridValue& v = d.grid[static_cast<size_t>(g)];
  if (v.var < 0) {
    e.constant += std::sqrt(v.fixed);
  } else {
    e.terms.push_back({c0 + v.var, std::sqrt(v.scale)});
  }
}

// b_g times coef as terms in the variables x (x0: the first), a fixed value's in the constant.
void AddB(const TemporalDiscretization& d, int x0, int g, double coef, conic::AffineExpr& e) {
  const GridValue& v = d.grid[static_cast<size_t>(g)];
  if (v.var < 0) {
    e.constant += coef * v.fixed;
  } else {
    e.terms.push_back({x0 + v.var, coef * v.scale});
  }
}

// The cells' time variables are held in one time unit tau, the median over cells of 1 / S_k at
// x = 1 (a cell's time over 2 ds at its reference speed), so that d_k / tau and tau S_k are
// both about 1; but never below 1. Measured on the long property sweep's slow minimum-jerk
// curves (paper rows): a path that takes 2000 s (5913) had d ~ 1e3 against S ~ 1e-3 and the
// conic solver stalled at a relative gap of 1e-6, while the same path at limits 10 times faster
// (200 s) was solved; with tau, 7 of those 11 stalls are solved. Below 1 (fast paths: d ~ 1e-5),
// two problems that had been solved (4395, 7356; T 0.018 and 0.010 s) ended at the iteration
// limit, so fast paths keep d in seconds.
double CellTimeUnit(const TemporalDiscretization& d) {
  std::vector<double> nominals;
  for (const Cell& cell : d.cells) {
    conic::AffineExpr e;
    AddRoot(d, 0, cell.first_grid, e);
    AddRoot(d, 0, cell.first_grid + 1, e);
    double nominal = e.constant;
    for (const conic::Term& t : e.terms) nominal += t.coef;
    if (nominal > 0.0 && std::isfinite(nominal)) nominals.push_back(nominal);
  }
  double tau = 1.0;
  if (!nominals.empty()) {
    std::nth_element(nominals.begin(), nominals.begin() + nominals.size() / 2, nominals.end());
    tau = std::max(1.0, 1.0 / nominals[nominals.size() / 2]);
  }
  return tau;
}

// The acceleration regularization rho * sum a^2 ds as one rotated cone over the cells' a.
void AddRegularization(const TemporalDiscretization& d, int x0, conic::ProblemBuilder* builder) {
  const int t = builder->AddVariables(1);
  // All cells share ds = 1/K, so rho * sum a^2 ds = rho ds t.
  builder->SetObjectiveCoefficient(t, d.rho * d.cells.front().ds);
  std::vector<conic::AffineExpr> rows;
  rows.reserve(d.cells.size() + 2);
  // (t / g, g / 2, a): the same cone as (t, 1/2, a), but with g ~ ||a|| at the optimum its first
  // two entries are of similar size instead of t >> 1/2, which made this one cone limit nearly
  // every step. g is half the bound acceleration_norm_scale (a is near its cap only in some cells).
  // Measured over natural cubics and rest-to-rest quintics, m = 2..100, K = 30..100, rho = 0.01..10
  // (36 problems): 5-12% fewer iterations in total per family than g = 1 (m = 10, K = 50,
  // rho = 0.1: 25 -> 19); g = the full bound, or a quarter of it, did worse on some families.
  const double g = 0.5 * d.acceleration_norm_scale;
  rows.push_back(conic::AffineExpr{{{t, 1.0 / g}}, 0.0});
  rows.push_back(conic::AffineExpr{{}, 0.5 * g});
  for (const Cell& cell : d.cells) {
    conic::AffineExpr a;
    AddB(d, x0, cell.first_grid + 1, 0.5 / cell.ds, a);
    AddB(d, x0, cell.first_grid, -0.5 / cell.ds, a);
    rows.push_back(std::move(a));
  }
  builder->AddRotatedCone(rows);
}

// The discretization's linear rows: an equality as one row of A, others as one or two rows of G.
void AddLinearRows(const TemporalDiscretization& d, int x0, conic::ProblemBuilder* builder) {
  std::vector<conic::Term> terms;
  // sign * row <= bound.
  const auto add_less_equal = [&](const LinearRow& row, double sign, double bound) {
    terms.clear();
    for (const auto& t : row.terms) terms.push_back({x0 + t.first, sign * t.second});
    builder->AddLessEqual(terms, bound);
  };
  for (const LinearRow& row : d.rows) {
    if (row.lower == row.upper) {
      // An equality (the jerk-limited mode's continuity of sddot): one row of A, not two opposite
      // inequalities, which would leave the cone rows no interior.
      terms.clear();
      for (const auto& t : row.terms) terms.push_back({x0 + t.first, t.second});
      builder->AddEquality(terms, row.upper);
      continue;
    }
    if (std::isfinite(row.upper)) add_less_equal(row, 1.0, row.upper);
    if (std::isfinite(row.lower)) add_less_equal(row, -1.0, -row.lower);
  }
}

// The quadrotor's norm limits: (bound, norm part) in a second-order cone.
void AddNormCones(const TemporalDiscretization& d, int x0, conic::ProblemBuilder* builder) {
  std::vector<conic::AffineExpr> soc(4);
  for (const ConeRow& r : d.cone_rows) {
    for (conic::AffineExpr& e : soc) {
      e.terms.clear();
      e.constant = 0.0;
    }
    soc[0].constant = r.bound_constant;
    for (int i = 0; i < 3; ++i) soc[static_cast<size_t>(i) + 1].constant = r.norm_constant(i);
    for (size_t j = 0; j < r.grid.size(); ++j) {
      if (r.bound[j] != 0.0) AddB(d, x0, r.grid[j], r.bound[j], soc[0]);
      for (int i = 0; i < 3; ++i) {
        if (r.norm[j](i) != 0.0) AddB(d, x0, r.grid[j], r.norm[j](i), soc[static_cast<size_t>(i) + 1]);
      }
    }
    builder->AddSecondOrderCone(soc);
  }
}

}  // namespace

conic::Problem BuildDiscretizedSocp(const TemporalDiscretization& d) {
  if (d.infeasible_reason) {
    throw std::invalid_argument("no SOCP to build: presolve proves the problem infeasible (" + *d.infeasible_reason +
                                ")");
  }
  if (d.num_vars == 0) {
    throw std::invalid_argument("no SOCP to build: every speed on the grid is fixed by the boundary");
  }
  if (!d.cubic_rows.empty()) {
    throw std::invalid_argument(
        "no SOCP to build: the discretization has exact (non-convex) jerk rows; "
        "the SOCP takes their linearization (JerkRows::kLinearized)");
  }
  conic::ProblemBuilder builder;
  const int nx = d.num_vars;
  const int x0 = builder.AddVariables(nx);
  const int c0 = builder.AddVariables(nx);
  const int d0 = builder.AddVariables(static_cast<int>(d.cells.size()));

  // Rows and terms are written into reused buffers (no allocation per cone or row).
  std::vector<conic::AffineExpr> cone(3);
  std::vector<conic::Term> terms;
  const auto set_row = [&cone](int r, std::initializer_list<conic::Term> row_terms, double constant) {
    cone[r].terms.assign(row_terms);
    cone[r].constant = constant;
  };
  for (int v = 0; v < nx; ++v) {
    set_row(0, {{x0 + v, 1.0}}, 0.0);
    set_row(1, {}, 0.5);
    set_row(2, {{c0 + v, 1.0}}, 0.0);
    builder.AddRotatedCone(cone);
    // x / upper <= 1, like every other linear row (right-hand side 1): the solver starts at s = e,
    // which is then the slack of every row at x = 0 (x <= upper with upper ~1e3 where the tangent is
    // short started 1e3 off and cost 4-6 iterations on long paths).
    if (std::isfinite(d.var_upper[v])) {
      terms.assign({{x0 + v, 1.0 / d.var_upper[v]}});
      builder.AddLessEqual(terms, 1.0);
    }
  }

  // Each cell's time 2 ds / (sqrt(b_k) + sqrt(b_k+1)) as 2 ds tau d_k in the objective, with the
  // rotated cone 2 d_k tau (sqrt(b_k) + sqrt(b_k+1)) >= 2 (tau: CellTimeUnit).
  const double tau = CellTimeUnit(d);
  const double sqrt2 = std::sqrt(2.0);
  for (size_t k = 0; k < d.cells.size(); ++k) {
    const Cell& cell = d.cells[k];
    const int dk = d0 + static_cast<int>(k);
    builder.SetObjectiveCoefficient(dk, 2.0 * cell.ds * cell.time_weight * tau);
    set_row(0, {{dk, 1.0}}, 0.0);
    set_row(1, {}, 0.0);
    AddRoot(d, c0, cell.first_grid, cone[1]);
    AddRoot(d, c0, cell.first_grid + 1, cone[1]);
    for (conic::Term& t : cone[1].terms) t.coef *= tau;
    cone[1].constant *= tau;
    set_row(2, {}, sqrt2);
    builder.AddRotatedCone(cone);
  }

  if (d.rho > 0.0) AddRegularization(d, x0, &builder);
  AddLinearRows(d, x0, &builder);
  AddNormCones(d, x0, &builder);
  return builder.Build();
}

namespace {

// The relative gap tolerance of the jerk-limited mode's convex solves (see SocpTemporalOptions).
constexpr double kJerkLimitedRelativeGap = 1e-7;

class SocpTemporalSolver final : public TemporalSolver {
 public:
  explicit SocpTemporalSolver(const SocpTemporalOptions& options) : options_(options) {
    conic::Solver::Options o;
    o.feasibility_tolerance = options.tolerance;
    o.absolute_gap_tolerance = options.tolerance;
    o.relative_gap_tolerance = options.tolerance;
    o.infeasibility_tolerance = options.tolerance;
    o.max_iterations = options.max_iterations;
    // Infeasible temporal problems drive tau to 0 over 10-15 iterations while the residual merit
    // barely moves; the solver's default window away from the optimum (4 x stall_iterations = 20)
    // lets them reach the certificate, and near the optimum its short window applies.
    solver_ = conic::Solver(o);
    o.relative_gap_tolerance = std::max(options.tolerance, kJerkLimitedRelativeGap);
    jerk_solver_ = conic::Solver(o);
  }

  TemporalBackend backend() const override { return TemporalBackend::kSocp; }

 protected:
  double jerk_ipopt_fallback_seconds() const override { return options_.jerk_ipopt_fallback_seconds; }
  std::int64_t jerk_ipopt_fallback_memory() const override { return options_.max_memory_bytes; }
  int structured_jerk_iterations() const override {
    return options_.structured ? std::min(internal::BandedIpmSettings().max_iterations, options_.max_iterations) : 0;
  }
  void SolveDiscretized(const TemporalDiscretization& d, TemporalResult* result, std::vector<double>* x) override {
    // The structured path first (banded_ipm.h) where it applies; the conic solver decides whenever
    // it does not end optimal.
    int banded_iterations = 0;
    double banded_seconds = 0.0;
    if (options_.structured) {
      const auto banded_start = Clock::now();
      internal::BandedIpmSettings settings;
      settings.tolerance = options_.tolerance;
      // J to 1e-2 x the tolerance: T agrees with the conic solver's to ~1e-10 relative.
      settings.gap_tolerance = 1e-2 * options_.tolerance;
      internal::BandedIpmOutcome b = internal::SolveBanded(d, settings);
      banded_seconds = Seconds(banded_start, Clock::now());
      if (b.kind == internal::BandedIpmOutcome::Kind::kOptimal) {
        result->iterations = b.iterations;
        result->solve_time_seconds = banded_seconds;
        *x = std::move(b.x);
        result->status = TemporalStatus::kOptimal;
        result->message = "tolerances met (structured path)";
        result->method = "structured";
        result->rows = b.rows;
        result->reduced_accuracy = false;
        return;
      }
      if (b.kind == internal::BandedIpmOutcome::Kind::kInfeasible) {
        result->iterations = 0;
        result->solve_time_seconds = banded_seconds;
        result->status = TemporalStatus::kInfeasible;
        result->message = b.message;
        return;
      }
      banded_iterations = b.iterations;
    }
    const auto start = Clock::now();
    const conic::Problem socp = BuildDiscretizedSocp(d);
    result->build_time_seconds += Seconds(start, Clock::now());

    const conic::Result r = (d.jerk_limited ? jerk_solver_ : solver_).Solve(socp);
    result->iterations = banded_iterations + r.iterations;
    result->method = "conic";
    result->rows = static_cast<int>(d.rows.size());
    result->solve_time_seconds = banded_seconds + r.solve_time_seconds;
    switch (r.status) {
      case conic::Status::kOptimal:
        x->assign(r.x.data(), r.x.data() + d.num_vars);
        result->status = TemporalStatus::kOptimal;
        result->message = r.message;
        result->reduced_accuracy = r.reduced_accuracy;
        if ((r.reduced_accuracy || d.MaxViolation(*x) > kScaleIntoRowsAbove) && ScaleIntoRows(d, x)) {
          result->message += "; scaled into the rows";
        }
        break;
      case conic::Status::kPrimalInfeasible:
        result->status = TemporalStatus::kInfeasible;
        result->message = "no time allocation satisfies the limits (conic solver: " + r.message + ")";
        break;
      case conic::Status::kIterationLimit:
        result->status = TemporalStatus::kIterationLimit;
        result->message = r.message;
        break;
      case conic::Status::kDualInfeasible:
      case conic::Status::kNumericalError:
      case conic::Status::kNotSolved:
        result->status = TemporalStatus::kNumericalError;
        result->message = std::string("conic solver: ") + conic::ToString(r.status) + ": " + r.message;
        break;
    }
  }

 private:
  SocpTemporalOptions options_;
  conic::Solver solver_;
  conic::Solver jerk_solver_;  // jerk-limited discretizations (see SocpTemporalOptions::tolerance)
};

}  // namespace

std::unique_ptr<TemporalSolver> MakeSocpTemporalSolver(const SocpTemporalOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("SocpTemporalOptions." + error);
  return std::make_unique<SocpTemporalSolver>(options);
}

conic::Problem BuildTemporalSocp(const TemporalProblem& problem) { return BuildDiscretizedSocp(Discretize(problem)); }

}  // namespace timeopt
