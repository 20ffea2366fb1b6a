// The paper's and certified mode's rows of each cell over (b^k, b^{k+1}) (AddCellRows in
// discretization_internal.h): the paper's acceleration at the cell middle, or the Bernstein
// coefficients of velocity and acceleration over the whole cell, with the rows that cannot bind
// left out (PruneCellRows) and, in certified mode, thinned (ThinCellRows).

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "discretization_internal.h"

namespace timeopt::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One row w . (b^k, b^{k+1}) <= 1 of a cell.
struct CellRow {
  Eigen::Vector2d w;
  LinearRow::Kind kind;
};

// Keeps the rows that can be active for some b >= 0: the points w on the upper-right convex hull,
// i.e. those maximizing w . b for some direction b in the non-negative quadrant (Farkas: a row is
// redundant exactly when its w lies below a convex combination of the others). Gift wrapping from
// the direction (1, 0) to (0, 1); O(rows x hull size), rows per cell are few.
void PruneCellRows(std::vector<CellRow>* rows) {
  std::vector<CellRow>& r = *rows;
  if (r.size() <= 1) return;
  // Start: the largest w0 (ties: the largest w1), optimal for b = (1, 0).
  size_t current = 0;
  for (size_t j = 1; j < r.size(); ++j) {
    if (r[j].w(0) > r[current].w(0) || (r[j].w(0) == r[current].w(0) && r[j].w(1) > r[current].w(1))) {
      current = j;
    }
  }
  // A buffer reused across cells and calls (one per thread): an allocation per cell was ~5% of
  // building a certified problem.
  thread_local std::vector<CellRow> kept;
  kept.assign(1, r[current]);
  for (size_t guard = 0; guard < r.size(); ++guard) {
    // The next vertex takes over at the smallest angle: for a candidate with larger w1 the switch
    // happens where (w_j - w_cur) . b = 0, tan(theta) = (w0_cur - w0_j) / (w1_j - w1_cur).
    const Eigen::Vector2d p = r[current].w;
    size_t next = r.size();
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < r.size(); ++j) {
      const double dq = r[j].w(1) - p(1);
      if (!(dq > 0.0)) continue;
      const double tan_theta = (p(0) - r[j].w(0)) / dq;
      if (tan_theta < best || (tan_theta == best && next < r.size() && r[j].w(1) > r[next].w(1))) {
        best = tan_theta;
        next = j;
      }
    }
    if (next == r.size()) break;
    current = next;
    kept.push_back(r[current]);
  }
  r.assign(kept.begin(), kept.end());
}

// True if x <= l A + (1 - l) C componentwise for some l in [0, 1]: then x . b <= max(A . b, C . b)
// for every b >= 0, so the row x . b <= 1 follows from A . b <= 1 and C . b <= 1.
bool Dominated(const Eigen::Vector2d& x, const Eigen::Vector2d& A, const Eigen::Vector2d& C) {
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 2; ++i) {
    const double diff = A(i) - C(i);  // x_i <= C_i + l diff
    if (diff > 0.0) {
      lo = std::max(lo, (x(i) - C(i)) / diff);
    } else if (diff < 0.0) {
      hi = std::min(hi, (x(i) - C(i)) / diff);
    } else if (x(i) > C(i)) {
      return false;
    }
  }
  return lo <= hi;
}

// The smallest factor f in {1, 1 + tolerance 2^-6, ..., 1 + tolerance} such that rows [first, last]
// are all dominated by the rows a and c scaled by f, or 0 if none is.
double RunFactor(const std::vector<CellRow>& r, size_t first, size_t last, size_t a, size_t c, double tolerance) {
  for (int k = 7; k >= 0; --k) {
    const double f = k == 7 ? 1.0 : 1.0 + tolerance * std::ldexp(1.0, -k);
    const Eigen::Vector2d A = f * r[a].w, C = f * r[c].w;
    bool ok = true;
    for (size_t j = first; j <= last && ok; ++j) ok = Dominated(r[j].w, A, C);
    if (ok) return f;
  }
  return 0.0;
}

