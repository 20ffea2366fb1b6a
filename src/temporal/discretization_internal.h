#pragma once

// Library-internal pieces of the temporal discretization, shared by Discretize (the paper's and the
// certified rows, discretization.cpp) and DiscretizeJerkLimited (jerk_discretization.cpp): small
// polynomials and their Bernstein coefficients, the row builder that folds fixed grid values into
// the bounds, and the stages both discretizations run.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <limits>
#include <sstream>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "discretization.h"

namespace timeopt::internal {

inline constexpr const char* kAxisNames[3] = {"x", "y", "z"};

// Relative slack for checking rows made only of constants (fixed grid values): rounding in
// |v|^2 / |f'|^2 and back is ~1e-15; 1e-9 keeps "exactly at the limit" feasible.
inline constexpr double kConstantRowSlack = 1e-9;
// Without a jerk limit, where |f'| at a grid point is below kSlowTangentShare of its largest on
// the piece (near a vanishing tangent: a minimum-jerk curve's rest end), the unknown x = b / S_i
// (AssignGridValues) is at most kSlowTangentCap = 1 / kSlowTangentShare^2 (1e4): sdot at most
// 1 / kSlowTangentShare times what moves the piece's longest tangent at the reference speed.
// Nothing else bounds b there but the acceleration rows beside it, and b reached 1e6 to 1e9
// times its value elsewhere on slow, long curves, where the conic solver stalled (at K = 1 on a
// straight piece T had no minimum). The time given up is that of the last stretch before the end
// where the optimum's sdot would be above the cap (+6.6e-5 of T at 0.05 m/s on the shipped
// waypoints, paper rows, K = 200). On the long property sweep (10,000 problems, seed 1) a share
// of 1e-2 left 11 paper-row minimum-jerk problems failing of 82 without the cap; 2e-3, though
// better on those and the 500 of the short sweep, left more than 25; 2e-2 left 7 (others: the
// conic solver's conditioning, not monotone in the cap) but cost 3.5e-4 of T at 0.05 m/s.
inline constexpr double kSlowTangentShare = 1e-2;
inline constexpr double kSlowTangentCap = 1.0 / (kSlowTangentShare * kSlowTangentShare);

// The largest value along the unit direction u that per-axis limits allow: min over the axes of
// limit / |u_axis| (axes that u hardly touches, |u_axis| <= 1e-12, bound nothing). Infinite when
// none does.
inline double LimitAlong(const Eigen::Vector3d& limit, const Eigen::Vector3d& u) {
  double along = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(u(axis)) > 1e-12) along = std::min(along, limit(axis) / std::abs(u(axis)));
  }
  return along;
}

// A piece's length from |f'| at 16 midpoints (a sizing estimate, not ArcLength's exact one).
inline double PieceLengthEstimate(const PiecewiseCurve& curve, int piece) {
  double length = 0.0;
  for (int k = 0; k < 16; ++k) length += curve.Evaluate(piece, (k + 0.5) / 16.0, 1).norm() / 16.0;
  return length;
}

// Where half point j (0 .. 2 K) of a piece with cell edges `edges` lies in s: the cells' ends and
// middles.
inline double HalfPointS(const std::vector<double>& edges, int j) {
  const int k = std::min(j / 2, static_cast<int>(edges.size()) - 2);
  return edges[static_cast<size_t>(k)] +
         0.5 * (j - 2 * k) * (edges[static_cast<size_t>(k) + 1] - edges[static_cast<size_t>(k)]);
}

