// Why a temporal problem is infeasible (TemporalResult::infeasibility), and the closest feasible
// answer (TemporalProblem::relax_boundary): hand-built cases with closed forms, both backends.

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../common/fixtures.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {
namespace {

using test_support::LinearPiece;
using test_support::LineProblem;
using ::testing::HasSubstr;

// A straight run of `run` metres along x into a right-angle corner (the vehicle stops there), then
// 3 m along y; vmax 2, amax 1, starting at `speed` along x.
TemporalProblem Corner(double run, double speed) {
  TemporalProblem p;
  p.curve = PiecewiseCurve({LinearPiece(Eigen::Vector3d::Zero(), Eigen::Vector3d(run, 0.0, 0.0)),
                            LinearPiece(Eigen::Vector3d(run, 0.0, 0.0), Eigen::Vector3d(run, 3.0, 0.0))});
  p.limits.max_velocity.setConstant(2.0);
  p.limits.max_acceleration.setConstant(1.0);
  p.boundary.start_velocity = Eigen::Vector3d(speed, 0.0, 0.0);
  p.cells_per_piece = 50;
  return p;
}

TEST(Infeasibility, StartSpeedAboveTheLimitIsNamedAndRelaxedToTheLimit) {
  TemporalProblem p = LineProblem(10.0, 20);
  p.boundary.start_velocity = Eigen::Vector3d(3.0, 0.0, 0.0);  // vmax = 2
  for (const TemporalBackend backend : {TemporalBackend::kSocp, TemporalBackend::kIpopt}) {
    const TemporalResult r = MakeTemporalSolver(backend)->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInfeasible);
    ASSERT_TRUE(r.infeasibility.has_value()) << ToString(backend);
    EXPECT_EQ(r.infeasibility->cause, "boundary_speed");
    EXPECT_EQ(r.infeasibility->where, "start");
    EXPECT_THAT(r.infeasibility->detail, HasSubstr("above the limit"));
    // Relaxed: the closest start is vmax exactly; from it, 8 m cruise and 2 s of braking: T = 6.
    TemporalProblem relaxed = p;
    relaxed.relax_boundary = true;
    const TemporalResult a = MakeTemporalSolver(backend)->Solve(relaxed);
    ASSERT_TRUE(a.is_success()) << a.message;
    ASSERT_TRUE(a.boundary_relaxation.has_value());
    EXPECT_NEAR(a.boundary_relaxation->start_speed, 2.0, 1e-9);
    EXPECT_NEAR(a.boundary_relaxation->start_speed_given, 3.0, 1e-12);
    EXPECT_NEAR(a.total_time, 6.0, 1e-6);
  }
}

// 1.9 m/s into a corner 1.5 m ahead with amax 1: braking needs 1.9^2 / 2 = 1.805 m. Braking fails
// at the corner (within one cell, 0.03 m); the fastest start that can stop there is sqrt(2 a d) =
// sqrt(3) m/s exactly (on a line the rows are exact at the grid points), and from it the answer is
// braking all the way, sqrt(3) s, then the 3 m leg from rest to rest (amax 1, too short for vmax:
// a triangle peaking at sqrt(3) m/s, 2 sqrt(3) s): 3 sqrt(3) s in all.
TEST(Infeasibility, CornerTooCloseToBrakeIsLocatedAndRelaxedToTheClosedForm) {
  const TemporalProblem p = Corner(1.5, 1.9);
  for (const TemporalBackend backend : {TemporalBackend::kSocp, TemporalBackend::kIpopt}) {
    const TemporalResult r = MakeTemporalSolver(backend)->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInfeasible) << ToString(backend);
    ASSERT_TRUE(r.infeasibility.has_value());
    EXPECT_EQ(r.infeasibility->cause, "braking");
    const std::string& where = r.infeasibility->where;
    const double s = std::stod(where.substr(where.find("s = ") + 4));
    EXPECT_NEAR(s, 1.5, 0.03 + 1e-9) << where;
    TemporalProblem relaxed = p;
    relaxed.relax_boundary = true;
    const TemporalResult a = MakeTemporalSolver(backend)->Solve(relaxed);
    ASSERT_TRUE(a.is_success()) << a.message;
    EXPECT_NEAR(a.boundary_relaxation->start_speed, std::sqrt(3.0), 1e-9);
    EXPECT_NEAR(a.total_time, 3.0 * std::sqrt(3.0), 1e-6);
  }
}

