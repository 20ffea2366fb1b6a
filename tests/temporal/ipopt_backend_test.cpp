// Tests of the Ipopt backend: the NLP's exact derivatives against finite differences, and the
// solver against closed forms, infeasible and invalid problems.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../../src/temporal/ipopt_nlp.h"
#include "timeopt/curve/interpolation.h"
#include "temporal/discretization.h"
#include "timeopt/temporal/temporal_solver.h"

#include "../common/fixtures.h"

namespace timeopt {
namespace {

using test_support::LinearPiece;
using test_support::LineProblem;
using ::testing::HasSubstr;

// Cubic Hermite piece from p0 to p1 with tangents t0, t1 (in s).
PolynomialPiece Hermite(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& t0,
                        const Eigen::Vector3d& t1) {
  PolynomialPiece::Coefficients c(3, 4);
  c.col(0) = p0;
  c.col(1) = t0;
  c.col(2) = 3.0 * (p1 - p0) - 2.0 * t0 - t1;
  c.col(3) = 2.0 * (p0 - p1) + t0 + t1;
  return PolynomialPiece(c);
}

// A random curve of three cubic pieces whose joints are G1 (tangent lengths differ by the
// factors 0.5 and 1.7, so grid values are shared with scale != 1), a given start velocity along
// the tangent (a fixed non-zero b) and rest at the end (a fixed b = 0 next to a free one).
TemporalProblem RandomG1Problem(std::mt19937& rng, int K, double rho) {
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  const auto rv = [&] { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  const Eigen::Vector3d p0 = rv(), p1 = rv(), p2 = rv(), p3 = rv();
  const Eigen::Vector3d t0 = rv(), t1 = rv(), t2 = rv(), t3 = rv();
  TemporalProblem p;
  p.curve = PiecewiseCurve({Hermite(p0, p1, t0, t1), Hermite(p1, p2, 0.5 * t1, t2), Hermite(p2, p3, 1.7 * t2, t3)});
  p.limits.max_velocity = Eigen::Vector3d(2.0, 3.0, 2.5);
  p.limits.max_acceleration = Eigen::Vector3d(1.0, 1.5, 2.0);
  p.boundary.start_velocity = 0.1 * t0;
  p.cells_per_piece = K;
  p.rho = rho;
  return p;
}

double Objective(IpoptTemporalNlp& nlp, const std::vector<double>& x) {
  double f = 0.0;
  EXPECT_TRUE(nlp.eval_f(static_cast<Ipopt::Index>(x.size()), x.data(), true, f));
  return f;
}

std::vector<double> Gradient(IpoptTemporalNlp& nlp, const std::vector<double>& x) {
  std::vector<double> g(x.size());
  EXPECT_TRUE(nlp.eval_grad_f(static_cast<Ipopt::Index>(x.size()), x.data(), true, g.data()));
  return g;
}

// The dense symmetric Hessian of the Lagrangian from the NLP's lower triangle, with the given
// objective factor and non-zero constraint multipliers (which must not matter: rows are linear;
// the exact jerk rows, whose multipliers do, have their own test below).
Eigen::MatrixXd DenseHessian(IpoptTemporalNlp& nlp, const std::vector<double>& x, double obj_factor) {
  Ipopt::Index n = 0, m = 0, nnz_jac = 0, nnz_h = 0;
  Ipopt::TNLP::IndexStyleEnum style;
  EXPECT_TRUE(nlp.get_nlp_info(n, m, nnz_jac, nnz_h, style));
  std::vector<Ipopt::Index> rows(static_cast<size_t>(nnz_h)), cols(static_cast<size_t>(nnz_h));
  EXPECT_TRUE(nlp.eval_h(n, x.data(), true, obj_factor, m, nullptr, true, nnz_h, rows.data(), cols.data(), nullptr));
  std::vector<double> lambda(static_cast<size_t>(m), 3.0);
  std::vector<double> values(static_cast<size_t>(nnz_h));
  EXPECT_TRUE(
      nlp.eval_h(n, x.data(), true, obj_factor, m, lambda.data(), true, nnz_h, nullptr, nullptr, values.data()));
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  std::set<std::pair<int, int>> seen;
  for (size_t e = 0; e < values.size(); ++e) {
    EXPECT_GE(rows[e], cols[e]) << "entry " << e << " is not in the lower triangle";
    EXPECT_TRUE(seen.insert({rows[e], cols[e]}).second) << "duplicate entry " << e;
    h(rows[e], cols[e]) = values[e];
    h(cols[e], rows[e]) = values[e];
  }
  return h;
}

// Central differences with step 1e-6 * max(1, |x_v|): truncation error ~h^2 |f'''| ~ 1e-12
// relative and rounding ~eps |f| / h ~ 1e-10 relative for the values here (b in [0.02, 0.2],
// derivatives up to ~1e3), so 1e-6 relative to the largest entry leaves a wide margin and still
// catches any wrong term (a wrong factor or sign changes entries by O(1) relative).
constexpr double kFiniteDifferenceTolerance = 1e-6;

// Checks the NLP's objective, gradient and Hessian (lower triangle, no duplicates, constraint
// multipliers ignored, scaled by obj_factor) at x against central differences.
void ExpectDerivativesMatchFiniteDifferences(const TemporalDiscretization& d, const std::vector<double>& x) {
  IpoptTemporalNlp nlp(d);
  const int n = d.num_vars;
  ASSERT_EQ(static_cast<int>(x.size()), n);
  // The objective is the discretization's own (same sums up to rounding: 1e-12 relative), times
  // the NLP's scale.
  ASSERT_TRUE(std::isfinite(nlp.objective_scale()) && nlp.objective_scale() > 0.0);
  EXPECT_NEAR(Objective(nlp, x), nlp.objective_scale() * d.Objective(x),
              1e-12 * nlp.objective_scale() * d.Objective(x));

  const std::vector<double> g = Gradient(nlp, x);
  std::vector<double> g_fd(static_cast<size_t>(n));
  Eigen::MatrixXd h_fd(n, n);
  for (int v = 0; v < n; ++v) {
    const double step = 1e-6 * std::max(1.0, std::abs(x[v]));
    std::vector<double> xp = x, xm = x;
    xp[v] += step;
    xm[v] -= step;
    g_fd[v] = (Objective(nlp, xp) - Objective(nlp, xm)) / (2.0 * step);
    const std::vector<double> gp = Gradient(nlp, xp), gm = Gradient(nlp, xm);
    for (int w = 0; w < n; ++w) h_fd(w, v) = (gp[w] - gm[w]) / (2.0 * step);
  }
  double g_scale = 0.0;
  for (double v : g_fd) g_scale = std::max(g_scale, std::abs(v));
  for (int v = 0; v < n; ++v) {
    EXPECT_NEAR(g[v], g_fd[v], kFiniteDifferenceTolerance * g_scale) << "var " << v;
  }
  const double obj_factor = 0.75;
  const Eigen::MatrixXd h = DenseHessian(nlp, x, obj_factor);
  const double h_scale = h_fd.cwiseAbs().maxCoeff();
  EXPECT_LT((h - obj_factor * h_fd).cwiseAbs().maxCoeff(), kFiniteDifferenceTolerance * h_scale);
}

TEST(IpoptTemporalNlp, GradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(7);
  for (double rho : {0.0, 0.7}) {
    const TemporalProblem problem = RandomG1Problem(rng, 6, rho);
    const TemporalDiscretization d = Discretize(problem);
    ASSERT_FALSE(d.infeasible_reason.has_value()) << *d.infeasible_reason;
    // The construction must exercise shared variables with scale != 1 and fixed ends.
    ASSERT_EQ(d.joints.size(), 2u);
    EXPECT_EQ(d.joints[0].type, JointType::kG1);
    EXPECT_EQ(d.joints[1].type, JointType::kG1);
    EXPECT_GT(d.grid.front().fixed, 0.0);
    EXPECT_LT(d.grid.front().var, 0);
    EXPECT_LT(d.grid.back().var, 0);
    std::uniform_real_distribution<double> u(0.02, 0.2);
    std::vector<double> x(static_cast<size_t>(d.num_vars));
    for (double& v : x) v = u(rng);
    ExpectDerivativesMatchFiniteDifferences(d, x);
  }
}

// A hand-made discretization where both ends of one cell are the same variable (with different
// scales), next to a fixed b = 0: the cell's cross term lands on a diagonal entry twice.
TEST(IpoptTemporalNlp, CellWithBothEndsOnOneVariable) {
  TemporalDiscretization d;
  d.num_pieces = 1;
  d.cells_per_piece = 3;
  d.rho = 0.4;
  d.num_vars = 2;
  d.grid = {GridValue{0, 1.0, 0.0}, GridValue{0, 2.5, 0.0}, GridValue{1, 0.5, 0.0}, GridValue{-1, 1.0, 0.0}};
  d.cells = {Cell{0, 0, 1.0 / 3}, Cell{0, 1, 1.0 / 3}, Cell{0, 2, 1.0 / 3}};
  d.var_upper = {std::numeric_limits<double>::infinity(), 1.0};
  ExpectDerivativesMatchFiniteDifferences(d, {0.3, 0.7});
  ExpectDerivativesMatchFiniteDifferences(d, {0.05, 0.02});
}

// Jerk-limited mode with exact rows: the cubic rows' Jacobian (eval_jac_g) and their part of the
// Hessian of the Lagrangian (eval_h with multipliers) against central differences of eval_g and
// of obj_factor grad f + J^T lambda. Same steps and tolerance as above: the rows are cubic in
// values ~0.1, so truncation is ~h^2 relative and any wrong term is O(1) relative.
TEST(IpoptTemporalNlp, ExactJerkRowsMatchFiniteDifferences) {
  std::mt19937 rng(5);
  TemporalProblem problem = RandomG1Problem(rng, 3, 0.0);
  problem.limits.max_jerk = Eigen::Vector3d(4.0, 5.0, 6.0);
  // The start moves at sdot = 0.1 (start_velocity = 0.1 f'(0)), so its acceleration must have the
  // curvature's part f'' sdot^2 across the path.
  problem.boundary.start_acceleration = 0.01 * problem.curve.Evaluate(0, 0.0, 2);
  const TemporalDiscretization d = DiscretizeJerkLimited(problem, JerkRows::kExact);
  ASSERT_FALSE(d.infeasible_reason.has_value()) << *d.infeasible_reason;
  ASSERT_FALSE(d.cubic_rows.empty());
  EXPECT_GT(d.grid.front().fixed, 0.0);  // a fixed, non-zero value inside some cubic rows
  IpoptTemporalNlp nlp(d);
  Ipopt::Index n = 0, m = 0, nnz_jac = 0, nnz_h = 0;
  Ipopt::TNLP::IndexStyleEnum style;
  ASSERT_TRUE(nlp.get_nlp_info(n, m, nnz_jac, nnz_h, style));
  ASSERT_EQ(m, static_cast<Ipopt::Index>(d.rows.size() + d.cubic_rows.size()));
  std::uniform_real_distribution<double> u(0.02, 0.2);
  std::vector<double> x(static_cast<size_t>(n));
  for (double& v : x) v = u(rng);
  std::vector<double> lambda(static_cast<size_t>(m));
  for (double& l : lambda) l = u(rng);
  const double obj_factor = 0.75;

  std::vector<Ipopt::Index> jr(static_cast<size_t>(nnz_jac)), jc(static_cast<size_t>(nnz_jac));
  ASSERT_TRUE(nlp.eval_jac_g(n, x.data(), true, m, nnz_jac, jr.data(), jc.data(), nullptr));
  const auto jacobian = [&](const std::vector<double>& at) {
    std::vector<double> values(static_cast<size_t>(nnz_jac));
    EXPECT_TRUE(nlp.eval_jac_g(n, at.data(), true, m, nnz_jac, nullptr, nullptr, values.data()));
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(m, n);
    for (size_t e = 0; e < values.size(); ++e) jac(jr[e], jc[e]) += values[e];
    return jac;
  };
  const auto constraints = [&](const std::vector<double>& at) {
    Eigen::VectorXd g(m);
    EXPECT_TRUE(nlp.eval_g(n, at.data(), true, m, g.data()));
    return g;
  };
  // The gradient of the Lagrangian obj_factor f + lambda . g.
  const auto lagrangian_gradient = [&](const std::vector<double>& at) {
    const std::vector<double> gf = Gradient(nlp, at);
    Eigen::VectorXd grad = obj_factor * Eigen::Map<const Eigen::VectorXd>(gf.data(), n);
    return Eigen::VectorXd(grad + jacobian(at).transpose() * Eigen::Map<const Eigen::VectorXd>(lambda.data(), m));
  };
  const Eigen::MatrixXd jac = jacobian(x);
  Eigen::MatrixXd jac_fd(m, n), h_fd(n, n);
  for (int v = 0; v < n; ++v) {
    const double step = 1e-6 * std::max(1.0, std::abs(x[v]));
    std::vector<double> xp = x, xm = x;
    xp[v] += step;
    xm[v] -= step;
    jac_fd.col(v) = (constraints(xp) - constraints(xm)) / (2.0 * step);
    h_fd.col(v) = (lagrangian_gradient(xp) - lagrangian_gradient(xm)) / (2.0 * step);
  }
  EXPECT_LT((jac - jac_fd).cwiseAbs().maxCoeff(), kFiniteDifferenceTolerance * jac_fd.cwiseAbs().maxCoeff());
  std::vector<Ipopt::Index> hr(static_cast<size_t>(nnz_h)), hc(static_cast<size_t>(nnz_h));
  std::vector<double> hv(static_cast<size_t>(nnz_h));
  ASSERT_TRUE(nlp.eval_h(n, x.data(), true, obj_factor, m, nullptr, true, nnz_h, hr.data(), hc.data(), nullptr));
  ASSERT_TRUE(nlp.eval_h(n, x.data(), true, obj_factor, m, lambda.data(), true, nnz_h, nullptr, nullptr, hv.data()));
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  std::set<std::pair<int, int>> seen;
  for (size_t e = 0; e < hv.size(); ++e) {
    EXPECT_GE(hr[e], hc[e]);
    EXPECT_TRUE(seen.insert({hr[e], hc[e]}).second) << "duplicate entry " << e;
    h(hr[e], hc[e]) = hv[e];
    h(hc[e], hr[e]) = hv[e];
  }
  EXPECT_LT((h - h_fd).cwiseAbs().maxCoeff(), kFiniteDifferenceTolerance * h_fd.cwiseAbs().maxCoeff());
}

// The Jacobian is the rows' coefficients and eval_g is J x (exact for linear rows up to
// rounding of sums of ~4 terms: 1e-12 relative).
TEST(IpoptTemporalNlp, ConstraintsAreTheLinearRows) {
  std::mt19937 rng(11);
  TemporalProblem problem = RandomG1Problem(rng, 5, 0.0);
  problem.limits.max_acceleration_change = 0.5;
  const TemporalDiscretization d = Discretize(problem);
  IpoptTemporalNlp nlp(d);
  Ipopt::Index n = 0, m = 0, nnz_jac = 0, nnz_h = 0;
  Ipopt::TNLP::IndexStyleEnum style;
  ASSERT_TRUE(nlp.get_nlp_info(n, m, nnz_jac, nnz_h, style));
  ASSERT_EQ(m, static_cast<Ipopt::Index>(d.rows.size()));
  std::vector<Ipopt::Index> rows(static_cast<size_t>(nnz_jac)), cols(static_cast<size_t>(nnz_jac));
  std::vector<double> values(static_cast<size_t>(nnz_jac));
  std::vector<double> x(static_cast<size_t>(n), 0.1);
  ASSERT_TRUE(nlp.eval_jac_g(n, x.data(), true, m, nnz_jac, rows.data(), cols.data(), nullptr));
  ASSERT_TRUE(nlp.eval_jac_g(n, x.data(), true, m, nnz_jac, nullptr, nullptr, values.data()));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (double& v : x) v = u(rng);
  std::vector<double> jx(static_cast<size_t>(m), 0.0), g(static_cast<size_t>(m));
  for (size_t e = 0; e < values.size(); ++e) jx[rows[e]] += values[e] * x[cols[e]];
  ASSERT_TRUE(nlp.eval_g(n, x.data(), true, m, g.data()));
  for (int i = 0; i < m; ++i) EXPECT_NEAR(g[i], jx[i], 1e-12 * std::max(1.0, std::abs(jx[i])));
}

// The starting point is strictly inside the variable bounds and satisfies every row that holds
// at x = 0 (all rows of a rest-to-rest problem).
TEST(IpoptTemporalNlp, StartingPointIsInteriorAndFeasible) {
  std::mt19937 rng(3);
  TemporalProblem problem = RandomG1Problem(rng, 20, 0.0);
  problem.boundary.start_velocity.setZero();
  const TemporalDiscretization d = Discretize(problem);
  const std::vector<double> x0 = IpoptTemporalNlp(d).StartingPoint();
  ASSERT_EQ(static_cast<int>(x0.size()), d.num_vars);
  for (int v = 0; v < d.num_vars; ++v) {
    EXPECT_GT(x0[v], 0.0);
    EXPECT_LT(x0[v], d.var_upper[v]);
  }
  EXPECT_EQ(d.MaxViolation(x0), 0.0);
}

// The closed form T = L/vmax + vmax/amax (L >= vmax^2/amax) or 2 sqrt(L/amax): the discretized
// problem reproduces it exactly when the switch points fall on grid points (s = 0.2 and 0.8 for
// L = 10, s = 0.5 for L = 1 and even K), because b is then exactly linear on every cell. Ipopt
// runs at tol 1e-10 with constraint violation 1e-9, so T matches to 1e-7 relative.
constexpr double kClosedFormTolerance = 1e-7;

TEST(IpoptBackend, StraightLineMatchesClosedForm) {
  auto solver = MakeIpoptTemporalSolver();
  EXPECT_EQ(solver->backend(), TemporalBackend::kIpopt);
  for (int K : {5, 10, 20, 50}) {
    const TemporalResult r = solver->Solve(LineProblem(10.0, K));
    ASSERT_EQ(r.status, TemporalStatus::kOptimal) << r.message;
    EXPECT_EQ(r.solver, "ipopt");
    EXPECT_NEAR(r.total_time, 7.0, 7.0 * kClosedFormTolerance) << "K=" << K;
    EXPECT_NEAR(r.objective, r.total_time, 1e-12);  // rho = 0
    ASSERT_EQ(r.piece_durations.size(), 1u);
    EXPECT_NEAR(r.piece_durations[0], r.total_time, 1e-12);
    EXPECT_GT(r.iterations, 0);
    EXPECT_GT(r.solve_time_seconds, 0.0);
  }
  for (int K : {2, 10, 50}) {
    const TemporalResult r = solver->Solve(LineProblem(1.0, K));
    ASSERT_EQ(r.status, TemporalStatus::kOptimal) << r.message;
    EXPECT_NEAR(r.total_time, 2.0, 2.0 * kClosedFormTolerance) << "K=" << K;
  }
}

// The same line of length 10 split at x = 4 into pieces of lengths 4 and 6 (a G1 joint with
// tangent ratio 4/6, so b is shared across the joint with scale (4/6)^2): the switch points
// x = 2 and x = 8 are s = 1/2 on piece 0 and s = 2/3 on piece 1, grid points for K = 30 and 60.
TEST(IpoptBackend, SplitLineWithUnequalPiecesMatchesClosedForm) {
  auto solver = MakeIpoptTemporalSolver();
  for (int K : {30, 60}) {
    TemporalProblem p = LineProblem(10.0, K);
    p.curve = PiecewiseCurve({LinearPiece(Eigen::Vector3d::Zero(), Eigen::Vector3d(4, 0, 0)),
                              LinearPiece(Eigen::Vector3d(4, 0, 0), Eigen::Vector3d(10, 0, 0))});
    const TemporalResult r = solver->Solve(p);
    ASSERT_EQ(r.status, TemporalStatus::kOptimal) << r.message;
    ASSERT_EQ(r.joints.size(), 1u);
    EXPECT_EQ(r.joints[0].type, JointType::kG1);
    EXPECT_NEAR(r.total_time, 7.0, 7.0 * kClosedFormTolerance) << "K=" << K;
    // Piece 0: accelerate over x in [0, 2] (2 s), cruise over [2, 4] (1 s).
    ASSERT_EQ(r.piece_durations.size(), 2u);
    EXPECT_NEAR(r.piece_durations[0], 3.0, 3.0 * kClosedFormTolerance) << "K=" << K;
  }
}

// A random G1 curve with rho: optimal, and the solution satisfies every row and bound of the
// discretization to 1e-8 (Ipopt's constr_viol_tol is 1e-9; 1e-8 allows for the rescaling of
// the rows inside Ipopt).
TEST(IpoptBackend, RandomCurveSolutionIsFeasible) {
  std::mt19937 rng(5);
  auto solver = MakeIpoptTemporalSolver();
  for (double rho : {0.0, 0.5}) {
    const TemporalProblem p = RandomG1Problem(rng, 30, rho);
    const TemporalResult r = solver->Solve(p);
    ASSERT_EQ(r.status, TemporalStatus::kOptimal) << r.message;
    EXPECT_GT(r.total_time, 0.0);
    EXPECT_GE(r.objective, r.total_time);
    const TemporalDiscretization d = Discretize(p);
    std::vector<double> x(static_cast<size_t>(d.num_vars));
    // Recover x from the profile: b at each free variable's first grid point / its scale.
    std::vector<bool> done(x.size(), false);
    for (int i = 0; i < d.num_pieces; ++i) {
      for (int k = 0; k <= d.cells_per_piece; ++k) {
        const GridValue& g = d.grid[static_cast<size_t>(d.GridIndex(i, k))];
        if (g.var < 0 || done[g.var]) continue;
        x[g.var] = r.profile.b(i, k) / g.scale;
        done[g.var] = true;
      }
    }
    EXPECT_LT(d.MaxViolation(x), 1e-8);
  }
}

TEST(IpoptBackend, InfeasibleProblemsAreReportedAsInfeasible) {
  auto solver = MakeIpoptTemporalSolver();
  {
    // A start speed of 3 along the tangent with vmax = 2. (Presolve should prove it from the
    // constant velocity row; with amax = 1 the first cell's acceleration row proves it too.)
    TemporalProblem p = LineProblem(10.0, 20);
    p.boundary.start_velocity = Eigen::Vector3d(3.0, 0.0, 0.0);
    const TemporalResult r = solver->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInfeasible);
    EXPECT_FALSE(r.message.empty());
    EXPECT_EQ(r.solver, "ipopt");
  }
  {
    // Start with acceleration 1 along x, end at rest with acceleration 0, but the acceleration
    // may change by only 1e-4 per cell: reaching 0 from 1 needs ~1e4 cells, there are 20.
    TemporalProblem p = LineProblem(10.0, 20);
    p.limits.max_acceleration_change = 1e-4;
    p.boundary.start_acceleration = Eigen::Vector3d(1.0, 0.0, 0.0);
    const TemporalResult r = solver->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInfeasible) << r.message;
    EXPECT_FALSE(r.message.empty());
  }
}

TEST(IpoptBackend, InvalidInputIsReportedWithTheField) {
  auto solver = MakeIpoptTemporalSolver();
  {
    const TemporalResult r = solver->Solve(LineProblem(10.0, 0));
    EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
    EXPECT_THAT(r.message, HasSubstr("K"));
  }
  {
    TemporalProblem p = LineProblem(10.0, 10);
    p.limits.max_velocity(1) = std::numeric_limits<double>::quiet_NaN();
    const TemporalResult r = solver->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
    EXPECT_THAT(r.message, HasSubstr("max_velocity"));
  }
  {
    // Invalid options are refused when the solver is made, naming the field, for both backends.
    IpoptTemporalOptions options;
    options.tolerance = -1.0;
    EXPECT_THAT([&] { MakeIpoptTemporalSolver(options); },
                ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("IpoptTemporalOptions.tolerance")));
    SocpTemporalOptions socp;
    socp.max_iterations = 0;
    EXPECT_THAT([&] { MakeSocpTemporalSolver(socp); },
                ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("SocpTemporalOptions.max_iterations")));
  }
}