// A ramp cell of the jerk-limited grid (CellShape::kRampStart / kRampEnd, temporal_profile.h): w at
// its three half points (its ends and its middle in w), rho_j = 1 / w_j^4 so that q_j = rho_j b_j,
// dw/du = w1 - w0 along the cell's coordinate u in [0, 1] (negative before a rest end), and eps =
// +1 after a rest start, -1 before a rest end (sddot = eps w (4 q + w dq/dw) / 6).
struct RampFrame {
  double w[3] = {0.0, 0.0, 0.0};
  double rho[3] = {1.0, 1.0, 1.0};
  double dw = 0.0;
  double eps = 1.0;
};
inline RampFrame RampFrameOf(CellShape shape, double s0, double s1) {
  RampFrame f;
  f.w[0] = TemporalProfile::RampW(shape, s0);
  f.w[2] = TemporalProfile::RampW(shape, s1);
  f.w[1] = 0.5 * (f.w[0] + f.w[2]);
  for (int j = 0; j < 3; ++j) f.rho[j] = 1.0 / ((f.w[j] * f.w[j]) * (f.w[j] * f.w[j]));
  f.dw = f.w[2] - f.w[0];
  f.eps = shape == CellShape::kRampStart ? 1.0 : -1.0;
  return f;
}
// The linearization point of a cell's jerk rows: the largest b of the quadratic through the
// previous solution's three half-grid values lb, at least floor.
double LinearizationPoint(const double (&lb)[3], double floor);
// A ramp cell's: the largest q = rho_j b_j on the cell from b at its three half-grid values (q >= b
// there, so the piece's floor of b bounds q as well).
inline double RampLinearizationPoint(const RampFrame& f, const double (&lb)[3], double floor) {
  const double lq[3] = {f.rho[0] * lb[0], f.rho[1] * lb[1], f.rho[2] * lb[2]};
  return LinearizationPoint(lq, floor);
}
// The shape and frame of full cell k of piece i of a jerk-limited discretization.
inline CellShape JerkCellShape(const TemporalDiscretization& d, int piece, int k) {
  return d.shapes[static_cast<size_t>(piece * (d.cells_per_piece / 2) + k)];
}
inline RampFrame RampFrameOf(const TemporalDiscretization& d, int piece, int k) {
  const std::vector<double>& e = d.cell_edges[static_cast<size_t>(piece)];
  return RampFrameOf(JerkCellShape(d, piece, k), e[static_cast<size_t>(k)], e[static_cast<size_t>(k) + 1]);
}
// HalfPointS of a jerk-limited discretization, where a ramp cell's middle half point is its middle
// in w.
inline double HalfPointS(const TemporalDiscretization& d, int piece, int j) {
  const std::vector<double>& edges = d.cell_edges[static_cast<size_t>(piece)];
  const int k = std::min(j / 2, static_cast<int>(edges.size()) - 2);
  const CellShape shape = JerkCellShape(d, piece, k);
  if (j == 2 * k + 1 && IsRampShape(shape)) {
    return TemporalProfile::RampMiddleS(shape, edges[static_cast<size_t>(k)], edges[static_cast<size_t>(k) + 1]);
  }
  return HalfPointS(edges, j);
}

inline double Angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Small polynomials (ascending coefficients) on the stack: certified mode multiplies at most two
// derivatives of a piece, so 2 * degree + 2 coefficients suffice (pieces of degree <= 30).
inline constexpr int kMaxSmallPoly = 64;
using SmallPoly = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxSmallPoly, 1>;

// Coefficients (ascending, in u in [0, 1]) of p(s0 + h u) for the polynomial with ascending
// coefficients `c` in s: a Taylor shift by repeated synthetic division, then the scaling by h^j.
inline SmallPoly Shifted(const SmallPoly& c, double s0, double h) {
  const int n = static_cast<int>(c.size());
  SmallPoly out = c;
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = n - 2; j >= i; --j) out(j) += s0 * out(j + 1);
  }
  double hj = 1.0;
  for (int j = 0; j < n; ++j) {
    out(j) *= hj;
    hj *= h;
  }
  return out;
}

inline SmallPoly Multiply(const SmallPoly& a, const SmallPoly& b) {
  SmallPoly out = SmallPoly::Zero(a.size() + b.size() - 1);
  for (int i = 0; i < a.size(); ++i) {
    for (int j = 0; j < b.size(); ++j) out(i + j) += a(i) * b(j);
  }
  return out;
}

