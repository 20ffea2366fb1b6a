// Tests of the temporal stage through both backends (SOCP with our conic solver, Ipopt NLP)
// against closed forms and against each other.

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "timeopt/curve/interpolation.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/io/temporal_io.h"
#include "temporal/discretization.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"

#include "../common/fixtures.h"

namespace timeopt {
namespace {

using test_support::LineProblem;
using test_support::RandomWalk;
using test_support::RestToRestTime;
using test_support::Segment;
using test_support::WalkProblem;
using ::testing::HasSubstr;

std::vector<TemporalBackend> Backends() { return {TemporalBackend::kSocp, TemporalBackend::kIpopt}; }

class BothBackends : public ::testing::TestWithParam<TemporalBackend> {
 protected:
  TemporalResult Solve(const TemporalProblem& p) { return MakeTemporalSolver(GetParam())->Solve(p); }
};

INSTANTIATE_TEST_SUITE_P(Temporal, BothBackends, ::testing::ValuesIn(Backends()),
                         [](const auto& info) { return std::string(ToString(info.param)); });

// The discretized problem reproduces the closed form exactly when the switch points between
// acceleration, cruise and braking fall on grid points (b is then exactly linear on every cell):
// L = 10, vmax = 2, amax = 1 switches at s = 0.2 and 0.8; L = 1 at s = 0.5. The solvers run at
// tolerance ~1e-9, so T matches to 1e-7 relative.
TEST_P(BothBackends, StraightLineMatchesClosedForm) {
  for (int K : {5, 10, 20, 50}) {
    const TemporalResult r = Solve(LineProblem(10.0, K));
    ASSERT_TRUE(r.is_success()) << r.message;
    EXPECT_NEAR(r.total_time, 7.0, 7.0 * 1e-7) << "K=" << K;
    EXPECT_NEAR(r.total_time, RestToRestTime(10.0, 2.0, 1.0), 1e-6);
  }
  for (int K : {2, 10, 40}) {
    const TemporalResult r = Solve(LineProblem(1.0, K));
    ASSERT_TRUE(r.is_success()) << r.message;
    EXPECT_NEAR(r.total_time, 2.0, 2.0 * 1e-7) << "K=" << K;
  }
}

// Along the direction (3, 4, 0)/5 the y axis binds: per-axis limits scale by 1/0.8, so
// v = 2.5, a = 1.25, T = 10/2.5 + 2.5/1.25 = 6, switching at s = 0.25 (K multiple of 4).
TEST_P(BothBackends, DiagonalLineScalesByTheLargestDirectionCosine) {
  for (int K : {4, 20, 40}) {
    TemporalProblem p = LineProblem(10.0, K);
    p.curve = Segment(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1 + 6, 2 + 8, 3));
    const TemporalResult r = Solve(p);
    ASSERT_TRUE(r.is_success()) << r.message;
    EXPECT_NEAR(r.total_time, 6.0, 6.0 * 1e-7) << "K=" << K;
  }
}

// A polyline along the axes stops at each corner: T is the sum of the rest-to-rest times. K = 30
// puts every switch point on the grid (s = 0.2, 0.5, 1/3 for lengths 10, 1, 6).
TEST_P(BothBackends, PolylineStopsAtCorners) {
  const double lengths[3] = {10.0, 1.0, 6.0};
  std::vector<PolynomialPiece> pieces;
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d to = at;
    to(i) += lengths[i];
    pieces.push_back(Segment(at, to).piece(0));
    at = to;
  }
  TemporalProblem p = LineProblem(1.0, 30);
  p.curve = PiecewiseCurve(pieces);
  const TemporalResult r = Solve(p);
  ASSERT_TRUE(r.is_success()) << r.message;
  const double expected = RestToRestTime(10, 2, 1) + RestToRestTime(1, 2, 1) + RestToRestTime(6, 2, 1);
  EXPECT_NEAR(r.total_time, expected, expected * 1e-7);
  ASSERT_EQ(r.joints.size(), 2u);
  for (const JointInfo& j : r.joints) {
    EXPECT_EQ(j.type, JointType::kStop);
    // The corners turn by a right angle: the reason says so (pi / 2 to the 6 digits printed).
    EXPECT_THAT(j.reason, ::testing::HasSubstr("the tangents turn by 1.5708 rad")) << j.joint;
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r.piece_durations[i], RestToRestTime(lengths[i], 2, 1), 1e-6);
  }
}

