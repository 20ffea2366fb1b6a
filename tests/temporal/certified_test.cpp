// The "certified" constraint mode (issue 8): limits that hold on the whole trajectory.

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "timeopt/curve/interpolation.h"
#include "temporal/discretization.h"
#include "timeopt/temporal/temporal_solver.h"

#include "../common/fixtures.h"

namespace timeopt {
namespace {

using test_support::RandomWalk;
using test_support::Segment;
using test_support::WalkProblem;

// A random walk from the origin.
Waypoints Walk(std::mt19937& rng, int count) { return RandomWalk(rng, count, Eigen::Vector3d::Zero()); }

TemporalProblem Problem(const PiecewiseCurve& curve, int K, ConstraintMode mode) {
  TemporalProblem p = WalkProblem(curve, K);
  p.constraint_mode = mode;
  return p;
}

class Certified : public ::testing::TestWithParam<TemporalBackend> {
 protected:
  TemporalResult Solve(const TemporalProblem& p) { return MakeTemporalSolver(GetParam())->Solve(p); }
};

INSTANTIATE_TEST_SUITE_P(Temporal, Certified, ::testing::Values(TemporalBackend::kSocp, TemporalBackend::kIpopt),
                         [](const auto& info) { return std::string(ToString(info.param)); });

// The dense check samples the exact trajectory 33 times per cell. In certified mode every
// Bernstein coefficient is within the limit, so the polynomial is everywhere; the solvers meet
// their rows to ~1e-10 relative, hence 1 + 1e-9.
TEST_P(Certified, DenseCheckFindsNoViolation) {
  std::mt19937 rng(77);
  for (int trial = 0; trial < 3; ++trial) {
    const Waypoints w = Walk(rng, 5);
    for (const PiecewiseCurve& curve :
         {NaturalCubicSpline(w), MinimumJerkSpline(w), MinimumJerkSpline(w, EndDerivatives{})}) {
      const TemporalResult r = Solve(Problem(curve, 30, ConstraintMode::kCertified));
      ASSERT_TRUE(r.is_success()) << r.message;
      EXPECT_LE(r.max_velocity_ratio, 1.0 + 1e-9);
      EXPECT_LE(r.max_acceleration_ratio, 1.0 + 1e-9);
    }
  }
}

// The paper's rows are a subset of what certified mode enforces at the same points (the cell-end
// Bernstein coefficients are the grid values; the mid-cell acceleration is a convex combination of
// the coefficients), so certified T >= paper T; both converge to the continuous optimum as K grows.
TEST_P(Certified, CostsLittleAndTheGapShrinksWithK) {
  std::mt19937 rng(5);
  const PiecewiseCurve curve = NaturalCubicSpline(Walk(rng, 7));
  double previous_gap = 1e9;
  for (int K : {10, 40, 160}) {
    const TemporalResult paper = Solve(Problem(curve, K, ConstraintMode::kPaper));
    const TemporalResult cert = Solve(Problem(curve, K, ConstraintMode::kCertified));
    ASSERT_TRUE(paper.is_success()) << paper.message;
    ASSERT_TRUE(cert.is_success()) << cert.message;
    const double gap = (cert.total_time - paper.total_time) / paper.total_time;
    EXPECT_GE(gap, -1e-8) << "K=" << K;  // solver tolerance ~1e-9 relative on each T
    EXPECT_LT(gap, previous_gap) << "K=" << K;
    previous_gap = gap;
  }
  EXPECT_LT(previous_gap, 5e-3);  // at K = 160 the price of certainty is below 0.5%
}

// On a straight line f'' = 0 and f' is constant, so certified rows coincide with the paper's and
// the closed form T = L/v + v/a = 7 is reproduced (switch points on the grid for K multiple of 5).
TEST_P(Certified, StraightLineMatchesClosedForm) {
  TemporalProblem p =
      Problem(Segment(Eigen::Vector3d::Zero(), Eigen::Vector3d(10, 0, 0)), 20, ConstraintMode::kCertified);
  p.limits.max_velocity.setConstant(2.0);
  p.limits.max_acceleration.setConstant(1.0);
  const TemporalResult r = Solve(p);
  ASSERT_TRUE(r.is_success()) << r.message;
  EXPECT_NEAR(r.total_time, 7.0, 7e-7);
}

}  // namespace
}  // namespace timeopt

