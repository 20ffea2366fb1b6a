#pragma once

// Curves and temporal problems shared by the tests of several modules (curve, temporal,
// trajectory): one definition each, so that every test means the same line or walk.

#include <cmath>
#include <ostream>
#include <random>

#include <Eigen/Core>

#include "timeopt/curve/interpolation.h"
#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/curve/polynomial_piece.h"
#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {

// Readable parameter names in test output (found by GoogleTest through argument-dependent lookup,
// so it lives in the enum's namespace).
inline void PrintTo(TemporalBackend backend, std::ostream* os) { *os << ToString(backend); }

namespace test_support {

// The straight piece from `from` to `to`: f(s) = from + s (to - from), s in [0, 1].
inline PolynomialPiece LinearPiece(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  PolynomialPiece::Coefficients c(3, 2);
  c.col(0) = from;
  c.col(1) = to - from;
  return PolynomialPiece(c);
}

// A straight segment from `from` to `to` as one linear piece.
inline PiecewiseCurve Segment(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  return PiecewiseCurve({LinearPiece(from, to)});
}

// Rest-to-rest minimum time along a line with speed limit v and acceleration limit a: accelerate,
// cruise, brake when the line is long enough to reach v (length >= v^2 / a), else accelerate to
// the middle and brake.
inline double RestToRestTime(double length, double v, double a) {
  return length >= v * v / a ? length / v + v / a : 2.0 * std::sqrt(length / a);
}

// A straight line of the given length along x, one linear piece, rest to rest, vmax = 2 m/s and
// amax = 1 m/s^2 per axis: at length 10 the closed form is T = 7 s (the contract's example).
inline TemporalProblem LineProblem(double length, int K) {
  TemporalProblem p;
  p.curve = Segment(Eigen::Vector3d::Zero(), Eigen::Vector3d(length, 0, 0));
  p.limits.max_velocity = Eigen::Vector3d::Constant(2.0);
  p.limits.max_acceleration = Eigen::Vector3d::Constant(1.0);
  p.cells_per_piece = K;
  return p;
}

// A random walk of `count` waypoints from `start`: horizontal steps uniform in [-4, 4] m per axis,
// vertical steps in [-1.2, 1.2] m (a flight more level than steep).
inline Waypoints RandomWalk(std::mt19937& rng, int count, const Eigen::Vector3d& start) {
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  Waypoints w(3, count);
  w.col(0) = start;
  for (int i = 1; i < count; ++i) {
    w.col(i) = w.col(i - 1) + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
  }
  return w;
}

// The same walk from a start drawn uniformly in [-4, 4]^3 m.
inline Waypoints RandomWalk(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  const Eigen::Vector3d start(u(rng), u(rng), u(rng));
  return RandomWalk(rng, count, start);
}

// A rest-to-rest problem on `curve` with limits sized for the random walks above (pieces of a few
// metres): vmax = (3, 3, 2) m/s, amax = (2, 2, 1.5) m/s^2, K cells per piece, paper rows.
inline TemporalProblem WalkProblem(const PiecewiseCurve& curve, int K) {
  TemporalProblem p;
  p.curve = curve;
  p.limits.max_velocity = Eigen::Vector3d(3.0, 3.0, 2.0);
  p.limits.max_acceleration = Eigen::Vector3d(2.0, 2.0, 1.5);
  p.cells_per_piece = K;
  return p;
}

// Rest-to-rest time along a line of length L with speed, acceleration and jerk limits v, a, j
// (the S-curve): each half accelerates to a peak speed vp and the rest cruises. Accelerating to
// vp takes vp / a + a / j and covers vp (vp / a + a / j) / 2 when vp >= a^2 / j (a is reached),
// else 2 sqrt(vp / j) covering vp sqrt(vp / j).
inline double SCurveTime(double L, double v, double a, double j) {
  const auto accel_time = [&](double vp) { return vp >= a * a / j ? vp / a + a / j : 2.0 * std::sqrt(vp / j); };
  const auto accel_distance = [&](double vp) { return 0.5 * vp * accel_time(vp); };
  if (2.0 * accel_distance(v) <= L) return (L - 2.0 * accel_distance(v)) / v + 2.0 * accel_time(v);
  // v is not reached: the peak speed where the two halves meet (accel_distance is increasing).
  double lo = 0.0, hi = v;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (2.0 * accel_distance(mid) < L ? lo : hi) = mid;
  }
  return 2.0 * accel_time(0.5 * (lo + hi));
}

}  // namespace test_support
}  // namespace timeopt