// With every grid value fixed (one cell from a given speed to a given speed) there is nothing
// to optimize: T is the cell's time 2 ds / (sqrt(b0) + sqrt(b1)) = 2 L / (v0 + v1) = 10 / 1.5.
TEST(IpoptBackend, FullyFixedProblemIsEvaluatedDirectly) {
  TemporalProblem p = LineProblem(5.0, 1);
  p.boundary.start_velocity = Eigen::Vector3d(1.0, 0.0, 0.0);
  p.boundary.end_velocity = Eigen::Vector3d(0.5, 0.0, 0.0);
  const TemporalResult r = MakeIpoptTemporalSolver()->Solve(p);
  ASSERT_EQ(r.status, TemporalStatus::kOptimal) << r.message;
  EXPECT_EQ(r.iterations, 0);
  EXPECT_NEAR(r.total_time, 10.0 / 1.5, 1e-12);
}

// The iteration limit is reported as such.
TEST(IpoptBackend, IterationLimitIsReported) {
  IpoptTemporalOptions options;
  options.max_iterations = 2;
  const TemporalResult r = MakeIpoptTemporalSolver(options)->Solve(LineProblem(10.0, 50));
  EXPECT_EQ(r.status, TemporalStatus::kIterationLimit) << r.message;
}

}  // namespace
}  // namespace timeopt
