// The rows of one cell of the jerk-limited discretization (jerk_cells.h): velocity, acceleration
// and jerk on whole cells, as rows of the discretization or as the structured path's templates.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "jerk_cells.h"

namespace timeopt::internal::jerk {

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
  if (IsRampShape(shape)) {
    // sddot = eps w (4 q + w q_w) / 6 at the end, q_w = (dq/du) / (dw/du) (RestPolys).
    const RampFrame f = RampFrameOf(c.d, piece, k);
    const int e = at_end ? 2 : 0;
    const double w = f.w[e];
    for (int j = 0; j < 3; ++j) {
      const double q_here = j == e ? 1.0 : 0.0;
      c.row.Add(g0 + j, coef * f.eps * w * f.rho[j] * (4.0 * q_here + w * slope[j] / f.dw) / 6.0);
    }
    return;
  }
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

namespace {

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

}  // namespace

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

// RampPolys of ramp cell k of piece i (see RestPolys), or false when the composed polynomials do not
// fit a SmallPoly. f^(n)(s(u)) with s = w^3 (after a rest start) or 1 - w^3 (before a rest end),
// w = w0 + dw u: each derivative of the piece composed with that cubic by Horner's scheme.
bool RampCellPolys(JerkContext& c, int piece, int k, RestPolys* out) {
  const int degree1 = static_cast<int>(c.derivatives[static_cast<size_t>(piece)][0].cols()) - 1;  // of f'
  if (6 * std::max(degree1, 0) + 6 > internal::kMaxSmallPoly) return false;
  const RampFrame f = RampFrameOf(c.d, piece, k);
  out->ramp = true;
  const SmallPoly w = (SmallPoly(2) << f.w[0], f.dw).finished();
  const SmallPoly w2 = Multiply(w, w), w3 = Multiply(w2, w), w4 = Multiply(w2, w2), w6 = Multiply(w3, w3);
  const SmallPoly s_of_u = f.eps > 0.0 ? w3 : SmallPoly(Sum(Constant(1.0), -w3));
  const auto composed = [&](int order, int axis) {
    const auto& coefs = c.derivatives[static_cast<size_t>(piece)][static_cast<size_t>(order - 1)];
    if (coefs.cols() == 0) return Constant(0.0);
    SmallPoly r = Constant(coefs(axis, coefs.cols() - 1));
    for (Eigen::Index i = coefs.cols() - 2; i >= 0; --i) r = Sum(Multiply(r, s_of_u), Constant(coefs(axis, i)));
    return r;
  };
  // Per value: q = rho_j L_j, q_w = rho_j L_j' / dw, q_ww = rho_j L_j'' / dw^2.
  SmallPoly q[3], qw[3], qww[3];
  for (int j = 0; j < 3; ++j) {
    q[j] = Basis(j) * f.rho[j];
    qw[j] = BasisDerivative(j) * (f.rho[j] / f.dw);
    qww[j] = Constant(kBasisSecond[j] * f.rho[j] / (f.dw * f.dw));
    out->q[j] = q[j];
  }
  for (int a = 0; a < 3; ++a) {
    const SmallPoly f1 = composed(1, a), f2 = composed(2, a), f3 = composed(3, a);
    for (int j = 0; j < 3; ++j) {
      const SmallPoly b = Multiply(w4, q[j]);
      const SmallPoly four_q_wqw = Sum(q[j] * 4.0, Multiply(w, qw[j]));
      const SmallPoly sddot = Multiply(w, four_q_wqw) * (f.eps / 6.0);
      const SmallPoly j1 = Sum(Sum(q[j] * 4.0, Multiply(w, qw[j]) * 6.0), Multiply(w2, qww[j])) * (1.0 / 18.0);
      const SmallPoly j2 = Multiply(w3, four_q_wqw) * (f.eps / 2.0);
      out->vel[a][j] = Multiply(Multiply(f1, f1), b);
      out->acc[a][j] = Sum(Multiply(f1, sddot), Multiply(f2, b));
      out->jerk[a][j] = Sum(Sum(Multiply(f1, j1), Multiply(f2, j2)), Multiply(f3, Multiply(w6, q[j])));
    }
  }
  return true;
}

namespace {

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

// The polynomials of one axis on a regular cell of length ds (in u), per half-grid value of the
// cell: the squared velocity f'^2 b, the acceleration f' b' / 2 + f'' b and the jerk's
// P = f' a' + 3 f'' a + f''' b (a rest cell's are in RestPolys, in w).
void AxisPolys(const SmallPoly& q, const SmallPoly& p2, const SmallPoly& p3, double ds, SmallPoly (&vel)[3],
               SmallPoly (&acc)[3], SmallPoly (&jerk)[3]) {
  const SmallPoly q2 = Multiply(q, q);
  for (int j = 0; j < 3; ++j) {
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
  }
}

// The rows sign * polys <= bound (both signs when two_sided) on the Bernstein coefficients of a
// cell whose first half-grid value is g0, every row of one kind in a common degree; as templates
// when the context collects them (DiscretizeJerkLimitedTemplates).
void EmitLimitRows(JerkContext& c, int piece, int k, int axis, int g0, const SmallPoly (&polys)[3], bool two_sided,
                   double bound, LinearRow::Kind kind) {
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
        return std::string("a limit on axis ") + kAxisNames[axis] + " in piece " + std::to_string(piece) + " cell " +
               std::to_string(k);
      });
    }
  }
}