inline SmallPoly Padded(const SmallPoly& a, int size) {
  SmallPoly out = SmallPoly::Zero(std::max<int>(size, static_cast<int>(a.size())));
  out.head(a.size()) = a;
  return out;
}

// Power-to-Bernstein conversion matrices by size, computed once per Discretize call:
// p_k = sum_{j <= k} C(k, j) / C(n, j) a_j. Each is stored as its lower triangle, row by row, and
// applied with raw pointers (this conversion was 8% of a jerk-limited solve's instructions through
// Eigen's element access).
class BernsteinTable {
 public:
  SmallPoly Convert(const SmallPoly& a) {
    const int size = static_cast<int>(a.size());
    if (size >= static_cast<int>(tables_.size())) tables_.resize(static_cast<size_t>(size) + 1);
    std::vector<double>& table = tables_[static_cast<size_t>(size)];
    if (table.empty()) {
      table.reserve(static_cast<size_t>(size * (size + 1) / 2));
      for (int k = 0; k < size; ++k) {
        for (int j = 0; j <= k; ++j) table.push_back(BinomialRatio(k, j, size - 1));
      }
    }
    SmallPoly p(size);
    const double* row = table.data();
    const double* x = a.data();
    double* out = p.data();
    for (int k = 0; k < size; ++k) {
      double sum = 0.0;
      for (int j = 0; j <= k; ++j) sum += row[j] * x[j];
      out[k] = sum;
      row += k + 1;
    }
    return p;
  }

 private:
  // C(k, j) / C(n, j) as a product of ratios (no overflow for large n).
  static double BinomialRatio(int k, int j, int n) {
    double r = 1.0;
    for (int i = 0; i < j; ++i) r *= static_cast<double>(k - i) / static_cast<double>(n - i);
    return r;
  }
  std::vector<std::vector<double>> tables_;
};

class RowBuilder {
 public:
  explicit RowBuilder(TemporalDiscretization& d) : d_(d) {}

  // Adds coef * b_g to the current row.
  void Add(int g, double coef) {
    const GridValue& v = d_.grid[static_cast<size_t>(g)];
    if (v.var < 0) {
      constant_ += coef * v.fixed;
      return;
    }
    for (auto& t : terms_) {
      if (t.first == v.var) {
        t.second += coef * v.scale;
        return;
      }
    }
    terms_.emplace_back(v.var, coef * v.scale);
  }

  // Finishes the row lower <= expression <= upper; what() names it for presolve messages (called
  // only when a constant row is found infeasible, so that building rows allocates no strings).
  template <typename What>
  void Finish(LinearRow::Kind kind, double lower, double upper, const What& what) {
    size_t nonzero = 0;
    for (const auto& t : terms_) nonzero += t.second != 0.0 ? 1 : 0;
    if (nonzero == 0) {
      // Scale the slack by the finite bounds only (an infinite one would disable the check).
      double scale = 1.0;
      if (std::isfinite(lower)) scale = std::max(scale, std::abs(lower));
      if (std::isfinite(upper)) scale = std::max(scale, std::abs(upper));
      if ((std::isfinite(lower) && constant_ < lower - kConstantRowSlack * scale) ||
          (std::isfinite(upper) && constant_ > upper + kConstantRowSlack * scale)) {
        if (!d_.infeasible_reason) {
          std::ostringstream ss;
          ss << what() << " is " << constant_ << ", outside [" << lower << ", " << upper
             << "] whatever the time allocation";
          d_.infeasible_reason = ss.str();
        }
      }
    } else {
      LinearRow row;
      row.kind = kind;
      row.terms.reserve(nonzero);
      for (const auto& t : terms_) {
        if (t.second != 0.0) row.terms.push_back(t);
      }
      row.lower = lower - constant_;
      row.upper = upper - constant_;
      d_.rows.push_back(std::move(row));
    }
    terms_.clear();
    constant_ = 0.0;
  }

 private:
  TemporalDiscretization& d_;
  std::vector<std::pair<int, double>> terms_;
  double constant_ = 0.0;
};

