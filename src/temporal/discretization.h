#pragma once

// The discretized temporal problem shared by every backend, so that the SOCP and the NLP solve
// exactly the same problem. Private to the temporal module: the public interface is the problem
// (timeopt/temporal/temporal_problem.h), the result (temporal_result.h) and the SOCP for other
// conic solvers (temporal_socp.h).
//
// Grid: piece i has grid points s_k = k ds, k = 0..K, ds = 1/K, and cells [s_k, s_{k+1}].
// Unknown: b at every grid point (b = sdot^2). Within a cell b is linear in s and a = sddot is
// constant: a = (b^{k+1} - b^k) / (2 ds) (eq. 26). The traversal time of a cell is then exactly
// 2 ds / (sqrt(b^k) + sqrt(b^{k+1})) and
//   J = sum over cells [ 2 ds / (sqrt(b^k) + sqrt(b^{k+1})) + rho a^2 ds ]      (eqs. 27-28)
//
// Presolve: each grid value is either fixed (a boundary velocity, a stop at a kink) or
// b_g = scale_g * x[var_g] with x the free unknowns. Joints (eq. 42): when the tangents at a
// joint are parallel and non-zero the first point of the next piece shares the variable of the
// last point of the previous piece with scale multiplied by (|f'_i(1)| / |f'_{i+1}(0)|)^2 (exactly
// eq. 43 when the ratio is 1); at a kink or a vanishing tangent both are fixed at 0. Rows are then
// written over x only: lower <= sum coef * x <= upper.

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "timeopt/conic/problem.h"
#include "timeopt/temporal/joints.h"
#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/trajectory/temporal_profile.h"

