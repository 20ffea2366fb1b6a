// The SOCP backend's structured path (SocpTemporalOptions::structured, src/temporal/banded_ipm.h)
// against the conic solver alone on the same problems: the same T, the same statuses, and the
// path really answering the problems it applies to.

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../common/fixtures.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/temporal/temporal_solver.h"
#include "temporal/banded_ipm.h"

namespace timeopt {
namespace {

using test_support::LineProblem;
using ::testing::HasSubstr;

TemporalResult SolveWith(const TemporalProblem& p, bool structured) {
  SocpTemporalOptions options;
  options.structured = structured;
  return MakeSocpTemporalSolver(options)->Solve(p);
}

// Random problems of every kind the path takes: natural cubic and minimum-jerk curves (tangents
// that vanish at rest ends), polylines (stops at the kinks), a start at speed, paper and certified
// rows, rho 0 and 0.3, K from 10 to 60. The path must answer every one of them (it applies to all)
// and agree with the conic solver in J to 2e-9 relative: against Ipopt at 1e-10 the path's J was
// within 7e-10 (one problem 7e-9, where the conic solver was as far: Ipopt's own error) and the
// conic solver's within 1.4e-9. T is J when rho = 0; with rho > 0 the optimum trades T against the
// regularization along a flat direction, and the conic solver's T was up to 4.5e-7 from Ipopt's
// (the path's 2e-9), hence 1e-6 there. Certified answers hold the limits on the dense check.
TEST(StructuredPath, AgreesWithTheConicSolverOnRandomProblems) {
  std::mt19937 rng(31);
  std::uniform_int_distribution<int> kind(0, 2);
  std::uniform_int_distribution<int> pieces(1, 6);
  std::uniform_int_distribution<int> cells(10, 60);
  for (int trial = 0; trial < 30; ++trial) {
    const Waypoints w = test_support::RandomWalk(rng, pieces(rng) + 1);
    PiecewiseCurve curve;
    const int k = kind(rng);
    if (k == 0) {
      curve = NaturalCubicSpline(w);
    } else if (k == 1) {
      curve = MinimumJerkSpline(w);
    } else {
      std::vector<PolynomialPiece> segments;
      for (Eigen::Index i = 0; i + 1 < w.cols(); ++i) {
        segments.push_back(test_support::LinearPiece(w.col(i), w.col(i + 1)));
      }
      curve = PiecewiseCurve(segments);
    }
    TemporalProblem p = test_support::WalkProblem(curve, cells(rng));
    if (trial % 2 == 1) p.constraint_mode = ConstraintMode::kCertified;
    if (trial % 3 == 2) p.rho = 0.3;
    if (k == 0 && trial % 4 == 0) {
      // A start at 40% of the speed the limits allow along the first tangent.
      const Eigen::Vector3d t = curve.Evaluate(0, 0.0, 1);
      const double cap = p.limits.max_velocity.cwiseQuotient(t.cwiseAbs()).minCoeff();
      p.boundary.start_velocity = 0.4 * cap * t;
      p.boundary.start_acceleration = curve.Evaluate(0, 0.0, 2) * (0.4 * cap) * (0.4 * cap);
    }
    const TemporalResult structured = SolveWith(p, true);
    const TemporalResult conic = SolveWith(p, false);
    ASSERT_TRUE(conic.is_success()) << trial << ": " << conic.message;
    ASSERT_TRUE(structured.is_success()) << trial << ": " << structured.message;
    EXPECT_THAT(structured.message, HasSubstr("structured path")) << trial;
    EXPECT_NEAR(structured.objective, conic.objective, 2e-9 * conic.objective) << trial;
    EXPECT_NEAR(structured.total_time, conic.total_time, (p.rho > 0.0 ? 1e-6 : 2e-9) * conic.total_time) << trial;
    if (p.constraint_mode == ConstraintMode::kCertified) {
      EXPECT_LE(structured.max_velocity_ratio, 1.0 + 1e-6) << trial;
      EXPECT_LE(structured.max_acceleration_ratio, 1.0 + 1e-6) << trial;
    }
  }
}

// Infeasible problems get the same status with and without the path: it never answers them (its
// reachability start finds no profile, or it does not converge) and the conic solver decides.
TEST(StructuredPath, InfeasibleProblemsKeepTheConicSolversStatus) {
  // 1.9 m/s at the start of a 0.5 m line that must end at rest with amax = 1: stopping takes
  // 1.8 m. Only the rows show it (the start speed is below vmax = 2).
  TemporalProblem short_stop = LineProblem(0.5, 20);
  short_stop.boundary.start_velocity = Eigen::Vector3d(1.9, 0.0, 0.0);
  for (const ConstraintMode mode : {ConstraintMode::kPaper, ConstraintMode::kCertified}) {
    short_stop.constraint_mode = mode;
    const TemporalResult structured = SolveWith(short_stop, true);
    const TemporalResult conic = SolveWith(short_stop, false);
    EXPECT_EQ(conic.status, TemporalStatus::kInfeasible) << conic.message;
    EXPECT_EQ(structured.status, conic.status) << structured.message;
  }
  // Over-speed at the start (presolve).
  TemporalProblem fast = LineProblem(10.0, 20);
  fast.boundary.start_velocity = Eigen::Vector3d(3.0, 0.0, 0.0);
  EXPECT_EQ(SolveWith(fast, true).status, SolveWith(fast, false).status);
}

// The closed form of the contract line (rest to rest, 10 m, vmax 2, amax 1: 7 s) through the path:
// the discretized optimum of a line is exact at the grid points, so T = 7 to the tolerances.
TEST(StructuredPath, ContractLineIsTheClosedForm) {
  const TemporalResult r = SolveWith(LineProblem(10.0, 50), true);
  ASSERT_TRUE(r.is_success()) << r.message;
  EXPECT_THAT(r.message, HasSubstr("structured path"));
  EXPECT_NEAR(r.total_time, 7.0, 1e-8);
}

// The passes over the rows four at a time (AVX2) and two at a time: the same programmes, summed in
// another order, on the kinds of problem each row width serves (paper and certified rows over two
// unknowns, rho 0 and 0.3; jerk-limited rows over three control values). Both answers
// meet the same tolerances, so they agree to those: J to 2e-9 relative, as against the conic
// solver above. A jerk-limited answer ends a sequential programme whose stopping test reads T to
// scp_tolerance (here 1e-7, so that both runs go to its fixed point): T to 1e-6 relative.
// (Measured: the same iterations, and J and T within 1.5e-15.)
TEST(StructuredPath, TheFourRowPassesGiveTheTwoRowAnswer) {
  if (!internal::WideRowPasses()) GTEST_SKIP() << "this processor has no AVX2 and FMA: only the two-row passes run";
  std::mt19937 rng(47);
  std::uniform_int_distribution<int> pieces(1, 6);
  std::uniform_int_distribution<int> cells(10, 60);
  for (int trial = 0; trial < 16; ++trial) {
    TemporalProblem p =
        test_support::WalkProblem(MinimumJerkSpline(test_support::RandomWalk(rng, pieces(rng) + 1)), cells(rng));
    const int kind = trial % 4;
    if (kind == 1) p.constraint_mode = ConstraintMode::kCertified;
    if (kind == 2) {
      p.limits.max_jerk = Eigen::Vector3d(4.0, 4.0, 3.0);
      p.scp_tolerance = 1e-7;
    }
    if (kind == 3) p.rho = 0.3;
    const TemporalResult wide = SolveWith(p, true);
    const bool was_on = internal::SetWideRowPasses(false);
    const TemporalResult narrow = SolveWith(p, true);
    internal::SetWideRowPasses(was_on);
    ASSERT_TRUE(wide.is_success()) << trial << ": " << wide.message;
    ASSERT_TRUE(narrow.is_success()) << trial << ": " << narrow.message;
    EXPECT_EQ(wide.method, "structured") << trial;
    EXPECT_EQ(narrow.method, "structured") << trial;
    if (kind != 2) {
      EXPECT_NEAR(wide.objective, narrow.objective, 2e-9 * narrow.objective) << trial;
    } else {
      EXPECT_NEAR(wide.total_time, narrow.total_time, 1e-6 * narrow.total_time) << trial;
    }
  }
}

}  // namespace
}  // namespace timeopt