// Boundary grid value from a given velocity and the tangent there; a free value gets `scale`.
GridValue BoundaryValue(const Eigen::Vector3d& velocity, const Eigen::Vector3d& tangent, const TemporalProblem& p,
                        const std::string& field, double scale, int* next_var);
// The type of every joint between pieces (C1, G1 with its speed ratio, or a stop).
void ClassifyJoints(const TemporalProblem& problem, TemporalDiscretization* out);
// A piece at most this share of the longest piece within two of it is tied (see
// TemporalDiscretization::tied; not of the whole curve: in a 127 m plan of 101 pieces that tied
// pieces of 0.2 m, and the structured path failed on the plan). Its K cells are then ~1e3 times
// shorter than its neighbours' and b on it ~1e6 times larger; the
// acceleration rows confined b's changes across it to a slab of relative width ~its length share,
// and the conic solvers stalled there: a 2 m line in pieces of 1 m, 0.1 um and 1 m had no answer
// without a jerk limit, and with one a 0.1 mm middle piece none at K = 50, a 1 mm one none at
// K >= 100 (see MarkTiedPieces for what the tie gives up).
inline constexpr double kTiedPieceShare = 2e-3;
// With a jerk limit, a piece whose rounding in b may make a jerk above this many times the limit
// (estimated as in MarkTiedPieces) is not tied. On the 2 m line with a middle piece (v 4, a 3,
// j 10) the estimate is 1.2-1.5 for 10 um at K = 200, 3 um at K = 50 and 1 um at K = 20, whose
// answers hold the jerk limit, and 9-16 for 1 um at K = 50 and 3 um at K = 200, where rounding made
// a jerk of 1.49 and 2.07 x the limit. (It overstates the noise: v is the fastest speed the limits
// allow, 3.5 m/s there against the 1.5 m/s flown.)
inline constexpr double kJerkRoundingRatio = 2.5;
// The same estimate with the answer's own speed on a tied piece, above which the answer is not
// taken (TiedPieceTooShortForItsSpeed). On a random quintic split around a short piece (v 2, a 2,
// j 4, K = 100) answers were as without the piece up to 0.46 and then fell away: 0.50 was 0.57%
// slower, 0.65 1.5%, and 3.3 um (above 0.59 by the limits' speed) 7.9%, all "optimal" with every
// limit held (rounding had moved the rows, not broken them). On the 2 m line 0.67 was exact and
// 0.92 broke the jerk limit.
inline constexpr double kTiedRoundingCheck = 0.35;
// Marks the tied pieces (d->tied, after the joints are classified). None where the problem limits
// the acceleration's change between cells (a tied piece holds its acceleration constant).
void MarkTiedPieces(const TemporalProblem& problem, TemporalDiscretization* d);
// With a jerk limit, the message refusing a piece that would be tied but is too short for any
// jerk-limited profile on it at this K (rounding in its b), or none. A valid problem is assumed.
std::optional<std::string> JerkPieceTooShort(const TemporalProblem& problem);
// With a jerk limit, after a solve: the message for a tied piece crossed so fast that rounding in
// its b could have moved its rows (the estimate of MarkTiedPieces with the answer's speed on it
// above kTiedRoundingCheck), or none.
std::optional<std::string> TiedPieceTooShortForItsSpeed(const TemporalProblem& problem, const TemporalProfile& profile);
// With a jerk limit, when a solve did not answer: the note for a tied piece short enough that the
// estimate with the limits' fastest speed is above kTiedRoundingCheck (rounding in its b may be
// why), or none.
std::optional<std::string> TiedPieceMayBeTooShort(const TemporalProblem& problem);
// One grid value per grid point (problem.cells_per_piece cells per piece); returns the tangent
// f'(k ds) at every grid point.
// With `free` set, a boundary with a non-zero speed gets a free value instead of a fixed one,
// bounded above by the given b (see FreeBoundaries).
struct FreeBoundaries;
std::vector<Eigen::Vector3d> AssignGridValues(const TemporalProblem& problem, TemporalDiscretization* out,
                                              FreeBoundaries* free = nullptr);
