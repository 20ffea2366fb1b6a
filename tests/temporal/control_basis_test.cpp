// The control values of the jerk-limited discretization (ControlBasis in discretization.h,
// src/temporal/control_basis.cpp): b at every half-grid value as an affine form of control values
// y such that every equality row of the discretization holds for any y, a basis that loses no
// freedom, and the structured path that solves over y against the general conic path.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../common/fixtures.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/curve/polynomial_piece.h"
#include "temporal/discretization.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {
namespace {

using test_support::LinearPiece;
using test_support::RandomWalk;
using test_support::WalkProblem;

struct NamedProblem {
  std::string name;
  TemporalProblem problem;
};

// Jerk-limited problems covering every case the basis builds: C2 joints of a natural cubic spline
// rest to rest (rest cells at both ends), a minimum-jerk spline (C4 joints; tangent and curvature
// vanish at both ends, so the boundary values are controls of their own), a start at speed with a
// given acceleration along the tangent (the first cell's P1 a constant) ending at rest, a polyline
// with sharp corners (stops: rest cells on both sides of every joint) and one sextic piece whose
// tangent and curvature vanish at both ends. K cells per piece.
std::vector<NamedProblem> JerkProblems(int K) {
  const Eigen::Vector3d jmax(6.0, 6.0, 4.0);
  std::mt19937 rng(17);
  std::vector<NamedProblem> problems;
  const auto add = [&](const std::string& name, TemporalProblem p) {
    p.limits.max_jerk = jmax;
    problems.push_back({name, p});
  };
  add("natural cubic spline, rest to rest", WalkProblem(NaturalCubicSpline(RandomWalk(rng, 5)), K));
  add("minimum-jerk spline", WalkProblem(MinimumJerkSpline(RandomWalk(rng, 4)), K));
  {
    // A natural cubic spline has f''(0) = 0, so an acceleration along the tangent is one the curve
    // can fly (its part across the path must be f'' sdot^2 = 0). 40% of the speed and 30% of the
    // acceleration the per-axis limits allow along the first tangent, speeding up.
    const PiecewiseCurve curve = NaturalCubicSpline(RandomWalk(rng, 4));
    TemporalProblem p = WalkProblem(curve, K);
    const Eigen::Vector3d unit = curve.Evaluate(0, 0.0, 1).normalized();
    const double v_cap = p.limits.max_velocity.cwiseQuotient(unit.cwiseAbs()).minCoeff();
    const double a_cap = p.limits.max_acceleration.cwiseQuotient(unit.cwiseAbs()).minCoeff();
    p.boundary.start_velocity = 0.4 * v_cap * unit;
    p.boundary.start_acceleration = 0.3 * a_cap * unit;
    add("start at speed and accelerating, end at rest", p);
  }
  {
    const Eigen::Vector3d a(0.0, 0.0, 0.0), b(4.0, 0.0, 0.0), c(4.0, 3.0, 0.5), d(1.0, 5.0, 1.0);
    add("polyline with sharp corners",
        WalkProblem(PiecewiseCurve({LinearPiece(a, b), LinearPiece(b, c), LinearPiece(c, d)}), K));
  }
  {
    // f(s) = p0 + A (10 s^3 - 15 s^4 + 6 s^5) + B s^3 (1 - s)^3: f' = s^2 (1 - s)^2 (30 A +
    // 3 B (1 - 2 s)), so f' and f'' vanish at s = 0 and 1, and f' does nowhere else (its x part is
    // 120 s^2 (1 - s)^2). A = (4, 2, 0.5), B = (0, 40, 0): a 0.6 m bulge sideways, so the piece
    // is curved (a quintic with these end conditions is a straight line). The coefficients are
    // small integers and halves, so f'(1) and f''(1) evaluate to exactly 0.
    PolynomialPiece::Coefficients coef = PolynomialPiece::Coefficients::Zero(3, 7);
    coef.col(0) = Eigen::Vector3d(1.0, -1.0, 0.5);
    coef.col(3) = Eigen::Vector3d(40.0, 60.0, 5.0);
    coef.col(4) = Eigen::Vector3d(-60.0, -150.0, -7.5);
    coef.col(5) = Eigen::Vector3d(24.0, 132.0, 3.0);
    coef.col(6) = Eigen::Vector3d(0.0, -40.0, 0.0);
    add("one piece whose tangent and curvature vanish at both ends",
        WalkProblem(PiecewiseCurve({PolynomialPiece(coef)}), K));
  }
  {
    // A run of two tied pieces (0.5 mm and 1 mm between metres, TemporalDiscretization::tied)
    // before a bend that starts without curvature (a cubic, f''(0) = 0, so no joint is a stop): the
    // joints' continuity rows carry b and sddot across the run.
    const Eigen::Vector3d a(0.0, 0.0, 0.0), b(1.0, 0.0, 0.0), c(1.0005, 0.0, 0.0), d(1.0015, 0.0, 0.0);
    PolynomialPiece::Coefficients bend = PolynomialPiece::Coefficients::Zero(3, 4);
    bend.col(0) = d;
    bend.col(1) = Eigen::Vector3d(1.0, 0.0, 0.0);
    bend.col(3) = Eigen::Vector3d(0.0, 0.5, 0.0);
    add("a run of two tied pieces before a bend",
        WalkProblem(PiecewiseCurve({LinearPiece(a, b), LinearPiece(b, c), LinearPiece(c, d), PolynomialPiece(bend)}),
                    K));
  }
  return problems;
}

// The size of a form's value at y: |constant| + sum |coef y|, the size its rounding is relative to.
double Magnitude(const ControlForm& f, const std::vector<double>& y) {
  double m = std::abs(f.constant);
  for (int t = 0; t < f.count; ++t) {
    m += std::abs(f.coef[static_cast<size_t>(t)] * y[static_cast<size_t>(f.first + t)]);
  }
  return m;
}

std::vector<double> RandomControls(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(0.1, 1.0);
  std::vector<double> y(static_cast<size_t>(n));
  for (double& v : y) v = u(rng);
  return y;
}

// A discretization with free values, no presolve verdict and a control basis.
::testing::AssertionResult HasControls(const TemporalDiscretization& d) {
  if (d.infeasible_reason) return ::testing::AssertionFailure() << "presolve: " << *d.infeasible_reason;
  if (d.num_vars <= 0) return ::testing::AssertionFailure() << "no free values";
  if (!d.controls) return ::testing::AssertionFailure() << "no control basis";
  return ::testing::AssertionSuccess();
}

// The truth: the basis is built so that the equality rows (sddot continuity between cells and
// across joints, the rest cells' shape, the boundary accelerations) hold identically in y, and a
// fixed grid value is a constant form. So for any y, b = form(y) gives one x per free value (the
// grid values sharing a variable at a joint are scale_g x for the same x) and x meets every
// equality row exactly but for rounding. Tolerances: the shared x agree to 1e-12 relative to the
// size of the forms' terms (the two forms differ by the factor rho of the scales, a few roundings
// of 1e-16 each); an equality row's residual is a sum of terms carrying such rounding, so 1e-9 of
// its largest term (coefficient times the size of x) is far above rounding and far below any real
// miss (a wrong knot formula leaves a residual of the order of the terms). A fixed value's
// constant is copied from the grid (1e-12 relative, the basis's own acceptance).
TEST(ControlBasis, EveryProfileOfTheControlsMeetsTheEqualityRows) {
  std::mt19937 rng(5);
  for (const NamedProblem& named : JerkProblems(24)) {
    SCOPED_TRACE(named.name);
    const TemporalDiscretization d = DiscretizeJerkLimited(named.problem, JerkRows::kNone);
    ASSERT_TRUE(HasControls(d));
    const ControlBasis& basis = *d.controls;
    ASSERT_GT(basis.num_controls, 0);
    ASSERT_EQ(basis.grid.size(), d.grid.size());

    for (size_t g = 0; g < d.grid.size(); ++g) {
      const GridValue& v = d.grid[g];
      const ControlForm& f = basis.grid[g];
      if (f.count > 0) {
        ASSERT_GE(f.first, 0) << g;
        ASSERT_LE(f.first + f.count, basis.num_controls) << g;
      }
      if (v.var >= 0) continue;
      EXPECT_EQ(f.count, 0) << "fixed grid value " << g;
      EXPECT_NEAR(f.constant, v.fixed, 1e-12 * std::max(1.0, std::abs(v.fixed))) << "fixed grid value " << g;
    }

    int equalities = 0;
    for (const LinearRow& row : d.rows) equalities += row.lower == row.upper ? 1 : 0;
    EXPECT_GT(equalities, 0);

    for (int trial = 0; trial < 20; ++trial) {
      const std::vector<double> y = RandomControls(rng, basis.num_controls);
      std::vector<double> x(static_cast<size_t>(d.num_vars), std::numeric_limits<double>::quiet_NaN());
      std::vector<double> size(static_cast<size_t>(d.num_vars), 0.0);  // the size of each x's terms
      std::vector<char> seen(static_cast<size_t>(d.num_vars), 0);
      for (size_t g = 0; g < d.grid.size(); ++g) {
        const GridValue& v = d.grid[g];
        if (v.var < 0) continue;
        const ControlForm& f = basis.grid[g];
        const double xv = f.Value(y) / v.scale;
        const double mv = Magnitude(f, y) / std::abs(v.scale);
        const size_t var = static_cast<size_t>(v.var);
        if (!seen[var]) {
          seen[var] = 1;
          x[var] = xv;
          size[var] = mv;
          continue;
        }
        EXPECT_NEAR(xv, x[var], 1e-12 * std::max(mv, size[var]))
            << "trial " << trial << ", var " << v.var << ", grid " << g;
        size[var] = std::max(size[var], mv);
      }
      for (int var = 0; var < d.num_vars; ++var) ASSERT_TRUE(seen[static_cast<size_t>(var)]) << "var " << var;

      for (size_t r = 0; r < d.rows.size(); ++r) {
        const LinearRow& row = d.rows[r];
        if (row.lower != row.upper) continue;
        double sum = 0.0, scale = std::abs(row.lower);
        for (const auto& [var, coef] : row.terms) {
          sum += coef * x[static_cast<size_t>(var)];
          scale = std::max(scale, std::abs(coef) * size[static_cast<size_t>(var)]);
        }
        EXPECT_LE(std::abs(sum - row.lower), 1e-9 * scale)
            << "trial " << trial << ", row " << r << " (kind " << static_cast<int>(row.kind) << ")";
      }
    }
  }
}

// The truth: a C1 piecewise quadratic b has one degree of freedom per regular cell (and one per
// free boundary value), exactly what the equality rows leave of the free values, so
// num_controls + equalities = num_vars on every problem here (the equality rows are independent:
// each fixes a different knot or rest-cell middle). The map y -> b is injective: FromGrid reads
// y_c back from b (P1 = (4 b_mid - b0 - b2) / 2 on a regular cell, the same in q = rho b on a ramp
// cell, b itself at a free boundary),
// and the form of each control's own grid value has a non-zero coefficient on it. Tolerance of the
// read-back: rounding of the forms' values, 1e-12 relative to the size of the terms FromGrid
// combines (divided by the control's scale).
TEST(ControlBasis, SpansTheSameProfilesAsTheGrid) {
  std::mt19937 rng(9);
  for (const NamedProblem& named : JerkProblems(24)) {
    SCOPED_TRACE(named.name);
    const TemporalDiscretization d = DiscretizeJerkLimited(named.problem, JerkRows::kNone);
    ASSERT_TRUE(HasControls(d));
    const ControlBasis& basis = *d.controls;
    const size_t n = static_cast<size_t>(basis.num_controls);
    ASSERT_EQ(basis.middle.size(), n);
    ASSERT_EQ(basis.at_knot.size(), n);
    ASSERT_EQ(basis.scale.size(), n);
    ASSERT_EQ(basis.grid.size(), d.grid.size());

    int equalities = 0;
    for (const LinearRow& row : d.rows) equalities += row.lower == row.upper ? 1 : 0;
    EXPECT_EQ(basis.num_controls + equalities, d.num_vars);

    const std::vector<double> y = RandomControls(rng, basis.num_controls);
    std::vector<double> b(d.grid.size()), size(d.grid.size());
    for (size_t g = 0; g < d.grid.size(); ++g) {
      b[g] = basis.grid[g].Value(y);
      size[g] = Magnitude(basis.grid[g], y);
    }
    for (int c = 0; c < basis.num_controls; ++c) {
      const size_t cs = static_cast<size_t>(c);
      const int g = basis.middle[cs];
      ASSERT_GE(g, 0);
      ASSERT_LT(g, static_cast<int>(d.grid.size()));
      const size_t gs = static_cast<size_t>(g);
      // y_c = P1 (or the boundary b) over the scale of the grid value it lives at; a ramp cell's P1
      // is q's, q = rho b (RampFrame), over rho_m times that scale.
      const int piece = g / (d.cells_per_piece + 1), k = (g - d.GridIndex(piece, 0)) / 2;
      double rho = 1.0;
      // (A control at a knot may be a piece's last grid value, k = K: no cell of its own.)
      const CellShape shape = basis.at_knot[cs] ? CellShape::kQuadratic
                                                : d.shapes[static_cast<size_t>(piece * (d.cells_per_piece / 2) + k)];
      if (IsRampShape(shape)) {
        const std::vector<double>& e = d.cell_edges[static_cast<size_t>(piece)];
        const double w = 0.5 * (TemporalProfile::RampW(shape, e[static_cast<size_t>(k)]) +
                                TemporalProfile::RampW(shape, e[static_cast<size_t>(k) + 1]));
        rho = 1.0 / (w * w * w * w);
      }
      EXPECT_DOUBLE_EQ(basis.scale[cs], d.grid[gs].scale * rho) << "control " << c;  // rho to rounding
      const ControlForm& f = basis.grid[gs];
      ASSERT_LE(f.first, c) << "control " << c;
      ASSERT_LT(c, f.first + f.count) << "control " << c;
      EXPECT_NE(f.coef[static_cast<size_t>(c - f.first)], 0.0) << "control " << c;
      const std::array<double, 3>& w = basis.read[cs];
      const double terms =
          basis.at_knot[cs] ? size[gs]
                            : std::abs(w[0]) * size[gs - 1] + std::abs(w[1]) * size[gs] + std::abs(w[2]) * size[gs + 1];
      EXPECT_NEAR(basis.FromGrid(c, b), y[cs], 1e-12 * terms / basis.scale[cs]) << "control " << c;
    }
  }
}

// The structured path (banded interior-point solves over the control values, the default) and
// the general conic path (structured = false) run the sequential convex programme on the same
// problems. Both must answer, each by its own path. Each stops when T changes by less than
// scp_tolerance (1e-4) relative, and each answer is a local optimum of the same convex
// approximations, so their T agree within 2e-4 relative (twice the stopping tolerance). Both are
// certified on whole cells, so the dense check of velocity, acceleration and jerk stays within
// 1e-6 of the limits (the solvers' row tolerance).
TEST(ControlBasis, StructuredAndGeneralPathsAgree) {
  SocpTemporalOptions general;
  general.structured = false;
  for (const NamedProblem& named : JerkProblems(24)) {
    SCOPED_TRACE(named.name);
    const TemporalResult structured = MakeSocpTemporalSolver()->Solve(named.problem);
    const TemporalResult conic = MakeSocpTemporalSolver(general)->Solve(named.problem);
    ASSERT_TRUE(structured.is_success()) << structured.message;
    ASSERT_TRUE(conic.is_success()) << conic.message;
    EXPECT_EQ(structured.method, "structured") << structured.message;
    EXPECT_EQ(conic.method, "conic") << conic.message;
    EXPECT_NEAR(structured.total_time, conic.total_time, 2e-4 * conic.total_time);
    // The same joints found (a property of the grid, not of the solve).
    ASSERT_EQ(structured.joints.size(), conic.joints.size());
    for (size_t j = 0; j < conic.joints.size(); ++j) EXPECT_EQ(structured.joints[j].type, conic.joints[j].type) << j;
    for (const TemporalResult* r : {&structured, &conic}) {
      SCOPED_TRACE(r->method);
      EXPECT_LE(r->max_jerk_ratio, 1.0 + 1e-6);
      EXPECT_LE(r->max_velocity_ratio, 1.0 + 1e-6);
      EXPECT_LE(r->max_acceleration_ratio, 1.0 + 1e-6);
    }
  }
}

// Which pieces are tied: those at most 2e-3 of the longest piece within two of them, between
// joints that are not stops. Truth by construction: the lengths are chosen on either side of the
// share. A rule against the whole curve's length had tied the 0.2 m pieces of a 127 m plan (101
// pieces), where the structured path then failed and the plan's temporal stage took 5.3 s
// instead of 77 ms; a 0.2 m piece among 1.25 m ones is not tied here.
TEST(TiedPieces, AreShortAgainstTheirNeighbours) {
  const auto tied = [](const std::vector<double>& lengths) {
    std::vector<PolynomialPiece> pieces;
    double x = 0.0;
    for (double l : lengths) {
      pieces.push_back(LinearPiece(Eigen::Vector3d(x, 0, 0), Eigen::Vector3d(x + l, 0, 0)));
      x += l;
    }
    TemporalProblem p = WalkProblem(PiecewiseCurve(pieces), 10);
    p.limits.max_jerk = Eigen::Vector3d::Constant(10.0);
    return DiscretizeJerkLimited(p, JerkRows::kNone).tied;
  };
  EXPECT_EQ(tied({1.0, 1e-3, 1.0}), std::vector<char>({0, 1, 0}));
  EXPECT_EQ(tied({1.0, 3e-3, 1.0}), std::vector<char>({0, 0, 0}));
  EXPECT_EQ(tied({1.0, 5e-4, 1e-3, 1.0}), std::vector<char>({0, 1, 1, 0}));
  std::vector<double> plan(100, 1.25);
  plan[50] = 0.2;
  const std::vector<char> none = tied(plan);
  EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
  plan[50] = 2e-3;
  const std::vector<char> one = tied(plan);
  EXPECT_EQ(std::count(one.begin(), one.end(), 1), 1);
  EXPECT_EQ(one[50], 1);
}

}  // namespace
}  // namespace timeopt
