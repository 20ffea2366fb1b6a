// The jerk-limited discretization (DiscretizeJerkLimited, declared in discretization.h).
//
// Unknowns: b = sdot^2 at the half-grid points s = j ds / 2 of every piece (K cells, 2 K + 1
// points). On a regular cell b is the quadratic through its three values, so sddot = b' / 2 is
// linear in s and sdddot = sdot da/ds; with u = (s - s_k) / ds in [0, 1] and the Lagrange basis
//   L0 = (1 - u)(1 - 2u),  Lm = 4u (1 - u),  L1 = u (2u - 1)   (values at u = 0, 1/2, 1),
//   b = sum_j b_j L_j,  a = sum_j b_j L_j' / (2 ds),  da/ds = sum_j b_j L_j'' / (2 ds^2).
// Along the curve (axis-wise): v = f' sdot, acc = f' a + f'' b, jerk = sdot (f' da/ds + 3 f'' a +
// f''' b). Velocity and acceleration are polynomials in u that are linear in the b_j, so their
// Bernstein coefficients bound them on the whole cell (linear rows). Jerk has the factor sqrt(b),
// which is not convex: with a constant bbar > 0 per cell, 1 / sqrt(b) >= (3 bbar - b) / (2 bbar^1.5)
// (the tangent of the convex 1 / sqrt(b) at bbar), so
//   |P(u)| + j b(u) / (2 bbar^1.5) <= 3 j / (2 sqrt(bbar)),   P = f' da/ds + 3 f'' a + f''' b,
// implies |jerk| = sqrt(b) |P| <= j. Its Bernstein coefficients are linear rows again. bbar is the
// largest b of the previous solution on the cell: the sequential convex programme's linearization.
// The Ipopt backend instead writes the limit exactly, b P^2 <= j^2, as cubic rows in the cell's
// three values (the Bernstein coefficients of that polynomial in u; see AddExactJerkRows).
//
// A cell that leaves rest (b = 0 and sddot = 0 at its start: a hover start, or after a stop) cannot
// have sddot linear in s (the time would be infinite). In its time fraction w it moves as s = s_k +
// L w^3, b = w^4 q(w) with q linear (RestPolys): a constant s-jerk when q is constant, easing off or
// building up otherwise. Its middle value is q at the rest point (alpha), its rows are those of a
// regular cell with polynomials in w, and it takes exactly 6 L / (sqrt(alpha) + sqrt(b1)). A cell
// that reaches rest is the mirror. (Pieces of degree above 10 keep a constant s-jerk:
// AddConstantJerkRestRows.)
//
// sddot is continuous: equality rows at every full grid point between cells and, at a joint
// without a stop, the tangential part of acc = f' a + f'' b equal on both sides (a joint whose
// curvature jumps across the path cannot keep the acceleration continuous at speed, so it becomes
// a stop). The boundary accelerations are met exactly: their part along the tangent fixes sddot at
// the end, the part across it must equal f'' sdot^2 or the problem is infeasible.
//
// The time of the half cells in the objective is the paper's 2 h / (sqrt(b^j) + sqrt(b^{j+1}))
// (an approximation of the quadratic's time; the reported T is the profile's exact time); a rest
// cell's two half cells are weighted 0 and 6 so that their sum is its exact time.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "discretization_internal.h"