// Thins a cell's hull (rows in hull order, as PruneCellRows leaves them) conservatively: a run of
// vertices between two kept ones is dropped when every vertex of the run is dominated (Dominated)
// by the kept pair scaled by a factor f <= 1 + tolerance, and the rows of that pair are tightened
// to f w . b <= 1 (the largest f of the runs next to them). Every original row still follows from
// the kept ones, so the limits still hold on the whole cell, and b shrinks by at most the factor
// (T grows by at most half the tolerance, relative). The two ends of the hull are always kept.
void ThinCellRows(std::vector<CellRow>* rows, double tolerance) {
  std::vector<CellRow>& r = *rows;
  if (r.size() <= 2 || !(tolerance > 0.0)) return;
  // Buffers reused across cells and calls (one per thread).
  thread_local std::vector<size_t> kept;
  thread_local std::vector<double> factor;
  thread_local std::vector<CellRow> out;
  kept.assign(1, 0);
  factor.assign(r.size(), 1.0);
  size_t run_start = 1;     // first dropped vertex of the current run (empty run if it is i)
  double run_factor = 1.0;  // the factor the current run needs with its next vertex
  auto close_run = [&](size_t next) {
    if (run_start < next) {
      factor[kept.back()] = std::max(factor[kept.back()], run_factor);
      factor[next] = std::max(factor[next], run_factor);
    }
  };
  for (size_t i = 1; i + 1 < r.size(); ++i) {
    const double f = RunFactor(r, run_start, i, kept.back(), i + 1, tolerance);
    if (f > 0.0) {
      run_factor = f;  // i joins the run
      continue;
    }
    close_run(i);
    kept.push_back(i);
    run_start = i + 1;
    run_factor = 1.0;
  }
  close_run(r.size() - 1);
  kept.push_back(r.size() - 1);
  out.clear();
  for (size_t k : kept) {
    out.push_back(r[k]);
    out.back().w *= factor[k];
  }
  r.assign(out.begin(), out.end());
}

// The paper's rows of one cell: per axis, the acceleration at the cell's middle, both signs.
void AddPaperCellRows(const TemporalLimits& limits, const Eigen::Matrix<double, 3, 2>& mid_acc,
                      std::vector<CellRow>* rows) {
  for (int a = 0; a < 3; ++a) {
    const double amax = limits.max_acceleration(a);
    const Eigen::Vector2d w(mid_acc(a, 0) / amax, mid_acc(a, 1) / amax);
    rows->push_back({w, LinearRow::Kind::kAcceleration});
    rows->push_back({-w, LinearRow::Kind::kAcceleration});
  }
}

// What certified mode's cell rows gather over the axes for the quadrotor's limits: the speed's
// square (sum over axes of f'^2) and the acceleration's Bernstein control points (coefficients on
// b0 and b1).
struct CertifiedCell {
  SmallPoly speed2;
  std::vector<Eigen::Vector3d> control0, control1;
};

