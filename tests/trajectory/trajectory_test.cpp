// The trajectory p(t) = f(s(t)) against closed forms on straight lines and against finite
// differences of itself on curved pieces (velocity from position, acceleration from velocity, jerk
// from acceleration), with profiles from the temporal solver and made by hand.

#include "timeopt/trajectory/trajectory.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "timeopt/curve/interpolation.h"
#include "timeopt/temporal/temporal_solver.h"

#include "../common/fixtures.h"

namespace timeopt {
namespace {

using test_support::LineProblem;
using test_support::RandomWalk;
using test_support::Segment;
using test_support::WalkProblem;

constexpr double kEps = std::numeric_limits<double>::epsilon();

// A line from (1, -2, 0.5) to (7, 6, 0.5) (length 10) with a hand-made profile of K = 4 cells:
// on each cell sddot is constant, so inside a cell the position is exactly quadratic in t.
TEST(Trajectory, StraightLineIsExactlyQuadraticInsideEveryCell) {
  const Eigen::Vector3d from(1.0, -2.0, 0.5), to(7.0, 6.0, 0.5);
  const Eigen::Vector3d d = to - from;  // f'(s), constant; f'' = f''' = 0
  const std::vector<double> b = {0.0, 0.0036, 0.0144, 0.01, 0.0};
  const Trajectory trajectory(Segment(from, to), TemporalProfile({b}));
  const TemporalProfile& profile = trajectory.profile();
  EXPECT_EQ(trajectory.duration(), profile.total_time());
  for (int k = 0; k < 4; ++k) {
    const double t0 = profile.TimeAt(0, k), t1 = profile.TimeAt(0, k + 1);
    const double v0 = std::sqrt(b[k]), a = (b[k + 1] - b[k]) / (2.0 * 0.25);  // v1^2 = v0^2 + 2 a ds
    // The closed forms below are met to rounding: a few operations on values of the size of |p|
    // and |f'|, so 8 eps relative. A step of a quarter of the cell keeps t +- h inside it; a
    // quadratic has no truncation error in the first and second central differences, so only
    // rounding remains: values of ~10 m with error ~eps each give eps |p| / h and 4 eps |p| / h^2,
    // and 8 times that is allowed.
    const double h = 0.25 * (t1 - t0);
    for (double fraction : {0.3, 0.5, 0.7}) {
      const double t = t0 + fraction * (t1 - t0), tau = t - t0;
      const TrajectoryState x = trajectory.Evaluate(t);
      // Closed form of constant acceleration along the line: s = s_k + v0 tau + a tau^2 / 2.
      const double s = 0.25 * k + v0 * tau + 0.5 * a * tau * tau;
      const double scale = x.position.norm();
      EXPECT_LT((x.position - (from + s * d)).norm(), 8 * kEps * scale) << "cell " << k;
      EXPECT_LT((x.velocity - (v0 + a * tau) * d).norm(), 8 * kEps * d.norm()) << "cell " << k;
      EXPECT_LT((x.acceleration - a * d).norm(), 8 * kEps * d.norm()) << "cell " << k;
      // Both terms of the jerk carry a derivative of the linear piece that is exactly zero.
      EXPECT_EQ(x.jerk, Eigen::Vector3d::Zero()) << "cell " << k;
      const Eigen::Vector3d before = trajectory.Evaluate(t - h).position;
      const Eigen::Vector3d after = trajectory.Evaluate(t + h).position;
      EXPECT_LT(((after - before) / (2.0 * h) - x.velocity).norm(), 8 * kEps * scale / h) << "cell " << k;
      EXPECT_LT(((after - 2.0 * x.position + before) / (h * h) - x.acceleration).norm(), 32 * kEps * scale / (h * h))
          << "cell " << k;
    }
  }
  // Rest to rest: zero speed at both ends (at the end, the rounding of v0 + a tau times |f'| = 10
  // m); the end state is the segment's end point.
  EXPECT_EQ(trajectory.Evaluate(0.0).velocity.norm(), 0.0);
  EXPECT_LT((trajectory.Evaluate(trajectory.duration()).position - to).norm(), 8 * kEps * to.norm());
  EXPECT_LT(trajectory.Evaluate(trajectory.duration()).velocity.norm(), 1e-15);
}

// The solved 10 m line (vmax 2, amax 1) is the bang-coast-bang closed form: x = t^2 / 2 until
// t = 2, then 2 m/s until t = 5, then braking to rest at t = 7. The switch points fall on the
// K = 20 grid, so the discrete optimum is the continuous one; the solver meets its rows to ~1e-9
// relative (T to 1e-7, see tests/temporal), so positions and velocities agree to 1e-6. The
// acceleration is constant per cell (1e-6 too), so the samples keep 1e-3 s away from the switches.
TEST(Trajectory, SolvedStraightLineMatchesBangCoastBang) {
  const TemporalProblem problem = LineProblem(10.0, 20);
  const TemporalResult result = MakeSocpTemporalSolver()->Solve(problem);
  ASSERT_TRUE(result.is_success()) << result.message;
  const Trajectory trajectory(problem.curve, result.profile);
  EXPECT_NEAR(trajectory.duration(), 7.0, 7e-7);
  for (double t = 0.0; t <= 7.0; t += 0.0123) {
    if (std::abs(t - 2.0) < 1e-3 || std::abs(t - 5.0) < 1e-3 || t > 7.0 - 1e-3) continue;
    double x = 0.0, v = 0.0, a = 0.0;
    if (t < 2.0) {
      x = 0.5 * t * t, v = t, a = 1.0;
    } else if (t < 5.0) {
      x = 2.0 + 2.0 * (t - 2.0), v = 2.0, a = 0.0;
    } else {
      x = 10.0 - 0.5 * (7.0 - t) * (7.0 - t), v = 7.0 - t, a = -1.0;
    }
    const TrajectoryState state = trajectory.Evaluate(t);
    EXPECT_LT((state.position - Eigen::Vector3d(x, 0, 0)).norm(), 1e-6) << "t = " << t;
    EXPECT_LT((state.velocity - Eigen::Vector3d(v, 0, 0)).norm(), 1e-6) << "t = " << t;
    EXPECT_LT((state.acceleration - Eigen::Vector3d(a, 0, 0)).norm(), 1e-6) << "t = " << t;
    EXPECT_EQ(state.jerk, Eigen::Vector3d::Zero()) << "t = " << t;
  }
}

// Time derivatives of p(t) = f(s(t)) inside a cell, where s''' = 0 (Faa di Bruno), only to size the
// finite differences' truncation error:
//   p'''  = f''' s'^3 + 3 f'' s' s''
//   p'''' = f'''' s'^4 + 6 f''' s'^2 s'' + 3 f'' s''^2
//   p^(5) = f^(5) s'^5 + 10 f'''' s'^3 s'' + 15 f''' s' s''^2
Eigen::Vector3d HigherDerivative(const Trajectory& trajectory, double t, int order) {
  const TemporalProfile::Point p = trajectory.profile().AtTime(t);
  const auto f = [&](int d) { return trajectory.curve().Evaluate(p.piece, p.s, d); };
  const double s1 = p.sdot, s2 = p.sddot;
  switch (order) {
    case 3:
      return f(3) * std::pow(s1, 3) + 3.0 * f(2) * s1 * s2;
    case 4:
      return f(4) * std::pow(s1, 4) + 6.0 * f(3) * s1 * s1 * s2 + 3.0 * f(2) * s2 * s2;
    case 5:
      return f(5) * std::pow(s1, 5) + 10.0 * f(4) * std::pow(s1, 3) * s2 + 15.0 * f(3) * s1 * s2 * s2;
  }
  throw std::invalid_argument("HigherDerivative: order 3, 4 or 5");
}

// The worst ratio of |error| / tolerance over the checks of one quantity, with where it was.
struct Worst {
  double ratio = 0.0;
  std::string where;
  void Update(double error, double tolerance, const std::string& at) {
    if (error / tolerance > ratio) ratio = error / tolerance, where = at;
  }
};

// Checks g'(t) against the central difference (g(t + h) - g(t - h)) / (2 h) for g = position,
// velocity, acceleration (g' = velocity, acceleration, jerk) at three points inside every cell.
//   Truncation: h^2 / 6 max |g'''| over [t - h, t + h]; g''' (p''', p'''' or p^(5)) is a polynomial
//   in t on the cell that changes by well under 1% over 2h, so 1.5 times its largest value at
//   t - h, t, t + h bounds it (computed by HigherDerivative). The error found is this leading term
//   itself (worst ratio to the tolerance 0.67 = 1 / 1.5).
//   Rounding: each value of g carries ~eps times the magnitudes in its evaluation (Horner over
//   coefficients up to ~10 times the values, tau = t - t_k), and t +- h are rounded to eps t, which
//   moves g by |g'| eps t: 100 eps (max |g| + |g'| t) / h.
// h = 1e-4 s: truncation ~2e-9 |g'''| (up to 1.5e-4 m/s^3 on the jerk of the quintics, 1e-6 of
// it), rounding ~1e-8 for |p| ~ 20 m at t ~ 20 s. The cells here are hundreds of h long; the check
// asserts that t +- h stays inside the cell.
void CheckFiniteDifferences(const Trajectory& trajectory, const std::string& name) {
  constexpr double kH = 1e-4;  // s
  const TemporalProfile& profile = trajectory.profile();
  const int m = profile.num_pieces(), K = profile.cells_per_piece();
  // Largest magnitudes of position, velocity, acceleration over the checked points.
  Eigen::Vector3d largest = Eigen::Vector3d::Zero();
  for (double t = 0.0; t <= trajectory.duration(); t += 0.01) {
    const TrajectoryState x = trajectory.Evaluate(t);
    const Eigen::Vector3d sizes(x.position.norm(), x.velocity.norm(), x.acceleration.norm());
    largest = largest.cwiseMax(sizes);
  }
  Worst worst[3];
  int checked = 0;
  double largest_jerk = 0.0;
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k < K; ++k) {
      const double t0 = profile.TimeAt(i, k), t1 = profile.TimeAt(i, k + 1);
      ASSERT_GT(0.25 * (t1 - t0), 2.0 * kH) << name << " piece " << i << " cell " << k;
      for (double fraction : {0.25, 0.5, 0.75}) {
        const double t = t0 + fraction * (t1 - t0);
        const TrajectoryState x = trajectory.Evaluate(t);
        const TrajectoryState before = trajectory.Evaluate(t - kH), after = trajectory.Evaluate(t + kH);
        const Eigen::Vector3d fd[3] = {(after.position - before.position) / (2.0 * kH),
                                       (after.velocity - before.velocity) / (2.0 * kH),
                                       (after.acceleration - before.acceleration) / (2.0 * kH)};
        const Eigen::Vector3d analytic[3] = {x.velocity, x.acceleration, x.jerk};
        const std::string at =
            name + " piece " + std::to_string(i) + " cell " + std::to_string(k) + " t = " + std::to_string(t);
        for (int q = 0; q < 3; ++q) {
          double third = 0.0;  // |g'''| = |p^(q+3)|
          for (double u : {t - kH, t, t + kH}) {
            third = std::max(third, HigherDerivative(trajectory, u, q + 3).norm());
          }
          const double truncation = kH * kH / 6.0 * 1.5 * third;
          const double rounding = 100.0 * kEps * (largest[q] + analytic[q].norm() * t) / kH;
          worst[q].Update((fd[q] - analytic[q]).norm(), truncation + rounding, at);
        }
        largest_jerk = std::max(largest_jerk, x.jerk.norm());
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 3 * m * K) << name;
  const char* checks[3] = {"velocity vs FD of position", "acceleration vs FD of velocity",
                           "jerk vs FD of acceleration"};
  for (int q = 0; q < 3; ++q) {
    EXPECT_LE(worst[q].ratio, 1.0) << name << ": " << checks[q] << ", worst at " << worst[q].where;
  }
  // Curved pieces: the jerk is far from zero, so the check above is not of zeros.
  EXPECT_GT(largest_jerk, 0.1) << name;
}

// Random walks through 5 waypoints, natural cubic and rest-to-rest minimum-jerk (quintic) fits,
// timed by the SOCP backend (paper and certified rows) and by a random hand-made b.
TEST(Trajectory, DerivativesMatchFiniteDifferencesOnCurvedPieces) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> speed_squared(0.05, 1.0);
  const auto socp = MakeSocpTemporalSolver();
  for (int trial = 0; trial < 3; ++trial) {
    const Waypoints w = RandomWalk(rng, 5);
    const PiecewiseCurve cubic = NaturalCubicSpline(w), quintic = MinimumJerkSpline(w);
    for (const bool is_quintic : {false, true}) {
      const PiecewiseCurve& curve = is_quintic ? quintic : cubic;
      const std::string name = std::string(is_quintic ? "quintic" : "cubic") + " trial " + std::to_string(trial);
      for (ConstraintMode mode : {ConstraintMode::kPaper, ConstraintMode::kCertified}) {
        TemporalProblem problem = WalkProblem(curve, 20);
        problem.constraint_mode = mode;
        const TemporalResult result = socp->Solve(problem);
        ASSERT_TRUE(result.is_success()) << name << ": " << result.message;
        CheckFiniteDifferences(Trajectory(curve, result.profile), name + " " + ToString(mode));
      }
      // A profile made by hand: b in [0.05, 1] at every grid point, shared at the joints.
      const int K = 12;
      std::vector<std::vector<double>> b(curve.num_pieces(), std::vector<double>(K + 1));
      for (int i = 0; i < curve.num_pieces(); ++i) {
        b[i][0] = i > 0 ? b[i - 1][K] : speed_squared(rng);
        for (int k = 1; k <= K; ++k) b[i][k] = speed_squared(rng);
      }
      CheckFiniteDifferences(Trajectory(curve, TemporalProfile(b)), name + " hand-made b");
    }
  }
}

TEST(Trajectory, SamplesClampingAndInvalidInput) {
  const Trajectory trajectory(Segment(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0)),
                              TemporalProfile({{0.25, 1.0, 0.25}}));
  const double T = trajectory.duration();  // two cells of 0.5 at mean speed 0.75: 4/3 s
  EXPECT_NEAR(T, 4.0 / 3.0, 1e-15);
  const std::vector<TrajectoryState> samples = trajectory.Sample(10.0);
  ASSERT_EQ(samples.size(), 15u);  // t = 0, 0.1, ..., 1.3 and T
  for (size_t n = 0; n + 1 < samples.size(); ++n) EXPECT_DOUBLE_EQ(samples[n].t, n / 10.0);
  EXPECT_EQ(samples.back().t, T);
  EXPECT_EQ(samples.back().position, trajectory.Evaluate(T).position);
  EXPECT_EQ(trajectory.Evaluate(-1.0).position, trajectory.Evaluate(0.0).position);
  EXPECT_EQ(trajectory.Evaluate(-1.0).t, 0.0);
  EXPECT_EQ(trajectory.Evaluate(T + 1.0).position, trajectory.Evaluate(T).position);
  EXPECT_EQ(trajectory.Evaluate(T + 1.0).t, T);
  EXPECT_THROW(trajectory.Sample(0.0), std::invalid_argument);
  EXPECT_THROW(trajectory.Sample(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_THROW(
      Trajectory(Segment(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0)), TemporalProfile({{1.0, 1.0}, {1.0, 1.0}})),
      std::invalid_argument);
}

}  // namespace
}  // namespace timeopt