namespace timeopt {
namespace {

using internal::BernsteinTable;
using internal::kAxisNames;
using internal::Multiply;
using internal::Padded;
using internal::RowBuilder;
using internal::Shifted;
using internal::SmallPoly;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative tolerance for "the boundary acceleration's part across the path equals f'' sdot^2"
// and "the curvature is continuous across a joint": rounding of fitted curves is ~1e-12.
constexpr double kNormalTolerance = 1e-6;
// The jerk rows' smallest linearization point relative to the largest b (see bbar_floor).
constexpr double kLinearizationFloor = 1e-4;
// The share of the jerk limit a constant s-jerk over a rest cell keeps at its rest point
// (RestJerkShare), at least; the cell is halved until it does. Against the time-domain reference
// on 12 rest-to-rest cubics and quintics (time_domain_reference_test.cpp), 0.9 left the smallest
// gaps of 0 (no halving), 0.8, 0.9 and 0.95 (on the curve that it halves most, +1.10% at K = 50,
// against +1.21 / +1.03 / +1.20%; no curve worse than with 0.95). 1 on a line: no halving there.
constexpr double kRestJerkShare = 0.9;
// A rest cell is halved as well while the jerk of a constant s-jerk somewhere on it, over the axes,
// is below this share of its largest value on the cell (RestJerkShares::lowest): there the optimum
// raises its s-jerk, which a rest cell's profile follows only so far. Against the same reference,
// this took the quintic whose start eases off most (its jerk falls to 45%) from +1.27% to +0.46%
// at K = 50; 0.5 left another curve at +0.77%, 0.7 at +0.56%.
constexpr double kRestJerkSlack = 0.7;
// A rest cell on a curve (either share below this) is at most one nominal cell long, so that T
// converges as K grows: a rest cell's profile has two degrees of freedom whatever K is. Lines keep
// their cells (a constant s-jerk is exact there).
constexpr double kCurvedRestShare = 0.95;
// The ratio of consecutive cell edges, in s, after a graded rest cell (CellEdges): in a regular cell
// the s-jerk is proportional to sdot, which grows like s^(2/3) along a ramp from rest, so a cell
// that spans a ratio r of s holds its jerk at about r^(-2/3) of its end's at its start. Against the
// same reference, 1.2 / 1.25 / 1.3 / 1.4 left the worst curve at K = 50 at +0.70 / +0.73 / +0.70 /
// +0.70% and 8 / 9 / 9 / 9 curves within 0.5%; 1.1 and 1.15 took too many of the K cells (+1.17,
// +0.94%). Cells growing by 1.25 in length (edges whose ratio falls from 2.25 towards 1.25), as
// before, left +0.81% and 8.
constexpr double kRestGrading = 1.25;
// The first cell of a braking start (BrakeCellSize): at most kBrakeCellShare of the longest cell
// that can brake and kBrakePhaseShare of the braking phase, at least kSmallestBrakeCell of the
// nominal cell (the grading after it is capped at K / 3 cells). Against the time-domain reference
// from 0.5 m/s at -2 m/s^2 (j = 10, a 10 m line): a phase share of 1/4, 1/6, 1/8 and 1/16 left
// +0.63 / +0.55 / +0.53 / +1.86% at K = 50; 1/32 had no answer there.
constexpr double kBrakeCellShare = 0.5;
constexpr double kBrakePhaseShare = 1.0 / 8.0;
constexpr double kSmallestBrakeCell = 1e-3;
// Where a nominal cell could brake, graded braking cells only if their grading back to the nominal
// cell takes at most this share of the K cells (BrakeCellSize).
constexpr double kBrakeGradingShare = 1.0 / 6.0;
// The cells after a braking start's first one grow so that their edges reach this many nominal
// cells within K / 3 cells (at least by kRestGrading). At K = 20, 0.5 m/s braking at 2 m/s^2
// (j = 10) on a 5 m line had its 6 graded cells reach 0.007 of the piece, and its braking phase
// (0.015) ended in a uniform cell of 0.07 whose quadratic b could not follow it: no answer; now
// T = 3.6076 s, Ipopt's exact rows on the same cells 3.6076 s. 2 nominal cells also solved it
// (3.6154 s) but moved K = 50 grids, which 1 leaves as they were.
constexpr double kBrakeGradingRoom = 1.0;
// The smallest rest cell, relative to the nominal cell 1 / K, and the largest, in s.
constexpr double kSmallestRestCell = 1.0 / 64.0;
constexpr double kLargestRestCell = 0.25;
// Parts of a regular cell with their own linearization of the jerk rows (see AddCellRows).
constexpr int kJerkSegments = 1;
// A rest cell's q can vary much more over the cell (alpha against b_far) than a regular cell's b:
// its jerk rows are linearized on kRestJerkParts equal parts of w, each at the largest q of the
// previous solution there. On the 12 reference curves (time_domain_reference_test.cpp) one part
// left T up to 0.06 points of a percent further from the reference, four gained nothing over two.
constexpr int kRestJerkParts = 2;

// The half-grid value of a rest cell that holds alpha (its middle) and the far one, relative to g0.
constexpr int kRestAlpha = 1;
int RestFar(CellShape shape) { return shape == CellShape::kRestStart ? 2 : 0; }

// Ascending coefficients (in u) of the Lagrange basis on u = 0, 1/2, 1 and its derivatives.
const SmallPoly& Basis(int j) {
  static const SmallPoly basis[3] = {(SmallPoly(3) << 1.0, -3.0, 2.0).finished(),
                                     (SmallPoly(3) << 0.0, 4.0, -4.0).finished(),
                                     (SmallPoly(3) << 0.0, -1.0, 2.0).finished()};
  return basis[j];
}
const SmallPoly& BasisDerivative(int j) {
  static const SmallPoly d[3] = {(SmallPoly(2) << -3.0, 4.0).finished(), (SmallPoly(2) << 4.0, -8.0).finished(),
                                 (SmallPoly(2) << -1.0, 4.0).finished()};
  return d[j];
}
constexpr double kBasisSecond[3] = {4.0, -8.0, 4.0};
// L_j'(0) and L_j'(1): the slopes of b in u at the cell's ends.
constexpr double kSlopeAtStart[3] = {-3.0, 4.0, -1.0};
constexpr double kSlopeAtEnd[3] = {1.0, -4.0, 3.0};

SmallPoly Constant(double c) { return (SmallPoly(1) << c).finished(); }

// The largest |p(u)| on [0, 1] bounded by its largest Bernstein coefficient.
double BernsteinMax(BernsteinTable& table, const SmallPoly& p) { return table.Convert(p).cwiseAbs().maxCoeff(); }

struct JerkContext {
  const TemporalProblem& problem;
  TemporalDiscretization& d;
  RowBuilder row;
  BernsteinTable bernstein;
  int K = 0;
  double ds = 0.0;  // the nominal cell length 1 / K (for scaling rows)
  // The smallest linearization point of the jerk rows: kLinearizationFloor times the largest b of
  // the linearization.
  double bbar_floor = 0.0;
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
SmallPoly InRestTime(const JerkContext& c, int piece, int k, int order, int axis) {
  const SmallPoly on_cell = c.OnCell(piece, k, order, axis);
  const SmallPoly from_rest =
      c.d.shapes[static_cast<size_t>(piece * c.K + k)] == CellShape::kRestStart ? on_cell : Shifted(on_cell, 1.0, -1.0);
  SmallPoly out = SmallPoly::Zero(3 * (from_rest.size() - 1) + 1);
  for (int j = 0; j < from_rest.size(); ++j) out(3 * j) = from_rest(j);
  return out;
}

// scale w^power p.
SmallPoly TimesPower(const SmallPoly& p, int power, double scale) {
  SmallPoly out = SmallPoly::Zero(p.size() + power);
  out.tail(p.size()) = scale * p;
  return out;
}

// a + b, of any two sizes.
SmallPoly Sum(const SmallPoly& a, const SmallPoly& b) {
  SmallPoly out = Padded(a, static_cast<int>(b.size()));
  out.head(b.size()) += b;
  return out;
}

// Is the point at the start (end = false) or end of piece i a rest point: b fixed at 0 and the
// acceleration required to be 0 there (a stop, or a boundary at rest with zero acceleration and a
// non-vanishing tangent)?
bool RestPoint(const JerkContext& c, int piece, bool end) {
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

// sddot at the start or end of full cell k of piece i as terms added to the row under
// construction, times `coef`.
void AddCellAcceleration(JerkContext& c, int piece, int k, bool at_end, double coef) {
  const CellShape shape = c.d.shapes[static_cast<size_t>(piece * c.K + k)];
  const int g0 = c.Half(piece, 2 * k);
  const double len = c.Len(piece, k);
  // A rest cell's sddot at its far end is +-(5 b_far - alpha) / (6 L) (RestPolys; 0 at the rest
  // point).
  if (shape == CellShape::kRestStart) {
    if (at_end) {
      c.row.Add(g0 + 2, 5.0 * coef / (6.0 * len));
      c.row.Add(g0 + kRestAlpha, -coef / (6.0 * len));
    }
    return;
  }
  if (shape == CellShape::kRestEnd) {
    if (!at_end) {
      c.row.Add(g0, -5.0 * coef / (6.0 * len));
      c.row.Add(g0 + kRestAlpha, coef / (6.0 * len));
    }
    return;
  }
  const double* slope = at_end ? kSlopeAtEnd : kSlopeAtStart;
  for (int j = 0; j < 3; ++j) c.row.Add(g0 + j, coef * slope[j] / (2.0 * len));
}

// A rest cell of a piece whose RestPolys do not fit (degree above 10): a constant s-jerk, its middle
// value (alpha) equal to b at its far end, bounded by rows on that value alone. (The structured
// path has no control basis for it; the general path solves such problems.)
void AddConstantJerkRestRows(JerkContext& c, int piece, int k) {
  const CellShape shape = c.d.shapes[static_cast<size_t>(piece * c.K + k)];
  const int g0 = c.Half(piece, 2 * k);
  const int far = shape == CellShape::kRestStart ? g0 + 2 : g0;
  const TemporalLimits& limits = c.problem.limits;
  // A constant s-jerk: alpha (the middle value) is b at the far end.
  c.row.Add(g0 + kRestAlpha, 1.0);
  c.row.Add(far, -1.0);
  c.row.Finish(LinearRow::Kind::kContinuity, 0.0, 0.0,
               [&] { return "rest cell shape in piece " + std::to_string(piece) + " cell " + std::to_string(k); });
  // With sigma in [0, 1] the fraction of the cell's time from rest (at the far end: 1), the cell
  // is s = s_rest +- len sigma^3 and b = b1 sigma^4, so per axis (f^(n) at s(sigma); upper signs
  // for a start, lower for an end, whose acceleration brakes while its s-jerk is still positive):
  //   v = sqrt(b1) f' sigma^2,  acc = b1 (+-f' 2 sigma / (3 len) + f'' sigma^4),
  //   jerk = b1^1.5 (f' 2 / (9 len^2) +- f'' 2 sigma^3 / len + f''' sigma^6),
  // polynomials in sigma times a power of b1 alone: the largest Bernstein coefficient of each
  // bounds it on the whole cell, with the signs of the terms kept (adding the largest |f'|, |f''|
  // and |f'''| on the cell instead held a curved start to half its jerk limit). Pieces whose
  // composed polynomials (3 deg f' + 3 coefficients) do not fit a SmallPoly keep that sum.
  const bool start = shape == CellShape::kRestStart;
  const double len = c.Len(piece, k);
  const double sign = start ? 1.0 : -1.0;
  const int degree1 = static_cast<int>(c.derivatives[static_cast<size_t>(piece)][0].cols()) - 1;  // of f'
  const bool exact = 3 * std::max(degree1, 0) + 3 <= internal::kMaxSmallPoly;
  double speed_per_b = 0.0;                             // sum over axes of the velocity bounds squared
  Eigen::Vector3d acc_per_b = Eigen::Vector3d::Zero();  // C per axis: |acc_axis| <= C b1
  for (int a = 0; a < 3; ++a) {
    double v_per_sqrt_b, acc_bound, jerk_per_b15;
    if (exact) {
      const SmallPoly f1 = InRestTime(c, piece, k, 1, a), f2 = InRestTime(c, piece, k, 2, a);
      const SmallPoly f3 = InRestTime(c, piece, k, 3, a);
      v_per_sqrt_b = BernsteinMax(c.bernstein, TimesPower(f1, 2, 1.0));
      acc_bound = BernsteinMax(c.bernstein, Sum(TimesPower(f1, 1, sign * 2.0 / (3.0 * len)), TimesPower(f2, 4, 1.0)));
      jerk_per_b15 = BernsteinMax(
          c.bernstein, Sum(Sum(TimesPower(f1, 0, 2.0 / (9.0 * len * len)), TimesPower(f2, 3, sign * 2.0 / len)),
                           TimesPower(f3, 6, 1.0)));
    } else {
      const double m1 = BernsteinMax(c.bernstein, c.OnCell(piece, k, 1, a));
      const double m2 = BernsteinMax(c.bernstein, c.OnCell(piece, k, 2, a));
      const double m3 = BernsteinMax(c.bernstein, c.OnCell(piece, k, 3, a));
      v_per_sqrt_b = m1;
      acc_bound = m1 / (1.5 * len) + m2;
      jerk_per_b15 = 2.0 * m1 / (9.0 * len * len) + 2.0 * m2 / len + m3;
    }
    const auto finish = [&](double per_b, LinearRow::Kind kind, const char* what) {
      if (!(per_b > 0.0)) return;
      c.row.Add(far, per_b);
      c.row.Finish(kind, -kInf, 1.0, [&] {
        return std::string(what) + " on axis " + kAxisNames[a] + " in the rest cell of piece " + std::to_string(piece);
      });
    };
    const double vmax = limits.max_velocity(a), amax = limits.max_acceleration(a);
    const double jmax = (*limits.max_jerk)(a);
    finish(v_per_sqrt_b * v_per_sqrt_b / (vmax * vmax), LinearRow::Kind::kVelocity, "velocity");
    finish(acc_bound / amax, LinearRow::Kind::kAcceleration, "acceleration");
    if (jerk_per_b15 > 0.0) {
      const double cap = std::pow(jmax / jerk_per_b15, 2.0 / 3.0);  // b^1.5 C <= j
      finish(1.0 / cap, LinearRow::Kind::kJerk, "jerk");
    }
    speed_per_b += v_per_sqrt_b * v_per_sqrt_b;
    acc_per_b(a) = acc_bound;
  }
  if (!limits.HasNormLimits()) return;
  // The quadrotor's limits, from the same per-axis bounds |v_axis|^2 <= b1 (its bound above)^2 and
  // |acc_axis| <= C_axis b1: sufficient, linear in b1.
  const auto row_le = [&](double per_b, double upper, LinearRow::Kind kind, const char* what) {
    if (!(per_b > 0.0)) return;
    c.row.Add(far, per_b);
    c.row.Finish(kind, -kInf, upper,
                 [&] { return std::string(what) + " in the rest cell of piece " + std::to_string(piece); });
  };
  const double g = limits.gravity;
  if (limits.max_speed) row_le(speed_per_b, *limits.max_speed * *limits.max_speed, LinearRow::Kind::kVelocity, "speed");
  if (limits.max_acceleration_norm) {
    row_le(acc_per_b.norm(), *limits.max_acceleration_norm, LinearRow::Kind::kAcceleration, "acceleration norm");
  }
  if (limits.max_thrust) row_le(acc_per_b.norm(), *limits.max_thrust - g, LinearRow::Kind::kAcceleration, "thrust");
  if (limits.min_thrust) row_le(acc_per_b(2), g - *limits.min_thrust, LinearRow::Kind::kAcceleration, "min thrust");
  if (limits.max_tilt) {
    const double tan_tilt = std::tan(*limits.max_tilt);
    row_le(acc_per_b.head<2>().norm() + tan_tilt * acc_per_b(2), tan_tilt * g, LinearRow::Kind::kAcceleration, "tilt");
  }
}

// The exact jerk rows of a cell on axis a (JerkRows::kExact): |jerk| <= j is b P^2 <= j^2 on the
// whole cell, with P = sum_j b_j P_j(u) and b = sum_j b_j basis_j(u) (the Lagrange basis L_j, or a
// rest cell's q and its own P in w). b P^2 is a polynomial in
// u whose coefficients are cubic forms in the cell's three values; each of its Bernstein
// coefficients <= j^2 makes one CubicRow (all of them together imply the limit on the cell).
void AddExactJerkRows(JerkContext& c, int piece, int k, const SmallPoly (&jerk)[3], const SmallPoly (&basis)[3],
                      double jmax) {
  const int g0 = c.Half(piece, 2 * k);
  SmallPoly product[3][3][3];
  int size = 0;
  for (int j = 0; j < 3; ++j) {
    for (int q = 0; q < 3; ++q) {
      for (int l = q; l < 3; ++l) {
        product[j][q][l] = Multiply(Multiply(basis[j], jerk[q]), jerk[l]);
        size = std::max(size, static_cast<int>(product[j][q][l].size()));
      }
    }
  }
  SmallPoly bern[3][3][3];
  for (int j = 0; j < 3; ++j) {
    for (int q = 0; q < 3; ++q) {
      for (int l = q; l < 3; ++l) {
        bern[j][q][l] = c.bernstein.Convert(Padded(product[j][q][l], size));
        bern[j][l][q] = bern[j][q][l];
      }
    }
  }
  const double scale = 1.0 / (jmax * jmax);
  for (int i = 0; i < size; ++i) {
    CubicRow row;
    bool positive = false;
    for (int j = 0; j < 3; ++j) {
      for (int q = 0; q < 3; ++q) {
        for (int l = 0; l < 3; ++l) {
          // The fully symmetric tensor of the same cubic form (the products are symmetric in q, l).
          const double v = scale * (bern[j][q][l](i) + bern[q][j][l](i) + bern[l][j][q](i)) / 3.0;
          row.coef[static_cast<size_t>(9 * j + 3 * q + l)] = v;
          positive = positive || v > 0.0;
        }
      }
    }
    if (!positive) continue;  // holds for b >= 0
    row.grid = {g0, g0 + 1, g0 + 2};
    c.d.cubic_rows.push_back(row);
  }
}

// The quadrotor's limits on a regular cell: the speed by the Bernstein coefficients of |f'|^2 b
// (linear rows), the acceleration by cones on every Bernstein control point of f' a + f'' b (its
// curve on the cell lies in their convex hull), through AddQuadrotorAccelerationRows.
void AddQuadrotorCellRows(JerkContext& c, int piece, int k, const SmallPoly (&speed)[3],
                          const SmallPoly (&acceleration)[3][3]) {
  const int g0 = c.Half(piece, 2 * k);
  const TemporalLimits& limits = c.problem.limits;
  const auto where = [&] { return "piece " + std::to_string(piece) + " cell " + std::to_string(k); };
  if (limits.max_speed) {
    int size = 3;
    for (int j = 0; j < 3; ++j) size = std::max<int>(size, static_cast<int>(speed[j].size()));
    SmallPoly bern[3];
    for (int j = 0; j < 3; ++j) bern[j] = c.bernstein.Convert(Padded(speed[j], size));
    const double s2 = *limits.max_speed * *limits.max_speed;
    for (int i = 0; i < size; ++i) {
      if (bern[0](i) <= 0.0 && bern[1](i) <= 0.0 && bern[2](i) <= 0.0) continue;
      for (int j = 0; j < 3; ++j) c.row.Add(g0 + j, bern[j](i) / s2);
      c.row.Finish(LinearRow::Kind::kVelocity, -kInf, 1.0, [&] { return "speed in " + where(); });
    }
  }
  int size = 1;
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) size = std::max<int>(size, static_cast<int>(acceleration[a][j].size()));
  }
  SmallPoly bern[3][3];
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) bern[a][j] = c.bernstein.Convert(Padded(acceleration[a][j], size));
  }
  const std::vector<int> grid = {g0, g0 + 1, g0 + 2};
  std::vector<Eigen::Vector3d> coef(3);
  for (int i = 0; i < size; ++i) {
    for (int j = 0; j < 3; ++j)
      coef[static_cast<size_t>(j)] = Eigen::Vector3d(bern[0][j](i), bern[1][j](i), bern[2][j](i));
    internal::AddQuadrotorAccelerationRows(limits, grid, coef, where, c.row, &c.d);
  }
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
struct RestPolys {
  SmallPoly q[3];        // q per half-grid value of the cell (0 at the rest point's)
  SmallPoly vel[3][3];   // f'^2 w^4 q: v^2, [axis][value]
  SmallPoly acc[3][3];   // [axis][value]
  SmallPoly jerk[3][3];  // P, [axis][value]
};

// RestPolys of cell k of piece i, or false when the composed polynomials do not fit a SmallPoly
// (pieces of degree above 10 keep a constant s-jerk, AddConstantJerkRestRows).
bool RestCellPolys(JerkContext& c, int piece, int k, RestPolys* out) {
  const CellShape shape = c.d.shapes[static_cast<size_t>(piece * c.K + k)];
  const bool start = shape == CellShape::kRestStart;
  const double sign = start ? 1.0 : -1.0, L = c.Len(piece, k);
  const int degree1 = static_cast<int>(c.derivatives[static_cast<size_t>(piece)][0].cols()) - 1;  // of f'
  // The largest polynomials: v^2 = f'^2 w^4 q, 6 deg f' + 6 coefficients, and the exact rows' q P^2,
  // 6 deg f' + 4.
  if (6 * std::max(degree1, 0) + 6 > internal::kMaxSmallPoly) return false;
  const int rest = start ? 0 : 2, alpha = kRestAlpha, far = RestFar(shape);
  // Per value (alpha, b_far): q, sddot's factor, the jerk's three factors.
  SmallPoly q[3], sddot[3], j1[3], j2[3];
  q[rest] = sddot[rest] = j1[rest] = j2[rest] = Constant(0.0);
  q[alpha] = (SmallPoly(2) << 1.0, -1.0).finished();
  q[far] = (SmallPoly(2) << 0.0, 1.0).finished();
  // sddot = w (4 alpha + 5 beta w) / (6 L) = [alpha (4 w - 5 w^2) + b_far 5 w^2] / (6 L)
  sddot[alpha] = (SmallPoly(3) << 0.0, 4.0, -5.0).finished() * (sign / (6.0 * L));
  sddot[far] = (SmallPoly(3) << 0.0, 0.0, 5.0).finished() * (sign / (6.0 * L));
  // (4 alpha + 10 beta w) / (18 L^2) and +-w^3 (4 alpha + 5 beta w) / (2 L), per value.
  j1[alpha] = (SmallPoly(2) << 4.0, -10.0).finished() / (18.0 * L * L);
  j1[far] = (SmallPoly(2) << 0.0, 10.0).finished() / (18.0 * L * L);
  j2[alpha] = (SmallPoly(5) << 0.0, 0.0, 0.0, 4.0, -5.0).finished() * (sign / (2.0 * L));
  j2[far] = (SmallPoly(5) << 0.0, 0.0, 0.0, 0.0, 5.0).finished() * (sign / (2.0 * L));
  for (int j = 0; j < 3; ++j) out->q[j] = q[j];
  for (int a = 0; a < 3; ++a) {
    const SmallPoly f1 = InRestTime(c, piece, k, 1, a), f2 = InRestTime(c, piece, k, 2, a);
    const SmallPoly f3 = InRestTime(c, piece, k, 3, a);
    for (int j = 0; j < 3; ++j) {
      const SmallPoly b = TimesPower(q[j], 4, 1.0);  // w^4 q = sdot^2
      out->vel[a][j] = Multiply(Multiply(f1, f1), b);
      out->acc[a][j] = Sum(Multiply(f1, sddot[j]), Multiply(f2, b));
      out->jerk[a][j] = Sum(Sum(Multiply(f1, j1[j]), Multiply(f2, j2[j])), Multiply(f3, TimesPower(q[j], 6, 1.0)));
    }
  }
  return true;
}

// The Lagrange basis on u = 0, 1/2, 1 (Basis) in Bernstein form of degree 2, and its derivatives
// (BasisDerivative) in Bernstein form of degree 1.
constexpr double kBasisBernstein[3][3] = {{1.0, -0.5, 0.0}, {0.0, 2.0, 0.0}, {0.0, -0.5, 1.0}};
constexpr double kBasisDerivativeBernstein[3][2] = {{-3.0, 1.0}, {4.0, -4.0}, {-1.0, 3.0}};

// z[j] += scale x L_j in Bernstein form for the three basis functions, x of degree n (z of degree
// n + 2): the product's coefficient k is alpha_k l0 x_k + beta_k l1 x_{k-1} + gamma_k l2 x_{k-2},
// with C(n, k) / C(n + 2, k), 2 C(n, k - 1) / C(n + 2, k) and C(n, k - 2) / C(n + 2, k); with the
// basis' Bernstein coefficients (kBasisBernstein) that is a - b / 2, 2 b and g - b / 2.
// kAssign: z[j] = ... instead (its n + 3 coefficients; no separate clearing, which compiled to a
// slow `rep stos` for these few values).
template <bool kAssign = false>
void AddTimesBasis(const double* x, int n, double scale, double (*z)[internal::kMaxSmallPoly]) {
  const double inv = scale / ((n + 2.0) * (n + 1.0));
  for (int k = 0; k <= n + 2; ++k) {
    const double a = k <= n ? (n + 2.0 - k) * (n + 1.0 - k) * inv * x[k] : 0.0;
    const double b = k >= 1 && k - 1 <= n ? 2.0 * k * (n + 2.0 - k) * inv * x[k - 1] : 0.0;
    const double g = k >= 2 ? k * (k - 1.0) * inv * x[k - 2] : 0.0;
    z[0][k] = (kAssign ? 0.0 : z[0][k]) + (a - 0.5 * b);
    z[1][k] = (kAssign ? 0.0 : z[1][k]) + 2.0 * b;
    z[2][k] = (kAssign ? 0.0 : z[2][k]) + (g - 0.5 * b);
  }
}
static_assert(kBasisBernstein[0][0] == 1.0 && kBasisBernstein[0][1] == -0.5 && kBasisBernstein[0][2] == 0.0 &&
                  kBasisBernstein[1][0] == 0.0 && kBasisBernstein[1][1] == 2.0 && kBasisBernstein[1][2] == 0.0 &&
                  kBasisBernstein[2][0] == 0.0 && kBasisBernstein[2][1] == -0.5 && kBasisBernstein[2][2] == 1.0,
              "AddTimesBasis folds these coefficients");

// z[j] += scale x L_j' likewise (z of degree n + 1): coefficient k is
// ((n + 1 - k) d0 x_k + k d1 x_{k-1}) / (n + 1).
// kAssign as for AddTimesBasis (n + 2 coefficients).
template <bool kAssign = false>
void AddTimesBasisDerivative(const double* x, int n, double scale, double (*z)[internal::kMaxSmallPoly]) {
  const double inv = scale / (n + 1.0);
  for (int k = 0; k <= n + 1; ++k) {
    const double p = k <= n ? (n + 1.0 - k) * inv * x[k] : 0.0;
    const double q = k >= 1 ? k * inv * x[k - 1] : 0.0;
    for (int j = 0; j < 3; ++j) {
      z[j][k] = (kAssign ? 0.0 : z[j][k]) + (kBasisDerivativeBernstein[j][0] * p + kBasisDerivativeBernstein[j][1] * q);
    }
  }
}

// Relative room left below a bound before a row counts as implied by others (rounding: the bounds
// below come from the cell's polynomials, the solver's from the curve).
constexpr double kImpliedMargin = 1e-9;

// An upper bound of b at each of a regular cell's three half-grid values (from g0) for every
// answer of the structured path: the fixed value, or the point velocity bound min_a vmax_a^2 /
// f'_a^2 that the solver keeps in every solve (BoundByPointVelocity in jerk_solver.cpp; an axis
// whose tangent may count as vanishing there bounds nothing), else infinity. tangent: f' on the
// cell per axis, in u.
void PointVelocityBounds(const JerkContext& c, int g0, const SmallPoly (&tangent)[3], double (&upper)[3]) {
  const TemporalLimits& limits = c.problem.limits;
  for (int j = 0; j < 3; ++j) {
    const GridValue& v = c.d.grid[static_cast<size_t>(g0 + j)];
    upper[j] = std::numeric_limits<double>::infinity();
    if (v.var < 0) {
      upper[j] = v.fixed;
      continue;
    }
    const double u = 0.5 * j;
    for (int a = 0; a < 3; ++a) {
      double t = 0.0;
      for (Eigen::Index i = tangent[a].size() - 1; i >= 0; --i) t = t * u + tangent[a](i);
      if (!(std::abs(t) > 2.0 * c.problem.zero_tangent_tolerance)) continue;
      upper[j] = std::min(upper[j], limits.max_velocity(a) * limits.max_velocity(a) / (t * t));
    }
  }
}

// A regular cell's velocity and acceleration rows and jerk templates on axis a: the templates'
// case of AddCellRows without the quadrotor's limits, the same rows in the same order. Here in
// Bernstein form: the curve's first three derivatives on the cell (q, p2, p3) and q^2 are
// converted once and every row family is a product with the basis, where AddCellRows multiplies
// power forms and converts each product (about half of the templates' instructions). False, with
// nothing added, unless the sizes are those of one polynomial and its derivatives with q of
// degree 2 or more: AddCellRows then writes the rows itself.
bool AddRegularAxisTemplates(JerkContext& c, int g0, double ds, int a, const SmallPoly& q, const SmallPoly& p2,
                             const SmallPoly& p3, const double (&upper)[3]) {
  constexpr int kN = internal::kMaxSmallPoly;
  const int dq = static_cast<int>(q.size()) - 1;
  if (dq < 2 || p2.size() != dq || p3.size() != dq - 1 || 2 * dq + 3 > kN) return false;
  const TemporalLimits& limits = c.problem.limits;
  const double vmax2 = limits.max_velocity(a) * limits.max_velocity(a);
  const double amax = limits.max_acceleration(a), jmax = (*limits.max_jerk)(a);
  const SmallPoly bq = c.bernstein.Convert(q), b2 = c.bernstein.Convert(p2), b3 = c.bernstein.Convert(p3);
  double w[3][kN];
  // The rows sign w_i . (b0, bm, b1) <= bound for each coefficient i (both signs when two_sided).
  const auto rows = [&](int size, bool two_sided, double bound, LinearRow::Kind kind) {
    for (const double sign : {1.0, -1.0}) {
      if (sign < 0.0 && !two_sided) break;
      for (int i = 0; i < size; ++i) {
        const double v[3] = {sign * w[0][i], sign * w[1][i], sign * w[2][i]};
        if (v[0] <= 0.0 && v[1] <= 0.0 && v[2] <= 0.0) continue;  // holds for b >= 0
        // Implied where 0 <= b <= upper (the point velocity bounds, which every solve of the
        // structured path keeps): left out (on the benchmark's curves, 60% of the velocity rows).
        double most = 0.0;
        for (int j = 0; j < 3; ++j) most += std::max(v[j], 0.0) * upper[j];
        if (most <= (1.0 - kImpliedMargin) * bound) continue;
        // Written in place, field by field (a row built on the stack and copied whole stalled on
        // store forwarding: a fifth of this function's time).
        internal::GridRow& row = c.templates->cell_rows.emplace_back();
        row.g0 = g0;
        row.kind = kind;
        for (int j = 0; j < 3; ++j) row.coef[static_cast<size_t>(j)] = v[j] / bound;
      }
    }
  };
  if (std::isfinite(vmax2)) {
    // v^2 = q^2 b, of degree 2 dq + 2.
    const SmallPoly q2 = c.bernstein.Convert(Multiply(q, q));
    AddTimesBasis<true>(q2.data(), 2 * dq, 1.0, w);
    rows(2 * dq + 3, false, vmax2, LinearRow::Kind::kVelocity);
  }
  if (std::isfinite(amax)) {
    // q b' / (2 ds) + p2 b, of degree dq + 1.
    AddTimesBasisDerivative<true>(bq.data(), dq, 1.0 / (2.0 * ds), w);
    AddTimesBasis(b2.data(), dq - 1, 1.0, w);
    rows(dq + 2, true, amax, LinearRow::Kind::kAcceleration);
  }
  // The jerk's factor q b'' / (2 ds^2) + 3 p2 b' / (2 ds) + p3 b, of degree dq.
  const int size = dq + 1;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < size; ++i) w[j][i] = bq(i) * (kBasisSecond[j] / (2.0 * ds * ds));
  }
  AddTimesBasisDerivative(b2.data(), dq - 1, 3.0 / (2.0 * ds), w);
  AddTimesBasis(b3.data(), dq - 2, 1.0, w);
  if (c.basis_size != size) {
    for (int j = 0; j < 3; ++j) c.basis_bernstein[j] = c.bernstein.Convert(Padded(Basis(j), size));
    c.basis_size = size;
  }
  for (const double sign : {1.0, -1.0}) {
    for (int i = 0; i < size; ++i) {
      internal::JerkRowTemplate& t = c.templates->jerk_rows.emplace_back();  // in place, as above
      t.g0 = g0;
      for (int j = 0; j < 3; ++j) {
        t.a[static_cast<size_t>(j)] = sign * w[j][i] / jmax;
        t.basis[static_cast<size_t>(j)] = c.basis_bernstein[j](i);
      }
      t.thin = static_cast<std::int8_t>(i % 2 == 1 && i + 1 < size);
    }
  }
  return true;
}