namespace timeopt {

// One grid value b_g: fixed, or scale * x[var].
struct GridValue {
  int var = -1;        // index into x, or -1 when fixed
  double scale = 1.0;  // b = scale * x[var]
  double fixed = 0.0;  // b when var < 0
};

struct LinearRow {
  enum class Kind {
    kVelocity,
    kAcceleration,
    kAccelerationChange,
    kBoundaryAcceleration,
    kJerk,        // jerk-limited mode: the linearized jerk rows
    kContinuity,  // jerk-limited mode: sddot continuous, rest-cell shape (equalities)
  };
  Kind kind = Kind::kAcceleration;
  std::vector<std::pair<int, double>> terms;  // (var, coef), distinct vars
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
};

// Jerk-limited mode with exact jerk rows (DiscretizeJerkLimited with JerkRows::kExact, for the
// Ipopt backend): a cubic form in the three half-grid values of one cell,
//   sum over j, k, l in {0, 1, 2} of coef[9 j + 3 k + l] b_{grid[j]} b_{grid[k]} b_{grid[l]} <= 1,
// with coef fully symmetric. Written over grid values (b_g, see GridValue), not over x.
struct CubicRow {
  std::array<int, 3> grid{};
  std::array<double, 27> coef{};
  double Value(const std::array<double, 3>& b) const;
};

// A second-order cone row over grid values, for the quadrotor's norm limits (limits.max_acceleration_norm,
// max_thrust, max_tilt) on one acceleration vector (a cell middle in paper mode, a Bernstein control
// point of a cell's acceleration in certified mode):
//   || norm_constant + sum_j norm[j] b_{grid[j]} || <= bound_constant + sum_j bound[j] b_{grid[j]},
// scaled so that bound_constant is 1. Written over grid values (b_g, see GridValue), not over x.
struct ConeRow {
  enum class Kind { kAccelerationNorm, kThrust, kTilt };
  Kind kind = Kind::kAccelerationNorm;
  std::vector<int> grid;
  std::vector<Eigen::Vector3d> norm;
  Eigen::Vector3d norm_constant = Eigen::Vector3d::Zero();
  std::vector<double> bound;
  double bound_constant = 1.0;
  // The two sides at the grid values b (one per entry of grid).
  Eigen::Vector3d NormPart(const std::vector<double>& b) const;
  double BoundPart(const std::vector<double>& b) const;
};

struct Cell {
  int piece = 0;
  int first_grid = 0;  // grid index of b^k; b^{k+1} is first_grid + 1
  double ds = 0.0;
  // The cell's time in the objective is time_weight * 2 ds / (sqrt(b^k) + sqrt(b^{k+1})). 1 but in
  // the jerk-limited mode's rest cells, whose b is not linear (see jerk_discretization.cpp).
  double time_weight = 1.0;
};

// Jerk-limited mode: b on the half grid as an affine function of control values y. On every
// piece b is a C1 piecewise quadratic in s (sddot = b' / 2 continuous), and such a spline has one
// degree of freedom per cell: the middle Bernstein coefficient P1 of each regular cell (b's
// control polygon on the cell is P0, P1, P2). A knot value between two regular cells is the
// length-weighted mean of their P1 (continuity of b'); at a cell that leaves or reaches rest, at a
// joint without a stop and at a boundary whose acceleration is given, the knot or P1 follows from
// the same continuity rows. So y satisfies every equality row of the discretization by
// construction, and every row over y touches at most three consecutive control values: the Newton
// system of an interior-point method over y is banded (banded_ipm.h). y_c = P1 / scale of the
// grid value in the cell's middle, so that y is about the squared speed relative to the limit, as
// x is.
struct ControlForm {
  static constexpr int kMaxTerms = 4;
  int first = 0;  // the first control value it touches
  int count = 0;  // how many consecutive ones (0: a constant)
  std::array<double, kMaxTerms> coef{};
  double constant = 0.0;
  double Value(const std::vector<double>& y) const {
    double v = constant;
    for (int t = 0; t < count; ++t) v += coef[static_cast<size_t>(t)] * y[static_cast<size_t>(first + t)];
    return v;
  }
};

struct ControlBasis {
  int num_controls = 0;
  std::vector<ControlForm> grid;  // b at every half-grid value (the discretization's grid)
  // Per control: the half-grid index of its cell's middle, or, for a boundary value that is free
  // (tangent and curvature vanish there, so b is bound by nothing but its cells), that value's.
  std::vector<int> middle;
  std::vector<char> at_knot;  // per control: 1 for such a boundary value
  std::vector<double> scale;  // per control: P1 (or the boundary b) = scale * y
  // Per control of a cell's P1: the weights of b at its cell's three half-grid values in P1 (-1/2,
  // 2, -1/2 on a regular cell; a ramp cell's P1 is q's, with the rho_j of its RampFrame).
  std::vector<std::array<double, 3>> read;
  // Control c of the profile with b at every half-grid value.
  double FromGrid(int c, const std::vector<double>& b) const {
    const size_t g = static_cast<size_t>(middle[static_cast<size_t>(c)]);
    const std::array<double, 3>& w = read[static_cast<size_t>(c)];
    const double value = at_knot[static_cast<size_t>(c)] ? b[g] : w[0] * b[g - 1] + w[1] * b[g] + w[2] * b[g + 1];
    return value / scale[static_cast<size_t>(c)];
  }
};

struct TemporalDiscretization {
  int num_pieces = 0;
  int cells_per_piece = 0;
  double rho = 0.0;
  // sqrt(N) times the median over cells of a_cap = min over axes of amax / |f'| at the cell middle
  // (N cells with a non-zero tangent; 1 if there are none): the size ||a|| can reach, which balances
  // the two sides of the rho cone t * 1 >= ||a||^2 in the SOCP (see socp_backend.cpp). The median,
  // not a root-sum-square, so that cells near a vanishing tangent (unbounded caps) do not set it.
  double acceleration_norm_scale = 1.0;
  int num_vars = 0;               // size of x
  std::vector<GridValue> grid;    // m (K + 1) values; piece i, point k at i (K + 1) + k
  std::vector<Cell> cells;        // m K cells in path order
  std::vector<double> var_upper;  // upper bound of each x (>= 0, may be +inf); x >= 0
  std::vector<LinearRow> rows;    // over x, constants folded into the bounds
  std::vector<JointInfo> joints;  // m - 1 entries
  // Per piece, 1 where it is tied (MarkTiedPieces): an interior piece negligibly short next to a
  // neighbour, between two joints without a stop. Without a jerk limit every grid value of it
  // shares the variable of its first (a constant speed across it); with one, b is a single line in
  // s over it, continuing the acceleration of the piece before (equality rows).
  std::vector<char> tied;
  std::vector<CubicRow> cubic_rows;  // JerkRows::kExact only; <= 1 each
  std::vector<ConeRow> cone_rows;    // the quadrotor's norm limits (VehicleLimits)
  // Jerk-limited mode (DiscretizeJerkLimited): the grid is the half grid, cells_per_piece = 2 K
  // half cells; shapes holds the shape of each of the m K full cells in path order.
  bool jerk_limited = false;
  std::vector<CellShape> shapes;
  // Jerk-limited mode: the K + 1 cell edges of every piece in [0, 1] (graded towards rest points).
  std::vector<std::vector<double>> cell_edges;
  // Jerk-limited mode: the control values that satisfy every equality row by construction (see
  // ControlBasis); empty when the grid has a case they do not cover (then only the general
  // solvers take it).
  std::optional<ControlBasis> controls;
  // Optional: b at every grid value of a nearby answer (the previous solve of a sequential convex
  // programme), where a solver that can use a start begins.
  std::vector<double> start_b;
  // Set when presolve already proves the problem infeasible (e.g. a boundary speed above the
  // limit); the backends then report infeasible with this message without solving.
  std::optional<std::string> infeasible_reason;

