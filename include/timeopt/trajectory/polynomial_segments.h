#pragma once

// A trajectory as polynomial segments in time, the form of polynomial planners and of
// mav_trajectory_generation: segment i runs for duration_i seconds, and its position on each axis
// is sum_j c_j tau^j in its own local time tau in [0, duration_i].
//
// Segments follow the profile's cells, split or joined in time where the tolerances allow:
// - a cell whose b is linear in s (profiles without a jerk limit) moves as s(tau) = s_k + v tau +
//   a tau^2 / 2, so f(s(tau)) is a polynomial of degree 2 n (n the curve's degree): the segment is
//   that polynomial, composed exactly (only rounding separates it from the trajectory);
// - the cells of a jerk-limited profile are not polynomial in time: the segment is the degree-7
//   polynomial that meets the trajectory's position, velocity, acceleration and jerk at both of its
//   ends (the cell's own one-sided values at a cell's edges, where the jerk steps). Consecutive
//   segments therefore join with continuous position, velocity and acceleration. One segment spans
//   1, 2, 4, ... consecutive cells, as many as meet the tolerances; a single cell that does not is
//   halved in time, and so on.
//
// Error bound. Each segment is compared with the trajectory at evenly spaced times, at least
// `check_rate_hz` and 8 per segment. Between two of them, h apart, an error e with known values
// at both ends obeys |e| <= max(|e_0|, |e_1|) + h^2 / 8 sup|e''|. For the position error e'' is
// the difference of the accelerations, bounded by the segment's (from its Bernstein coefficients)
// plus the trajectory's over the cell (interval bounds of f', f'', f''' over the cell and of sdot,
// sddot, sdddot from the cell's formulas); for the velocity error, the jerks likewise. The check
// spacing is made fine enough that the h^2 term is at most 5% of the tolerance. The acceleration
// error is bounded to first order, max(|e_0|, |e_1|) + h / 2 sup|e'| with e' the difference of the
// jerks (the trajectory's jerk steps between cells), and its spacing likewise. The bounds per
// axis are combined as a Euclidean norm: max_position_error and max_velocity_error bound the
// distance between the segments and the trajectory at every time, not only at the checked ones.

#include <array>
#include <vector>

#include <Eigen/Core>

#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

struct PolynomialFitOptions {
  double max_position_error = 1e-3;  // m, > 0
  double max_velocity_error = 1e-2;  // m/s, > 0
  // m/s^2, > 0: segments that span several cells smooth the jerk's steps, and their acceleration
  // may then leave the trajectory's (and its limits) by as much as this.
  double max_acceleration_error = 2e-2;
  double check_rate_hz = 1000.0;  // Hz, > 0: the least density of the comparison
  // At most this many segments; more is std::invalid_argument (tolerances too tight for the
  // trajectory's length).
  int max_segments = 1000000;
  // At most this many evaluations of the trajectory in all (about 1 us each); more is
  // std::invalid_argument (tolerances so tight that the comparisons would take minutes).
  double max_comparisons = 2e7;

  // Throws std::invalid_argument naming the field.
  void Validate() const;
};

struct PolynomialSegment {
  double start = 0.0;     // s, from the trajectory's start
  double duration = 0.0;  // s, > 0
  // Row a: axis a's coefficients in ascending powers of local time (m, m/s, m/s^2, ...).
  Eigen::Matrix<double, 3, Eigen::Dynamic> coefficients;
  bool exact = false;  // composed exactly (a linear cell), not fitted
};

struct PolynomialSegments {
  std::vector<PolynomialSegment> segments;
  int degree = 0;                       // the largest segment degree
  double max_position_error = 0.0;      // m, bound over all times (see the header comment)
  double max_velocity_error = 0.0;      // m/s, likewise
  double max_acceleration_error = 0.0;  // m/s^2, likewise (first-order slack between compared times)
  double largest_checked_gap = 0.0;     // s, the widest spacing of compared times
};

// Throws std::invalid_argument for bad options, or when a segment cannot meet the tolerances
// (more than max_segments segments, or a segment shorter than 1e-9 of the trajectory).
PolynomialSegments FitPolynomialSegments(const Trajectory& trajectory, const PolynomialFitOptions& options = {});

// Position (derivative 0), velocity (1), acceleration (2) or jerk (3) of a segment at local time tau.
Eigen::Vector3d EvaluateSegment(const PolynomialSegment& segment, double tau, int derivative = 0);

}  // namespace timeopt
