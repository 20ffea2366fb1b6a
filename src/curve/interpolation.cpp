#include "timeopt/curve/interpolation.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "banded_solver.h"

namespace timeopt {
namespace {

void CheckWaypoints(const Waypoints& waypoints, const char* who) {
  if (waypoints.cols() < 2) {
    throw std::invalid_argument(std::string(who) + ": expected at least 2 waypoints, got " +
                                std::to_string(waypoints.cols()));
  }
  for (int i = 0; i < waypoints.cols(); ++i) {
    if (!waypoints.col(i).allFinite()) {
      throw std::invalid_argument(std::string(who) + ": waypoint " + std::to_string(i) + " is not finite");
    }
  }
}

void CheckOptional(const std::optional<Eigen::Vector3d>& v, const char* name) {
  if (v && !v->allFinite()) {
    throw std::invalid_argument(std::string("MinimumJerkSpline: ") + name + " is not finite");
  }
}

// Quintic Hermite basis on [0, 1]: coefficients (ascending) = H * [p0 v0 a0 p1 v1 a1]'.
Eigen::Matrix<double, 6, 6> QuinticHermite() {
  Eigen::Matrix<double, 6, 6> h;
  h << 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0.5, 0, 0, 0, -10, -6, -1.5, 10, -4, 0.5, 15, 8, 1.5, -15, 7, -1, -6,
      -3, -0.5, 6, -3, 0.5;
  return h;
}

// Row vector r with r * coefficients = derivative `order` of a quintic at s.
Eigen::Matrix<double, 1, 6> DerivativeRow(int order, double s) {
  Eigen::Matrix<double, 1, 6> row = Eigen::Matrix<double, 1, 6>::Zero();
  for (int j = order; j < 6; ++j) {
    double factor = 1.0;
    for (int i = 0; i < order; ++i) factor *= j - i;
    row(j) = factor * std::pow(s, j - order);
  }
  return row;
}

}  // namespace

EndDerivatives EndDerivatives::RestToRest() {
  EndDerivatives ends;
  ends.start_velocity = ends.start_acceleration = Eigen::Vector3d::Zero();
  ends.end_velocity = ends.end_acceleration = Eigen::Vector3d::Zero();
  return ends;
}

Waypoints MergeCoincidentWaypoints(const Waypoints& waypoints, double fraction, int* merged) {
  CheckWaypoints(waypoints, "MergeCoincidentWaypoints");
  if (!(fraction >= 0.0 && fraction < 1.0)) {
    throw std::invalid_argument("MergeCoincidentWaypoints: fraction must be in [0, 1), got " +
                                std::to_string(fraction));
  }
  // (An extent beyond the doubles, waypoints near +-1e308, is taken as the largest double.)
  double extent = (waypoints.rowwise().maxCoeff() - waypoints.rowwise().minCoeff()).stableNorm();
  if (!std::isfinite(extent)) extent = std::numeric_limits<double>::max();
  const double tolerance = fraction * extent;
  std::vector<Eigen::Index> kept = {0};
  const Eigen::Index n = waypoints.cols();
  for (Eigen::Index i = 1; i < n; ++i) {
    const bool coincides = (waypoints.col(i) - waypoints.col(kept.back())).norm() <= tolerance;
    if (!coincides) {
      kept.push_back(i);
    } else if (i == n - 1 && kept.size() > 1) {
      kept.back() = i;  // the last waypoint is the goal: it replaces the one it coincides with
    }
  }
  if (kept.size() < 2) {
    throw std::invalid_argument("MergeCoincidentWaypoints: all " + std::to_string(n) + " waypoints coincide (within " +
                                std::to_string(tolerance) + " m): there is no path through them");
  }
  if (merged != nullptr) *merged = static_cast<int>(n - static_cast<Eigen::Index>(kept.size()));
  Waypoints out(3, static_cast<Eigen::Index>(kept.size()));
  for (size_t k = 0; k < kept.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = waypoints.col(kept[k]);
  return out;
}

PiecewiseCurve NaturalCubicSpline(const Waypoints& p) {
  CheckWaypoints(p, "NaturalCubicSpline");
  const int m = static_cast<int>(p.cols()) - 1;  // pieces
  // Second derivatives M_i at the knots: M_0 = M_m = 0 and
  // M_{i-1} + 4 M_i + M_{i+1} = 6 (p_{i+1} - 2 p_i + p_{i-1}) inside (unit knot spacing).
  internal::BandedSystem system(m + 1, 1, 1);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m + 1, 3);
  system.Add(0, 0, 1.0);
  system.Add(m, m, 1.0);
  for (int i = 1; i < m; ++i) {
    system.Add(i, i - 1, 1.0);
    system.Add(i, i, 4.0);
    system.Add(i, i + 1, 1.0);
    rhs.row(i) = 6.0 * (p.col(i + 1) - 2.0 * p.col(i) + p.col(i - 1)).transpose();
  }
  const Eigen::MatrixXd M = system.Solve(rhs);
  std::vector<PolynomialPiece> pieces;
  pieces.reserve(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector3d mi = M.row(i).transpose(), mj = M.row(i + 1).transpose();
    PolynomialPiece::Coefficients c(3, 4);
    c.col(0) = p.col(i);
    c.col(1) = p.col(i + 1) - p.col(i) - (2.0 * mi + mj) / 6.0;
    c.col(2) = mi / 2.0;
    c.col(3) = (mj - mi) / 6.0;
    pieces.emplace_back(std::move(c));
  }
  return PiecewiseCurve(std::move(pieces));
}

PiecewiseCurve MinimumJerkSpline(const Waypoints& p, const EndDerivatives& ends) {
  CheckWaypoints(p, "MinimumJerkSpline");
  CheckOptional(ends.start_velocity, "start_velocity");
  CheckOptional(ends.start_acceleration, "start_acceleration");
  CheckOptional(ends.end_velocity, "end_velocity");
  CheckOptional(ends.end_acceleration, "end_acceleration");
  const int m = static_cast<int>(p.cols()) - 1;
  if (m == 1 && !ends.start_velocity && !ends.start_acceleration && !ends.end_velocity && !ends.end_acceleration) {
    throw std::invalid_argument(
        "MinimumJerkSpline: with 2 waypoints and all end derivatives free the minimum is not "
        "unique (every quadratic through the points has zero jerk); give at least one end "
        "derivative");
  }
  // Unknowns: velocity v_i (index 2i) and acceleration a_i (index 2i+1) at each knot, per axis.
  // Equations 2i, 2i+1 belong to knot i: jerk and snap continuity inside, end conditions at the
  // ends. Each touches knots i-1..i+1 only, so the system is banded (kl = 3, ku = 3 suffice).
  const int n = 2 * (m + 1);
  internal::BandedSystem system(n, 3, 3);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
  const Eigen::Matrix<double, 6, 6> H = QuinticHermite();

  // Adds weight * (row * H) * [p_k v_k a_k p_{k+1} v_{k+1} a_{k+1}] to equation `eq`: the
  // velocity/acceleration parts go to the matrix, the known positions to the right-hand side.
  const auto add_piece_row = [&](int eq, int piece, const Eigen::Matrix<double, 1, 6>& row, double weight) {
    const Eigen::Matrix<double, 1, 6> r = weight * row * H;
    for (int end = 0; end < 2; ++end) {
      const int knot = piece + end;
      rhs.row(eq) -= r(3 * end) * p.col(knot).transpose();
      system.Add(eq, 2 * knot, r(3 * end + 1));
      system.Add(eq, 2 * knot + 1, r(3 * end + 2));
    }
  };
  const auto fix = [&](int eq, int unknown, const Eigen::Vector3d& value) {
    system.Add(eq, unknown, 1.0);
    rhs.row(eq) = value.transpose();
  };

  // Start knot: given derivative, or the natural condition (free velocity: snap = 0; free
  // acceleration: jerk = 0).
  if (ends.start_velocity)
    fix(0, 0, *ends.start_velocity);
  else
    add_piece_row(0, 0, DerivativeRow(4, 0.0), 1.0);
  if (ends.start_acceleration)
    fix(1, 1, *ends.start_acceleration);
  else
    add_piece_row(1, 0, DerivativeRow(3, 0.0), 1.0);
  // Interior knots: jerk and snap continuous (the optimality conditions of the jerk integral).
  for (int i = 1; i < m; ++i) {
    add_piece_row(2 * i, i - 1, DerivativeRow(3, 1.0), 1.0);
    add_piece_row(2 * i, i, DerivativeRow(3, 0.0), -1.0);
    add_piece_row(2 * i + 1, i - 1, DerivativeRow(4, 1.0), 1.0);
    add_piece_row(2 * i + 1, i, DerivativeRow(4, 0.0), -1.0);
  }
  if (ends.end_velocity)
    fix(2 * m, 2 * m, *ends.end_velocity);
  else
    add_piece_row(2 * m, m - 1, DerivativeRow(4, 1.0), 1.0);
  if (ends.end_acceleration)
    fix(2 * m + 1, 2 * m + 1, *ends.end_acceleration);
  else
    add_piece_row(2 * m + 1, m - 1, DerivativeRow(3, 1.0), 1.0);

  const Eigen::MatrixXd va = system.Solve(rhs);
  std::vector<PolynomialPiece> pieces;
  pieces.reserve(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) {
    Eigen::Matrix<double, 6, 3> hermite;
    hermite.row(0) = p.col(i).transpose();
    hermite.row(1) = va.row(2 * i);
    hermite.row(2) = va.row(2 * i + 1);
    hermite.row(3) = p.col(i + 1).transpose();
    hermite.row(4) = va.row(2 * i + 2);
    hermite.row(5) = va.row(2 * i + 3);
    pieces.emplace_back(PolynomialPiece::Coefficients((H * hermite).transpose()));
  }
  return PiecewiseCurve(std::move(pieces));
}

}  // namespace timeopt
