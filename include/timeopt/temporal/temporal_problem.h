#pragma once

// The minimum-time temporal problem of Gao et al. (IROS 2018, Sect. IV): for a fixed spatial curve
// f(s) made of m unit pieces, find the mapping s(t) that traverses it in minimum time subject to
// per-axis velocity and acceleration limits.
//
// With b(s) = sdot^2 and a(s) = sddot, velocity and acceleration along the curve are
//   v(s) = f'(s) sqrt(b(s)),   acc(s) = f'(s) a(s) + f''(s) b(s),   b'(s) = 2 a(s),
// and the traversal time is T = integral ds / sqrt(b(s)). The discretization (K cells per piece,
// b at grid points, a constant per cell) is described in docs/temporal.md.
// SI units: metres, seconds.

#include <array>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "timeopt/core/vehicle_limits.h"
#include "timeopt/curve/piecewise_curve.h"

namespace timeopt {

// The temporal stage's limits are the vehicle's (timeopt/core/vehicle_limits.h).
using TemporalLimits = VehicleLimits;

// Velocity and acceleration at both ends. A velocity must be parallel to the curve's tangent
// there (eqs. 46-47). Accelerations only enter through max_acceleration_change.
struct TemporalBoundary {
  Eigen::Vector3d start_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_acceleration = Eigen::Vector3d::Zero();
  Eigen::Vector3d end_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d end_acceleration = Eigen::Vector3d::Zero();
};

enum class ConstraintMode {
  // Exactly the paper: velocity at grid points (eq. 41), acceleration at cell middles (eq. 40).
  kPaper,
  // Rows that hold on the whole cell: every Bernstein coefficient of f'^2 b and of f' a + f'' b
  // on the cell is within the limits (convex hull property), so the continuous trajectory is.
  kCertified,
};

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<ConstraintMode, 2> kConstraintModes = {
    ConstraintMode::kPaper,
    ConstraintMode::kCertified,
};
const char* ToString(ConstraintMode mode);
// The enumerator named `text` (as ToString writes it) into *mode; false when none is.
bool FromString(const std::string& text, ConstraintMode* mode);

// The defaults of every entry point that times a curve to be flown (the planner, `timeopt
// waypoints`, Python's Limits and TemporalProblem): 2 m/s, 2 m/s^2 and 10 m/s^3 per axis, with
// certified rows, so that the limits hold between grid points and the acceleration is continuous
// (a jerk-input vehicle flies it). The jerk value: a multirotor changes its acceleration by
// tilting its thrust, so |jerk| is about its body rate times |a + g|; a calm 1 rad/s at
// |a + g| ~ 10 m/s^2 gives 10 m/s^3. A default-constructed TemporalProblem and a problem JSON keep
// the paper's defaults (docs/formats.md).
inline VehicleLimits FlightLimits() {
  VehicleLimits limits;
  limits.max_velocity.setConstant(2.0);
  limits.max_acceleration.setConstant(2.0);
  limits.max_jerk = Eigen::Vector3d::Constant(10.0);
  return limits;
}
inline constexpr ConstraintMode kFlightConstraintMode = ConstraintMode::kCertified;

// The fewest cells per piece of a jerk-limited problem (TemporalProblem::Validate): a piece that
// starts or ends at rest spends a cell at each such end on the rest, and needs a regular one between.
inline constexpr int kMinJerkLimitedCellsPerPiece = 3;

// The largest number of cells per piece a problem may ask for: 100000 (ds = 1e-5) is far finer
// than any use needs, and keeps a problem's memory bounded per piece (a few MB).
inline constexpr int kMaxCellsPerPiece = 100000;
// The most cells in all (pieces x cells per piece, twice that with a jerk limit): memory grows with
// the cells (rows, cones, the KKT system; measured 1.5-8.8 KB per cell without a jerk limit, see
// TemporalPeakBytes), so this bounds a problem's size whatever the machine; a memory budget
// (the CLI's --max-memory) refuses less (the benchmarks go to 20,000).
inline constexpr long long kMaxCells = 2000000;

struct TemporalProblem {
  PiecewiseCurve curve;  // unit pieces, s in [0, 1] each
  TemporalLimits limits;
  TemporalBoundary boundary;
  // Cells per piece (K >= 1); ds = 1 / K. The paper suggests 30-50.
  int cells_per_piece = 50;
  // Weight of the acceleration regularization rho * sum a^2 ds (eq. 27), s^2 / m-free (the
  // objective is in seconds plus rho times (1/s^2)^2 units); >= 0.
  double rho = 0.0;
  ConstraintMode constraint_mode = ConstraintMode::kPaper;
  // Tangents at a joint whose angle is below this (radians) are treated as parallel (G1 joint:
  // speed continuous); a larger angle is a kink where the vehicle stops. Also the tolerance on a
  // boundary velocity's angle to the tangent. 1e-6 rad: curves fitted in double precision are
  // parallel to ~1e-12, real corners are far above.
  double parallel_tolerance = 1e-6;
  // A tangent shorter than this (m per unit s) counts as vanishing: the vehicle stops there.
  // 1e-9: far below any tangent of a curve that moves a millimetre per piece.
  double zero_tangent_tolerance = 1e-9;

