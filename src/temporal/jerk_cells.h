// The jerk-limited discretization's shared pieces (jerk_discretization.cpp, jerk_cell_rows.cpp):
// the context of one discretization (JerkContext), the Lagrange basis of a cell's b, and the rows
// of a cell (AddCellRows and the rest cells' forms).

#pragma once

#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "discretization_internal.h"

namespace timeopt::internal::jerk {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative tolerance for "the boundary acceleration's part across the path equals f'' sdot^2"
// and "the curvature is continuous across a joint": rounding of fitted curves is ~1e-12.
inline constexpr double kNormalTolerance = 1e-6;
// The jerk rows' smallest linearization point relative to the largest b (see bbar_floors).
inline constexpr double kLinearizationFloor = 1e-4;
// Parts of a regular cell with their own linearization of the jerk rows (see AddCellRows).
inline constexpr int kJerkSegments = 1;
// A rest cell's q can vary much more over the cell (alpha against b_far) than a regular cell's b:
// its jerk rows are linearized on kRestJerkParts equal parts of w, each at the largest q of the
// previous solution there. On the 12 reference curves (time_domain_reference_test.cpp) one part
// left T up to 0.06 points of a percent further from the reference, four gained nothing over two.
inline constexpr int kRestJerkParts = 2;

// The half-grid value of a rest cell that holds alpha (its middle) and the far one, relative to g0.
inline constexpr int kRestAlpha = 1;
inline int RestFar(CellShape shape) { return shape == CellShape::kRestStart ? 2 : 0; }

// Ascending coefficients (in u) of the Lagrange basis on u = 0, 1/2, 1 and its derivatives.
inline const SmallPoly& Basis(int j) {
  static const SmallPoly basis[3] = {(SmallPoly(3) << 1.0, -3.0, 2.0).finished(),
                                     (SmallPoly(3) << 0.0, 4.0, -4.0).finished(),
                                     (SmallPoly(3) << 0.0, -1.0, 2.0).finished()};
  return basis[j];
}
inline const SmallPoly& BasisDerivative(int j) {
  static const SmallPoly d[3] = {(SmallPoly(2) << -3.0, 4.0).finished(), (SmallPoly(2) << 4.0, -8.0).finished(),
                                 (SmallPoly(2) << -1.0, 4.0).finished()};
  return d[j];
}
inline constexpr double kBasisSecond[3] = {4.0, -8.0, 4.0};
// L_j'(0) and L_j'(1): the slopes of b in u at the cell's ends.
inline constexpr double kSlopeAtStart[3] = {-3.0, 4.0, -1.0};
inline constexpr double kSlopeAtEnd[3] = {1.0, -4.0, 3.0};

inline SmallPoly Constant(double c) { return (SmallPoly(1) << c).finished(); }

// The largest |p(u)| on [0, 1] bounded by its largest Bernstein coefficient.
inline double BernsteinMax(BernsteinTable& table, const SmallPoly& p) { return table.Convert(p).cwiseAbs().maxCoeff(); }

struct JerkContext {
  const TemporalProblem& problem;
  TemporalDiscretization& d;
  RowBuilder row;
  BernsteinTable bernstein;
  int K = 0;
  double ds = 0.0;  // the nominal cell length 1 / K (for scaling rows)
  // The smallest linearization point of the jerk rows per piece: kLinearizationFloor times the
  // largest b of the linearization on the piece (LinearizationFloors).
  std::vector<double> bbar_floors;
  // Derivatives 1..3 of every piece (rows: axes).
  std::vector<std::array<PolynomialPiece::Coefficients, 3>> derivatives;
  // Where the regular cells' velocity, acceleration and jerk rows go (DiscretizeJerkLimitedTemplates),
  // or null.
  internal::JerkTemplates* templates = nullptr;
  // The Lagrange basis in Bernstein form of basis_size coefficients (for the jerk templates).
  int basis_size = -1;
  SmallPoly basis_bernstein[3];
  // sddot at the start and the end where the boundary acceleration fixes it (AddBoundaryAcceleration).
  std::optional<double> boundary_sddot[2];
  // b at the start and the end where the boundary acceleration fixes b itself (a vanishing tangent).
  std::optional<double> boundary_b[2];

