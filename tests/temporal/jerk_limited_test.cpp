// The jerk-limited temporal stage (limits.max_jerk): closed-form S-curves, dense checks of the
// flown quantities, the sequential convex programme, both backends, the simulator, bad input.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../common/fixtures.h"
#include "../common/run_cli.h"
#include "timeopt/core/files.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {
namespace {

using test_support::SCurveTime;
using test_support::Segment;
using ::testing::HasSubstr;

TemporalProblem JerkLine(const Eigen::Vector3d& to, double v, double a, double j, int K) {
  TemporalProblem p;
  p.curve = Segment(Eigen::Vector3d::Zero(), to);
  p.limits.max_velocity.setConstant(v);
  p.limits.max_acceleration.setConstant(a);
  p.limits.max_jerk = Eigen::Vector3d::Constant(j);
  p.cells_per_piece = K;
  return p;
}

TEST(JerkLimited, SCurveClosedFormItself) {
  // The issue's example: L = 10, v = 4, a = 3, j = 10 gives L / v + v / a + a / j.
  EXPECT_NEAR(SCurveTime(10.0, 4.0, 3.0, 10.0), 10.0 / 4.0 + 4.0 / 3.0 + 0.3, 1e-12);
  // No cruise, a reached: vp solves vp (vp / a + a / j) = L.
  const double vp = 1.5 * (-0.3 + std::sqrt(0.09 + 4.0 * 2.0 / 3.0));
  EXPECT_NEAR(SCurveTime(2.0, 4.0, 3.0, 10.0), 2.0 * (vp / 3.0 + 0.3), 1e-9);
}

// Lines along an axis, along a diagonal (the per-axis limits scale by the direction cosine: the
// binding axis has |cos| = 1 / sqrt(3), so the line's limits are sqrt(3) times the axis ones),
// a short line where v is not reached and a shorter one where a is not reached either. Targets
// of the issue: never below the closed form (that would be a violated limit; 1e-9 for the
// solver's tolerance), within 1% above it at K = 50 and within 0.25% at K = 200 (measured: at most
// 0.03% and 0.006%, the rest cells sized to the jerk ramp).
TEST(JerkLimited, LinesAreWithinTheTargetsOfTheSCurveAndNeverBelow) {
  struct Case {
    Eigen::Vector3d to;
    double v, a, j, exact;
  };
  const double c = 1.0 / std::sqrt(3.0);
  const Case cases[] = {
      {Eigen::Vector3d(10.0, 0.0, 0.0), 4.0, 3.0, 10.0, SCurveTime(10.0, 4.0, 3.0, 10.0)},
      {Eigen::Vector3d(10.0, 10.0, 10.0) * c, 4.0 * c, 3.0 * c, 10.0 * c, SCurveTime(10.0, 4.0, 3.0, 10.0)},
      {Eigen::Vector3d(0.0, 2.0, 0.0), 4.0, 3.0, 10.0, SCurveTime(2.0, 4.0, 3.0, 10.0)},
      {Eigen::Vector3d(0.0, 0.0, 0.5), 4.0, 3.0, 10.0, SCurveTime(0.5, 4.0, 3.0, 10.0)},
  };
  for (const Case& k : cases) {
    for (const auto& [K, target] : {std::pair<int, double>{50, 0.01}, std::pair<int, double>{200, 0.0025}}) {
      const TemporalResult r = MakeSocpTemporalSolver()->Solve(JerkLine(k.to, k.v, k.a, k.j, K));
      ASSERT_TRUE(r.is_success()) << r.message;
      EXPECT_GE(r.total_time, k.exact * (1.0 - 1e-9)) << k.to.transpose() << " K " << K;
      EXPECT_LE(r.total_time, k.exact * (1.0 + target)) << k.to.transpose() << " K " << K;
      EXPECT_LE(r.max_jerk_ratio, 1.0 + 1e-6);
      std::printf("%g K %d: %+.4f%%\n", k.to.norm(), K, 100.0 * (r.total_time / k.exact - 1.0));
    }
  }
}

// Random cubic and quintic curves: the 1 kHz samples respect v, a and j (the dense check is
// certified by the rows, so only the solver's tolerance is allowed: 1e-6), the jerk columns agree
// with finite differences of the sampled acceleration, and the acceleration never jumps: between
// two samples it changes by at most jmax dt (the jerk limit), across cells, joints and at the ends
// (it starts and ends at 0 for these rest-to-rest problems).
TEST(JerkLimited, DenseSamplesRespectEveryLimitAndAccelerationIsContinuous) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 4; ++trial) {
    const Waypoints w = test_support::RandomWalk(rng, 4);
    TemporalProblem p = test_support::WalkProblem(trial % 2 == 0 ? NaturalCubicSpline(w) : MinimumJerkSpline(w), 30);
    p.limits.max_jerk = Eigen::Vector3d(6.0, 6.0, 4.0);
    const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
    ASSERT_TRUE(r.is_success()) << r.message;
    const Trajectory trajectory(p.curve, r.profile);
    const double rate = 1000.0, dt = 1.0 / rate;
    const std::vector<TrajectoryState> samples = trajectory.Sample(rate);
    EXPECT_LT(samples.front().acceleration.norm(), 1e-9);
    EXPECT_LT(samples.back().acceleration.norm(), 1e-9);
    for (size_t i = 0; i < samples.size(); ++i) {
      const TrajectoryState& s = samples[i];
      for (int a = 0; a < 3; ++a) {
        EXPECT_LE(std::abs(s.velocity(a)), p.limits.max_velocity(a) * (1.0 + 1e-6));
        EXPECT_LE(std::abs(s.acceleration(a)), p.limits.max_acceleration(a) * (1.0 + 1e-6));
        EXPECT_LE(std::abs(s.jerk(a)), (*p.limits.max_jerk)(a) * (1.0 + 1e-6));
      }
      if (i + 1 < samples.size()) {
        const double h = samples[i + 1].t - s.t;
        const Eigen::Vector3d change = samples[i + 1].acceleration - s.acceleration;
        for (int a = 0; a < 3; ++a) {
          // |change| <= jmax h: the mean of the jerk over the step is within the limit.
          EXPECT_LE(std::abs(change(a)), (*p.limits.max_jerk)(a)*h * (1.0 + 1e-6) + 1e-12);
        }
        if (i > 0 && h > 0.5 * dt) {
          // The central difference of the acceleration is the mean jerk over [t_{i-1}, t_{i+1}],
          // which lies within the jerk's range there. The jerk may jump where two cells meet (its
          // da/ds factor does), so the range is that of the three samples, widened by 1% of jmax
          // for the jerk's smooth change between samples (at most 1e3 m/s^4 x 1 ms here).
          const Eigen::Vector3d fd =
              (samples[i + 1].acceleration - samples[i - 1].acceleration) / (samples[i + 1].t - samples[i - 1].t);
          for (int a = 0; a < 3; ++a) {
            const double lo = std::min({samples[i - 1].jerk(a), s.jerk(a), samples[i + 1].jerk(a)});
            const double hi = std::max({samples[i - 1].jerk(a), s.jerk(a), samples[i + 1].jerk(a)});
            const double slack = 0.01 * (*p.limits.max_jerk)(a);
            EXPECT_GE(fd(a), lo - slack) << s.t;
            EXPECT_LE(fd(a), hi + slack) << s.t;
          }
        }
      }
    }
  }
}

