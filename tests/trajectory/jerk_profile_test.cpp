// Jerk-limited temporal profiles (quadratic, rest and ramp cells) against truths written here
// independently: cell times by tanh-sinh quadrature of 1 / sqrt(b) and the rest cells' closed form
// 3 ds / sqrt(b), the time map by its inverse, the derivatives of s(t) by finite differences, and
// the trajectory's jerk by finite differences of its acceleration.

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/curve/polynomial_piece.h"
#include "timeopt/trajectory/temporal_profile.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {
namespace {

using Grid = std::vector<std::vector<double>>;
using Shapes = std::vector<std::vector<CellShape>>;
constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kPi = 3.141592653589793238462643383279502884;

// Integral over [0, ds] of f(x, ds - x) by tanh-sinh quadrature: x = ds / (1 + exp(-pi sinh u)),
// whose distances to both ends are formed without cancellation, so integrands singular like
// x^(-1/2) or x^(-2/3) at an end are integrated to full accuracy. The nodes stop at |u| = 4.5,
// where x / ds < e^(-140); the tail left out is below 1e-20 of the integral for those
// singularities. `step` is the node spacing in u.
template <typename F>
double TanhSinh(F f, double ds, double step) {
  // Kahan summation: the ~1150 terms would otherwise add ~eps sqrt(N) of rounding.
  double sum = 0.0, carry = 0.0;
  const int n = static_cast<int>(std::lround(4.5 / step));
  for (int j = -n; j <= n; ++j) {
    const double u = j * step;
    const double v = 0.5 * kPi * std::sinh(u);
    const double x = ds / (1.0 + std::exp(-2.0 * v)), rest = ds / (1.0 + std::exp(2.0 * v));
    if (!(x > 0.0) || !(rest > 0.0)) continue;
    const double weight = ds * 0.5 * kPi * std::cosh(u) / (2.0 * std::cosh(v) * std::cosh(v));
    const double term = weight * f(x, rest) - carry;
    const double next = sum + term;
    carry = (next - sum) - term;
    sum = next;
  }
  return step * sum;
}

// The cell time of b quadratic through (b0, bm, b1) at 0, ds / 2, ds, by quadrature of
// 1 / sqrt(b). b is expanded about the nearer end (with the distance to that end exact), so that
// where b vanishes at an end it keeps its relative accuracy. Two spacings are compared: the
// quadrature must agree between them to 1e-15 relative (rounding of the sum, a few eps) before it
// is used as the truth.
double QuadratureTime(double b0, double bm, double b1, double ds) {
  const double c2 = 2.0 * (b0 - 2.0 * bm + b1) / (ds * ds);
  const double c1 = (-3.0 * b0 + 4.0 * bm - b1) / ds;
  const double d1 = (b0 - 4.0 * bm + 3.0 * b1) / ds;
  auto f = [&](double x, double rest) {
    const double b = x <= rest ? b0 + x * (c1 + c2 * x) : b1 - rest * (d1 - c2 * rest);
    return 1.0 / std::sqrt(b);
  };
  const double coarse = TanhSinh(f, ds, 1.0 / 64), fine = TanhSinh(f, ds, 1.0 / 128);
  EXPECT_NEAR(coarse, fine, 1e-15 * fine) << "quadrature not converged";
  return fine;
}

// One piece of K cells, each given as (b0, bm, b1) and a shape, chained: b1 of one cell is b0 of
// the next.
TemporalProfile OnePiece(const std::vector<double>& half, const std::vector<CellShape>& shapes) {
  return TemporalProfile::JerkLimited(Grid{half}, Shapes{shapes});
}

// The profile of the continuity tests: K = 4 cells on each of two pieces, rest start, two
// quadratic cells, rest end. Between the rest cells b is one quadratic q(s) = 1 + alpha (s - ds)
// + gamma (s - ds)^2 with alpha = 4 / (3 ds) (the slope b' = 2 sddot that the rest-start cell ends
// with, sddot = b / (1.5 ds)) and gamma = -2 / (3 ds^2), the value for which q'(3 ds) =
// -4 q(3 ds) / (3 ds), the slope the rest-end cell starts with. So sddot is continuous everywhere:
// q = 1, 1.5, 5/3, 1.5, 1 at s = 1/4 .. 3/4. The rest cells' middle values are those of a
// constant s-jerk, 2^(-4/3) times their far ends.
const double kConstantJerkMiddle = std::pow(2.0, -4.0 / 3.0);
TemporalProfile SmoothRestToRest() {
  const double m = kConstantJerkMiddle;
  const std::vector<double> half = {0.0, m, 1.0, 1.5, 5.0 / 3.0, 1.5, 1.0, m, 0.0};
  const std::vector<CellShape> shapes = {CellShape::kRestStart, CellShape::kQuadratic, CellShape::kQuadratic,
                                         CellShape::kRestEnd};
  return TemporalProfile::JerkLimited(Grid{half, half}, Shapes{shapes, shapes});
}

TEST(JerkProfile, QuadraticCellTimesMatchQuadrature) {
  const double ds = 0.5;  // K = 2 cells: the cell and its mirror
  // (b0, bm, b1): concave and convex; c2 within 1e-13 of 0 on both sides and exactly 0 (the
  // closed forms' cancellation-prone limit); a minimum and a maximum inside; b = 0 at the start,
  // at the end, at both ends; steep braking; constant.
  const std::vector<std::array<double, 3>> cells = {
      {1.0, 1.3, 2.0}, {1.0, 1.6, 2.0},  {1.0, 1.5 + 1e-13, 2.0}, {1.0, 1.5 - 1e-13, 2.0},
      {1.0, 1.5, 2.0}, {2.0, 0.5, 1.5},  {0.5, 2.0, 1.0},         {0.0, 0.3, 1.0},
      {0.0, 0.6, 1.0}, {1.0, 0.3, 0.0},  {0.0, 1.0, 0.0},         {4.0, 1.0, 0.01},
      {3.0, 3.0, 3.0}, {1e-6, 0.5, 1.0}, {1.0, 0.26, 0.1},        {0.2, 0.2 + 1e-9, 0.2}};
  for (const auto& c : cells) {
    const TemporalProfile profile =
        OnePiece({c[0], c[1], c[2], c[1], c[0]}, {CellShape::kQuadratic, CellShape::kQuadratic});
    const double truth = QuadratureTime(c[0], c[1], c[2], ds);
    // The closed forms are a dozen operations on terms of one sign (a few eps), the quadrature a
    // sum of ~1150 positive terms (~eps sqrt(N)): 1e-14 relative covers both; a form with
    // cancellation loses ~1e-3 at c2 ~ 1e-12.
    const std::string label = std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]);
    EXPECT_NEAR(profile.TimeAt(0, 1), truth, 1e-14 * truth) << label;
    // The mirror cell takes the same time.
    EXPECT_NEAR(profile.total_time() - profile.TimeAt(0, 1), truth, 1e-14 * truth) << label;
  }
  // b = 4 bm (sigma / ds)(1 - sigma / ds) from rest to rest: the integral is pi ds / (2 sqrt(bm)).
  // Here K = 1, so ds = 1.
  EXPECT_NEAR(OnePiece({0.0, 1.0, 0.0}, {CellShape::kQuadratic}).total_time(), kPi / 2.0, 4 * kEps);
}