// Certified mode's rows of cell k (of length ds) of a piece on axis a, from the piece's first and
// second derivatives: the Bernstein coefficients of velocity and acceleration over the whole cell.
void AddCertifiedAxisRows(const TemporalLimits& limits, const PolynomialPiece::Coefficients& first_derivative,
                          const PolynomialPiece::Coefficients& second_derivative, int k, double ds, int a,
                          bool quadrotor, BernsteinTable& bernstein, CertifiedCell* cell, std::vector<CellRow>* rows) {
  const double amax = limits.max_acceleration(a);
  const double vmax2 = limits.max_velocity(a) * limits.max_velocity(a);
  // Certified velocity: Bernstein coefficients of f'(s(u))^2 ((1 - u) b0 + u b1).
  const SmallPoly q = Shifted(first_derivative.row(a).transpose(), k * ds, ds);
  const SmallPoly one_minus_u = Eigen::Vector2d(1.0, -1.0), u = Eigen::Vector2d(0.0, 1.0);
  if (limits.max_speed) {
    const SmallPoly q2 = Multiply(q, q);
    const int size = static_cast<int>(std::max(cell->speed2.size(), q2.size()));
    cell->speed2 = Padded(cell->speed2, size) + Padded(q2, size);
  }
  if (q.cwiseAbs().maxCoeff() > 0.0 && std::isfinite(vmax2)) {
    const SmallPoly q2 = Multiply(q, q);
    SmallPoly w0 = bernstein.Convert(Multiply(q2, one_minus_u));
    SmallPoly w1 = bernstein.Convert(Multiply(q2, u));
    // The end coefficients are f'^2 b at the grid points; the other grid value's weight there
    // is zero exactly (not up to the rounding of the conversion).
    w0(w0.size() - 1) = 0.0;
    w1(0) = 0.0;
    for (int j = 0; j < w0.size(); ++j) {
      rows->push_back({Eigen::Vector2d(w0(j), w1(j)) / vmax2, LinearRow::Kind::kVelocity});
    }
  }
  // Certified acceleration: f'(s(u)) (b1 - b0) / (2 ds) + f''(s(u)) ((1 - u) b0 + u b1).
  const SmallPoly p2 = Shifted(second_derivative.row(a).transpose(), k * ds, ds);
  const SmallPoly p2a = Multiply(p2, one_minus_u);
  const SmallPoly p2b = Multiply(p2, u);
  const int size = static_cast<int>(std::max(q.size(), p2a.size()));
  const SmallPoly c0 = bernstein.Convert(Padded(-q / (2.0 * ds), size) + Padded(p2a, size));
  const SmallPoly c1 = bernstein.Convert(Padded(q / (2.0 * ds), size) + Padded(p2b, size));
  if (quadrotor) {
    if (a == 0) {
      cell->control0.assign(static_cast<size_t>(size), Eigen::Vector3d::Zero());
      cell->control1.assign(static_cast<size_t>(size), Eigen::Vector3d::Zero());
    }
    for (int j = 0; j < size; ++j) {
      cell->control0[static_cast<size_t>(j)](a) = c0(j);
      cell->control1[static_cast<size_t>(j)](a) = c1(j);
    }
  }
  if (!std::isfinite(amax)) return;  // no limit on this axis
  for (int j = 0; j < size; ++j) {
    const Eigen::Vector2d w(c0(j) / amax, c1(j) / amax);
    rows->push_back({w, LinearRow::Kind::kAcceleration});
    rows->push_back({-w, LinearRow::Kind::kAcceleration});
  }
}

// Certified mode's quadrotor rows of a cell over grid values `cell_grid`: the acceleration's
// control points within the (convex) cones, which bounds the whole cell since the acceleration
// curve lies in their convex hull, into `row` directly; the speed's Bernstein coefficients into
// *rows.
void AddCertifiedQuadrotorRows(const TemporalLimits& limits, const CertifiedCell& cell,
                               const std::vector<int>& cell_grid, const std::function<std::string()>& where,
                               BernsteinTable& bernstein, RowBuilder& row, TemporalDiscretization* d,
                               std::vector<CellRow>* rows) {
  for (size_t j = 0; j < cell.control0.size(); ++j) {
    AddQuadrotorAccelerationRows(limits, cell_grid, {cell.control0[j], cell.control1[j]}, where, row, d);
  }
  if (limits.max_speed && cell.speed2.cwiseAbs().maxCoeff() > 0.0) {
    // Certified speed: Bernstein coefficients of |f'(s(u))|^2 ((1 - u) b0 + u b1).
    const SmallPoly one_minus_u = Eigen::Vector2d(1.0, -1.0), u = Eigen::Vector2d(0.0, 1.0);
    SmallPoly w0 = bernstein.Convert(Multiply(cell.speed2, one_minus_u));
    SmallPoly w1 = bernstein.Convert(Multiply(cell.speed2, u));
    w0(w0.size() - 1) = 0.0;
    w1(0) = 0.0;
    const double s2 = *limits.max_speed * *limits.max_speed;
    for (int j = 0; j < w0.size(); ++j) {
      rows->push_back({Eigen::Vector2d(w0(j), w1(j)) / s2, LinearRow::Kind::kVelocity});
    }
  }
}

}  // namespace