  int GridIndex(int piece, int k) const { return piece * (cells_per_piece + 1) + k; }
  // b at grid point g for the given x.
  double GridB(int g, const std::vector<double>& x) const;
  // Objective J and its time part T for x (infinite when a cell has b = 0 at both ends).
  double Objective(const std::vector<double>& x, double* total_time = nullptr) const;
  // Largest violation of the rows (linear, cubic and cone) and bounds for x (0 when feasible), in
  // the rows' units.
  double MaxViolation(const std::vector<double>& x) const;
};

// Validates the problem (throws std::invalid_argument) and builds the discretization.
TemporalDiscretization Discretize(const TemporalProblem& problem);

// How DiscretizeJerkLimited writes the jerk limit |jerk| = sqrt(b) |P| <= j of regular cells.
enum class JerkRows {
  kNone,        // left out: the sequential convex programme's first, jerk-free solve
  kLinearized,  // linear rows, 1 / sqrt(b) bounded by its tangent at a previous solution's b
  kExact,       // cubic rows b P^2 <= j^2 (CubicRow): not convex, for the Ipopt backend
};

// The jerk-limited discretization (problem.limits.max_jerk set): b on the half grid of every cell,
// b quadratic and sddot linear and continuous on regular cells, constant s-jerk on cells that
// leave or reach rest, and velocity, acceleration and jerk rows certified on every whole cell (by
// the Bernstein coefficients of the cell's polynomials in s). The jerk rows of regular cells are
// written as `jerk_rows` says; kLinearized needs `linearization` (b at every half-grid point,
// m (2 K + 1) values, of a previous solution), and any solution of that convex problem satisfies
// the true jerk limit. Rest cells' jerk bounds are exact and linear in every mode.
TemporalDiscretization DiscretizeJerkLimited(const TemporalProblem& problem, JerkRows jerk_rows,
                                             const std::vector<double>* linearization = nullptr);

// The conic program of the SOCP backend over `d` (BuildTemporalSocp of the problem, public, is this
// of its Discretize; socp_backend.cpp). Throws std::invalid_argument when presolve already proved d
// infeasible or every grid value is fixed.
conic::Problem BuildDiscretizedSocp(const TemporalDiscretization& d);

}  // namespace timeopt