// The sequential convex programme: every convex solve is feasible for the true jerk limit (each
// linearized row is conservative), and the reported T never increases with more solves (the best
// jerk-feasible solve is kept). The first solve is linearized at the jerk-free certified optimum.
// No solve is faster than the same problem without a jerk limit (certified rows, b linear on the
// same K cells): the grids differ, so 0.1% is allowed, well above their discretization difference
// and well below what the jerk limit costs here (several percent).
TEST(JerkLimited, EveryIterateIsJerkFeasibleAndTNeverIncreases) {
  std::mt19937 rng(8);
  TemporalProblem p = test_support::WalkProblem(NaturalCubicSpline(test_support::RandomWalk(rng, 4)), 30);
  p.limits.max_jerk = Eigen::Vector3d(5.0, 5.0, 3.0);
  TemporalProblem jerk_free = p;
  jerk_free.limits.max_jerk.reset();
  jerk_free.constraint_mode = ConstraintMode::kCertified;
  const TemporalResult lower = MakeSocpTemporalSolver()->Solve(jerk_free);
  ASSERT_TRUE(lower.is_success()) << lower.message;
  double previous = std::numeric_limits<double>::infinity();
  for (int n = 1; n <= 5; ++n) {
    p.max_scp_iterations = n;
    const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
    ASSERT_TRUE(r.is_success()) << r.message;
    EXPECT_LE(r.max_jerk_ratio, 1.0 + 1e-6) << n;
    EXPECT_LE(r.total_time, previous * (1.0 + 1e-12)) << n;
    previous = r.total_time;
    ASSERT_GE(r.scp_history.size(), 1u);
    EXPECT_LE(r.scp_history.size(), static_cast<size_t>(n));
    for (double t : r.scp_history) EXPECT_GE(t, lower.total_time * (1.0 - 1e-3));
    // The answer is the best solve; on the structured path the first one (a looser linearization
    // point) is never it.
    const auto first =
        r.scp_history.size() > 1 && r.method == "structured" ? r.scp_history.begin() + 1 : r.scp_history.begin();
    EXPECT_NEAR(r.total_time, *std::min_element(first, r.scp_history.end()), 1e-12 * r.total_time);
  }
}

