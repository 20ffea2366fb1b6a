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
#include "jerk_cells.h"
#include "jerk_grid.h"

namespace timeopt {
namespace {
using internal::BernsteinTable;
using internal::BrakeCellSize;
using internal::CellEdges;
using internal::RestCellSize;
using internal::RestSize;
using internal::RowBuilder;
using internal::SmallPoly;
using internal::jerk::AddCellAcceleration;
using internal::jerk::AddCellRows;
using internal::jerk::AddConstantJerkRestRows;
using internal::jerk::JerkContext;
using internal::jerk::kLinearizationFloor;
using internal::jerk::kNormalTolerance;
using internal::jerk::kRestAlpha;
using internal::jerk::RestCellPolys;
using internal::jerk::RestFar;
using internal::jerk::RestPoint;
using internal::jerk::RestPolys;

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
    if (across.norm() > kNormalTolerance * scale) {
      j.type = JointType::kStop;
      j.reason = "the curvature jumps (the acceleration across the path could not stay continuous at speed)";
    }
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
      if (!IsRestShape(shape)) continue;
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

std::vector<double> LinearizationFloors(const TemporalDiscretization& d, const std::vector<double>& linearization) {
  std::vector<double> largest(static_cast<size_t>(d.num_pieces), 0.0);
  for (size_t g = 0; g < linearization.size(); ++g) {
    double& l = largest[static_cast<size_t>(PieceOf(d, static_cast<int>(g)))];
    l = std::max(l, linearization[g]);
  }
  for (double& l : largest) l = std::max(kLinearizationFloor * l, std::numeric_limits<double>::min());
  return largest;
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
  internal::MarkTiedPieces(problem, &d);
  internal::AssignGridValues(half, &d);
  internal::MakeCells(half, &d);
  internal::CheckBoundaryAccelerations(problem, &d);

  JerkContext c{problem, d, RowBuilder(d), BernsteinTable(), K, 1.0 / K, {}, {}, templates, -1, {}, {}, {}};
  if (linearization != nullptr) c.bbar_floors = internal::LinearizationFloors(d, *linearization);
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
    // Ramp cells need the rest cells' polynomials (RestCellPolys: degree up to 10). Ipopt's exact
    // rows keep the regular cells after a rest cell: on ramp cells its solves slowed from 0.4 s to
    // 58 s (a quintic of the reference set at K = 100, 46 against 309 iterations, most of them
    // restoring feasibility), and at K = 200 ran out of time.
    const int degree1 = static_cast<int>(c.derivatives[static_cast<size_t>(i)][0].cols()) - 1;
    int ramp[2] = {0, 0};
    d.cell_edges[static_cast<size_t>(i)] = CellEdges(K,
                                                     rest_start ? RestCellSize(problem, i, false, rest_end)
                                                     : i == 0   ? BrakeCellSize(problem, i, false, K)
                                                                : RestSize(),
                                                     rest_end     ? RestCellSize(problem, i, true, rest_start)
                                                     : i == m - 1 ? BrakeCellSize(problem, i, true, K)
                                                                  : RestSize(),
                                                     jerk_rows == JerkRows::kExact ? nullptr : &ramp,
                                                     6 * std::max(degree1, 0) + 6 <= internal::kMaxSmallPoly);
    for (int k = 1; k <= ramp[0]; ++k) d.shapes[static_cast<size_t>(i * K + k)] = CellShape::kRampStart;
    for (int k = K - 1 - ramp[1]; k < K - 1; ++k) d.shapes[static_cast<size_t>(i * K + k)] = CellShape::kRampEnd;
    for (int k = 0; k < K; ++k) {
      const CellShape shape = d.shapes[static_cast<size_t>(i * K + k)];
      Cell& first = d.cells[static_cast<size_t>(2 * (i * K + k))];
      Cell& second = d.cells[static_cast<size_t>(2 * (i * K + k) + 1)];
      if (!IsRampShape(shape)) {
        first.ds = second.ds = 0.5 * c.Len(i, k);
        continue;
      }
      // A ramp cell's half cells meet at its middle in w; the time of each in the objective is
      // weighted so that it is exact where q is constant (a constant s-jerk): 3 |dw| / sqrt(q) over
      // a half cell [wa, wb] against 2 |s(wb) - s(wa)| / (sqrt(b_a) + sqrt(b_b)), b = w^4 q.
      const double middle = TemporalProfile::RampMiddleS(shape, c.Start(i, k), c.Start(i, k) + c.Len(i, k));
      first.ds = std::abs(middle - c.Start(i, k));
      second.ds = std::abs(c.Start(i, k) + c.Len(i, k) - middle);
      const internal::RampFrame f = internal::RampFrameOf(shape, c.Start(i, k), c.Start(i, k) + c.Len(i, k));
      const auto weight = [](double wa, double wb) {
        return 1.5 * (wa * wa + wb * wb) / (wa * wa + wa * wb + wb * wb);
      };
      first.time_weight = weight(f.w[0], f.w[1]);
      second.time_weight = weight(f.w[1], f.w[2]);
    }
  }
  // Rest cells take 6 L / (sqrt(alpha) + sqrt(b_far)): the half cell between alpha (the middle
  // value) and b_far, of length L / 2, with weight 6; the one between the rest point and alpha with
  // weight 0 (RestPolys).
  for (size_t cell = 0; cell < d.shapes.size(); ++cell) {
    if (!IsRestShape(d.shapes[cell])) continue;
    const bool start = d.shapes[cell] == CellShape::kRestStart;
    d.cells[2 * cell].time_weight = start ? 0.0 : 6.0;
    d.cells[2 * cell + 1].time_weight = start ? 6.0 : 0.0;
  }

  // ---- rows of every cell ----
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k < K; ++k) {
      RestPolys rest;
      const CellShape shape = d.shapes[static_cast<size_t>(i * K + k)];
      if (shape == CellShape::kQuadratic) {
        AddCellRows(c, i, k, jerk_rows, linearization, nullptr);
      } else if (IsRampShape(shape)) {
        if (!RampCellPolys(c, i, k, &rest)) throw std::logic_error("a ramp cell on a piece of too high a degree");
        AddCellRows(c, i, k, jerk_rows, linearization, &rest);
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
  // ---- a tied piece's b is one line in s: each cell's middle value the mean of its ends (with
  // the continuity rows above, one slope over the piece). Each row divided by its middle value's
  // scale, so that it reads in x. ----
  for (int i = 0; i < m; ++i) {
    if (!d.tied[static_cast<size_t>(i)]) continue;
    for (int k = 0; k < K; ++k) {
      const int g = c.Half(i, 2 * k);
      const double unit = 1.0 / d.grid[static_cast<size_t>(g + 1)].scale;
      c.row.Add(g + 1, unit);
      c.row.Add(g, -0.5 * unit);
      c.row.Add(g + 2, -0.5 * unit);
      c.row.Finish(LinearRow::Kind::kContinuity, 0.0, 0.0,
                   [&] { return "b linear on the tied piece " + std::to_string(i) + " at cell " + std::to_string(k); });
    }
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