// Cells whose b is constant up to rounding (values a few ulps apart, as an optimizer leaves them on
// a cruise at the speed limit): c1, c2 and b'(h) are then all rounding, and a c2 taken apart from
// the slopes made these cells' times 1.2e-9 relative off (a jerk-limited answer's T then differed
// from its own profile's). Against quadrature, to the 1e-14 above.
TEST(JerkProfile, CellsConstantUpToRoundingTakeTheirExactTime) {
  const double ds = 0.5;
  const std::vector<std::array<double, 3>> cells = {
      {1.545716132050762e-05, 1.5457161320507616e-05, 1.545716132050762e-05},
      {1.5457161320508572e-05, 1.5457161320507616e-05, 1.545716132050745e-05},
      {1.5457161320507616e-05, 1.5457161320507616e-05, 1.545716132050764e-05},
      {2.0, 2.0 - 4.0 * kEps, 2.0 + 2.0 * kEps}};
  for (const auto& c : cells) {
    const TemporalProfile profile =
        OnePiece({c[0], c[1], c[2], c[1], c[0]}, {CellShape::kQuadratic, CellShape::kQuadratic});
    const double truth = QuadratureTime(c[0], c[1], c[2], ds);
    EXPECT_NEAR(profile.TimeAt(0, 1), truth, 1e-14 * truth) << c[0] << " " << c[1] << " " << c[2];
    EXPECT_NEAR(profile.total_time() - profile.TimeAt(0, 1), truth, 1e-14 * truth);
  }
}

TEST(JerkProfile, RestCellTimesMatchClosedFormAndQuadrature) {
  const double ds = 0.5;  // K = 2 cells
  for (double b_far : {1e-4, 0.3, 1.0, 7.5}) {
    const double m = kConstantJerkMiddle * b_far;
    const TemporalProfile profile = OnePiece({0.0, m, b_far, m, 0.0}, {CellShape::kRestStart, CellShape::kRestEnd});
    // b = b_far (sigma / ds)^(4/3): 1 / sqrt(b) ~ sigma^(-2/3) at the start, within tanh-sinh's
    // reach. Written with the distance to the singular end for the rest-end mirror.
    auto rest = [&](double x, double) { return 1.0 / std::sqrt(b_far * std::pow(x / ds, 4.0 / 3.0)); };
    const double quadrature = TanhSinh(rest, ds, 1.0 / 128);
    const double closed = 3.0 * ds / std::sqrt(b_far);
    // Closed form against itself: the same three operations, a few eps.
    EXPECT_NEAR(profile.TimeAt(0, 1), closed, 4 * kEps * closed) << b_far;
    EXPECT_NEAR(profile.total_time(), 2.0 * closed, 8 * kEps * closed) << b_far;
    // The quadrature of a x^(-2/3) singularity converges more slowly: 1e-13 relative.
    EXPECT_NEAR(profile.TimeAt(0, 1), quadrature, 1e-13 * closed) << b_far;
    EXPECT_EQ(profile.shape(0, 0), CellShape::kRestStart);
    EXPECT_EQ(profile.shape(0, 1), CellShape::kRestEnd);
  }
}