TEST_P(BothBackends, BoundaryVelocityAlongTheTangentIsHonored) {
  TemporalProblem p = LineProblem(10.0, 20);
  p.boundary.start_velocity = Eigen::Vector3d(1.0, 0, 0);
  p.boundary.end_velocity = Eigen::Vector3d(0.5, 0, 0);
  const TemporalResult r = Solve(p);
  ASSERT_TRUE(r.is_success()) << r.message;
  const Trajectory traj(p.curve, r.profile);
  // b at the ends is fixed by presolve, so the velocity is exact up to rounding.
  EXPECT_LT((traj.Evaluate(0.0).velocity - p.boundary.start_velocity).norm(), 1e-12);
  EXPECT_LT((traj.Evaluate(traj.duration()).velocity - p.boundary.end_velocity).norm(), 1e-9);
  // Closed form: accelerate from 1 to 2 (1.5 m, 1 s), cruise, brake from 2 to 0.5 (1.875 m, 1.5 s).
  const double expected = 1.0 + (10.0 - 1.5 - 1.875) / 2.0 + 1.5;
  // The switch points s = 0.15 and 0.8125 are off the K = 20 grid, so the discretized T is a bit
  // above the continuous optimum: bracket it.
  EXPECT_GE(r.total_time, expected - 1e-7);
  EXPECT_LE(r.total_time, expected * 1.01);

  p.boundary.start_velocity = Eigen::Vector3d(1.0, 0.5, 0);
  const TemporalResult bad = Solve(p);
  EXPECT_EQ(bad.status, TemporalStatus::kInvalidInput);
  EXPECT_THAT(bad.message, HasSubstr("boundary.start_velocity"));
}

TEST_P(BothBackends, InfeasibleProblemsAreReportedAsInfeasible) {
  TemporalProblem fast = LineProblem(10.0, 20);
  fast.boundary.start_velocity = Eigen::Vector3d(3.0, 0, 0);  // above vmax = 2
  EXPECT_EQ(Solve(fast).status, TemporalStatus::kInfeasible);

  // Over-speed at both ends with an acceleration limit that would allow it otherwise: only the
  // fixed boundary values violate the velocity limit (caught by presolve, not by the rows).
  TemporalProblem both_fast = LineProblem(10.0, 20);
  both_fast.limits.max_acceleration.setConstant(100.0);
  both_fast.boundary.start_velocity = both_fast.boundary.end_velocity = Eigen::Vector3d(3.0, 0, 0);
  EXPECT_EQ(Solve(both_fast).status, TemporalStatus::kInfeasible);
  both_fast.constraint_mode = ConstraintMode::kCertified;
  EXPECT_EQ(Solve(both_fast).status, TemporalStatus::kInfeasible);

  // Start with acceleration 1 m/s^2 along the line and stop with 0, while the acceleration may
  // change by only 1e-4 per cell: over 20 cells it cannot move by more than 2e-3, and a rest-to-rest
  // profile needs the accelerations to sum to zero. Only the solver can find this out.
  TemporalProblem jerky = LineProblem(10.0, 20);
  jerky.limits.max_acceleration_change = 1e-4;
  jerky.boundary.start_acceleration = Eigen::Vector3d(1.0, 0, 0);
  const TemporalResult r = Solve(jerky);
  EXPECT_EQ(r.status, TemporalStatus::kInfeasible) << r.message;
}

// Both backends share one skeleton, so a curve whose numbers cannot be represented gets the same
// answer from both: invalid input naming the piece (before, 1e308 was invalid input from the SOCP
// backend but a numerical error from Ipopt, and 1e160 a false "infeasible" from the SOCP backend).
TEST_P(BothBackends, HugeCoefficientsAreInvalidInputForBothBackends) {
  for (const double huge : {1e308, 1e200, 1e160, 1e101}) {
    TemporalProblem p = LineProblem(10.0, 10);
    PolynomialPiece::Coefficients c = p.curve.piece(0).coefficients();
    c.conservativeResize(Eigen::NoChange, 3);
    c.col(2) << huge, 0.0, 0.0;
    p.curve = PiecewiseCurve({PolynomialPiece(c)});
    const TemporalResult r = Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInvalidInput) << huge << ": " << r.message;
    EXPECT_THAT(r.message, HasSubstr("curve.pieces[0]"));
  }
}