// The velocity, acceleration and jerk rows of a regular cell (b quadratic in u through its three
// half-grid values), or of a rest cell given its RestPolys (b = w^4 q, q linear; see above): the
// same rows over the cell's three values, from the polynomials of each.
void AddCellRows(JerkContext& c, int piece, int k, JerkRows mode, const std::vector<double>* lin,
                 const RestPolys* rest) {
  const int g0 = c.Half(piece, 2 * k);
  const TemporalLimits& limits = c.problem.limits;
  const double ds = c.Len(piece, k);
  if (c.templates != nullptr && mode == JerkRows::kNone) c.templates->cells.push_back(g0);
  if (rest == nullptr) {
    // b >= 0 on the whole cell: its Bernstein coefficients b0, 2 bm - (b0 + b1) / 2, b1 (the end
    // values are >= 0 already).
    c.row.Add(g0 + 1, -2.0);
    c.row.Add(g0, 0.5);
    c.row.Add(g0 + 2, 0.5);
  } else {
    c.row.Add(g0 + kRestAlpha, -1.0);  // q >= 0 on the cell: alpha >= 0 (b_far is)
  }
  c.row.Finish(LinearRow::Kind::kVelocity, -kInf, 0.0, [&] { return std::string("b >= 0"); });
  // The quantity under the jerk's square root per value: b's basis, or a rest cell's q.
  SmallPoly root_basis[3];
  for (int j = 0; j < 3; ++j) root_basis[j] = rest == nullptr ? Basis(j) : rest->q[j];

  // The quadrotor's limits: the speed's polynomials summed over axes, the acceleration's per axis.
  const bool quadrotor = limits.HasNormLimits();
  SmallPoly speed[3], acceleration[3][3];  // [grid value], [axis][grid value]
  for (int j = 0; j < 3; ++j) speed[j] = SmallPoly::Zero(1);
  const bool as_templates = rest == nullptr && c.templates != nullptr && mode == JerkRows::kNone && !quadrotor;
  SmallPoly tangent[3];
  for (int a = 0; a < 3; ++a) tangent[a] = c.OnCell(piece, k, 1, a);
  double upper[3];
  if (as_templates) PointVelocityBounds(c, g0, tangent, upper);
  for (int a = 0; a < 3; ++a) {
    const SmallPoly& q = tangent[a];
    const SmallPoly p2 = c.OnCell(piece, k, 2, a);
    const SmallPoly p3 = c.OnCell(piece, k, 3, a);
    if (as_templates && AddRegularAxisTemplates(c, g0, ds, a, q, p2, p3, upper)) continue;
    const double vmax2 = limits.max_velocity(a) * limits.max_velocity(a);
    const double amax = limits.max_acceleration(a), jmax = (*limits.max_jerk)(a);
    SmallPoly vel[3], acc[3], jerk[3];
    const SmallPoly q2 = Multiply(q, q);
    for (int j = 0; j < 3 && rest != nullptr; ++j) {
      vel[j] = rest->vel[a][j];
      acc[j] = rest->acc[a][j];
      jerk[j] = rest->jerk[a][j];
      if (quadrotor) {
        const int size = static_cast<int>(std::max(speed[j].size(), vel[j].size()));
        speed[j] = Padded(speed[j], size) + Padded(vel[j], size);
        acceleration[a][j] = acc[j];
      }
    }
    for (int j = 0; j < 3 && rest == nullptr; ++j) {
      vel[j] = Multiply(q2, Basis(j));
      acc[j] = Padded(Multiply(q, BasisDerivative(j)) / (2.0 * ds), 0);
      const SmallPoly curvature = Multiply(p2, Basis(j));
      const int size = static_cast<int>(std::max(acc[j].size(), curvature.size()));
      acc[j] = Padded(acc[j], size) + Padded(curvature, size);
      const SmallPoly j1 = q * (kBasisSecond[j] / (2.0 * ds * ds));
      const SmallPoly j2 = Multiply(p2, BasisDerivative(j)) * (3.0 / (2.0 * ds));
      const SmallPoly j3 = Multiply(p3, Basis(j));
      const int js = static_cast<int>(std::max({j1.size(), j2.size(), j3.size()}));
      jerk[j] = Padded(j1, js) + Padded(j2, js) + Padded(j3, js);
      if (quadrotor) {
        const int size = static_cast<int>(std::max(speed[j].size(), vel[j].size()));
        speed[j] = Padded(speed[j], size) + Padded(vel[j], size);
        acceleration[a][j] = acc[j];
      }
    }
    // Every row of one kind in a common degree, converted to Bernstein form per grid value.
    // The rows sign * polys <= bound (both signs when two_sided) on the cell's Bernstein
    // coefficients, converted once.
    const auto emit = [&](SmallPoly(&polys)[3], bool two_sided, double bound, LinearRow::Kind kind) {
      int size = 0;
      for (int j = 0; j < 3; ++j) size = std::max<int>(size, static_cast<int>(polys[j].size()));
      size = std::max(size, 3);
      SmallPoly bern[3];
      for (int j = 0; j < 3; ++j) bern[j] = c.bernstein.Convert(Padded(polys[j], size));
      for (const double sign : {1.0, -1.0}) {
        if (sign < 0.0 && !two_sided) break;
        for (int i = 0; i < size; ++i) {
          const double w[3] = {sign * bern[0](i), sign * bern[1](i), sign * bern[2](i)};
          if (w[0] <= 0.0 && w[1] <= 0.0 && w[2] <= 0.0) continue;  // holds for b >= 0
          if (c.templates != nullptr) {
            // Over the cell's grid values, for the structured path (DiscretizeJerkLimitedTemplates).
            internal::GridRow row;
            row.g0 = g0;
            row.kind = kind;
            for (int j = 0; j < 3; ++j) row.coef[static_cast<size_t>(j)] = w[j] / bound;
            c.templates->cell_rows.push_back(row);
            continue;
          }
          for (int j = 0; j < 3; ++j) c.row.Add(g0 + j, w[j] / bound);
          c.row.Finish(kind, -kInf, 1.0, [&] {
            return std::string("a limit on axis ") + kAxisNames[a] + " in piece " + std::to_string(piece) + " cell " +
                   std::to_string(k);
          });
        }
      }
    };
    SmallPoly part_basis[3];
    const auto emit_part = [&](SmallPoly(&polys)[3], double sign, double kappa, double bound) {
      int size = 0;
      for (int j = 0; j < 3; ++j) size = std::max<int>(size, static_cast<int>(polys[j].size()));
      SmallPoly bern[3];
      for (int j = 0; j < 3; ++j) {
        bern[j] = c.bernstein.Convert(sign * Padded(polys[j], size) + kappa * Padded(part_basis[j], size));
      }
      for (int i = 0; i < size; ++i) {
        if (bern[0](i) <= 0.0 && bern[1](i) <= 0.0 && bern[2](i) <= 0.0) continue;
        for (int j = 0; j < 3; ++j) c.row.Add(g0 + j, bern[j](i) / bound);
        c.row.Finish(LinearRow::Kind::kJerk, -kInf, 1.0, [&] {
          return std::string("jerk on axis ") + kAxisNames[a] + " in piece " + std::to_string(piece) + " cell " +
                 std::to_string(k);
        });
      }
    };
    if (std::isfinite(vmax2)) emit(vel, false, vmax2, LinearRow::Kind::kVelocity);
    if (std::isfinite(amax)) {
      emit(acc, true, amax, LinearRow::Kind::kAcceleration);
    }
    if (mode == JerkRows::kExact) AddExactJerkRows(c, piece, k, jerk, root_basis, jmax);
    if (mode == JerkRows::kNone && c.templates != nullptr) {
      int size = 0;
      for (int j = 0; j < 3; ++j)
        size = std::max<int>(size, static_cast<int>(std::max(jerk[j].size(), root_basis[j].size())));
      // A regular cell's rows in Bernstein form over the whole cell (the basis depends on the size
      // alone: converted once per size); a rest cell's per part, below.
      SmallPoly bern_jerk[3], rest_bernstein[3];
      if (rest == nullptr) {
        for (int j = 0; j < 3; ++j) bern_jerk[j] = c.bernstein.Convert(Padded(jerk[j], size));
      }
      if (rest == nullptr && c.basis_size != size) {
        for (int j = 0; j < 3; ++j) c.basis_bernstein[j] = c.bernstein.Convert(Padded(Basis(j), size));
        c.basis_size = size;
      }
      const SmallPoly(&bern_basis)[3] = rest != nullptr ? rest_bernstein : c.basis_bernstein;
      const int parts = rest != nullptr ? kRestJerkParts : 1;
      for (int part = 0; part < parts; ++part) {
        const double w0 = static_cast<double>(part) / parts, w1 = (part + 1.0) / parts;
        if (rest != nullptr) {
          for (int j = 0; j < 3; ++j) {
            bern_jerk[j] = c.bernstein.Convert(Shifted(Padded(jerk[j], size), w0, w1 - w0));
            rest_bernstein[j] = c.bernstein.Convert(Shifted(Padded(root_basis[j], size), w0, w1 - w0));
          }
        }
        for (const double sign : {1.0, -1.0}) {
          for (int i = 0; i < size; ++i) {
            internal::JerkRowTemplate t;
            t.g0 = g0;
            if (rest != nullptr) {
              t.rest_far = static_cast<std::int8_t>(RestFar(c.d.shapes[static_cast<size_t>(piece * c.K + k)]));
              t.part = static_cast<std::int8_t>(part);
              t.parts = static_cast<std::int8_t>(parts);
            }
            for (int j = 0; j < 3; ++j) {
              t.a[static_cast<size_t>(j)] = sign * bern_jerk[j](i) / jmax;
              t.basis[static_cast<size_t>(j)] = bern_basis[j](i);
            }
            c.templates->jerk_rows.push_back(t);
          }
        }
      }
    }
    if (mode == JerkRows::kLinearized) {
      // The jerk rows on kJerkSegments equal parts of the cell, each linearized at the previous
      // solution's largest b on that part. One part: on the S-curve line (v 4, a 3, j 10) four
      // parts gave the same T to 6 digits at K = 20..200, took 2-3 x longer and ended some
      // solves at reduced accuracy.
      const double lb[3] = {(*lin)[static_cast<size_t>(g0)], (*lin)[static_cast<size_t>(g0 + 1)],
                            (*lin)[static_cast<size_t>(g0 + 2)]};
      const auto previous_b = [&](double u) {
        return lb[0] * (1 - u) * (1 - 2 * u) + lb[1] * 4 * u * (1 - u) + lb[2] * u * (2 * u - 1);
      };
      const int parts = rest != nullptr ? kRestJerkParts : kJerkSegments;
      for (int part = 0; part < parts; ++part) {
        const double u0 = static_cast<double>(part) / parts, u1 = (part + 1.0) / parts;
        double b = std::max(previous_b(u0), previous_b(u1));
        if (rest != nullptr) {
          // A rest cell's q is linear: its largest value on the part is at an end of it.
          const double alpha = lb[kRestAlpha], far = lb[RestFar(c.d.shapes[static_cast<size_t>(piece * c.K + k)])];
          b = std::max(alpha + (far - alpha) * u0, alpha + (far - alpha) * u1);
        }
        // The quadratic's vertex inside the part.
        const double c2 = 2.0 * (lb[0] - 2.0 * lb[1] + lb[2]), c1 = -3.0 * lb[0] + 4.0 * lb[1] - lb[2];
        if (c2 < 0.0 && rest == nullptr) {
          const double vertex = -c1 / (2.0 * c2);
          if (vertex > u0 && vertex < u1) b = std::max(b, previous_b(vertex));
        }
        // Never linearize at b near 0: the tangent would be nearly vertical and its row badly
        // scaled (a floor of 1e-12 made the conic solver stall). Any b > 0 keeps the row
        // conservative; below bbar_floor the rows only loosen.
        b = std::max(b, c.bbar_floor);
        static_assert(kJerkSegments == 1, "LinearizationPoint is the one-part rule");
        const double kappa = jmax / (2.0 * b * std::sqrt(b));
        const double bound = 3.0 * jmax / (2.0 * std::sqrt(b));
        SmallPoly part_jerk[3];
        for (int j = 0; j < 3; ++j) {
          part_jerk[j] = Shifted(jerk[j], u0, u1 - u0);
          const SmallPoly basis = Shifted(root_basis[j], u0, u1 - u0);
          const int size = static_cast<int>(std::max(part_jerk[j].size(), basis.size()));
          part_basis[j] = Padded(basis, size);
          part_jerk[j] = Padded(part_jerk[j], size);
        }
        emit_part(part_jerk, 1.0, kappa, bound);
        emit_part(part_jerk, -1.0, kappa, bound);
      }
    }
  }
  if (quadrotor) AddQuadrotorCellRows(c, piece, k, speed, acceleration);
}