// The two backends solve the same grid with the jerk limit written two ways: the SOCP backend by
// sequential convex programming over tangent bounds of 1 / sqrt(b), Ipopt once with the exact,
// non-convex rows b P^2 <= j^2. Both are certified and both are local answers; the issue asks for
// 0.2%. Ipopt's T is the lower one, by 0 (the line) to 1.6e-4 (the quintic): the SCP linearizes
// 1 / sqrt(b) at the cell's largest b, so where the jerk binds at a smaller b of the same cell its
// bound keeps some slack, which the exact rows do not. That is not the SCP stopping early: with
// scp_tolerance 1e-9 it ends at the same T to 9 digits. Ipopt <= SCP is asserted with 1e-6 of
// room for the solvers' tolerances. Both answers must hold the jerk limit on the dense check.
TEST(JerkLimited, BothBackendsAgreeAndTheExactRowsAreNotAbove) {
  std::mt19937 rng(21);
  std::vector<TemporalProblem> problems = {JerkLine(Eigen::Vector3d(6.0, 3.0, 0.0), 3.0, 2.0, 8.0, 20)};
  for (int trial = 0; trial < 2; ++trial) {
    const Waypoints w = test_support::RandomWalk(rng, 3);
    TemporalProblem p = test_support::WalkProblem(trial == 0 ? NaturalCubicSpline(w) : MinimumJerkSpline(w), 20);
    p.limits.max_jerk = Eigen::Vector3d(6.0, 6.0, 4.0);
    problems.push_back(p);
  }
  for (const TemporalProblem& p : problems) {
    const TemporalResult socp = MakeSocpTemporalSolver()->Solve(p);
    const TemporalResult ipopt = MakeIpoptTemporalSolver()->Solve(p);
    ASSERT_TRUE(socp.is_success()) << socp.message;
    ASSERT_TRUE(ipopt.is_success()) << ipopt.message;
    EXPECT_EQ(ipopt.scp_iterations, 0);  // one non-convex solve
    EXPECT_LE(ipopt.max_jerk_ratio, 1.0 + 1e-6);
    EXPECT_LE(socp.max_jerk_ratio, 1.0 + 1e-6);
    EXPECT_NEAR(socp.total_time, ipopt.total_time, 2e-3 * socp.total_time);
    EXPECT_LE(ipopt.total_time, socp.total_time * (1.0 + 1e-6));
  }
}