// The cells (problem.cells_per_piece per piece), and the verdict on a piece of one cell that must
// start and end at rest.
void MakeCells(const TemporalProblem& problem, TemporalDiscretization* out);
// The boundary states against the quadrotor's limits: their accelerations within them, and from
// or into rest some acceleration along the path left (max_thrust = g on a level start leaves
// none). Sets d->infeasible_reason if not.
void CheckBoundaryAccelerations(const TemporalProblem& problem, TemporalDiscretization* d);
// The paper's or certified mode's rows of every cell over (b^k, b^{k+1}) (cell_rows.cpp), with
// mid_acc the curve's acceleration factors at each cell's middle (MidCellAccelerations).
void AddCellRows(const TemporalProblem& problem, const std::vector<Eigen::Matrix<double, 3, 2>>& mid_acc,
                 RowBuilder& row, TemporalDiscretization* out);
// Keeps, per variable, only the tightest row that bounds it alone, as its upper bound.
void KeepTightestUpperBounds(TemporalDiscretization* d);
// The boundary speeds made free (DiscretizeWithFreeBoundaries): for the start and the end, the
// free value that stands for it (-1 when the boundary is at rest or its tangent vanishes), the
// given b there (the value's upper bound, in b) and its scale (b = scale x).
struct FreeBoundaries {
  int var[2] = {-1, -1};
  double given_b[2] = {0.0, 0.0};
  double scale[2] = {1.0, 1.0};
};
// Discretize with the boundary speeds free below the given ones: the problem that
// TemporalProblem::relax_boundary and the diagnosis of an infeasible problem look at.
TemporalDiscretization DiscretizeWithFreeBoundaries(const TemporalProblem& problem, FreeBoundaries* free);

// The largest acceleration norm the quadrotor's limits allow (infinite without any).
double QuadrotorAccelerationCap(const TemporalLimits& limits);
// The quadrotor's acceleration limits on one acceleration vector sum_j coef[j] b_{grid[j]} (a cell
// middle, or a Bernstein control point of a cell's acceleration): cone rows for the norm, the
// largest thrust and the tilt, linear rows (through `row`) for the smallest thrust and the thrust
// pointing up; a row on fixed values only is decided at once (infeasible_reason naming where()).
void AddQuadrotorAccelerationRows(const TemporalLimits& limits, const std::vector<int>& grid,
                                  const std::vector<Eigen::Vector3d>& coef, const std::function<std::string()>& where,
                                  RowBuilder& row, TemporalDiscretization* d);