// True when every point of `piece` lies on one line (its coefficients of degree >= 1 all parallel,
// up to rounding), so that its derivatives of every order point along its tangent.
bool StraightPiece(const PolynomialPiece& piece) {
  const auto& c = piece.coefficients();
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 1; k < c.cols(); ++k) {
    if (c.col(k).norm() > direction.norm()) direction = c.col(k);
  }
  if (!(direction.norm() > 0.0)) return false;
  direction.normalize();
  for (Eigen::Index k = 1; k < c.cols(); ++k) {
    const Eigen::Vector3d v = c.col(k);
    if ((v - v.dot(direction) * direction).norm() > 1e-12 * std::max(v.norm(), c.rightCols(c.cols() - 1).norm()))
      return false;
  }
  return true;
}

// The boundary acceleration at the start (end = false) or end of the path.
void AddBoundaryAcceleration(JerkContext& c, bool end) {
  const TemporalProblem& p = c.problem;
  const int m = p.curve.num_pieces();
  const int piece = end ? m - 1 : 0;
  const int k = end ? c.K - 1 : 0;
  const double s = end ? 1.0 : 0.0;
  const CellShape shape = c.d.shapes[static_cast<size_t>(piece * c.K + k)];
  if (shape == (end ? CellShape::kRestEnd : CellShape::kRestStart)) return;  // at rest, acc = 0
  const std::string field = end ? "boundary.end_acceleration" : "boundary.start_acceleration";
  const Eigen::Vector3d acc = end ? p.boundary.end_acceleration : p.boundary.start_acceleration;
  const Eigen::Vector3d f1 = p.curve.Evaluate(piece, s, 1), f2 = p.curve.Evaluate(piece, s, 2);
  const int g = end ? c.Half(piece, 2 * c.K) : c.Half(piece, 0);
  const GridValue& v = c.d.grid[static_cast<size_t>(g)];
  const auto infeasible = [&](const std::string& why) {
    if (!c.d.infeasible_reason) c.d.infeasible_reason = field + " cannot be reached: " + why;
  };
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(acc(axis)) > p.limits.max_acceleration(axis) * (1.0 + internal::kConstantRowSlack)) {
      std::ostringstream ss;
      ss << acc(axis) << " m/s^2 on axis " << internal::kAxisNames[axis] << " is above its limit "
         << p.limits.max_acceleration(axis) << " m/s^2";
      infeasible(ss.str());
      return;
    }
  }
  if (f1.norm() > p.zero_tangent_tolerance) {
    // b is fixed by the boundary velocity; the part across the path is f'' b.
    const double b = v.fixed;
    const Eigen::Vector3d unit = f1.normalized();
    const Eigen::Vector3d rest = acc - f2 * b;
    const Eigen::Vector3d across = rest - rest.dot(unit) * unit;
    const double scale = std::max({acc.norm(), f2.norm() * b, 1e-12});
    if (across.norm() > kNormalTolerance * scale) {
      std::ostringstream ss;
      ss << "across the path it must be " << (f2 * b - (f2 * b).dot(unit) * unit).transpose()
         << " m/s^2 (the curvature at this speed), got " << (acc - acc.dot(unit) * unit).transpose();
      infeasible(ss.str());
      return;
    }
    AddCellAcceleration(c, piece, k, end, 1.0);
    const double a = rest.dot(f1) / f1.squaredNorm();
    if (!c.d.infeasible_reason && StraightPiece(p.curve.piece(piece))) {
      // On a straight piece the jerk lies along the path, at most j_t = min over axes of j / |u|
      // (u the unit tangent). A start braking at |a| (or an end reached while speeding up, in
      // reverse) gets its acceleration back to 0 no sooner than |a| / j_t, and meanwhile slows by at
      // least a^2 / (2 j_t): below that speed the vehicle would have to reverse.
      const double a_path = (end ? 1.0 : -1.0) * acc.dot(unit);  // > 0: braking away from the end
      const double speed = f1.norm();
      const double j = internal::LimitAlong(*p.limits.max_jerk, unit);
      const double v_path = std::sqrt(b) * speed;
      if (a_path > 0.0 && std::isfinite(j) && v_path < a_path * a_path / (2.0 * j) * (1.0 - 1e-9)) {
        std::ostringstream ss;
        ss << field << " cannot be flown: at " << v_path << " m/s with " << a_path << " m/s^2 "
           << (end ? "of speeding up into the end" : "of braking") << " along a straight path and a jerk limit of " << j
           << " m/s^3 along it, the speed reaches 0 before the acceleration does (it needs at least "
           << a_path * a_path / (2.0 * j) << " m/s)";
        c.d.infeasible_reason = ss.str();
      }
    }
    c.boundary_sddot[end ? 1 : 0] = a;
    c.row.Finish(LinearRow::Kind::kBoundaryAcceleration, a, a, [&] { return field; });
    return;
  }
  // Vanishing tangent: acc = f'' b whatever sddot is.
  if (f2.norm() <= p.zero_tangent_tolerance) {
    if (acc.norm() > 1e-9) infeasible("the curve's first and second derivatives vanish there, so only 0 is possible");
    return;
  }
  const double b = acc.dot(f2) / f2.squaredNorm();
  if (b < 0.0 || (acc - f2 * b).norm() > kNormalTolerance * std::max(acc.norm(), 1e-12)) {
    infeasible("the tangent vanishes there, so it must be a non-negative multiple of f''");
    return;
  }
  c.row.Add(g, 1.0);
  c.row.Finish(LinearRow::Kind::kBoundaryAcceleration, b, b, [&] { return field; });
  c.boundary_b[end ? 1 : 0] = b;
}