// A rest cell's polynomials in its time fraction have 6 deg f' + 6 coefficients; pieces of degree
// above 10 keep a rest cell of constant s-jerk instead (AddConstantJerkRestRows), which the
// structured path has no basis for. Such a piece (degree 12: a cubic with small higher terms) must
// still be solved, flown within its limits, and agree with the exact rows as above.
TEST(JerkLimited, PiecesOfHighDegreeKeepAConstantJerkRestCell) {
  PolynomialPiece::Coefficients c = PolynomialPiece::Coefficients::Zero(3, 13);
  c.col(1) << 3.0, 1.0, 0.2;
  c.col(2) << 1.0, 2.0, 0.0;
  c.col(3) << -0.5, -1.0, 0.1;
  for (int j = 4; j < 13; ++j) c.col(j) << 0.01 / j, -0.02 / j, 0.005;
  TemporalProblem p = test_support::WalkProblem(PiecewiseCurve({PolynomialPiece(c)}), 30);
  p.limits.max_jerk = Eigen::Vector3d(6.0, 6.0, 4.0);
  const TemporalResult socp = MakeSocpTemporalSolver()->Solve(p);
  const TemporalResult ipopt = MakeIpoptTemporalSolver()->Solve(p);
  ASSERT_TRUE(socp.is_success()) << socp.message;
  ASSERT_TRUE(ipopt.is_success()) << ipopt.message;
  EXPECT_EQ(socp.method, "conic");
  EXPECT_LE(socp.max_jerk_ratio, 1.0 + 1e-6);
  EXPECT_LE(socp.max_acceleration_ratio, 1.0 + 1e-6);
  EXPECT_NEAR(socp.total_time, ipopt.total_time, 2e-3 * socp.total_time);
  EXPECT_LE(ipopt.total_time, socp.total_time * (1.0 + 1e-6));
}

// From 36 cells per piece the structured path starts from the programme solved once on a third of
// the cells (docs/temporal.md), and its first solve then takes only the rows near their bound
// there. Its answers must stand against the exact rows as the jerk-free start's do (the test
// above): within the issue's 0.2% of Ipopt's T, not above it by more than the solvers' 1e-6,
// the dense jerk check held, and answered by the structured path itself.
TEST(JerkLimited, TheCoarseStartAgreesWithTheExactRows) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 2; ++trial) {
    const Waypoints w = test_support::RandomWalk(rng, 3);
    TemporalProblem p =
        test_support::WalkProblem(trial == 0 ? NaturalCubicSpline(w) : MinimumJerkSpline(w), trial == 0 ? 48 : 60);
    p.limits.max_jerk = Eigen::Vector3d(6.0, 6.0, 4.0);
    const TemporalResult socp = MakeSocpTemporalSolver()->Solve(p);
    const TemporalResult ipopt = MakeIpoptTemporalSolver()->Solve(p);
    ASSERT_TRUE(socp.is_success()) << socp.message;
    ASSERT_TRUE(ipopt.is_success()) << ipopt.message;
    EXPECT_EQ(socp.method, "structured") << socp.message;
    EXPECT_LE(socp.max_jerk_ratio, 1.0 + 1e-6);
    EXPECT_NEAR(socp.total_time, ipopt.total_time, 2e-3 * socp.total_time);
    EXPECT_LE(ipopt.total_time, socp.total_time * (1.0 + 1e-6));
  }
}

// The jerk-input quadrotor flies these profiles from hover within 1% of the limits (its controller
// holds the jerk feed-forward over each 1 ms step, so it lags the reference by a little).
TEST(JerkLimited, TheSimulatedQuadrotorHoldsTheLimitsWithinOnePercent) {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 2; ++trial) {
    const Waypoints w = test_support::RandomWalk(rng, 4);
    TemporalProblem p = test_support::WalkProblem(MinimumJerkSpline(w), 30);
    p.limits.max_jerk = Eigen::Vector3d(6.0, 6.0, 4.0);
    const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
    ASSERT_TRUE(r.is_success()) << r.message;
    const FeasibilityReport flight =
        QuadrotorSim().Fly(Trajectory(p.curve, r.profile), p.limits, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    EXPECT_LE(flight.max_velocity_ratio, 1.01);
    EXPECT_LE(flight.max_acceleration_ratio, 1.01);
  }
}

// One long quintic piece (the contract's 3-axis test curve scaled by `size`), jerk-limited, K = 50.
TemporalProblem LongQuintic(double size, double limit_scale) {
  PolynomialPiece::Coefficients c = PolynomialPiece::Coefficients::Zero(3, 5);
  c.row(0) << 0.0, 10.0, 0.0, 0.0, -3.0;
  c.row(1) << 0.0, 0.0, 6.0, -6.0, 0.0;
  TemporalProblem p;
  p.curve = PiecewiseCurve({PolynomialPiece(c * size)});
  p.limits.max_velocity.setConstant(2.0 * limit_scale);
  p.limits.max_acceleration.setConstant(1.0 * limit_scale);
  p.limits.max_jerk = Eigen::Vector3d::Constant(5.0 * limit_scale);
  p.cells_per_piece = 50;
  return p;
}