TEST_P(BothBackends, InvalidInputNamesTheField) {
  TemporalProblem p = LineProblem(10.0, 0);
  TemporalResult r = Solve(p);
  EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
  EXPECT_THAT(r.message, HasSubstr("discretization.K"));

  p = LineProblem(10.0, 10);
  p.limits.max_velocity(1) = -1.0;
  r = Solve(p);
  EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
  EXPECT_THAT(r.message, HasSubstr("limits.max_velocity[1]"));

  p = LineProblem(10.0, 10);
  p.limits.max_acceleration(0) = std::numeric_limits<double>::quiet_NaN();
  r = Solve(p);
  EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
  EXPECT_THAT(r.message, HasSubstr("limits.max_acceleration[0]"));

  p = LineProblem(10.0, 10);
  p.curve = PiecewiseCurve();
  r = Solve(p);
  EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
  EXPECT_THAT(r.message, HasSubstr("curve"));

  p = LineProblem(10.0, 10);
  p.rho = -1.0;
  EXPECT_EQ(Solve(p).status, TemporalStatus::kInvalidInput);

  for (double thinning : {-1e-4, 0.5, std::numeric_limits<double>::quiet_NaN()}) {
    p = LineProblem(10.0, 10);
    p.certified_thinning = thinning;
    r = Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
    EXPECT_THAT(r.message, HasSubstr("certified_thinning"));
  }
}

TemporalProblem RandomProblem(std::mt19937& rng, int pieces, bool quintic, int K) {
  const Waypoints w = RandomWalk(rng, pieces + 1);
  return WalkProblem(quintic ? MinimumJerkSpline(w) : NaturalCubicSpline(w), K);
}

// Rest-to-rest minimum-jerk curves have a vanishing tangent at both ends, where the acceleration
// cap amax / |f'| that sizes the rho cone grows without bound. With the cone sized by those few
// cells (a root-sum-square of the caps) 2 of these 12 ended with reduced accuracy (32 of 240 in a
// wider sweep); sized by the median cap all reach the solver's 1e-8 tolerances. J is compared with
// Ipopt to 1e-7 relative, ten times both solvers' tolerance (with rho > 0, J, not T, is what both
// determine sharply).
// SocpTemporalOptions compare every field: a change of any one makes two options differ (the
// planner keeps its solver only while they are equal).
TEST(TemporalOptions, EveryFieldTakesPartInEquality) {
  const SocpTemporalOptions base;
  EXPECT_TRUE(base == SocpTemporalOptions());
  std::vector<SocpTemporalOptions> changed(5, base);
  changed[0].tolerance = 1e-7;
  changed[1].max_iterations = 50;
  changed[2].structured = false;
  changed[3].jerk_ipopt_fallback_seconds = 5.0;
  changed[4].max_memory_bytes = 1 << 20;
  for (size_t i = 0; i < changed.size(); ++i) EXPECT_TRUE(changed[i] != base) << "field " << i;
}

TEST(TemporalBackends, RhoConeOnRestToRestQuinticsReachesFullAccuracy) {
  std::mt19937 rng(2026);
  const auto socp = MakeSocpTemporalSolver();
  const auto ipopt = MakeIpoptTemporalSolver();
  for (int pieces : {4, 10}) {
    for (double rho : {0.01, 0.1, 1.0}) {
      for (int K : {50, 100}) {
        TemporalProblem p = RandomProblem(rng, pieces, true, K);
        p.rho = rho;
        const TemporalResult a = socp->Solve(p), b = ipopt->Solve(p);
        ASSERT_TRUE(a.is_success()) << a.message;
        ASSERT_TRUE(b.is_success()) << b.message;
        const std::string label =
            std::to_string(pieces) + " pieces, rho=" + std::to_string(rho) + " K=" + std::to_string(K);
        EXPECT_FALSE(a.reduced_accuracy) << label << ": " << a.message;
        EXPECT_NEAR(a.objective, b.objective, 1e-7 * b.objective) << label;
      }
    }
  }
}