// Far enough from the corner (10 m), the same start is feasible: no diagnosis, and relax_boundary
// changes nothing.
TEST(Infeasibility, FeasibleProblemsAreUntouched) {
  TemporalProblem p = Corner(10.0, 1.9);
  const TemporalResult plain = MakeSocpTemporalSolver()->Solve(p);
  p.relax_boundary = true;
  const TemporalResult relaxed = MakeSocpTemporalSolver()->Solve(p);
  ASSERT_TRUE(plain.is_success()) << plain.message;
  ASSERT_TRUE(relaxed.is_success()) << relaxed.message;
  EXPECT_FALSE(plain.infeasibility.has_value());
  EXPECT_FALSE(relaxed.boundary_relaxation.has_value());
  EXPECT_DOUBLE_EQ(plain.total_time, relaxed.total_time);
}

// The start-state relaxation's bisection stops within this of the largest scale that solves
// (TemporalSolver::RelaxStartState).
constexpr double kStartScaleTolerance = 0.01;

// A boundary acceleration that lambda_a cannot bring to rest (1 m/s^2, changing by 1e-4 per
// cell over 20 cells): named from the solver's verdict. Relaxed, the start state is scaled towards
// rest: the acceleration by lambda^2, the largest lambda within the bisection's 0.01 (checked by
// solving at lambda and just above lambda + 0.01).
TEST(Infeasibility, UnreachableBoundaryAccelerationWithLambdaA) {
  TemporalProblem p = LineProblem(10.0, 20);
  p.limits.max_acceleration_change = 1e-4;
  const Eigen::Vector3d a0(1.0, 0.0, 0.0);
  p.boundary.start_acceleration = a0;
  for (const TemporalBackend backend : {TemporalBackend::kSocp, TemporalBackend::kIpopt}) {
    std::unique_ptr<TemporalSolver> solver = MakeTemporalSolver(backend);
    p.relax_boundary = false;
    const TemporalResult r = solver->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInfeasible) << ToString(backend);
    ASSERT_TRUE(r.infeasibility.has_value());
    EXPECT_FALSE(r.boundary_relaxation.has_value());
    EXPECT_FALSE(r.infeasibility->cause.empty());
    p.relax_boundary = true;
    const TemporalResult relaxed = solver->Solve(p);
    ASSERT_EQ(relaxed.status, TemporalStatus::kOptimal) << ToString(backend) << ": " << relaxed.message;
    ASSERT_TRUE(relaxed.boundary_relaxation.has_value());
    ASSERT_TRUE(relaxed.infeasibility.has_value());  // why the given start could not be flown
    const double lambda = relaxed.boundary_relaxation->start_scale;
    EXPECT_EQ(relaxed.boundary_relaxation->start_acceleration, "scaled");
    EXPECT_GT(lambda, 0.0);
    EXPECT_LT(lambda, 1.0);
    TemporalProblem at = p;
    at.relax_boundary = false;
    at.boundary.start_acceleration = lambda * lambda * a0;
    EXPECT_EQ(solver->Solve(at).status, TemporalStatus::kOptimal) << ToString(backend);
    // Just past the bisection's bracket: infeasible (1e-3 above it, clear of the solver's rounding).
    const double above = lambda + kStartScaleTolerance + 1e-3;
    at.boundary.start_acceleration = above * above * a0;
    EXPECT_NE(solver->Solve(at).status, TemporalStatus::kOptimal) << ToString(backend) << " lambda " << lambda;
  }
}