TEST(JerkProfile, RestCellsWhoseSJerkChangesMatchQuadrature) {
  // b = w^4 (alpha + beta w) with sigma = ds w^3: the middle value bm (w^3 = 1/2) over b_far from
  // the smallest allowed, 2^(-5/3) (alpha = 0), through a constant s-jerk (2^(-4/3)) to a
  // decreasing s-jerk (larger bm). The time is the integral of 1 / sqrt(b) over sigma, here by
  // quadrature in w: dsigma = 3 ds w^2 dw, so 1 / sqrt(b) dsigma = 3 ds dw / sqrt(alpha + beta w).
  const double ds = 0.5, b_far = 2.0;
  for (double ratio : {std::pow(2.0, -5.0 / 3.0), 0.33, kConstantJerkMiddle, 0.5, 0.9}) {
    const double bm = ratio * b_far;
    const TemporalProfile profile = OnePiece({0.0, bm, b_far, bm, 0.0}, {CellShape::kRestStart, CellShape::kRestEnd});
    const double w_mid = std::cbrt(0.5);
    const double beta = (b_far - bm / std::pow(w_mid, 4)) / (1.0 - w_mid);
    const double alpha = std::max(0.0, b_far - beta);  // 2^(-5/3): 0 within rounding, as the profile takes it
    // alpha = 0 makes 1 / sqrt(q) ~ w^(-1/2) at w = 0, within tanh-sinh's reach.
    const auto integrand = [&](double w, double) { return 3.0 * ds / std::sqrt(std::max(alpha + beta * w, 1e-300)); };
    const double quadrature = TanhSinh(integrand, 1.0, 1.0 / 128);
    // The closed form 6 ds / (sqrt(alpha) + sqrt(b_far)) against a sum of ~1000 positive terms:
    // 1e-13 relative (the alpha = 0 case converges like the singular one above).
    EXPECT_NEAR(profile.TimeAt(0, 1), quadrature, 1e-13 * quadrature) << ratio;
    EXPECT_NEAR(profile.total_time(), 2.0 * quadrature, 2e-13 * quadrature) << ratio;
    // The middle value is kept, and b at the middle in s is it.
    EXPECT_EQ(profile.half_b(0, 1), bm);
    EXPECT_NEAR(std::pow(profile.AtS(0, 0.25).sdot, 2), bm, 1e-13 * b_far) << ratio;
  }
  // Below 2^(-5/3) the cell would need q < 0 at rest.
  EXPECT_THROW(OnePiece({0.0, 0.3 * b_far, b_far, 0.3 * b_far, 0.0}, {CellShape::kRestStart, CellShape::kRestEnd}),
               std::invalid_argument);
}

// A mixed profile of every jerk-limited shape over two pieces (b0 = 0 quadratic start included;
// the rest start's s-jerk grows through its cell, the rest end's eases off).
TemporalProfile Mixed() {
  return TemporalProfile::JerkLimited(
      Grid{{0.0, 0.3, 0.8, 1.5, 2.0, 0.5, 1.5, 1.1, 0.0}, {0.0, 0.3, 1.0, 0.2, 0.05, 0.5, 2.0, 0.9, 0.0}},
      Shapes{{CellShape::kRestStart, CellShape::kQuadratic, CellShape::kQuadratic, CellShape::kQuadratic},
             {CellShape::kQuadratic, CellShape::kQuadratic, CellShape::kQuadratic, CellShape::kRestEnd}});
}

// One piece with ramp cells (S = 0.2 of it at each end, cells uniform in w = s^(1/3) from each rest
// point: edges S / 27, 8 S / 27, S), a quadratic cell between them, and values whose q = b / w^4
// rises and falls across the ramp cells; the rest cells keep a constant s-jerk.
const double kRampS = 0.2;
std::vector<double> RampedEdges() {
  const double S = kRampS;
  return {0.0, S / 27.0, 8.0 * S / 27.0, S, 1.0 - S, 1.0 - 8.0 * S / 27.0, 1.0 - S / 27.0, 1.0};
}
TemporalProfile Ramped() {
  const double m = kConstantJerkMiddle;
  using S = CellShape;
  return TemporalProfile::JerkLimited(
      Grid{{0.0, m * 0.05, 0.05, 0.2, 0.4, 0.7, 1.0, 1.3, 1.1, 0.8, 0.5, 0.15, 0.04, m * 0.04, 0.0}},
      Shapes{{S::kRestStart, S::kRampStart, S::kRampStart, S::kQuadratic, S::kRampEnd, S::kRampEnd, S::kRestEnd}},
      Grid{RampedEdges()});
}

