#include "timeopt/temporal/temporal_problem.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "timeopt/core/enum_strings.h"

namespace timeopt {
namespace {

std::string Num(double v) {
  std::ostringstream ss;
  ss << v;
  return ss.str();
}

void CheckPositive(double v, const std::string& field) {
  if (!std::isfinite(v) || !(v > 0.0)) {
    throw std::invalid_argument(field + ": expected a positive finite number, got " + Num(v));
  }
}

// Positive, or +infinity for "no limit on this axis".
void CheckPositiveOrNone(double v, const std::string& field) {
  if (std::isnan(v) || !(v > 0.0)) {
    throw std::invalid_argument(field + ": expected a positive number (or none), got " + Num(v));
  }
}

constexpr double kHalfPi = 1.57079632679489661923;

void CheckFinite(const Eigen::Vector3d& v, const std::string& field) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(v(a))) {
      throw std::invalid_argument(field + "[" + std::to_string(a) + "]: expected a finite number");
    }
  }
}

}  // namespace

const char* ToString(ConstraintMode mode) {
  switch (mode) {
    case ConstraintMode::kPaper:
      return "paper";
    case ConstraintMode::kCertified:
      return "certified";
  }
  return "unknown";
}

bool FromString(const std::string& text, ConstraintMode* mode) { return EnumFromString(text, kConstraintModes, mode); }