  // Drop the velocity and acceleration rows of a cell that cannot be active for any b >= 0 (they
  // lie inside the convex hull of the others), and keep one row per grid value of the rows that
  // bound it alone (certified mode: the velocity at a grid point, from both cells around it). The
  // feasible set and the optimum are unchanged; only the solve gets faster. Off: every row of the
  // formulation is passed to the solver.
  bool prune_redundant_rows = true;

  // Certified mode, with prune_redundant_rows: the hull of a cell's rows is thinned. Runs of nearly
  // parallel rows (Bernstein coefficients of a smooth polynomial) are dropped when the two rows around
  // them, tightened by a factor f <= 1 + certified_thinning, imply them; those rows are then tightened
  // by f. The result is never looser than the coefficients (the limits still hold on every cell) and
  // T grows by at most certified_thinning / 2 relative; the solve needs fewer rows and iterations.
  // Measured on 20 random curves at K = 50 (experiments/certified_vs_paper.cpp), solve time relative
  // to paper mode / certified T over paper T (median, max): 0 -> 1.67 x, +0.334% / +0.465%;
  // 3e-4 -> 1.33 x, +0.339% / +0.473%; 6e-4 -> 1.22-1.25 x, +0.348% / +0.485%. 0 keeps the exact
  // hull. In [0, 0.01].
  double certified_thinning = 6e-4;

  // Jerk-limited mode (limits.max_jerk set): the jerk rows are not convex, so the SOCP backend
  // solves a sequence of convex problems, each conservative for the true jerk limit (sequential
  // convex programming). It stops when T changes by less than scp_tolerance relative, or after
  // max_scp_iterations convex solves after the first (jerk-free) one. A programme that ends
  // otherwise (out of iterations, or a convex solve that failed) answers only if its last step
  // changed T by at most 1%, with reduced_accuracy; else iteration_limit or numerical_error. The
  // Ipopt backend writes the jerk rows exactly and solves once (these two are not used).
  // scp_tolerance in (0, 0.1], max_scp_iterations in [1, 100].
  double scp_tolerance = 1e-4;
  // An infeasible problem answers with the closest boundary it can fly instead (the result's
  // boundary_relaxation), and the minimum time for it:
  // - the paper's and certified rows where they make a chain along the path (no lambda_a, jerk
  //   limit or quadrotor acceleration cones): the start speed lowered as little as possible, then
  //   the end speed, along their tangents; boundary accelerations are not relaxed;
  // - otherwise (a jerk limit, lambda_a, or the cones of max_acceleration_norm, the thrust and the
  //   tilt), with a start in motion: the start state scaled towards rest, its velocity by the largest lambda (within
  //   0.01) that can be flown and its acceleration by lambda^2 (what the same curve gives at that speed; a braking
  //   start keeps its braking along the path when it can). A jerk-limited solve that fails numerically is relaxed the
  //   same way (a start exactly at a limit leaves an interior-point method no interior at the first grid point).
  // Otherwise the status stays infeasible, with the diagnosis.
  bool relax_boundary = false;
  int max_scp_iterations = 30;

  // Throws std::invalid_argument naming the offending field ("limits.max_velocity[1]: expected a
  // positive finite number, got -1").
  void Validate() const;
};

}  // namespace timeopt