// The conic solves of the sequential convex programme lose their accuracy on long pieces (here
// 300 m at vmax 2: T ~ 117 s against jerk ramps of ~0.2 s) and end in a numerical error; the SOCP
// backend then solves the exact rows with Ipopt. The answer must be Ipopt's own (the same solver
// on the same rows: T to 1e-12 relative), flyable (dense ratios within the 1e-6 of the rows'
// tolerances), and say what happened. Where neither solves it in time, the fallback's CPU cap
// ends the solve with a status naming both.
TEST(JerkLimited, AFailedConicSolveFallsBackToTheExactRowsWithinItsCap) {
  const TemporalProblem long_piece = LongQuintic(30.0, 1.0);
  const TemporalResult socp = MakeSocpTemporalSolver()->Solve(long_piece);
  const TemporalResult ipopt = MakeIpoptTemporalSolver()->Solve(long_piece);
  ASSERT_TRUE(ipopt.is_success()) << ipopt.message;
  ASSERT_TRUE(socp.is_success()) << socp.message;
  if (socp.solver == "ipopt") {
    EXPECT_THAT(socp.message, HasSubstr("solved by Ipopt's exact jerk rows"));
    EXPECT_NEAR(socp.total_time, ipopt.total_time, 1e-12 * ipopt.total_time);
  } else {
    // The conic solves succeeded after all: then they must agree with the exact rows as on the
    // benchmark curves (BothBackendsAgreeAndTheExactRowsAreNotAbove: within 2e-4, never below).
    EXPECT_GE(socp.total_time, ipopt.total_time * (1.0 - 1e-9));
    EXPECT_LE(socp.total_time, ipopt.total_time * (1.0 + 2e-4));
  }
  EXPECT_LE(socp.max_velocity_ratio, 1.0 + 1e-6);
  EXPECT_LE(socp.max_acceleration_ratio, 1.0 + 1e-6);
  EXPECT_LE(socp.max_jerk_ratio, 1.0 + 1e-6);

  // The cap: conic solves stopped by an iteration limit of 5, and a fallback given 1e-6 CPU s. The
  // structured path is off: from the certified guess it needs no more than 5 iterations here.
  SocpTemporalOptions capped;
  capped.structured = false;
  capped.max_iterations = 5;
  capped.jerk_ipopt_fallback_seconds = 1e-6;
  const TemporalResult hopeless = MakeSocpTemporalSolver(capped)->Solve(LongQuintic(1.0, 1.0));
  EXPECT_EQ(hopeless.status, TemporalStatus::kIterationLimit) << hopeless.message;
  EXPECT_THAT(hopeless.message, HasSubstr("Ipopt's exact jerk rows did not solve it either"));
  EXPECT_THAT(hopeless.message, HasSubstr("CPU time limit"));
  SocpTemporalOptions negative;
  negative.jerk_ipopt_fallback_seconds = -1.0;
  EXPECT_THROW(MakeSocpTemporalSolver(negative), std::invalid_argument);
}