// Per-cell rows over (b^k, b^{k+1}): the paper's acceleration at the cell middle, or certified
// mode's Bernstein coefficients of velocity and acceleration over the whole cell.
void AddCellRows(const TemporalProblem& problem, const std::vector<Eigen::Matrix<double, 3, 2>>& mid_acc,
                 RowBuilder& row, TemporalDiscretization* out) {
  TemporalDiscretization& d = *out;
  const PiecewiseCurve& curve = problem.curve;
  const int m = curve.num_pieces();
  const double ds = 1.0 / problem.cells_per_piece;
  const TemporalLimits& limits = problem.limits;
  const bool certified = problem.constraint_mode == ConstraintMode::kCertified;
  // Every velocity and acceleration row of a cell involves only its two grid values, so after
  // dividing by its limit it reads w . (b^k, b^{k+1}) <= 1. With b >= 0 only the rows on the
  // upper-right convex hull of the points w can be active (see PruneCellRows); the others are
  // dropped when prune_redundant_rows is set. The feasible set is unchanged.
  std::vector<CellRow> cell_rows;
  std::vector<PolynomialPiece::Coefficients> first_derivative, second_derivative;
  BernsteinTable bernstein;
  if (certified) {
    for (int i = 0; i < m; ++i) {
      if (curve.piece(i).degree() > 30) {
        throw std::invalid_argument("curve piece " + std::to_string(i) + " has degree " +
                                    std::to_string(curve.piece(i).degree()) + "; certified mode supports degree <= 30");
      }
      first_derivative.push_back(curve.piece(i).Derivative(1).coefficients());
      second_derivative.push_back(curve.piece(i).Derivative(2).coefficients());
    }
  }
  const bool quadrotor = limits.HasNormLimits();
  CertifiedCell certified_cell;
  for (size_t ci = 0; ci < d.cells.size(); ++ci) {
    const Cell& c = d.cells[ci];
    const int k = c.first_grid - d.GridIndex(c.piece, 0);
    cell_rows.clear();
    const std::vector<int> cell_grid = {c.first_grid, c.first_grid + 1};
    const std::function<std::string()> where = [&] {
      return "piece " + std::to_string(c.piece) + " cell " + std::to_string(k);
    };
    if (!certified) {
      if (quadrotor) {
        AddQuadrotorAccelerationRows(limits, cell_grid, {mid_acc[ci].col(0), mid_acc[ci].col(1)}, where, row, &d);
      }
      AddPaperCellRows(limits, mid_acc[ci], &cell_rows);
    } else {
      certified_cell.speed2 = SmallPoly::Zero(1);
      for (int a = 0; a < 3; ++a) {
        AddCertifiedAxisRows(limits, first_derivative[static_cast<size_t>(c.piece)],
                             second_derivative[static_cast<size_t>(c.piece)], k, ds, a, quadrotor, bernstein,
                             &certified_cell, &cell_rows);
      }
      if (quadrotor)
        AddCertifiedQuadrotorRows(limits, certified_cell, cell_grid, where, bernstein, row, &d, &cell_rows);
    }
    if (problem.prune_redundant_rows) PruneCellRows(&cell_rows);
    if (certified && problem.prune_redundant_rows) ThinCellRows(&cell_rows, problem.certified_thinning);
    for (const CellRow& r : cell_rows) {
      if (r.w(0) <= 0.0 && r.w(1) <= 0.0) continue;  // holds for every b >= 0
      row.Add(c.first_grid, r.w(0));
      row.Add(c.first_grid + 1, r.w(1));
      row.Finish(r.kind, -std::numeric_limits<double>::infinity(), 1.0, [&] {
        return std::string(r.kind == LinearRow::Kind::kVelocity ? "velocity" : "acceleration") +
               " (relative to its limit) in piece " + std::to_string(c.piece) + " cell " + std::to_string(k);
      });
    }
  }
}

}  // namespace timeopt::internal