void TemporalProblem::Validate() const {
  if (curve.empty()) throw std::invalid_argument("curve: expected at least 1 piece, got 0");
  for (int i = 0; i < curve.num_pieces(); ++i) {
    const auto& c = curve.piece(i).coefficients();
    if (c.cols() < 2 || c.rightCols(c.cols() - 1).cwiseAbs().maxCoeff() == 0.0) {
      throw std::invalid_argument("curve.pieces[" + std::to_string(i) +
                                  "]: the piece has zero length (constant polynomial)");
    }
    // The rows multiply squared tangents by b and by the degree's factors; above 1e100 m their
    // products could overflow a double, and both backends would fail in different ways. Such a
    // curve is refused alike by both, naming the piece (1e100 m is beyond any unit of length).
    constexpr double kMaxCoefficient = 1e100;
    const double largest = c.cwiseAbs().maxCoeff();
    if (!(largest <= kMaxCoefficient)) {
      throw std::invalid_argument("curve.pieces[" + std::to_string(i) + "]: a coefficient's magnitude is " +
                                  Num(largest) + " m, above the supported 1e100 m");
    }
  }
  // The pieces must meet (C0): a gap between them would be flown as a jump. The tolerance is
  // relative to the curve's size (the largest distance of a joint from the start, and 1 m): fitted
  // curves meet to rounding, ~1e-12 relative.
  double size = 0.0;
  const Eigen::Vector3d origin = curve.Evaluate(0, 0.0);
  for (int i = 0; i < curve.num_pieces(); ++i) size = std::max(size, (curve.Evaluate(i, 1.0) - origin).norm());
  constexpr double kJointGapTolerance = 1e-9;
  for (int i = 0; i + 1 < curve.num_pieces(); ++i) {
    const double gap = (curve.Evaluate(i + 1, 0.0) - curve.Evaluate(i, 1.0)).norm();
    if (!(gap <= kJointGapTolerance * std::max(1.0, size))) {
      throw std::invalid_argument("curve.pieces[" + std::to_string(i + 1) + "]: starts " + Num(gap) +
                                  " m from where curve.pieces[" + std::to_string(i) + "] ends (the pieces must meet)");
    }
  }
  for (int a = 0; a < 3; ++a) {
    CheckPositiveOrNone(limits.max_velocity(a), "limits.max_velocity[" + std::to_string(a) + "]");
    CheckPositiveOrNone(limits.max_acceleration(a), "limits.max_acceleration[" + std::to_string(a) + "]");
  }
  if (limits.max_speed) CheckPositive(*limits.max_speed, "limits.max_speed");
  if (limits.max_acceleration_norm) CheckPositive(*limits.max_acceleration_norm, "limits.max_acceleration_norm");
  if (limits.max_thrust) CheckPositive(*limits.max_thrust, "limits.max_thrust");
  CheckPositive(limits.gravity, "limits.gravity");
  if (limits.min_thrust && !(std::isfinite(*limits.min_thrust) && *limits.min_thrust >= 0.0)) {
    throw std::invalid_argument("limits.min_thrust: expected a finite number >= 0, got " + Num(*limits.min_thrust));
  }
  if (limits.max_tilt && !(*limits.max_tilt > 0.0 && *limits.max_tilt < kHalfPi)) {
    throw std::invalid_argument("limits.max_tilt: expected an angle in (0, pi/2) radians, got " +
                                Num(*limits.max_tilt));
  }
  if (limits.min_thrust && limits.max_thrust && *limits.min_thrust > *limits.max_thrust) {
    throw std::invalid_argument("limits.min_thrust: " + Num(*limits.min_thrust) + " is above limits.max_thrust " +
                                Num(*limits.max_thrust));
  }
  if (limits.max_thrust && *limits.max_thrust < limits.gravity) {
    throw std::invalid_argument("limits.max_thrust: " + Num(*limits.max_thrust) +
                                " m/s^2 cannot hold the vehicle against gravity (" + Num(limits.gravity) + ")");
  }
  // Something must bound the speed and the acceleration on every axis, or the time has no minimum.
  if (!limits.max_speed && !limits.max_velocity.allFinite()) {
    throw std::invalid_argument(
        "limits: the speed is unbounded: give limits.max_velocity on every axis or "
        "limits.max_speed");
  }
  // (max_tilt alone bounds the horizontal acceleration only: a climbing curve then needs max_thrust
  // as well, or the time has no minimum and the solver reports it.)
  if (!limits.max_acceleration_norm && !limits.max_thrust && !limits.max_tilt && !limits.max_acceleration.allFinite()) {
    throw std::invalid_argument(
        "limits: the acceleration is unbounded: give limits.max_acceleration on every "
        "axis, limits.max_acceleration_norm, limits.max_thrust or limits.max_tilt");
  }
  if (limits.max_acceleration_change) {
    CheckPositive(*limits.max_acceleration_change, "limits.max_acceleration_change");
  }
  CheckFinite(boundary.start_velocity, "boundary.start_velocity");
  CheckFinite(boundary.start_acceleration, "boundary.start_acceleration");
  CheckFinite(boundary.end_velocity, "boundary.end_velocity");
  CheckFinite(boundary.end_acceleration, "boundary.end_acceleration");
  if (cells_per_piece < 1) {
    throw std::invalid_argument("discretization.K: expected at least 1 cell per piece, got " +
                                std::to_string(cells_per_piece));
  }
  if (limits.max_jerk && cells_per_piece < kMinJerkLimitedCellsPerPiece) {
    // A piece that starts or ends at rest has a rest cell at that end; with fewer than three cells
    // no regular cell is left between them, and the answer is infeasible or far off (K = 2 gave
    // T = 1e6 s on a 5 m line whose optimum is 3.7 s).
    throw std::invalid_argument("discretization.K: a jerk-limited problem needs at least " +
                                std::to_string(kMinJerkLimitedCellsPerPiece) + " cells per piece, got " +
                                std::to_string(cells_per_piece));
  }
  if (static_cast<long long>(curve.num_pieces()) * cells_per_piece * (limits.max_jerk ? 2 : 1) > kMaxCells) {
    throw std::invalid_argument("discretization.K: " + std::to_string(curve.num_pieces()) + " pieces x " +
                                std::to_string(cells_per_piece) + " cells is above the " + std::to_string(kMaxCells) +
                                " cells this library takes (several KB of memory each)");
  }
  if (cells_per_piece > kMaxCellsPerPiece) {
    throw std::invalid_argument("discretization.K: at most " + std::to_string(kMaxCellsPerPiece) +
                                " cells per piece, got " + std::to_string(cells_per_piece));
  }
  if (limits.max_jerk) {
    for (int a = 0; a < 3; ++a) {
      CheckPositive((*limits.max_jerk)(a), "limits.max_jerk[" + std::to_string(a) + "]");
    }
    if (rho != 0.0) {
      throw std::invalid_argument(
          "rho: the acceleration regularization is not supported together "
          "with limits.max_jerk (a jerk limit already smooths sddot); use 0");
    }
    if (limits.max_acceleration_change) {
      throw std::invalid_argument(
          "limits.max_acceleration_change: not used together with "
          "limits.max_jerk (the jerk limit bounds the acceleration's change)");
    }
  }
  if (!(scp_tolerance > 0.0 && scp_tolerance <= 0.1)) {
    throw std::invalid_argument("scp_tolerance: expected a number in (0, 0.1], got " + Num(scp_tolerance));
  }
  if (max_scp_iterations < 1 || max_scp_iterations > 100) {
    throw std::invalid_argument("max_scp_iterations: expected an integer in [1, 100], got " +
                                std::to_string(max_scp_iterations));
  }
  if (!std::isfinite(rho) || rho < 0.0) {
    throw std::invalid_argument("rho: expected a finite number >= 0, got " + Num(rho));
  }
  if (!(certified_thinning >= 0.0 && certified_thinning <= 0.01)) {
    throw std::invalid_argument("certified_thinning: expected a number in [0, 0.01], got " + Num(certified_thinning));
  }
  CheckPositive(parallel_tolerance, "parallel_tolerance");
  CheckPositive(zero_tangent_tolerance, "zero_tangent_tolerance");
}

}  // namespace timeopt
