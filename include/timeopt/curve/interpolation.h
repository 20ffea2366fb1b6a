#pragma once

// Curves through waypoints with unit piece durations in s: piece i joins waypoint i to
// waypoint i + 1 on s in [0, 1].

#include <optional>

#include <Eigen/Core>

#include "timeopt/curve/piecewise_curve.h"

namespace timeopt {

// Waypoints as columns, at least two, all finite.
using Waypoints = Eigen::Matrix<double, 3, Eigen::Dynamic>;

// Consecutive waypoints closer than this fraction of the waypoints' extent (the diagonal of their
// bounding box) coincide: 1e-6, a tenth of a millimetre on a 100 m path, far below any spacing that
// means something to a vehicle and far above the rounding of a CSV file's coordinates.
inline constexpr double kCoincidentWaypointFraction = 1e-6;

// The waypoints without those that coincide with the one kept before them (see
// kCoincidentWaypointFraction; `fraction` of the extent), keeping the first and the last (a last
// waypoint replaces a kept one it coincides with). A spline through a coincident pair has a piece
// of (almost) no length between them: its tangent nearly vanishes, so the vehicle stops there, and
// the spline loops back on itself around it (a 2 m line through (0, 1, 1 + 1e-9, 2) m was 2.35 m
// long). `merged`, if given, gets the number dropped. Throws std::invalid_argument when fewer than
// two distinct waypoints remain, or for non-finite values.
Waypoints MergeCoincidentWaypoints(const Waypoints& waypoints, double fraction = kCoincidentWaypointFraction,
                                   int* merged = nullptr);

// The C2 natural cubic spline (zero second derivative at both ends) through the waypoints.
// Throws std::invalid_argument for fewer than two waypoints or non-finite values.
PiecewiseCurve NaturalCubicSpline(const Waypoints& waypoints);

// End conditions for the minimum-jerk fit: a given value, or free (std::nullopt), in which case
// the natural boundary condition of the variational problem holds instead.
struct EndDerivatives {
  std::optional<Eigen::Vector3d> start_velocity;      // f'(0) of the first piece
  std::optional<Eigen::Vector3d> start_acceleration;  // f''(0) of the first piece
  std::optional<Eigen::Vector3d> end_velocity;        // f'(1) of the last piece
  std::optional<Eigen::Vector3d> end_acceleration;    // f''(1) of the last piece

  // Zero velocity and acceleration at both ends (rest to rest).
  static EndDerivatives RestToRest();
};

// The piecewise quintic through the waypoints that minimizes the jerk integral in s,
// sum_i integral_0^1 |f_i'''(s)|^2 ds, among all C2 curves with the given end derivatives. The
// optimum is C4 at the interior waypoints; it is found by one banded linear solve (bandwidth
// independent of the number of pieces, so linear time).
PiecewiseCurve MinimumJerkSpline(const Waypoints& waypoints, const EndDerivatives& ends = EndDerivatives::RestToRest());

}  // namespace timeopt