// b(s) of a ramp cell [s0, s1] of the profile, written here from the definition in
// temporal_profile.h: w = s^(1/3) (or (1 - s)^(1/3) before a rest end), q the quadratic in w
// through q_j = b_j / w_j^4 at w0, (w0 + w1) / 2, w1 (Lagrange form), b = w^4 q(w).
double RampB(bool start, double s0, double s1, double b0, double bm, double b1, double s) {
  const auto w_of = [&](double x) { return std::cbrt(start ? x : 1.0 - x); };
  const double w0 = w_of(s0), w1 = w_of(s1), wm = 0.5 * (w0 + w1), w = w_of(s);
  const double q0 = b0 / std::pow(w0, 4), qm = bm / std::pow(wm, 4), q1 = b1 / std::pow(w1, 4);
  const double q = q0 * (w - wm) * (w - w1) / ((w0 - wm) * (w0 - w1)) +
                   qm * (w - w0) * (w - w1) / ((wm - w0) * (wm - w1)) +
                   q1 * (w - w0) * (w - wm) / ((w1 - w0) * (w1 - wm));
  return std::pow(w, 4) * q;
}

TEST(JerkProfile, RampCellTimesMatchQuadrature) {
  const TemporalProfile profile = Ramped();
  const std::vector<double> e = RampedEdges();
  int checked = 0;
  for (int k = 0; k < profile.cells_per_piece(); ++k) {
    const CellShape shape = profile.shape(0, k);
    if (!IsRampShape(shape)) continue;
    const double b0 = profile.half_b(0, 2 * k), bm = profile.half_b(0, 2 * k + 1), b1 = profile.half_b(0, 2 * k + 2);
    // b is smooth and positive on the cell: the quadrature of 1 / sqrt(b) in s converges to
    // rounding (the two spacings agree to 1e-15).
    const auto f = [&](double x, double) {
      return 1.0 / std::sqrt(RampB(shape == CellShape::kRampStart, e[k], e[k + 1], b0, bm, b1, e[k] + x));
    };
    const double ds = e[k + 1] - e[k];
    const double coarse = TanhSinh(f, ds, 1.0 / 64), fine = TanhSinh(f, ds, 1.0 / 128);
    ASSERT_NEAR(coarse, fine, 1e-15 * fine);
    // The profile's closed form (3 times a quadratic cell's time in w) against it: both a few ulps.
    EXPECT_NEAR(profile.TimeAt(0, k + 1) - profile.TimeAt(0, k), fine, 1e-13 * fine) << "cell " << k;
    // b at the middle half point is b at the middle in w.
    const double w = 0.5 * (TemporalProfile::RampW(shape, e[k]) + TemporalProfile::RampW(shape, e[k + 1]));
    const double s_mid = shape == CellShape::kRampStart ? w * w * w : 1.0 - w * w * w;
    EXPECT_NEAR(TemporalProfile::RampMiddleS(shape, e[k], e[k + 1]), s_mid, 1e-15);
    EXPECT_NEAR(profile.AtS(0, s_mid).sdot, std::sqrt(bm), 1e-13) << "cell " << k;
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

// With q constant, the rest cell and the ramp cells after it are one constant s-jerk from rest:
// s = w^3 with dw/dt = sqrt(q) / 3, so s = J t^3 / 6 with J = 2 q^1.5 / 9, exactly (the closed form
// here, not the profile's formulas).
TEST(JerkProfile, ConstantQIsOneConstantSJerkAcrossRestAndRampCells) {
  const double q = 7.0, S = 0.3;
  const double e1 = S / 64.0, e2 = 8.0 * S / 64.0, e3 = 27.0 * S / 64.0, e4 = S;  // w = 1/4 .. 1 of S^(1/3)
  const auto b_at = [&](double s) { return std::pow(s, 4.0 / 3.0) * q; };
  const auto mid = [&](double a, double b) {
    const double w = 0.5 * (std::cbrt(a) + std::cbrt(b));
    return b_at(w * w * w);
  };
  using Sh = CellShape;
  const TemporalProfile profile = TemporalProfile::JerkLimited(
      Grid{{0.0, kConstantJerkMiddle * b_at(e1), b_at(e1), mid(e1, e2), b_at(e2), mid(e2, e3), b_at(e3), mid(e3, e4),
            b_at(e4), b_at(e4), b_at(e4)}},
      Shapes{{Sh::kRestStart, Sh::kRampStart, Sh::kRampStart, Sh::kRampStart, Sh::kQuadratic}},
      Grid{{0.0, e1, e2, e3, e4, 1.0}});
  const double J = 2.0 * std::pow(q, 1.5) / 9.0;
  const double t_ramp = std::cbrt(6.0 * S / J);
  EXPECT_NEAR(profile.TimeAt(0, 4), t_ramp, 1e-13 * t_ramp);
  // (Up to the last ramp cell's end: the quadratic cell after it, b constant, starts with sddot = 0.)
  for (int j = 1; j < 200; ++j) {
    const double t = t_ramp * j / 200.0;
    const TemporalProfile::Point p = profile.AtTime(t);
    // Each value a few ulps of its size, through the time inversion (Newton to a few ulps of t).
    EXPECT_NEAR(p.s, J * t * t * t / 6.0, 1e-13 * S) << "t " << t;
    EXPECT_NEAR(p.sdot, 0.5 * J * t * t, 1e-12 * J * t_ramp * t_ramp) << "t " << t;
    EXPECT_NEAR(p.sddot, J * t, 1e-12 * J * t_ramp) << "t " << t;
    EXPECT_NEAR(p.sdddot, J, 1e-12 * J) << "t " << t;
  }
  const TemporalProfile::Point end = profile.InCell(0, 3, e4 - e3);
  EXPECT_NEAR(end.sddot, J * t_ramp, 1e-12 * J * t_ramp);
  EXPECT_NEAR(end.sdddot, J, 1e-12 * J);
}

TEST(JerkProfile, AtTimeInvertsTimeAtS) {
  for (const TemporalProfile& profile : {Mixed(), SmoothRestToRest(), Ramped()}) {
    const double T = profile.total_time();
    int checked = 0;
    for (int i = 0; i < profile.num_pieces(); ++i) {
      for (int j = 0; j <= 400; ++j) {
        const double s = j / 400.0;
        const double t = profile.TimeAtS(i, s);
        const TemporalProfile::Point p = profile.AtTime(t);
        // t carries the rounding of a sum of cell times (~eps T) and the inversion a few ulps of
        // the cell time: s is off by sdot times that plus the rounding of s itself, bounded by
        // 16 eps (1 + sdot T).
        const double tolerance = 16 * kEps * (1.0 + p.sdot * T);
        // A grid point shared by two pieces is reached at one time; AtTime names the later piece.
        if (p.piece != i) {
          EXPECT_TRUE((s == 1.0 && p.piece == i + 1 && p.s < tolerance) ||
                      (s == 0.0 && p.piece == i - 1 && p.s > 1.0 - tolerance))
              << "piece " << i << " s " << s;
          continue;
        }
        EXPECT_NEAR(p.s, s, tolerance) << "piece " << i << " s " << s;
        // The state at s is the state at its time.
        const TemporalProfile::Point q = profile.AtS(i, s);
        // sdot moves with s by sddot / sdot, or like sigma^(2/3) near a rest start (b ~
        // sigma^(4/3)): an s error of 1e-13 moves it by at most ~(1e-13)^(2/3) ~ 2e-9.
        EXPECT_NEAR(p.sdot, q.sdot, 1e-8) << "piece " << i << " s " << s;
        ++checked;
      }
      // Grid times agree with the integral of 1 / sdot up to each grid point.
      for (int k = 0; k <= profile.cells_per_piece(); ++k) {
        EXPECT_NEAR(profile.TimeAtS(i, profile.CellStart(i, k)), profile.TimeAt(i, k), 4 * kEps * T);
      }
    }
    EXPECT_GE(checked, profile.num_pieces() * 395);
  }
}

// Central differences of g at t with step h, and an estimate of their truncation error from the
// difference to step 2 h (Richardson: D(h) - D(2h) ~ 3 * error of D(h)).
template <typename G>
std::pair<double, double> CentralDifference(G g, double t, double h) {
  const double d1 = (g(t + h) - g(t - h)) / (2.0 * h);
  const double d2 = (g(t + 2.0 * h) - g(t - 2.0 * h)) / (4.0 * h);
  return {d1, std::abs(d1 - d2) / 3.0};
}

TEST(JerkProfile, DerivativesMatchFiniteDifferencesInsideCells) {
  for (const TemporalProfile& profile : {Mixed(), SmoothRestToRest(), Ramped()}) {
    const int K = profile.cells_per_piece();
    int checked = 0;
    for (int i = 0; i < profile.num_pieces(); ++i) {
      for (int k = 0; k < K; ++k) {
        const double t0 = profile.TimeAt(i, k);
        const double t1 = k + 1 < K ? profile.TimeAt(i, k + 1) : profile.piece_durations()[i] + profile.TimeAt(i, 0);
        // A step of 1e-4 of the cell keeps t +- 2h inside it. Each value is accurate to a few ulps
        // of its size V (s ~ 1, the rest below ~10): rounding adds ~8 eps V / h to the
        // difference; truncation is estimated by Richardson and allowed twice over, plus 1e-9 for
        // the estimate's own error (h^4 terms).
        const double h = 1e-4 * (t1 - t0);
        for (double fraction : {0.05, 0.3, 0.5, 0.77, 0.95}) {
          const double t = t0 + fraction * (t1 - t0);
          const TemporalProfile::Point p = profile.AtTime(t);
          const double rounding = 8 * kEps * 10.0 / h;
          const auto ds_dt = CentralDifference(
              [&](double x) {
                const TemporalProfile::Point q = profile.AtTime(x);
                return q.piece * 1.0 + q.s;  // continuous across the piece joint
              },
              t, h);
          const auto dsdot = CentralDifference([&](double x) { return profile.AtTime(x).sdot; }, t, h);
          const auto dsddot = CentralDifference([&](double x) { return profile.AtTime(x).sddot; }, t, h);
          const std::string label =
              "piece " + std::to_string(i) + " cell " + std::to_string(k) + " at " + std::to_string(fraction);
          EXPECT_NEAR(p.sdot, ds_dt.first, 2 * ds_dt.second + rounding + 1e-9) << label;
          EXPECT_NEAR(p.sddot, dsdot.first, 2 * dsdot.second + rounding + 1e-9) << label;
          EXPECT_NEAR(p.sdddot, dsddot.first, 2 * dsddot.second + rounding + 1e-9) << label;
          ++checked;
        }
      }
    }
    EXPECT_EQ(checked, profile.num_pieces() * K * 5);
  }
}

TEST(JerkProfile, InCellIsAtSInsideACellAndItsOwnStateAtItsEnds) {
  const TemporalProfile profile = Mixed();
  for (int i = 0; i < profile.num_pieces(); ++i) {
    for (int k = 0; k < profile.cells_per_piece(); ++k) {
      const double start = profile.CellStart(i, k), length = profile.CellLength(i, k);
      // Inside: the same cell, the same formulas (AtS's sigma is (start + 0.3 L) - start, 0.3 L to
      // an ulp of s, so agreement to 1e-12 relative).
      const TemporalProfile::Point inside = profile.InCell(i, k, 0.3 * length),
                                   at = profile.AtS(i, start + 0.3 * length);
      EXPECT_NEAR(inside.sdot, at.sdot, 1e-12 * std::max(1.0, std::abs(at.sdot)));
      EXPECT_NEAR(inside.sdddot, at.sdddot, 1e-12 * std::max(1.0, std::abs(at.sdddot)));
      // At its start, the cell's own state is AtS's (a grid point belongs to the cell that starts there).
      EXPECT_EQ(profile.InCell(i, k, 0.0).sdot, profile.AtS(i, start).sdot);
      // At its end, this cell's state: the speed is continuous, so it is the next cell's to rounding
      // (b is continuous across cells; 1e-12 relative).
      if (k + 1 < profile.cells_per_piece()) {
        const double end = profile.InCell(i, k, length).sdot, next = profile.AtS(i, start + length).sdot;
        EXPECT_NEAR(end, next, 1e-12 * std::max(1.0, next)) << "piece " << i << " cell " << k;
      }
    }
  }
}

// InCellSamples forms a cell once for its samples: the same formulas as InCell at each sample, so
// the same values bit for bit, on every shape of cell (rest, quadratic).
TEST(JerkProfile, InCellSamplesAreInCellAtEachSample) {
  for (const TemporalProfile& profile : {Mixed(), SmoothRestToRest(), Ramped()}) {
    const int n = 7;
    std::vector<TemporalProfile::Point> samples(n + 1);
    for (int i = 0; i < profile.num_pieces(); ++i) {
      for (int k = 0; k < profile.cells_per_piece(); ++k) {
        profile.InCellSamples(i, k, n, samples.data());
        for (int j = 0; j <= n; ++j) {
          const TemporalProfile::Point p =
              profile.InCell(i, k, (static_cast<double>(j) / n) * profile.CellLength(i, k));
          EXPECT_EQ(samples[j].s, p.s) << "piece " << i << " cell " << k << " sample " << j;
          EXPECT_EQ(samples[j].sdot, p.sdot) << "piece " << i << " cell " << k << " sample " << j;
          EXPECT_EQ(samples[j].sddot, p.sddot) << "piece " << i << " cell " << k << " sample " << j;
          EXPECT_EQ(samples[j].sdddot, p.sdddot) << "piece " << i << " cell " << k << " sample " << j;
        }
      }
    }
  }
}

TEST(JerkProfile, SddotIsContinuousAndRestEndsAreAtRest) {
  const TemporalProfile profile = SmoothRestToRest();
  const double T = profile.total_time();
  // Rest start: sigma = J t^3 / 6, so exactly zero speed and acceleration at t = 0.
  const TemporalProfile::Point start = profile.AtTime(0.0);
  EXPECT_EQ(start.sdot, 0.0);
  EXPECT_EQ(start.sddot, 0.0);
  EXPECT_GT(start.sdddot, 0.0);
  // Rest end at T: the time left is the rounding of T (~eps T), and sdot ~ J r^2, sddot ~ J r.
  const TemporalProfile::Point end = profile.AtTime(T);
  EXPECT_EQ(end.piece, 1);
  EXPECT_NEAR(end.s, 1.0, 1e-15);
  EXPECT_NEAR(end.sdot, 0.0, 1e-15);
  EXPECT_NEAR(end.sddot, 0.0, 1e-13);
  EXPECT_GT(end.sdddot, 0.0);  // braking eases off: the jerk is positive
  // Just inside the rest-end cell sddot is negative (braking).
  EXPECT_LT(profile.AtTime(T - 1e-3).sddot, 0.0);
  // Across every grid time, sdot and sddot change only by their rate over 2 delta (delta = 1e-9
  // s): |sddot| <= 6 and |sdddot| <= 60 here, so 1e-7 bounds both jumps with a wide margin over
  // rounding; a jump of sddot between a rest cell and a quadratic one would be of order 1.
  const double delta = 1e-9;
  for (int i = 0; i < 2; ++i) {
    for (int k = (i == 0 ? 1 : 0); k <= 4; ++k) {
      if (i == 1 && k == 4) continue;
      const double t = profile.TimeAt(i, k);
      const TemporalProfile::Point before = profile.AtTime(t - delta), after = profile.AtTime(t + delta);
      EXPECT_NEAR(before.sdot, after.sdot, 1e-7) << "piece " << i << " point " << k;
      EXPECT_NEAR(before.sddot, after.sddot, 1e-7) << "piece " << i << " point " << k;
    }
  }
}

// A cubic piece with all of f', f'', f''' nonzero.
PolynomialPiece Cubic(double scale) {
  PolynomialPiece::Coefficients c(3, 4);
  c << 0.0, 2.0, -1.0, 0.5 * scale,  //
      1.0, 0.5, 1.5, -0.7 * scale,   //
      -0.5, 1.0, 0.0, 0.3 * scale;
  return PolynomialPiece(c);
}

PolynomialPiece Straight(double length) {
  PolynomialPiece::Coefficients c = PolynomialPiece::Coefficients::Zero(3, 2);
  c(0, 1) = length;
  return PolynomialPiece(c);
}

TEST(JerkProfile, TrajectoryJerkMatchesFiniteDifferencesOfAcceleration) {
  const double L = 3.0;
  const Trajectory line(PiecewiseCurve({Straight(L), Straight(L)}), Mixed());
  const Trajectory curved(PiecewiseCurve({Cubic(1.0), Cubic(-2.0)}), Mixed());
  const TemporalProfile& profile = line.profile();
  int checked = 0;
  for (int i = 0; i < 2; ++i) {
    for (int k = 0; k < 4; ++k) {
      const double t0 = profile.TimeAt(i, k);
      const double t1 = k < 3 ? profile.TimeAt(i, k + 1) : profile.TimeAt(i, 0) + profile.piece_durations()[i];
      const double h = 1e-4 * (t1 - t0);
      for (double fraction : {0.1, 0.5, 0.9}) {
        const double t = t0 + fraction * (t1 - t0);
        // On the line f' = (L, 0, 0), f'' = f''' = 0: acceleration L sddot and jerk L sdddot.
        const TemporalProfile::Point p = profile.AtTime(t);
        const TrajectoryState x = line.Evaluate(t);
        EXPECT_NEAR(x.acceleration.x(), L * p.sddot, 4 * kEps * L * std::abs(p.sddot));
        EXPECT_NEAR(x.jerk.x(), L * p.sdddot, 4 * kEps * L * std::abs(p.sdddot));
        EXPECT_EQ(x.jerk.y(), 0.0);
        // Jerk against differences of the acceleration, per axis, tolerance as in the profile
        // test: Richardson estimate twice over, rounding 8 eps V / h for |a| ~ V <= 100, 1e-8.
        for (const Trajectory* trajectory : {&line, &curved}) {
          const TrajectoryState y = trajectory->Evaluate(t);
          for (int axis = 0; axis < 3; ++axis) {
            const auto d =
                CentralDifference([&](double s) { return trajectory->Evaluate(s).acceleration(axis); }, t, h);
            EXPECT_NEAR(y.jerk(axis), d.first, 2 * d.second + 8 * kEps * 100.0 / h + 1e-8)
                << "piece " << i << " cell " << k << " axis " << axis;
            const auto v = CentralDifference([&](double s) { return trajectory->Evaluate(s).velocity(axis); }, t, h);
            EXPECT_NEAR(y.acceleration(axis), v.first, 2 * v.second + 8 * kEps * 100.0 / h + 1e-8)
                << "piece " << i << " cell " << k << " axis " << axis;
          }
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 48);
}

TEST(JerkProfile, LinearProfilesReportLinearCells) {
  const TemporalProfile profile(Grid{{0.0, 0.36, 1.44, 1.0}});
  EXPECT_FALSE(profile.jerk_limited());
  EXPECT_TRUE(SmoothRestToRest().jerk_limited());
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(profile.shape(0, k), CellShape::kLinear);
    // Midpoint of a linear b, exactly as documented.
    EXPECT_EQ(profile.half_b(0, 2 * k + 1), 0.5 * (profile.b(0, k) + profile.b(0, k + 1)));
    const double t = 0.5 * (profile.TimeAt(0, k) + profile.TimeAt(0, k + 1));
    EXPECT_EQ(profile.AtTime(t).sdddot, 0.0);
    // TimeAtS at a grid point is the grid time (the same sum), within its rounding.
    EXPECT_NEAR(profile.TimeAtS(0, k / 3.0), profile.TimeAt(0, k), 4 * kEps * profile.total_time());
  }
  for (CellShape shape : kCellShapes) {
    CellShape back = CellShape::kLinear;
    EXPECT_TRUE(FromString(ToString(shape), &back));
    EXPECT_EQ(back, shape);
  }
}

// Expects JerkLimited to throw with a message containing `needle` (the piece and cell it names).
void ExpectRejected(const Grid& half, const Shapes& shapes, const std::string& needle) {
  try {
    TemporalProfile::JerkLimited(half, shapes);
    ADD_FAILURE() << "accepted; expected an error naming '" << needle << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(JerkProfile, InvalidProfilesAreRejected) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  using S = CellShape;
  const std::vector<S> two = {S::kQuadratic, S::kQuadratic};
  ExpectRejected(Grid{}, Shapes{}, "at least 1 piece");
  ExpectRejected(Grid{{1, 1, 1}}, Shapes{}, "shapes for 1 pieces, got 0");
  ExpectRejected(Grid{{1, 1, 1, 1}}, Shapes{{S::kQuadratic}}, "2K + 1");
  ExpectRejected(Grid{{1}}, Shapes{{}}, "2K + 1");
  ExpectRejected(Grid{{1, 1, 1, 1, 1}, {1, 1, 1}}, Shapes{two, two}, "piece 1 has 3 half-grid");
  ExpectRejected(Grid{{1, 1, 1, 1, 1}}, Shapes{{S::kQuadratic}}, "piece 0 has 1 cell shapes");
  ExpectRejected(Grid{{1, 1, 1, -1e-9, 1}}, Shapes{two}, "half point 3 (cell 1)");
  ExpectRejected(Grid{{1, nan, 1, 1, 1}}, Shapes{two}, "half point 1 (cell 0)");
  ExpectRejected(Grid{{1, 1, 1, 1, inf}}, Shapes{two}, "half point 4 (cell 1)");
  ExpectRejected(Grid{{1, 1, 1}}, Shapes{{S::kLinear}}, "cell 0 of piece 0 is linear");
  // b = 0 at the start with zero slope: b ~ c2 sigma^2, 1 / sqrt(b) ~ 1 / sigma, infinite time.
  ExpectRejected(Grid{{1, 1, 1, 1, 1}, {0.0, 0.25, 1.0, 1, 1}}, Shapes{two, two},
                 "cell 0 of piece 1: b = sdot^2 reaches 0 with zero slope");
  // ... and at the end.
  ExpectRejected(Grid{{1, 0.25, 0.0}}, Shapes{{S::kQuadratic}}, "cell 0 of piece 0: b = sdot^2 reaches 0");
  // b touching 0 inside (a double root at the middle): 1 / |sigma - ds/2|, infinite.
  ExpectRejected(Grid{{1, 1, 1, 0.0, 1}}, Shapes{two}, "cell 1 of piece 0: b = sdot^2 reaches 0");
  // Three positive values with b dipping below 0 between them.
  ExpectRejected(Grid{{1, 0.05, 0.2}}, Shapes{{S::kQuadratic}},
                 "cell 0 of piece 0: the quadratic b = sdot^2 drops below 0");
  // Rest cells: a far end at rest, or a near end not at rest.
  ExpectRejected(Grid{{0, 0, 0, 0.5, 1}}, Shapes{{S::kRestStart, S::kQuadratic}}, "cell 0 of piece 0 starts at rest");
  ExpectRejected(Grid{{0.1, 0.3, 1, 1, 1}}, Shapes{{S::kRestStart, S::kQuadratic}}, "cell 0 of piece 0 starts at rest");
  ExpectRejected(Grid{{1, 1, 1, 0.5, 0.2}}, Shapes{{S::kQuadratic, S::kRestEnd}}, "cell 1 of piece 0 ends at rest");
  ExpectRejected(Grid{{1, 0.5, 0, 0, 0}}, Shapes{{S::kQuadratic, S::kRestEnd}}, "cell 1 of piece 0 ends at rest");
  // Ramp cells: at the rest point itself, with b = 0 at a half point, or q below 0 between them.
  const auto rejected_ramp = [](const Grid& b, const Shapes& shapes, const std::string& needle) {
    try {
      TemporalProfile::JerkLimited(b, shapes, Grid{{0.0, 0.5, 1.0}});
      ADD_FAILURE() << "accepted; expected an error naming: " << needle;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  rejected_ramp(Grid{{1, 1, 1, 1, 1}}, Shapes{{S::kRampStart, S::kQuadratic}},
                "cell 0 of piece 0 is a ramp cell at its piece's start");
  rejected_ramp(Grid{{1, 1, 1, 1, 1}}, Shapes{{S::kQuadratic, S::kRampEnd}},
                "cell 1 of piece 0 is a ramp cell at its piece's end");
  rejected_ramp(Grid{{1, 1, 1, 0, 1}}, Shapes{{S::kQuadratic, S::kRampStart}}, "b > 0 at its three half points");
  rejected_ramp(Grid{{1, 1, 1, 0.01, 1}}, Shapes{{S::kQuadratic, S::kRampStart}}, "q = b / w^4 drops below 0");
}

}  // namespace
}  // namespace timeopt