// The two backends solve the same discretization with independent algorithms (conic interior
// point vs. Ipopt on the NLP in b): agreement of T to 1e-6 relative is the target and
// well above both solvers' tolerances (~1e-9).
TEST(TemporalBackends, SocpAndIpoptAgreeOnRandomCurves) {
  std::mt19937 rng(42);
  const auto socp = MakeSocpTemporalSolver();
  const auto ipopt = MakeIpoptTemporalSolver();
  for (int pieces : {2, 5, 12, 20}) {
    for (bool quintic : {false, true}) {
      for (double rho : {0.0, 0.5}) {
        TemporalProblem p = RandomProblem(rng, pieces, quintic, 20);
        p.rho = rho;
        const TemporalResult a = socp->Solve(p), b = ipopt->Solve(p);
        ASSERT_TRUE(a.is_success()) << a.message;
        ASSERT_TRUE(b.is_success()) << b.message;
        EXPECT_NEAR(a.total_time, b.total_time, 1e-6 * b.total_time)
            << pieces << " pieces, quintic=" << quintic << " rho=" << rho;
        EXPECT_NEAR(a.objective, b.objective, 1e-6 * b.objective);
      }
    }
  }
}

// The conic solver's iteration count does not grow with the path length (it starts from the centered
// point, and the velocity bounds are scaled like the other rows). Measured: 18-20 iterations at 2,500
// cells, where the least-squares start with unscaled bounds needed 29; 23 separates the two.
TEST(TemporalBackends, LongPathsNeedNoMoreIterations) {
  std::mt19937 rng(77);
  const auto socp = MakeSocpTemporalSolver();
  for (int trial = 0; trial < 2; ++trial) {
    const TemporalProblem p = RandomProblem(rng, 50, false, 50);
    const TemporalResult r = socp->Solve(p);
    ASSERT_TRUE(r.is_success()) << r.message;
    EXPECT_LE(r.iterations, 23) << "trial " << trial;
  }
}

// tests/temporal/data/NAME.json solved by the SOCP and the Ipopt backend, in that order.
std::pair<TemporalResult, TemporalResult> SolveDataProblemWithBothBackends(const std::string& name) {
  const TemporalProblem p =
      ReadTemporalProblemJson(std::string(TIMEOPT_SOURCE_DIR) + "/tests/temporal/data/" + name + ".json");
  return {MakeSocpTemporalSolver()->Solve(p), MakeIpoptTemporalSolver()->Solve(p)};
}

// Curves that the planner's time-coupled baseline produced (polynomials in time, 10 pieces, rest to
// rest, certified rows, K = 20): pieces with tangents from 0.006 to 2 m per unit s, so the optimal b
// spans 1 to 1e4. Before the unknowns were scaled per piece the conic solver stalled on both (no
// progress after 65 iterations; the iteration limit of 100) while Ipopt solved them; now both
// backends agree to the 1e-6.
// The structured path (SocpTemporalOptions::structured) answers them too, in 48-50 iterations of its
// own (its cap is 60; they are its hardest known cases: the steps shrink mid-way in a few cells
// whose rows form narrow slabs), and agrees with the conic solver to 1e-9 relative.
TEST(TemporalBackends, TimeAllocatedCurvesWithSlowPieces) {
  SocpTemporalOptions conic_only;
  conic_only.structured = false;
  for (const char* name : {"time_allocated_a", "time_allocated_b"}) {
    const TemporalProblem p =
        ReadTemporalProblemJson(std::string(TIMEOPT_SOURCE_DIR) + "/tests/temporal/data/" + name + ".json");
    const TemporalResult a = MakeSocpTemporalSolver(conic_only)->Solve(p);
    const TemporalResult b = MakeIpoptTemporalSolver()->Solve(p);
    const TemporalResult structured = MakeSocpTemporalSolver()->Solve(p);
    ASSERT_TRUE(a.is_success()) << name << ": " << a.message;
    ASSERT_TRUE(b.is_success()) << name << ": " << b.message;
    ASSERT_TRUE(structured.is_success()) << name << ": " << structured.message;
    EXPECT_NEAR(a.total_time, b.total_time, 1e-6 * b.total_time) << name;
    EXPECT_LE(a.iterations, 40) << name;  // 21-22 measured
    EXPECT_THAT(structured.message, HasSubstr("structured path")) << name;
    EXPECT_NEAR(structured.total_time, a.total_time, 1e-9 * a.total_time) << name;
  }
}