// Units. The jerk-limited solve runs in the problem's own units (curve size 1, time of the binding
// limit), so the same problem in micrometres, metres or 1000 km (curve and limits scaled
// together: the same motion) must give the same T to 1e-9, the rounding of the rows, and ratios
// that do not move either; both backends. Badly proportioned problems (a 1 cm curve at limits of
// 1e4, where the speed limit is 5e4 times what the jerk allows; a 1e7 m curve at 1e-4) are
// solved, and a speed limit that cannot bind does not change T: 1e2, 1e4 and 1e8 against the same
// acceleration and jerk give the same T to 1e-8 (two solves of different rows to the solver's
// tolerances).
TEST(JerkLimited, TheAnswerDoesNotDependOnUnitsOrOnLimitsThatCannotBind) {
  for (const TemporalBackend backend : kTemporalBackends) {
    std::unique_ptr<TemporalSolver> solver = MakeTemporalSolver(backend);
    const TemporalResult metres = solver->Solve(LongQuintic(1.0, 1.0));
    ASSERT_TRUE(metres.is_success()) << metres.message;
    for (const double unit : {1e-6, 1e-3, 1e3, 1e6}) {
      const TemporalResult r = solver->Solve(LongQuintic(unit, unit));
      ASSERT_TRUE(r.is_success()) << ToString(backend) << " unit " << unit << ": " << r.message;
      EXPECT_NEAR(r.total_time, metres.total_time, 1e-9 * metres.total_time) << ToString(backend) << " " << unit;
      EXPECT_NEAR(r.max_jerk_ratio, metres.max_jerk_ratio, 1e-6) << ToString(backend) << " " << unit;
      EXPECT_NEAR(r.profile.total_time(), r.total_time, 1e-9 * r.total_time);
    }
  }
  std::unique_ptr<TemporalSolver> socp = MakeSocpTemporalSolver();
  for (const auto& [size, limits] : {std::pair<double, double>{1e-2, 1e4}, {1e7, 1e-4}, {1e-3, 1e4}}) {
    const TemporalResult r = socp->Solve(LongQuintic(size, limits));
    ASSERT_TRUE(r.is_success()) << size << " m at limits x " << limits << ": " << r.message;
    EXPECT_EQ(r.solver, "socp") << r.message;  // solved by the conic solves, no fallback
    EXPECT_LE(r.max_jerk_ratio, 1.0 + 1e-6);
    EXPECT_LE(r.max_acceleration_ratio, 1.0 + 1e-6);
  }
  double reference = 0.0;
  for (const double vmax : {1e2, 1e4, 1e8}) {
    TemporalProblem p = LongQuintic(1.0, 1.0);
    p.limits.max_velocity.setConstant(vmax);
    p.limits.max_acceleration.setConstant(31.0);
    p.limits.max_jerk = Eigen::Vector3d::Constant(1.0);
    const TemporalResult r = socp->Solve(p);
    ASSERT_TRUE(r.is_success()) << "vmax " << vmax << ": " << r.message;
    EXPECT_LT(r.max_velocity_ratio, 0.1);  // the speed limit indeed does not bind
    if (reference == 0.0) reference = r.total_time;
    EXPECT_NEAR(r.total_time, reference, 1e-8 * reference) << "vmax " << vmax;
  }
}

// The linearized jerk rows are an inner approximation: their having no solution at the jerk-free
// answer is not a certificate. The property sweep found such a problem (its problem 5972: a
// polyline of 4 pieces started at 0.4 m/s, K = 6) that the SOCP backend called infeasible while
// Ipopt's exact rows solve it. Since the jerk-free guess caps accelerations the jerk limit cannot
// reach, the structured path answers it, within 1e-6 of Ipopt's T (measured 6e-8; the SCP stops
// at scp_tolerance 1e-4 of T's change, and Ipopt's exact rows on the same cells are the truth).
// A marginal braking start (0.21 m/s at -2 m/s^2, j = 10: the speed falls to 0.01 m/s) still has
// no solution at its first linearization: a numerical failure that says so, not "infeasible".
TEST(JerkLimited, AnInfeasibleLinearizationIsNotACertificate) {
  const TemporalProblem p = ReadTemporalProblemJson(std::string(TIMEOPT_SOURCE_DIR) +
                                                    "/tests/temporal/data/jerk_linearization_infeasible.json");
  const TemporalResult exact = MakeIpoptTemporalSolver()->Solve(p);
  ASSERT_TRUE(exact.is_success()) << exact.message;
  EXPECT_LE(exact.max_jerk_ratio, 1.0 + 1e-6);
  SocpTemporalOptions no_fallback;
  no_fallback.jerk_ipopt_fallback_seconds = 0.0;
  const TemporalResult conic = MakeSocpTemporalSolver(no_fallback)->Solve(p);
  ASSERT_TRUE(conic.is_success()) << conic.message;
  EXPECT_NEAR(conic.total_time, exact.total_time, 1e-6 * exact.total_time);
  EXPECT_LE(conic.max_jerk_ratio, 1.0 + 1e-6);

  TemporalProblem marginal = JerkLine(Eigen::Vector3d(10.0, 0.0, 0.0), 4.0, 3.0, 10.0, 50);
  marginal.constraint_mode = ConstraintMode::kCertified;
  marginal.boundary.start_velocity = Eigen::Vector3d(0.21, 0, 0);
  marginal.boundary.start_acceleration = Eigen::Vector3d(-2.0, 0, 0);
  // Whichever way the general path fails on this marginal start (its first linearization has no
  // solution, or the conic solve breaks down first), it is a numerical error, not a verdict.
  const TemporalResult r = MakeSocpTemporalSolver(no_fallback)->Solve(marginal);
  EXPECT_EQ(r.status, TemporalStatus::kNumericalError) << r.message;
  EXPECT_THAT(r.message, ::testing::AnyOf(HasSubstr("does not prove the problem infeasible"),
                                          HasSubstr("conic solver: numerical_error")));
}