namespace timeopt {
namespace {

// Pruning keeps exactly the feasible set: random b >= 0 (scaled around the optimum's magnitude) is
// feasible for the pruned rows iff it is for the full rows, in both modes.
TEST(RowPruning, KeepsTheFeasibleSetAndTheOptimum) {
  std::mt19937 rng(12);
  const Waypoints w = Walk(rng, 5);
  for (ConstraintMode mode : {ConstraintMode::kPaper, ConstraintMode::kCertified}) {
    for (const PiecewiseCurve& curve : {NaturalCubicSpline(w), MinimumJerkSpline(w)}) {
      TemporalProblem p = Problem(curve, 10, mode);
      p.certified_thinning = 0.0;  // exact pruning only (thinning: the next test)
      TemporalProblem full = p;
      full.prune_redundant_rows = false;
      const TemporalDiscretization dp = Discretize(p), df = Discretize(full);
      ASSERT_EQ(dp.num_vars, df.num_vars);
      EXPECT_LT(dp.rows.size(), df.rows.size());
      // At most one pruned row is an upper bound on a variable alone (the tightest of those the
      // cells produce); the full rows have several (both cells around a grid point in certified mode).
      auto most_upper_bounds = [](const TemporalDiscretization& d) {
        std::vector<int> count(d.num_vars, 0);
        for (const LinearRow& row : d.rows) {
          if (row.terms.size() == 1 && row.terms[0].second > 0.0 && !std::isfinite(row.lower)) {
            ++count[row.terms[0].first];
          }
        }
        return *std::max_element(count.begin(), count.end());
      };
      EXPECT_LE(most_upper_bounds(dp), 1);
      if (mode == ConstraintMode::kCertified) {
        EXPECT_GE(most_upper_bounds(df), 2);
      }
      const auto socp = MakeSocpTemporalSolver();
      const TemporalResult rp = socp->Solve(p), rf = socp->Solve(full);
      ASSERT_TRUE(rp.is_success()) << rp.message;
      ASSERT_TRUE(rf.is_success()) << rf.message;
      // Same problem, so the same optimum up to the solver tolerance (1e-8 relative).
      EXPECT_NEAR(rp.total_time, rf.total_time, 1e-7 * rf.total_time);

      // Sample around the optimum, feasible and infeasible points.
      std::vector<double> x0(dp.num_vars);
      for (int i = 0; i < dp.num_pieces; ++i) {
        for (int k = 0; k <= 10; ++k) {
          const GridValue& g = dp.grid[dp.GridIndex(i, k)];
          if (g.var >= 0) x0[g.var] = rp.profile.b(i, k) / g.scale;
        }
      }
      std::uniform_real_distribution<double> factor(0.5, 1.1);
      int agree = 0, feasible = 0;
      for (int trial = 0; trial < 400; ++trial) {
        // Even trials: a common factor <= 1 (all rows are homogeneous in b here, so feasible);
        // odd trials: independent factors, mostly infeasible.
        std::vector<double> x = x0;
        const double common = 0.5 + 0.5 * factor(rng) / 1.1;
        for (double& v : x) v *= trial % 2 == 0 ? common : factor(rng);
        // Violations are in different units (pruned rows are divided by their limit), so compare
        // the verdicts with a tolerance far below the perturbation (>= 1e-3 relative typically).
        const bool fp = dp.MaxViolation(x) <= 1e-9, ff = df.MaxViolation(x) <= 1e-9;
        agree += fp == ff;
        feasible += ff;
      }
      EXPECT_EQ(agree, 400) << "mode " << ToString(mode);
      EXPECT_GT(feasible, 0);
    }
  }
}

// Thinning (TemporalProblem::certified_thinning) only tightens: every x that the thinned rows allow
// satisfies the exact certified rows (checked at points around both optima, where the rows are
// nearly active), and T lies between the exact certified T and that T times 1 + thinning / 2 (the
// bound the thinning guarantees), up to the solver's 1e-8 relative tolerance.
TEST(CertifiedThinning, ImpliesTheExactRowsAndCostsAtMostHalfTheTolerance) {
  std::mt19937 rng(31);
  const auto socp = MakeSocpTemporalSolver();
  int only_exact = 0;  // points that only the exact rows allow, over all curves
  for (int c = 0; c < 4; ++c) {
    const Waypoints w = Walk(rng, 5);
    TemporalProblem thin =
        Problem(c % 2 ? MinimumJerkSpline(w) : NaturalCubicSpline(w), 20, ConstraintMode::kCertified);
    thin.certified_thinning = 1e-3;  // larger than the default, so that the effect is measurable
    TemporalProblem exact = thin;
    exact.certified_thinning = 0.0;
    const TemporalDiscretization dt = Discretize(thin), de = Discretize(exact);
    ASSERT_EQ(dt.num_vars, de.num_vars);
    EXPECT_LT(dt.rows.size(), de.rows.size());

    const TemporalResult rt = socp->Solve(thin), re = socp->Solve(exact);
    ASSERT_TRUE(rt.is_success()) << rt.message;
    ASSERT_TRUE(re.is_success()) << re.message;
    EXPECT_GE(rt.total_time, re.total_time * (1.0 - 1e-8));
    EXPECT_LE(rt.total_time, re.total_time * (1.0 + 0.5e-3 + 1e-8));
    EXPECT_LE(rt.max_acceleration_ratio, 1.0 + 1e-9);
    EXPECT_LE(rt.max_velocity_ratio, 1.0 + 1e-9);

    // Points around each optimum: a common factor in [0.996, 1.002] (the rows are homogeneous in b,
    // so it moves across the boundary) times independent factors within 2e-4 of 1 per grid value.
    std::uniform_real_distribution<double> common(0.996, 1.002), jitter(1.0 - 2e-4, 1.0 + 2e-4);
    int thin_feasible = 0;
    for (const TemporalResult* r : {&rt, &re}) {
      std::vector<double> x0(dt.num_vars);
      for (int i = 0; i < dt.num_pieces; ++i) {
        for (int k = 0; k <= 20; ++k) {
          const GridValue& g = dt.grid[dt.GridIndex(i, k)];
          if (g.var >= 0) x0[g.var] = r->profile.b(i, k) / g.scale;
        }
      }
      for (int trial = 0; trial < 300; ++trial) {
        std::vector<double> x = x0;
        const double t = common(rng);
        for (double& v : x) v *= t * jitter(rng);
        // Rows are relative to their limits (violations ~1 for a full violation): 1e-12 is rounding.
        const bool ft = dt.MaxViolation(x) <= 0.0, fe = de.MaxViolation(x) <= 1e-12;
        if (ft) {
          ++thin_feasible;
          EXPECT_TRUE(fe) << "curve " << c << ": a point the thinned rows allow violates the exact ones";
        } else if (fe) {
          ++only_exact;
        }
      }
    }
    EXPECT_GT(thin_feasible, 0);
  }
  EXPECT_GT(only_exact, 0);  // thinning does tighten
}

}  // namespace
}  // namespace timeopt