// A rest cell of length h at the start (end = false) or end of piece i with a constant s-jerk: per
// axis its jerk is b1^1.5 (f' 2 / (9 h^2) +- f'' 2 sigma^3 / h + f''' sigma^6) (see
// AddConstantJerkRestRows). Each relative to the axis' limit, and taken over the axes at a point:
// at the rest point (sigma = 0) and its lowest value anywhere on the cell, both over its largest
// value anywhere on the cell. On a line both are 1. Where the curvature makes the jerk grow through
// the cell, the start keeps only the share at_rest of its jerk limit; where it makes the jerk fall,
// the optimum raises its s-jerk there. Sampled at 33 points (they only size the cell; the rows bound
// the jerk exactly).
struct RestJerkShares {
  double at_rest = 1.0;
  double lowest = 1.0;
};
RestJerkShares RestJerkShare(const TemporalProblem& p, int piece, bool end, double h) {
  const double sign = end ? -1.0 : 1.0;
  double at_rest = 0.0, largest = 0.0, lowest = kInf;
  for (int q = 0; q <= 32; ++q) {
    double here = 0.0;
    const double sigma = q / 32.0, sigma3 = sigma * sigma * sigma;
    const double s = end ? 1.0 - h * sigma3 : h * sigma3;
    const Eigen::Vector3d f1 = p.curve.Evaluate(piece, s, 1), f2 = p.curve.Evaluate(piece, s, 2);
    const Eigen::Vector3d f3 = p.curve.Evaluate(piece, s, 3);
    for (int a = 0; a < 3; ++a) {
      const double jerk =
          std::abs(f1(a) * 2.0 / (9.0 * h * h) + sign * f2(a) * 2.0 * sigma3 / h + f3(a) * sigma3 * sigma3);
      const double share = jerk / (*p.limits.max_jerk)(a);
      largest = std::max(largest, share);
      here = std::max(here, share);
    }
    if (q == 0) at_rest = here;
    lowest = std::min(lowest, here);
  }
  RestJerkShares r;
  if (largest > 0.0) {
    r.at_rest = at_rest / largest;
    r.lowest = lowest / largest;
  }
  return r;
}