// Fewer than 3 cells per piece leave a rest-to-rest line no regular cell between its rest cells:
// invalid input naming K and the smallest that works (K = 2 once answered "optimal" with T = 1e6 s
// on this line, whose S-curve optimum is 3.7 s; K = 1 "infeasible"). From K = 3 on it is solved,
// and T falls toward the closed form as K grows (above it: the grid is conservative).
TEST(JerkLimited, TooFewCellsAreInvalidInputNamingTheSmallestK) {
  for (const int K : {1, 2}) {
    const TemporalResult r =
        MakeSocpTemporalSolver()->Solve(JerkLine(Eigen::Vector3d(5.0, 0.0, 0.0), 2.0, 2.0, 10.0, K));
    EXPECT_EQ(r.status, TemporalStatus::kInvalidInput) << K;
    EXPECT_THAT(r.message, HasSubstr("discretization.K: a jerk-limited problem needs at least 3 cells per piece"));
  }
  double previous = std::numeric_limits<double>::infinity();
  for (const int K : {3, 10, 50}) {
    const TemporalResult r =
        MakeSocpTemporalSolver()->Solve(JerkLine(Eigen::Vector3d(5.0, 0.0, 0.0), 2.0, 2.0, 10.0, K));
    ASSERT_EQ(r.status, TemporalStatus::kOptimal) << K;
    EXPECT_LT(r.total_time, previous) << K;
    EXPECT_LT(r.total_time, 2.5 * 3.7) << K;
    previous = r.total_time;
  }
}

TEST(JerkLimited, BadJerkLimitsAreInvalidInputAndUnreachableAccelerationsInfeasible) {
  for (const double bad : {-1.0, 0.0, std::numeric_limits<double>::quiet_NaN()}) {
    TemporalProblem p = JerkLine(Eigen::Vector3d(5.0, 0.0, 0.0), 2.0, 1.0, 5.0, 20);
    (*p.limits.max_jerk)(1) = bad;
    const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
    EXPECT_EQ(r.status, TemporalStatus::kInvalidInput);
    EXPECT_THAT(r.message, HasSubstr("limits.max_jerk[1]"));
  }
  // Starting at rest on a straight line with an acceleration across it: no sddot can make it.
  TemporalProblem p = JerkLine(Eigen::Vector3d(5.0, 0.0, 0.0), 2.0, 1.0, 5.0, 20);
  p.boundary.start_acceleration = Eigen::Vector3d(0.0, 0.5, 0.0);
  const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
  EXPECT_EQ(r.status, TemporalStatus::kInfeasible);
  EXPECT_THAT(r.message, HasSubstr("boundary.start_acceleration cannot be reached"));

  // The command line: exit 2 for a negative limit, exit 3 for the unreachable acceleration.
  const std::string dir = ::testing::TempDir();
  WriteTextFile(dir + "/neg_jerk.json",
                R"({"curve": {"pieces": [{"x": [0, 5], "y": [0, 0], "z": [0, 0]}]},
                    "limits": {"max_velocity": 2, "max_acceleration": 1, "max_jerk": -3}})");
  EXPECT_EQ(testing_support::RunCli("temporal " + dir + "/neg_jerk.json").exit_code, 2);
  WriteTextFile(dir + "/across.json",
                R"({"curve": {"pieces": [{"x": [0, 5], "y": [0, 0], "z": [0, 0]}]},
                    "limits": {"max_velocity": 2, "max_acceleration": 1, "max_jerk": 5},
                    "boundary": {"start_acceleration": [0, 0.5, 0]}})");
  const testing_support::CliRun run = testing_support::RunCli("temporal " + dir + "/across.json");
  EXPECT_EQ(run.exit_code, 3) << run.output;
  EXPECT_THAT(run.output, HasSubstr("cannot be reached"));
}

}  // namespace
}  // namespace timeopt