// Two random problems of tests/temporal/cvxopt_cross_check.py's kind (rho > 0 and lambda_a, K = 50
// and 100) on which the last full steps traded one criterion for another: the primal residual,
// spoiled by rounding in the final solves, went above the tolerance as the gap came below it, and the
// solve ended with reduced accuracy (best iterates 1.02-1.4x from the tolerances). The midpoint of
// such a step (the conic solver's lookback, see Solver::Solve) meets all of them; J agrees with
// Ipopt to 1e-7 relative.
TEST(TemporalBackends, RhoAndLambdaEndGameReachesFullAccuracy) {
  for (const char* name : {"lookback_rho_lambda_a", "lookback_rho_lambda_b"}) {
    const auto [a, b] = SolveDataProblemWithBothBackends(name);
    ASSERT_TRUE(a.is_success()) << name << ": " << a.message;
    ASSERT_TRUE(b.is_success()) << name << ": " << b.message;
    EXPECT_FALSE(a.reduced_accuracy) << name << ": " << a.message;
    EXPECT_NEAR(a.objective, b.objective, 1e-7 * b.objective) << name;
  }
}

// The rho cone is balanced by the size ||a|| can reach: sqrt(N) times the median over the N cells of
// min_j amax_j / |f'_j|. On a line of length L along x only the x axis has a tangent (|f'| = L
// everywhere), so every cell's cap is amax / L: the scale is sqrt(K) amax / L exactly (up to rounding).
TEST(TemporalDiscretization, AccelerationNormScaleOnAStraightLine) {
  for (int K : {5, 20, 80}) {
    TemporalProblem p = LineProblem(10.0, K);
    p.limits.max_acceleration = Eigen::Vector3d(1.5, 0.1, 0.1);  // y and z have no tangent: ignored
    const TemporalDiscretization d = Discretize(p);
    EXPECT_NEAR(d.acceleration_norm_scale, std::sqrt(K) * 1.5 / 10.0, 1e-12) << "K=" << K;
  }
}

// Acceleration of the exact trajectory at the middle of cell k of piece i, computed from the
// curve and b alone (b is linear on the cell, so b(s_mid) = (b^k + b^{k+1}) / 2).
Eigen::Vector3d MidCellAcceleration(const TemporalProblem& p, const TemporalProfile& prof, int i, int k) {
  const double s = prof.CellStart(i, k) + 0.5 * prof.CellLength(i, k);
  return p.curve.Evaluate(i, s, 1) * prof.a(i, k) + p.curve.Evaluate(i, s, 2) * 0.5 * (prof.b(i, k) + prof.b(i, k + 1));
}

TEST_P(BothBackends, RhoRaisesTimeAndLowersAccelerationEnergy) {
  std::mt19937 rng(5);
  const TemporalProblem base = RandomProblem(rng, 4, false, 20);
  double previous_T = 0.0, previous_energy = std::numeric_limits<double>::infinity();
  for (double rho : {0.0, 0.5, 5.0}) {
    TemporalProblem p = base;
    p.rho = rho;
    const TemporalResult r = Solve(p);
    ASSERT_TRUE(r.is_success()) << r.message;
    double energy = 0.0;
    for (int i = 0; i < r.profile.num_pieces(); ++i) {
      for (int k = 0; k < r.profile.cells_per_piece(); ++k) energy += std::pow(r.profile.a(i, k), 2);
    }
    // Strict monotonicity with margins far above the solver tolerance.
    EXPECT_GT(r.total_time, previous_T + 1e-6) << "rho=" << rho;
    EXPECT_LT(energy, previous_energy - 1e-6) << "rho=" << rho;
    previous_T = r.total_time;
    previous_energy = energy;
  }
}