// Cell edges of a piece in [0, 1]: K cells, with a rest cell at an end that is a rest point sized
// to the ramp from rest (RampLength): there the vehicle moves with constant s-jerk over the whole
// cell, which is exactly the jerk-saturated start along a line, and sddot grows like s^(1/3), which
// cells with sddot linear in s follow badly (one line per cell keeps the jerk below its limit over
// most of the cell). Measured against the closed form on lines (v 4, a 3, j 10) of 10 m, 2 m (v not
// reached) and 0.5 m (a not reached either), at K = 50 / 200: +0.012 / +0.0014%, +0.031 / +0.0058%
// and +0.53 / +0.13%. The previous rule, a rest cell of ~1/256 of the piece whatever the limits
// (graded by halving), gave +0.39 / +0.07% and +0.77 / +0.78% on the first two: on the 2 m line
// the ramp spans 4.5 cells at K = 200, where the jerk reached only 70-85% of its limit.
// The part of piece i (in s) that a jerk-limited start from rest at its start (end = false) or a
// stop at its end takes to build up its acceleration: along the tangent u at that point, the
// limits are v = min_axis vmax / |u_axis| (and so on); the jerk-saturated ramp reaches
// a_p = min(a, sqrt(v j)) after a_p^3 / (6 j^2) metres, which is |f'| times as much in s. On a
// line this is exactly where the constant s-jerk of a rest cell ends. 0 when the tangent vanishes.
double RampLength(const TemporalProblem& p, int piece, bool end, bool rest_to_rest) {
  const Eigen::Vector3d f1 = p.curve.Evaluate(piece, end ? 1.0 : 0.0, 1);
  const double speed = f1.norm();
  if (!(speed > p.zero_tangent_tolerance)) return 0.0;
  const Eigen::Vector3d unit = f1 / speed;
  double v = internal::LimitAlong(p.limits.max_velocity, unit);
  double a = internal::LimitAlong(p.limits.max_acceleration, unit);
  const double j = internal::LimitAlong(*p.limits.max_jerk, unit);
  // The quadrotor's limits on an acceleration a w along w = the tangent (leaving rest) or minus it
  // (reaching rest): ||a w + g e3||^2 = a^2 + 2 a g w_z + g^2 <= max_thrust^2, a w_z + g >= min_thrust,
  // and along a level w the tilt allows g tan(tilt).
  if (p.limits.max_speed) v = std::min(v, *p.limits.max_speed);
  if (p.limits.max_acceleration_norm) a = std::min(a, *p.limits.max_acceleration_norm);
  const double g = p.limits.gravity;
  const Eigen::Vector3d w = (end ? -1.0 : 1.0) * f1 / speed;
  if (p.limits.max_thrust) {
    const double T = *p.limits.max_thrust;
    a = std::min(a, -g * w(2) + std::sqrt(std::max(0.0, T * T - g * g * (1.0 - w(2) * w(2)))));
  }
  if (p.limits.min_thrust && w(2) < -1e-12) a = std::min(a, (g - *p.limits.min_thrust) / -w(2));
  if (p.limits.max_tilt) {
    const double level = Eigen::Vector2d(w(0), w(1)).norm();
    if (level > 1e-12) a = std::min(a, g * std::tan(*p.limits.max_tilt) / level);
  }
  if (!(a > 0.0)) return 0.0;
  // A curved start cannot go faster than its curvature kappa allows: |f'' across| = kappa v^2 <= a.
  const Eigen::Vector3d f2 = p.curve.Evaluate(piece, end ? 1.0 : 0.0, 2);
  const double kappa = f1.cross(f2).norm() / (speed * speed * speed);
  if (kappa > 0.0) v = std::min(v, std::sqrt(a / kappa));
  double peak = std::min(a, std::sqrt(v * j));
  if (rest_to_rest) {
    // From rest to rest within the piece, a line of length P peaks at (P j^2 / 2)^(1/3) (jerk +j,
    // -j, -j, +j over equal times) when neither a nor v is reached. P from |f'| at 16 midpoints.
    peak = std::min(peak, std::cbrt(0.5 * internal::PieceLengthEstimate(p.curve, piece) * j * j));
  }
  const double length = peak * peak * peak / (6.0 * j * j);
  return std::isfinite(length) ? length / speed : 0.0;
}