// A jerk-limited start too fast to stop within the path (3 m/s, 1 m to rest; v 4, a 3, j 10): the
// start is scaled to the largest speed that can brake to rest in 1 m. Closed form: an S-curve stop
// from v (>= a^2 / j) takes v (v / a + a / j) / 2 metres, so v = 2.0405 m/s, lambda = 0.6802. The
// answer is within the bisection's 0.01 below it, and not above it by more than the grid's
// rounding (1e-3).
TEST(Infeasibility, JerkLimitedStartTooFastToStopIsScaledToTheClosedForm) {
  TemporalProblem p = LineProblem(1.0, 50);
  p.limits.max_velocity = Eigen::Vector3d::Constant(4.0);
  p.limits.max_acceleration = Eigen::Vector3d::Constant(3.0);
  p.limits.max_jerk = Eigen::Vector3d::Constant(10.0);
  p.constraint_mode = ConstraintMode::kCertified;
  p.boundary.start_velocity = Eigen::Vector3d(3.0, 0.0, 0.0);
  std::unique_ptr<TemporalSolver> solver = MakeSocpTemporalSolver();
  const TemporalResult plain = solver->Solve(p);
  EXPECT_NE(plain.status, TemporalStatus::kOptimal);
  p.relax_boundary = true;
  const TemporalResult r = solver->Solve(p);
  ASSERT_EQ(r.status, TemporalStatus::kOptimal) << r.message;
  ASSERT_TRUE(r.boundary_relaxation.has_value());
  const double v = 0.5 * (-0.9 + std::sqrt(0.81 + 24.0));  // v^2 / 3 + 0.3 v = 2
  const double lambda = r.boundary_relaxation->start_scale;
  // The bisection's bracket (plus 1e-4 for T's own tolerance), and the certified rows' rounding:
  // they are never looser than the limits, so the answer may sit a little low, never 1e-3 high.
  EXPECT_GE(lambda, v / 3.0 - kStartScaleTolerance - 1e-4);
  EXPECT_LE(lambda, v / 3.0 + 1e-3);
  EXPECT_NEAR(r.boundary_relaxation->start_speed, 3.0 * lambda, 1e-12);  // the same number, scaled
  EXPECT_EQ(r.boundary_relaxation->start_acceleration, "scaled");        // no braking given to keep
  EXPECT_LE(r.max_jerk_ratio, 1.0 + 1e-6);
  EXPECT_EQ(r.message.rfind("boundary relaxed: start state scaled by", 0), 0u) << r.message;
}

// Pieces that do not meet (piece 1 starts 4 m from where piece 0 ends) are invalid input naming
// the piece and the gap, from both backends (they used to be solved as if joined, and the samples
// jumped 4 m).
TEST(CurveValidation, PiecesThatDoNotMeetAreInvalidInput) {
  TemporalProblem p = LineProblem(10.0, 10);
  p.curve = PiecewiseCurve({LinearPiece(Eigen::Vector3d::Zero(), Eigen::Vector3d(5.0, 0.0, 0.0)),
                            LinearPiece(Eigen::Vector3d(5.0, 4.0, 0.0), Eigen::Vector3d(10.0, 4.0, 0.0))});
  for (const TemporalBackend backend : {TemporalBackend::kSocp, TemporalBackend::kIpopt}) {
    const TemporalResult r = MakeTemporalSolver(backend)->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInvalidInput) << ToString(backend);
    EXPECT_THAT(r.message, HasSubstr("curve.pieces[1]: starts 4 m from where curve.pieces[0] ends"));
  }
}

// Units do not change the answer: the contract line (10 m, vmax 2, amax 1: 7 s) written in units
// from micrometres to 100 km (lengths and limits scaled by c) gives 7 s to 1e-9 relative, in both
// modes and with both backends (the SOCP backend's structured path normalizes its rows; the conic
// solver alone called some of these infeasible, issue 23).
TEST(ScaleInvariance, TheContractLineInAnyUnitTakesSevenSeconds) {
  for (const double c : {1e-6, 1e-3, 1.0, 1e3, 1e5}) {
    TemporalProblem p = LineProblem(10.0 * c, 50);
    p.limits.max_velocity.setConstant(2.0 * c);
    p.limits.max_acceleration.setConstant(1.0 * c);
    for (const ConstraintMode mode : {ConstraintMode::kPaper, ConstraintMode::kCertified}) {
      p.constraint_mode = mode;
      for (const TemporalBackend backend : {TemporalBackend::kSocp, TemporalBackend::kIpopt}) {
        const TemporalResult r = MakeTemporalSolver(backend)->Solve(p);
        ASSERT_TRUE(r.is_success()) << c << " " << ToString(mode) << " " << ToString(backend) << ": " << r.message;
        EXPECT_NEAR(r.total_time, 7.0, 7e-9) << c << " " << ToString(mode) << " " << ToString(backend);
      }
    }
  }
}

// Sizes that drive memory are capped before any allocation: 1,000 pieces x 10,000 cells (1e7
// cells, ~10 GB) is invalid input naming K and the cap.
TEST(CurveValidation, TooManyCellsAreInvalidInput) {
  std::vector<PolynomialPiece> pieces;
  for (int i = 0; i < 1000; ++i) pieces.push_back(LinearPiece(Eigen::Vector3d(i, 0, 0), Eigen::Vector3d(i + 1, 0, 0)));
  TemporalProblem p = LineProblem(10.0, 10000);
  p.curve = PiecewiseCurve(pieces);
  const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
  EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
  EXPECT_THAT(r.message, HasSubstr("discretization.K"));
  EXPECT_THAT(r.message, HasSubstr("2000000"));
}

}  // namespace
}  // namespace timeopt