TEST_P(BothBackends, LimitsHoldAtGridPointsAndCellMiddlesWithAccelerationChangeBound) {
  std::mt19937 rng(8);
  TemporalProblem p = RandomProblem(rng, 5, true, 20);
  p.limits.max_acceleration_change = 0.3;
  const TemporalResult r = Solve(p);
  ASSERT_TRUE(r.is_success()) << r.message;
  const Trajectory traj(p.curve, r.profile);
  const TemporalProfile& prof = r.profile;
  // Interior-point solutions approach the active limits from inside or within the feasibility
  // tolerance (1e-9 relative to data of size ~1-100): 1e-7 absolute holds with margin.
  const double tol = 1e-7;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  bool first = true;
  for (int i = 0; i < prof.num_pieces(); ++i) {
    for (int k = 0; k <= prof.cells_per_piece(); ++k) {
      const TrajectoryState s = traj.Evaluate(prof.TimeAt(i, k));
      EXPECT_LE((s.velocity.cwiseAbs() - p.limits.max_velocity).maxCoeff(), tol);
    }
    for (int k = 0; k < prof.cells_per_piece(); ++k) {
      // Find the time of the cell middle from the sampled trajectory's own t <-> s map:
      // s(t) = s_k + sqrt(b^k) tau + a tau^2 / 2 = s_k + ds / 2.
      const double v0 = std::sqrt(prof.b(i, k)), a = prof.a(i, k), h = 0.5 * prof.CellLength(i, k);
      const double tau = std::abs(a) < 1e-14 ? h / v0 : (-v0 + std::sqrt(v0 * v0 + 2 * a * h)) / a;
      const TrajectoryState s = traj.Evaluate(prof.TimeAt(i, k) + tau);
      EXPECT_LE((s.acceleration.cwiseAbs() - p.limits.max_acceleration).maxCoeff(), tol);
      EXPECT_LT((s.acceleration - MidCellAcceleration(p, prof, i, k)).norm(), 1e-8);
      const Eigen::Vector3d acc = MidCellAcceleration(p, prof, i, k);
      if (first) {
        EXPECT_LE((acc - p.boundary.start_acceleration).cwiseAbs().maxCoeff(), 0.3 + tol);
      } else {
        EXPECT_LE((acc - previous).cwiseAbs().maxCoeff(), 0.3 + tol);
      }
      previous = acc;
      first = false;
    }
  }
  EXPECT_LE((previous - p.boundary.end_acceleration).cwiseAbs().maxCoeff(), 0.3 + tol);
}

// --- curves from other planners (issue 7) ---

// Natural cubic spline through waypoints with knot spacing h_i (chord lengths), each piece in its
// own parameter tau in [0, h_i]: C2 in tau, only G1 once rescaled to unit pieces. Built here with
// a dense solve, independently of the library's unit-spacing spline.
CurveFile ChordLengthCubic(const Waypoints& w) {
  const int m = static_cast<int>(w.cols()) - 1;
  std::vector<double> h(m);
  for (int i = 0; i < m; ++i) h[i] = (w.col(i + 1) - w.col(i)).norm();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m + 1, m + 1);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m + 1, 3);
  A(0, 0) = A(m, m) = 1.0;
  for (int i = 1; i < m; ++i) {
    A(i, i - 1) = h[i - 1];
    A(i, i) = 2.0 * (h[i - 1] + h[i]);
    A(i, i + 1) = h[i];
    rhs.row(i) = 6.0 * ((w.col(i + 1) - w.col(i)) / h[i] - (w.col(i) - w.col(i - 1)) / h[i - 1]).transpose();
  }
  const Eigen::MatrixXd M = A.fullPivLu().solve(rhs);
  std::string json = "{\"pieces\": [";
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector3d mi = M.row(i).transpose(), mj = M.row(i + 1).transpose();
    Eigen::Matrix<double, 3, 4> c;
    c.col(0) = w.col(i);
    c.col(1) = (w.col(i + 1) - w.col(i)) / h[i] - h[i] * (2.0 * mi + mj) / 6.0;
    c.col(2) = mi / 2.0;
    c.col(3) = (mj - mi) / (6.0 * h[i]);
    json += (i ? "," : "") + std::string("{");
    for (int a = 0; a < 3; ++a) {
      json += std::string(a ? "," : "") + "\"" + "xyz"[a] + "\": [";
      for (int j = 0; j < 4; ++j) {
        char buf[40];
        std::snprintf(buf, sizeof(buf), "%s%.17g", j ? "," : "", c(a, j));
        json += buf;
      }
      json += "]";
    }
    json += "}";
  }
  json += "], \"durations\": [";
  for (int i = 0; i < m; ++i) {
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%s%.17g", i ? "," : "", h[i]);
    json += buf;
  }
  return ParseCurveJson(json + "]}");
}