// The rest cell at the start (end = false) or end of piece i: the ramp from rest (RampLength),
// halved (at most 5 times) until a constant s-jerk over it keeps at least kRestJerkShare of the
// jerk limit at the rest point (on a curve the terms of f'' and f''' grow through the cell) and
// nowhere less than kRestJerkSlack of its largest value (where they fall, the optimum's s-jerk
// grows).
struct RestSize {
  double cell = 0.0;  // the rest cell's length in s (0: none)
  bool halved = false;
  bool curved = false;   // a constant s-jerk over the cell keeps less than kCurvedRestShare somewhere
  bool braking = false;  // not a rest cell: the first cell of a braking start (BrakeCellSize)
};
RestSize RestCellSize(const TemporalProblem& p, int piece, bool end, bool rest_to_rest) {
  RestSize r;
  r.cell = RampLength(p, piece, end, rest_to_rest);
  if (!(r.cell > 0.0)) return r;
  RestJerkShares shares = RestJerkShare(p, piece, end, std::min(r.cell, kLargestRestCell));
  for (int halving = 0; halving < 5 && (shares.at_rest < kRestJerkShare || shares.lowest < kRestJerkSlack); ++halving) {
    r.cell *= 0.5;
    r.halved = true;
    shares = RestJerkShare(p, piece, end, std::min(r.cell, kLargestRestCell));
  }
  r.curved = std::min(shares.at_rest, shares.lowest) < kCurvedRestShare;
  return r;
}

// The first cell of a start in motion that brakes along the path (sddot < 0 at b0 = sdot^2 > 0), or
// the last one of an end reached while still speeding up: b falls from b0 with slope 2 sddot, and
// a quadratic cell of length h keeps its middle Bernstein coefficient b0 - |sddot| h (the row
// b >= 0) non-negative only while h <= b0 / |sddot|. A longer cell cannot brake at all: a start at
// 0.5 m/s braking at 2 m/s^2 with a jerk limit of 10 (flyable: it slows to 0.3 m/s) was called
// infeasible at K = 50 on a 10 m line (cells of 0.2 m against 0.125 m). So that cell is
// kBrakeCellShare of the bound (and a share of the braking phase, below), and the cells after it
// grow as after a halved rest cell. None (cell 0) where the end does not brake, where that cell
// would be a nominal one or more, or where a nominal cell can brake and the grading is dear (below).
RestSize BrakeCellSize(const TemporalProblem& p, int piece, bool end, int K) {
  RestSize r;
  const Eigen::Vector3d v = end ? p.boundary.end_velocity : p.boundary.start_velocity;
  const Eigen::Vector3d acc = end ? p.boundary.end_acceleration : p.boundary.start_acceleration;
  const Eigen::Vector3d f1 = p.curve.Evaluate(piece, end ? 1.0 : 0.0, 1),
                        f2 = p.curve.Evaluate(piece, end ? 1.0 : 0.0, 2);
  const double t2 = f1.squaredNorm();
  if (!(std::sqrt(t2) > p.zero_tangent_tolerance) || !(v.squaredNorm() > 0.0)) return r;
  const double b = v.squaredNorm() / t2;
  const double sddot = (acc - f2 * b).dot(f1) / t2;
  const double slope_against = end ? sddot : -sddot;  // > 0: b falls away from the end
  if (!(slope_against > 0.0) || !std::isfinite(b / slope_against)) return r;
  // The braking phase along the tangent: the jerk limit along it brings sddot back to 0 in
  // t = |a| / j, over v t - |a| t^2 / 2 + j t^3 / 6 metres; in a quadratic cell the s-jerk is at
  // most j / (the cell's largest sdot), so that phase needs cells of a fraction of its length.
  const double speed = std::sqrt(t2);
  const double j = internal::LimitAlong(*p.limits.max_jerk, f1 / speed);
  // The braking along the path, m/s^2 (the acceleration's tangential part), and the speed, m/s.
  const double a_path = (end ? 1.0 : -1.0) * acc.dot(f1) / speed, v_path = std::sqrt(b) * speed;
  const double must = kBrakeCellShare * b / slope_against;
  double h = must;
  if (std::isfinite(j) && j > 0.0 && a_path > 0.0) {
    const double t = a_path / j;
    const double phase = std::max(0.0, v_path * t - 0.5 * a_path * t * t + j * t * t * t / 6.0) / speed;
    h = std::min(h, kBrakePhaseShare * phase);
  }
  if (!(h > 0.0) || !(h < 1.0 / K)) return r;
  // Where a nominal cell can brake, only if the grading back to it takes at most K / 6 cells: they
  // come from the rest of the piece (at K = 20, 1 m/s braking at 1 m/s^2 on a 10 m line took 4.16 s
  // with 6 graded cells, 4.00 s without; at K = 200, 0.5 m/s at 2 m/s^2 took 4.29 s without them,
  // 4.23 s with them).
  if (!(must < 1.0 / K) && std::log(1.0 / (K * h)) / std::log(kRestGrading) > kBrakeGradingShare * K) return r;
  r.cell = h;
  r.halved = true;
  r.braking = true;
  return r;
}

std::vector<double> CellEdges(int K, const RestSize& rest_start, const RestSize& rest_end) {
  const double ds = 1.0 / K;
  // The cells of one end, from the rest point on. A rest cell halved below its ramp (RestSize), or
  // one on a curve longer than a nominal cell and cut to one, is followed by cells whose edges grow
  // by kRestGrading up to the nominal cell, which carry on the ramp (sdot grows like the time
  // squared there, and a cell whose ends differ much in sdot holds its jerk well below the limit at
  // its start). Otherwise, a ramp of at least half a nominal cell gets one rest cell of its length
  // (at most a quarter of the piece); a shorter one h, h, 2 h, ..., 2^(n-1) h with the last one
  // widened so that they sum to ds. At most K / 3 cells per end.
  const auto graded = [&](const RestSize& rest) {
    std::vector<double> g;
    double h = rest.cell;
    if (!(h > 0.0) || K < 4) return g;
    if (rest.halved || (rest.curved && h > ds)) {
      g.push_back(
          std::min({std::max(h, (rest.braking ? kSmallestBrakeCell : kSmallestRestCell) * ds), ds, kLargestRestCell}));
      // Cells from edge e to kRestGrading e: each kRestGrading - 1 times the s already covered.
      // After a braking start's first cell they grow faster where that would not reach the nominal
      // cell within the K / 3 cells (kBrakeGradingRoom).
      double growth = kRestGrading;
      if (rest.braking && K / 3 > 1) {
        growth = std::max(growth, std::pow(kBrakeGradingRoom * ds / g.back(), 1.0 / (K / 3 - 1)));
      }
      for (double next = g.back() * (growth - 1.0); next < ds && static_cast<int>(g.size()) < K / 3; next *= growth) {
        g.push_back(next);
      }
      return g;
    }
    if (h >= 0.5 * ds) {
      g.push_back(std::min(h, kLargestRestCell));
      return g;
    }
    h = std::max(h, kSmallestRestCell * ds);
    const int n = std::min(static_cast<int>(std::floor(std::log2(ds / h))), K / 4 - 1);
    if (n < 1) return g;
    h = std::max(h, std::ldexp(ds, -n - 1));
    g.push_back(h);
    for (int j = 0; j < n; ++j) g.push_back(std::ldexp(h, j));
    double sum = 0.0;
    for (double c : g) sum += c;
    g.back() += ds - sum;
    return g;
  };
  std::vector<double> head = graded(rest_start), tail = graded(rest_end);
  std::reverse(tail.begin(), tail.end());
  double graded_length = 0.0;
  for (double h : head) graded_length += h;
  for (double h : tail) graded_length += h;
  const int uniform = K - static_cast<int>(head.size() + tail.size());
  const double middle_size = (1.0 - graded_length) / uniform;
  std::vector<double> edges(1, 0.0);
  for (double h : head) edges.push_back(edges.back() + h);
  for (int k = 0; k < uniform; ++k) edges.push_back(edges.back() + middle_size);
  for (double h : tail) edges.push_back(edges.back() + h);
  edges.back() = 1.0;
  return edges;
}

// A joint whose curvature jumps across the path cannot keep the acceleration continuous at
// speed: it becomes a stop.
void StopWhereCurvatureJumps(const TemporalProblem& p, TemporalDiscretization* d) {
  for (JointInfo& j : d->joints) {
    if (j.type == JointType::kStop) continue;
    const Eigen::Vector3d f1b = p.curve.Evaluate(j.joint + 1, 0.0, 1);
    const Eigen::Vector3d f2a = p.curve.Evaluate(j.joint, 1.0, 2);
    const Eigen::Vector3d f2b = p.curve.Evaluate(j.joint + 1, 0.0, 2);
    const double r2 = j.speed_ratio * j.speed_ratio;  // b after the joint over b before it
    const Eigen::Vector3d diff = f2a - r2 * f2b;
    const Eigen::Vector3d unit = f1b.normalized();
    const Eigen::Vector3d across = diff - diff.dot(unit) * unit;
    const double scale = std::max({f2a.norm(), r2 * f2b.norm(), f1b.squaredNorm() * 1e-6});
    if (across.norm() > kNormalTolerance * scale) j.type = JointType::kStop;
  }
}

TemporalDiscretization DiscretizeJerkLimitedImpl(const TemporalProblem& problem, JerkRows jerk_rows,
                                                 const std::vector<double>* linearization,
                                                 internal::JerkTemplates* templates);

}  // namespace