// The jerk rows of one axis as templates for the structured path, which linearizes them when it
// solves: a regular cell's in Bernstein form over the whole cell (the basis depends on the size
// alone: converted once per size), a rest cell's per part of kRestJerkParts.
void AddJerkTemplates(JerkContext& c, int piece, int k, int g0, const SmallPoly (&jerk)[3],
                      const SmallPoly (&root_basis)[3], double jmax, const RestPolys* rest) {
  int size = 0;
  for (int j = 0; j < 3; ++j) {
    size = std::max<int>(size, static_cast<int>(std::max(jerk[j].size(), root_basis[j].size())));
  }
  SmallPoly bern_jerk[3], rest_bernstein[3];
  if (rest == nullptr) {
    for (int j = 0; j < 3; ++j) bern_jerk[j] = c.bernstein.Convert(Padded(jerk[j], size));
  }
  if (rest == nullptr && c.basis_size != size) {
    for (int j = 0; j < 3; ++j) c.basis_bernstein[j] = c.bernstein.Convert(Padded(Basis(j), size));
    c.basis_size = size;
  }
  const SmallPoly(&bern_basis)[3] = rest != nullptr ? rest_bernstein : c.basis_bernstein;
  const int parts = rest != nullptr && !rest->ramp ? kRestJerkParts : 1;
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
          t.rest_far = static_cast<std::int8_t>(rest->ramp ? internal::kRampTemplate
                                                           : RestFar(c.d.shapes[static_cast<size_t>(piece * c.K + k)]));
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

// The jerk rows of one axis on kJerkSegments equal parts of the cell (a rest cell: kRestJerkParts),
// each linearized at the previous solution's (lin) largest b on that part. One part: on the
// S-curve line (v 4, a 3, j 10) four parts gave the same T to 6 digits at K = 20..200, took 2-3 x
// longer and ended some solves at reduced accuracy.
void AddLinearizedJerkRows(JerkContext& c, int piece, int k, int axis, int g0, const SmallPoly (&jerk)[3],
                           const SmallPoly (&root_basis)[3], double jmax, const std::vector<double>& lin,
                           const RestPolys* rest) {
  const double lb[3] = {lin[static_cast<size_t>(g0)], lin[static_cast<size_t>(g0 + 1)],
                        lin[static_cast<size_t>(g0 + 2)]};
  const auto previous_b = [&](double u) {
    return lb[0] * (1 - u) * (1 - 2 * u) + lb[1] * 4 * u * (1 - u) + lb[2] * u * (2 * u - 1);
  };
  // The rows sign * P + kappa * basis <= bound on the part's Bernstein coefficients.
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
        return std::string("jerk on axis ") + kAxisNames[axis] + " in piece " + std::to_string(piece) + " cell " +
               std::to_string(k);
      });
    }
  };
  const int parts = rest != nullptr && !rest->ramp ? kRestJerkParts : kJerkSegments;
  for (int part = 0; part < parts; ++part) {
    const double u0 = static_cast<double>(part) / parts, u1 = (part + 1.0) / parts;
    double b = std::max(previous_b(u0), previous_b(u1));
    if (rest != nullptr && rest->ramp) {
      b = internal::RampLinearizationPoint(RampFrameOf(c.d, piece, k), lb, c.bbar_floors[static_cast<size_t>(piece)]);
    } else if (rest != nullptr) {
      // A rest cell's q is linear: its largest value on the part is at an end of it.
      const double alpha = lb[kRestAlpha], far = lb[RestFar(c.d.shapes[static_cast<size_t>(piece * c.K + k)])];
      b = std::max(alpha + (far - alpha) * u0, alpha + (far - alpha) * u1);
    }
    // The quadratic's vertex inside the part.
    const double c2 = 2.0 * (lb[0] - 2.0 * lb[1] + lb[2]), c1 = -3.0 * lb[0] + 4.0 * lb[1] - lb[2];
    if (c2 < 0.0 && rest == nullptr) {  // (a ramp cell's largest q is above)
      const double vertex = -c1 / (2.0 * c2);
      if (vertex > u0 && vertex < u1) b = std::max(b, previous_b(vertex));
    }
    // Never linearize at b near 0: the tangent would be nearly vertical and its row badly
    // scaled (a floor of 1e-12 made the conic solver stall). Any b > 0 keeps the row
    // conservative; below the floor the rows only loosen.
    if (rest == nullptr) {
      b = std::max(b, c.bbar_floors[static_cast<size_t>(piece)]);
    } else if (!rest->ramp) {
      b = std::max(b, internal::RestCellFloor(c.bbar_floors[static_cast<size_t>(piece)], c.Len(piece, k)));
    }
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

}  // namespace

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
  } else if (rest->ramp) {
    // q >= 0 on the cell: its middle Bernstein coefficient, over rho_m.
    const RampFrame f = RampFrameOf(c.d, piece, k);
    c.row.Add(g0 + 1, -2.0);
    c.row.Add(g0, 0.5 * f.rho[0] / f.rho[1]);
    c.row.Add(g0 + 2, 0.5 * f.rho[2] / f.rho[1]);
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
    if (rest != nullptr) {
      for (int j = 0; j < 3; ++j) {
        vel[j] = rest->vel[a][j];
        acc[j] = rest->acc[a][j];
        jerk[j] = rest->jerk[a][j];
      }
    } else {
      AxisPolys(q, p2, p3, ds, vel, acc, jerk);
    }
    if (quadrotor) {
      for (int j = 0; j < 3; ++j) {
        const int size = static_cast<int>(std::max(speed[j].size(), vel[j].size()));
        speed[j] = Padded(speed[j], size) + Padded(vel[j], size);
        acceleration[a][j] = acc[j];
      }
    }
    if (std::isfinite(vmax2)) EmitLimitRows(c, piece, k, a, g0, vel, false, vmax2, LinearRow::Kind::kVelocity);
    if (std::isfinite(amax)) EmitLimitRows(c, piece, k, a, g0, acc, true, amax, LinearRow::Kind::kAcceleration);
    if (mode == JerkRows::kExact) AddExactJerkRows(c, piece, k, jerk, root_basis, jmax);
    if (mode == JerkRows::kNone && c.templates != nullptr) {
      AddJerkTemplates(c, piece, k, g0, jerk, root_basis, jmax, rest);
    }
    if (mode == JerkRows::kLinearized) AddLinearizedJerkRows(c, piece, k, a, g0, jerk, root_basis, jmax, *lin, rest);
  }
  if (quadrotor) AddQuadrotorCellRows(c, piece, k, speed, acceleration);
}

}  // namespace timeopt::internal::jerk