TEST_P(BothBackends, DurationCurveMatchesRescaledCurveAndVelocityIsContinuous) {
  std::mt19937 rng(21);
  const CurveFile file = ChordLengthCubic(RandomWalk(rng, 6));
  TemporalProblem p = LineProblem(1.0, 30);
  p.curve = file.curve;  // rescaled to unit pieces on reading
  // The same curve rescaled by hand from the durations: identical coefficients up to rounding.
  TemporalProblem q = p;
  const TemporalResult a = Solve(p);
  ASSERT_TRUE(a.is_success()) << a.message;
  for (const JointInfo& j : a.joints) EXPECT_EQ(j.type, JointType::kG1);
  const TemporalResult b = Solve(q);
  EXPECT_NEAR(a.total_time, b.total_time, 1e-9 * a.total_time);

  // Velocity is continuous at every joint: evaluate just before and after each joint time.
  const Trajectory traj(p.curve, a.profile);
  for (int i = 1; i < a.profile.num_pieces(); ++i) {
    const double t = a.profile.TimeAt(i, 0);
    const Eigen::Vector3d before = p.curve.Evaluate(i - 1, 1.0, 1) * std::sqrt(a.profile.b(i - 1, 30));
    const Eigen::Vector3d after = p.curve.Evaluate(i, 0.0, 1) * std::sqrt(a.profile.b(i, 0));
    EXPECT_LT((before - after).norm(), 1e-9) << "joint " << i;
    EXPECT_LT((traj.Evaluate(t - 1e-12).velocity - traj.Evaluate(t + 1e-12).velocity).norm(), 1e-9);
  }
}

TEST(TemporalJoints, C1CurveUsesThePapersJointRule) {
  std::mt19937 rng(3);
  TemporalProblem p = RandomProblem(rng, 6, true, 10);
  const TemporalDiscretization d = Discretize(p);
  for (const JointInfo& j : d.joints) {
    EXPECT_EQ(j.type, JointType::kC1);
    EXPECT_EQ(j.speed_ratio, 1.0);
  }
  // eq. 43: the last point of a piece and the first of the next are the same unknown with the same
  // scale (b = scale x), so b is the same value on both sides.
  for (int i = 0; i + 1 < d.num_pieces; ++i) {
    const GridValue& a = d.grid[d.GridIndex(i, 10)];
    const GridValue& b = d.grid[d.GridIndex(i + 1, 0)];
    EXPECT_EQ(a.var, b.var);
    EXPECT_EQ(b.scale, a.scale);
  }
}

// The discretization converges to the continuous-time optimum on a G1 curve: T(K=200) is within
// 0.05% of T(K=800) (the target).
TEST(TemporalConvergence, G1CurveConvergesInK) {
  std::mt19937 rng(31);
  const CurveFile file = ChordLengthCubic(RandomWalk(rng, 5));
  TemporalProblem p = LineProblem(1.0, 200);
  p.curve = file.curve;
  const auto socp = MakeSocpTemporalSolver();
  const TemporalResult coarse = socp->Solve(p);
  p.cells_per_piece = 800;
  const TemporalResult fine = socp->Solve(p);
  ASSERT_TRUE(coarse.is_success()) << coarse.message;
  ASSERT_TRUE(fine.is_success()) << fine.message;
  // (Paper-mode rows sit at different points for different K, so neither grid's problem is a
  // relaxation of the other: only the distance is asserted, not its sign.)
  EXPECT_LE(std::abs(coarse.total_time - fine.total_time), 5e-4 * fine.total_time);
}

}  // namespace
}  // namespace timeopt