namespace internal {

double LinearizationPoint(const double (&lb)[3], double floor) {
  double b = std::max(lb[0], lb[2]);
  // The quadratic's vertex inside the cell.
  const double c2 = 2.0 * (lb[0] - 2.0 * lb[1] + lb[2]), c1 = -3.0 * lb[0] + 4.0 * lb[1] - lb[2];
  if (c2 < 0.0) {
    const double u = -c1 / (2.0 * c2);
    if (u > 0.0 && u < 1.0)
      b = std::max(b, lb[0] * (1 - u) * (1 - 2 * u) + lb[1] * 4 * u * (1 - u) + lb[2] * u * (2 * u - 1));
  }
  return std::max(b, floor);
}

namespace {
template <typename F>
void ForEachRestCell(const TemporalDiscretization& d, F f) {
  const int K = d.cells_per_piece / 2;
  for (int i = 0; i < d.num_pieces; ++i) {
    for (int k = 0; k < K; ++k) {
      const CellShape shape = d.shapes[static_cast<size_t>(i * K + k)];
      if (shape == CellShape::kQuadratic) continue;
      const size_t g0 = static_cast<size_t>(d.GridIndex(i, 2 * k));
      f(g0 + kRestAlpha, g0 + static_cast<size_t>(RestFar(shape)));
    }
  }
}
}  // namespace

void RestAlphaToMiddles(const TemporalDiscretization& d, std::vector<double>* b) {
  ForEachRestCell(d,
                  [&](size_t alpha, size_t far) { (*b)[alpha] = TemporalProfile::RestMiddle((*b)[alpha], (*b)[far]); });
}

void RestMiddlesToAlpha(const TemporalDiscretization& d, std::vector<double>* b) {
  ForEachRestCell(d, [&](size_t alpha, size_t far) {
    (*b)[alpha] = std::max(0.0, TemporalProfile::RestAlpha((*b)[alpha], (*b)[far]));
  });
}

void RestAlphaOfConstantJerk(const TemporalDiscretization& d, std::vector<double>* b) {
  ForEachRestCell(d, [&](size_t alpha, size_t far) { (*b)[alpha] = (*b)[far]; });
}

double LinearizationFloor(const std::vector<double>& linearization) {
  double largest = 0.0;
  for (double b : linearization) largest = std::max(largest, b);
  return std::max(kLinearizationFloor * largest, std::numeric_limits<double>::min());
}

TemporalDiscretization DiscretizeJerkLimitedTemplates(const TemporalProblem& problem, JerkTemplates* templates) {
  // Emptied, keeping their memory (a solver keeps its templates from one solve to the next).
  templates->cell_rows.clear();
  templates->jerk_rows.clear();
  templates->cells.clear();
  // Room for a regular cell's rows at the curve's largest degree, so that the vectors seldom grow
  // (each growth copied them and touched fresh pages: on the default plan both grew once): with
  // f' of degree dq, 3 (2 dq + 3) velocity and 6 (dq + 2) acceleration rows at most, and 6 (dq + 1)
  // jerk templates, and 256 more of each for rest cells, whose polynomials in w have about three
  // times the degree (on the benchmark's cubics their two rest cells took 54 and 156 more); where a
  // curve has more, the vectors grow in a solver's first solve only (it keeps them).
  int dq = 0;
  for (int i = 0; i < problem.curve.num_pieces(); ++i) dq = std::max(dq, problem.curve.piece(i).degree() - 1);
  const size_t cells = static_cast<size_t>(problem.curve.num_pieces()) * static_cast<size_t>(problem.cells_per_piece);
  templates->cell_rows.reserve(static_cast<size_t>(12 * dq + 21) * cells + 256);
  templates->jerk_rows.reserve(static_cast<size_t>(6 * dq + 6) * cells + 256);
  return DiscretizeJerkLimitedImpl(problem, JerkRows::kNone, nullptr, templates);
}

}  // namespace internal

TemporalDiscretization DiscretizeJerkLimited(const TemporalProblem& problem, JerkRows jerk_rows,
                                             const std::vector<double>* linearization) {
  return DiscretizeJerkLimitedImpl(problem, jerk_rows, linearization, nullptr);
}

namespace {

TemporalDiscretization DiscretizeJerkLimitedImpl(const TemporalProblem& problem, JerkRows jerk_rows,
                                                 const std::vector<double>* linearization,
                                                 internal::JerkTemplates* templates) {
  problem.Validate();
  if (!problem.limits.max_jerk) {
    throw std::invalid_argument("DiscretizeJerkLimited: limits.max_jerk is not set");
  }
  if ((jerk_rows == JerkRows::kLinearized) != (linearization != nullptr)) {
    throw std::invalid_argument(jerk_rows == JerkRows::kLinearized
                                    ? "DiscretizeJerkLimited: kLinearized needs a linearization"
                                    : "DiscretizeJerkLimited: a linearization is only used by kLinearized");
  }
  const int m = problem.curve.num_pieces();
  const int K = problem.cells_per_piece;
  // The shared stages run on the half grid: 2 K cells of ds / 2 per piece.
  TemporalProblem half = problem;
  half.cells_per_piece = 2 * K;
  TemporalDiscretization d;
  d.num_pieces = m;
  d.cells_per_piece = 2 * K;
  d.rho = problem.rho;
  d.jerk_limited = true;
  d.grid.resize(static_cast<size_t>(m) * static_cast<size_t>(2 * K + 1));
  if (linearization != nullptr && linearization->size() != d.grid.size()) {
    throw std::invalid_argument("DiscretizeJerkLimited: the linearization has " +
                                std::to_string(linearization->size()) + " values, expected " +
                                std::to_string(d.grid.size()));
  }
  internal::ClassifyJoints(half, &d);
  StopWhereCurvatureJumps(problem, &d);
  internal::AssignGridValues(half, &d);
  internal::MakeCells(half, &d);
  internal::CheckBoundaryAccelerations(problem, &d);

  JerkContext c{problem, d, RowBuilder(d), BernsteinTable(), K, 1.0 / K, 0.0, {}, templates, -1, {}, {}, {}};
  if (linearization != nullptr) c.bbar_floor = internal::LinearizationFloor(*linearization);
  for (int i = 0; i < m; ++i) {
    std::array<PolynomialPiece::Coefficients, 3> derivative;
    for (int order = 1; order <= 3; ++order) {
      const PolynomialPiece& piece = problem.curve.piece(i);
      derivative[static_cast<size_t>(order - 1)] =
          piece.degree() >= order ? piece.Derivative(order).coefficients() : PolynomialPiece::Coefficients();
    }
    c.derivatives.push_back(derivative);
  }

  // ---- cell shapes ----
  d.shapes.assign(static_cast<size_t>(m * K), CellShape::kQuadratic);
  for (int i = 0; i < m; ++i) {
    const bool rest_start = RestPoint(c, i, false), rest_end = RestPoint(c, i, true);
    if (rest_start && rest_end && K == 1) {
      if (!d.infeasible_reason) {
        d.infeasible_reason =
            "piece " + std::to_string(i) + " must leave rest and reach it again within one cell: use K >= 2";
      }
    }
    if (rest_start) d.shapes[static_cast<size_t>(i * K)] = CellShape::kRestStart;
    if (rest_end && !(rest_start && K == 1)) d.shapes[static_cast<size_t>(i * K + K - 1)] = CellShape::kRestEnd;
  }
  if (d.infeasible_reason) return d;
  // ---- graded cells; each half cell is half its cell ----
  d.cell_edges.resize(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) {
    const bool rest_start = d.shapes[static_cast<size_t>(i * K)] == CellShape::kRestStart;
    const bool rest_end = d.shapes[static_cast<size_t>(i * K + K - 1)] == CellShape::kRestEnd;
    d.cell_edges[static_cast<size_t>(i)] = CellEdges(K,
                                                     rest_start ? RestCellSize(problem, i, false, rest_end)
                                                     : i == 0   ? BrakeCellSize(problem, i, false, K)
                                                                : RestSize(),
                                                     rest_end     ? RestCellSize(problem, i, true, rest_start)
                                                     : i == m - 1 ? BrakeCellSize(problem, i, true, K)
                                                                  : RestSize());
    for (int k = 0; k < K; ++k) {
      const double half = 0.5 * c.Len(i, k);
      d.cells[static_cast<size_t>(2 * (i * K + k))].ds = half;
      d.cells[static_cast<size_t>(2 * (i * K + k) + 1)].ds = half;
    }
  }
  // Rest cells take 6 L / (sqrt(alpha) + sqrt(b_far)): the half cell between alpha (the middle
  // value) and b_far, of length L / 2, with weight 6; the one between the rest point and alpha with
  // weight 0 (RestPolys).
  for (size_t cell = 0; cell < d.shapes.size(); ++cell) {
    if (d.shapes[cell] == CellShape::kQuadratic) continue;
    const bool start = d.shapes[cell] == CellShape::kRestStart;
    d.cells[2 * cell].time_weight = start ? 0.0 : 6.0;
    d.cells[2 * cell + 1].time_weight = start ? 6.0 : 0.0;
  }

  // ---- rows of every cell ----
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k < K; ++k) {
      RestPolys rest;
      if (d.shapes[static_cast<size_t>(i * K + k)] == CellShape::kQuadratic) {
        AddCellRows(c, i, k, jerk_rows, linearization, nullptr);
      } else if (RestCellPolys(c, i, k, &rest)) {
        AddCellRows(c, i, k, jerk_rows, linearization, &rest);
      } else {
        AddConstantJerkRestRows(c, i, k);
      }
    }
  }

  // ---- sddot continuous between cells, and across joints without a stop ----
  for (int i = 0; i < m; ++i) {
    for (int k = 1; k < K; ++k) {
      AddCellAcceleration(c, i, k - 1, true, c.ds);
      AddCellAcceleration(c, i, k, false, -c.ds);
      c.row.Finish(LinearRow::Kind::kContinuity, 0.0, 0.0,
                   [&] { return "sddot continuity in piece " + std::to_string(i) + " at cell " + std::to_string(k); });
    }
  }
  for (const JointInfo& j : d.joints) {
    if (j.type == JointType::kStop) continue;
    // Tangential part of f'_i a_i + f''_i b_i = f'_{i+1} a_{i+1} + f''_{i+1} b_{i+1}, with
    // b_{i+1} = r^2 b_i (the shared grid value): |f'_{i+1}|^2 a_{i+1} = f'_{i+1} . f'_i a_i +
    // f'_{i+1} . (f''_i - r^2 f''_{i+1}) b_i, divided by |f'_{i+1}|^2 and times ds.
    const Eigen::Vector3d f1a = problem.curve.Evaluate(j.joint, 1.0, 1);
    const Eigen::Vector3d f1b = problem.curve.Evaluate(j.joint + 1, 0.0, 1);
    const Eigen::Vector3d f2a = problem.curve.Evaluate(j.joint, 1.0, 2);
    const Eigen::Vector3d f2b = problem.curve.Evaluate(j.joint + 1, 0.0, 2);
    const double r2 = j.speed_ratio * j.speed_ratio;
    const double n2 = f1b.squaredNorm();
    AddCellAcceleration(c, j.joint + 1, 0, false, c.ds);
    AddCellAcceleration(c, j.joint, K - 1, true, -c.ds * f1b.dot(f1a) / n2);
    c.row.Add(c.Half(j.joint, 2 * K), -c.ds * f1b.dot(f2a - r2 * f2b) / n2);
    c.row.Finish(LinearRow::Kind::kContinuity, 0.0, 0.0,
                 [&] { return "sddot continuity at joint " + std::to_string(j.joint); });
  }
  AddBoundaryAcceleration(c, false);
  AddBoundaryAcceleration(c, true);
  if (problem.prune_redundant_rows) internal::KeepTightestUpperBounds(&d);
  if (!d.infeasible_reason && d.num_vars > 0) {
    d.controls = internal::BuildControlBasis(problem, d, c.boundary_sddot, c.boundary_b);
  }
  return d;
}

}  // namespace

}  // namespace timeopt