// A linearized jerk row of a cell before its linearization point bbar is known (the sequential
// convex programme's rows, see jerk_discretization.cpp): the row is
//   sum_j (a[j] 2 sqrt(bbar) / 3 + basis[j] / (3 bbar)) b_{g0 + j} <= 1
// over the cell's three half-grid values (a already divided by the axis' jerk limit), with bbar =
// LinearizationPoint of a regular cell, or for part `part` of `parts` equal parts of a rest cell
// (rest_far >= 0), [w0, w1] = [part, part + 1] / parts, the largest q there,
// q(w) = alpha (1 - w) + b_far w with alpha its middle value and b_far the value g0 + rest_far (at
// least the same floor). 56 bytes: a solve reads every template once or twice per round, and at
// 80 bytes (w0, w1 and jmax stored) they were 0.7 MB of the 10/50 benchmark's working memory.
// The linearization floor of a rest cell of length L (in s) from its piece's floor (LinearizationFloors,
// in b): a rest cell's q is b at its far end over w^4, w = 1 there, where a ramp's q = b / s^(4/3) is
// about the same all along the ramp; so the piece's floor, which bounds b, is L^(4/3) times that
// in the rest cell's q. (The piece's floor itself held a rest cell of 4e-5 of the piece, whose b
// was below it, to 0.8 of its jerk limit: the whole ramp after it started 10% slower.)
inline double RestCellFloor(double piece_floor, double L) { return piece_floor * std::cbrt(L) * L; }
// JerkRowTemplate::rest_far of a ramp cell's rows (linearized at the largest q = b / w^4 on the
// cell, RampFrame).
inline constexpr std::int8_t kRampTemplate = -2;
struct JerkRowTemplate {
  int g0 = 0;
  std::int8_t rest_far = -1;
  std::int8_t part = 0, parts = 1;
  // 1 for a regular cell's coefficient of odd index below its last: a programme whose answer is
  // only a linearization point may leave it out (the jerk is then bounded at every other
  // coefficient).
  std::int8_t thin = 0;
  std::array<double, 3> a{};
  std::array<double, 3> basis{};
  double w0() const { return static_cast<double>(part) / parts; }
  double w1() const { return (part + 1.0) / parts; }
};
static_assert(sizeof(JerkRowTemplate) == 56, "JerkRowTemplate: 56 bytes");
// A row sum_j coef[j] b_{g0 + j} <= 1 over a regular cell's three half-grid values.
struct GridRow {
  int g0 = 0;
  LinearRow::Kind kind = LinearRow::Kind::kVelocity;
  std::array<double, 3> coef{};
};
struct JerkTemplates {
  std::vector<GridRow> cell_rows;          // the regular cells' velocity and acceleration rows
  std::vector<JerkRowTemplate> jerk_rows;  // their jerk rows, one per Bernstein coefficient, axis and sign
  std::vector<int> cells;                  // the first grid value (g0) of every cell with rows above
};
// For the structured path: the jerk-limited discretization without the regular cells' velocity,
// acceleration and jerk rows (JerkRows::kNone otherwise), which go to *templates instead, over grid
// values (no rows over the free values to build). Its rows alone are not the problem.
TemporalDiscretization DiscretizeJerkLimitedTemplates(const TemporalProblem& problem, JerkTemplates* templates);
// A jerk-limited rest cell's middle half-grid value is q at its rest point (alpha; see
// jerk_discretization.cpp), where a profile holds b at the cell's middle in s. In place on b at
// every half-grid value of the jerk-limited d: alpha to b at the middle, and back (alpha clamped at
// 0, for a guess from a profile of other cells).
void RestAlphaToMiddles(const TemporalDiscretization& d, std::vector<double>* b);
void RestMiddlesToAlpha(const TemporalDiscretization& d, std::vector<double>* b);
// alpha of a constant s-jerk (b at the far end) in every rest cell's middle value.
void RestAlphaOfConstantJerk(const TemporalDiscretization& d, std::vector<double>* b);
// The floors of LinearizationPoint for a linearization (b at every half-grid value of the jerk
// discretization d), one per piece: kLinearizationFloor times the piece's largest b. Per piece,
// not over the curve: b scales as 1 / |f'|^2, and a floor taken over the curve had linearized the
// jerk rows of a 1 m piece far above its b (so far too tight) beside a 1 mm piece whose b is 1e6
// times larger (a 2 m line in pieces of 1 m, 1 mm and 1 m was "optimal" at 2.5 x its time).
std::vector<double> LinearizationFloors(const TemporalDiscretization& d, const std::vector<double>& linearization);
// The piece of half-grid value g of the jerk discretization d.
inline int PieceOf(const TemporalDiscretization& d, int g) { return g / (d.cells_per_piece + 1); }

// The control values of a jerk-limited discretization (ControlBasis; control_basis.cpp), from its
// shapes, cell edges, grid values and joints, with the sddot that a boundary acceleration fixes at
// the start and the end (none where it fixes none). A rest cell's middle value (q at its rest
// point, see jerk_discretization.cpp) is a control of its own. A boundary where the tangent vanishes has b fixed by its
// acceleration instead (boundary_b) and sddot free. Checked against every equality row of d; none when a case is not
// covered.
std::optional<ControlBasis> BuildControlBasis(const TemporalProblem& problem, const TemporalDiscretization& d,
                                              const std::optional<double> (&boundary_sddot)[2],
                                              const std::optional<double> (&boundary_b)[2]);

}  // namespace timeopt::internal