  // The half-grid index of half point j of piece i.
  int Half(int piece, int j) const { return d.GridIndex(piece, j); }
  // Where cell k of piece i starts, and its length (cells are graded towards rest points).
  double Start(int piece, int k) const { return d.cell_edges[static_cast<size_t>(piece)][static_cast<size_t>(k)]; }
  double Len(int piece, int k) const {
    const std::vector<double>& e = d.cell_edges[static_cast<size_t>(piece)];
    return e[static_cast<size_t>(k) + 1] - e[static_cast<size_t>(k)];
  }
  // Derivative `order` (1..3) of piece i on cell k as a polynomial in u, axis a.
  SmallPoly OnCell(int piece, int k, int order, int a) const {
    const auto& c = derivatives[static_cast<size_t>(piece)][static_cast<size_t>(order - 1)];
    if (c.cols() == 0) return Constant(0.0);
    return Shifted(c.row(a).transpose(), Start(piece, k), Len(piece, k));
  }
};

// Derivative `order` of piece i on rest cell k as a polynomial in the cell's time fraction w from
// its rest point (see RestPolys): the cell's polynomial in u, with u = w^3 at a start and
// u = 1 - w^3 at an end.
inline SmallPoly InRestTime(const JerkContext& c, int piece, int k, int order, int axis) {
  const SmallPoly on_cell = c.OnCell(piece, k, order, axis);
  const SmallPoly from_rest =
      c.d.shapes[static_cast<size_t>(piece * c.K + k)] == CellShape::kRestStart ? on_cell : Shifted(on_cell, 1.0, -1.0);
  SmallPoly out = SmallPoly::Zero(3 * (from_rest.size() - 1) + 1);
  for (int j = 0; j < from_rest.size(); ++j) out(3 * j) = from_rest(j);
  return out;
}

// scale w^power p.
inline SmallPoly TimesPower(const SmallPoly& p, int power, double scale) {
  SmallPoly out = SmallPoly::Zero(p.size() + power);
  out.tail(p.size()) = scale * p;
  return out;
}

// a + b, of any two sizes.
inline SmallPoly Sum(const SmallPoly& a, const SmallPoly& b) {
  SmallPoly out = Padded(a, static_cast<int>(b.size()));
  out.head(b.size()) += b;
  return out;
}

// Is the point at the start (end = false) or end of piece i a rest point: b fixed at 0 and the
// acceleration required to be 0 there (a stop, or a boundary at rest with zero acceleration and a
// non-vanishing tangent)?
inline bool RestPoint(const JerkContext& c, int piece, bool end) {
  const TemporalProblem& p = c.problem;
  const int m = p.curve.num_pieces();
  const int g = end ? c.Half(piece, 2 * c.K) : c.Half(piece, 0);
  const GridValue& v = c.d.grid[static_cast<size_t>(g)];
  if (v.var >= 0 || v.fixed != 0.0) return false;
  const bool boundary = end ? piece == m - 1 : piece == 0;
  if (!boundary) return true;  // a stop at a joint
  const Eigen::Vector3d& acc = end ? p.boundary.end_acceleration : p.boundary.start_acceleration;
  return acc.isZero(0.0);
}

// A rest cell (b = 0 and sddot = 0 at its rest point) in its own time coordinate w in [0, 1] from
// the rest point (see temporal_profile.h): s = s_rest +- L w^3 and b = w^4 q(w) with q linear,
// q = alpha (1 - w) + b_far w. Its middle half-grid value is alpha (q at the rest point), not b at
// the middle, so that the cell's time is the exact 6 L / (sqrt(alpha) + sqrt(b_far)) of two values
// (the half cell (alpha, b_far) with weight 6, the other with weight 0). Per axis, with f^(n) at
// s(w) and the upper signs for a start (the lower for an end, which brakes while its s-jerk is
// positive):
//   v = f' w^2 sqrt(q),   acc = +-f' w (4 alpha + 5 beta w) / (6 L) + f'' w^4 q,
//   jerk = sqrt(q) P,   P = f' (4 alpha + 10 beta w) / (18 L^2) +- f'' w^3 (4 alpha + 5 beta w) / (2 L)
//                           + f''' w^6 q,
// with beta = b_far - alpha: polynomials in w linear in (alpha, b_far), like a regular cell's in u
// and its three values. The jerk has the same form sqrt(q) P as a regular cell's sqrt(b) P, so the
// same linearization (at the largest q on each of kRestJerkParts parts of the cell) or exact cubic
// rows bound it.
// beta = 0 is a constant s-jerk from rest (the only rest shape before), exact on a line; beta < 0
// lets the s-jerk ease off as the curvature terms grow.
// A ramp cell (CellShape::kRampStart / kRampEnd; RampCellPolys) has the same form in its coordinate
// u in [0, 1] along the cell, w = w0 + (w1 - w0) u: b = w^4 q(w), q quadratic through q_j = rho_j
// b_j (RampFrame), so its polynomials are a rest cell's with q's Lagrange basis times rho_j, and
//   sddot = eps w (4 q + w q_w) / 6,  P = f' (4 q + 6 w q_w + w^2 q_ww) / 18 + eps f'' w^3 (4 q + w
//   q_w) / 2 + f''' w^6 q,
// q_w = dq/dw; ramp is set (the jerk rows are linearized at the largest q on the whole cell).
struct RestPolys {
  bool ramp = false;
  SmallPoly q[3];        // q per half-grid value of the cell (0 at the rest point's)
  SmallPoly vel[3][3];   // f'^2 w^4 q: v^2, [axis][value]
  SmallPoly acc[3][3];   // [axis][value]
  SmallPoly jerk[3][3];  // P, [axis][value]
};

// The rows of one cell (jerk_cell_rows.cpp).
void AddCellAcceleration(JerkContext& c, int piece, int k, bool at_end, double coef);
void AddConstantJerkRestRows(JerkContext& c, int piece, int k);
bool RestCellPolys(JerkContext& c, int piece, int k, RestPolys* out);
bool RampCellPolys(JerkContext& c, int piece, int k, RestPolys* out);
void AddCellRows(JerkContext& c, int piece, int k, JerkRows mode, const std::vector<double>* lin,
                 const RestPolys* rest);

}  // namespace timeopt::internal::jerk
