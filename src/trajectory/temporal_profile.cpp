#include "timeopt/trajectory/temporal_profile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "timeopt/core/enum_strings.h"

namespace timeopt {

const char* ToString(CellShape shape) {
  switch (shape) {
    case CellShape::kLinear:
      return "linear";
    case CellShape::kQuadratic:
      return "quadratic";
    case CellShape::kRestStart:
      return "rest_start";
    case CellShape::kRestEnd:
      return "rest_end";
    case CellShape::kRampStart:
      return "ramp_start";
    case CellShape::kRampEnd:
      return "ramp_end";
  }
  return "unknown";
}

bool FromString(const std::string& text, CellShape* shape) { return EnumFromString(text, kCellShapes, shape); }

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kEps = std::numeric_limits<double>::epsilon();

// The time integral of 1 / sqrt(b) over an interval of length L on which b = b_lo + slope_lo x +
// c2 x^2 rises, its slope b' going from slope_lo >= 0 to slope_hi >= 0 (b_hi >= b_lo; c2 =
// (slope_hi - slope_lo) / (2 L)). Infinite when b_lo = 0 and slope_lo = 0 (b ~ c2 x^2 near x = 0,
// a log singularity).
//
// Every term below is a sum of non-negative numbers, which is why callers reflect and split a cell
// into rising pieces first: the textbook antiderivatives subtract nearly equal logarithms or
// angles and lose all digits as c2 -> 0.
// - c2 > 0: P(x) = b'/2 + sqrt(c2 b) has P' = sqrt(c2) P / sqrt(b), so the time is
//   ln(P_hi / P_lo) / sqrt(c2) = log1p(sqrt(c2) W / P_lo) / sqrt(c2), where
//   P_hi - P_lo = sqrt(c2) W, W = sqrt(c2) L + sqrt(b_hi) - sqrt(b_lo).
// - c2 < 0, k = sqrt(-c2): phi(x) = atan2(b'/2, k sqrt(b)) has phi' = -k / sqrt(b) and the vector
//   (k sqrt(b), b'/2) keeps its length, so the time is (phi_lo - phi_hi) / k = atan2(k S, C) / k from
//   the cross and dot products of the end vectors with k taken out of the cross product:
//   S = slope_lo (sqrt(b_hi) - sqrt(b_lo)) / 2 + k^2 L sqrt(b_lo),
//   C = k^2 sqrt(b_lo b_hi) + slope_lo slope_hi / 4.
// - c2 = 0: b linear, 2 L / (sqrt(b_lo) + sqrt(b_hi)).
// Both curved forms tend to the linear one as c2 -> 0 with relative rounding only (log1p(x) / y
// and atan2(y z, w) / y stay accurate for small x, y). sqrt(b_hi) - sqrt(b_lo) is formed as
// (b_hi - b_lo) / (sqrt(b_hi) + sqrt(b_lo)) with b_hi - b_lo = L (slope_lo + slope_hi) / 2 (b' is
// linear): a sum of non-negative slopes, where subtracting b_lo from a b_hi that was itself
// computed (the extremum) would lose the digits of a small rise, and the same slopes as in the
// other terms, so that the result is the exact time of a quadratic within rounding of its data.
double RisingTime(double b_lo, double b_hi, double slope_lo, double slope_hi, double L) {
  if (!(L > 0.0)) return 0.0;
  // c2 from the slopes themselves (b' is linear), so that every term below agrees with the others.
  // A c2 formed apart from the slopes, on a cell whose b is constant up to rounding (c1, c2 and
  // b'(h) all rounding of the three b values, 1e-19 against b = 1.5e-5), put the difference of the
  // two into W, where it weighs against sqrt(c2) L: the cell's time came out 1.2e-9 relative off.
  const double c2 = (slope_hi - slope_lo) / (2.0 * L);
  const double r_lo = std::sqrt(b_lo), r_hi = std::sqrt(b_hi);
  const double root_sum = r_lo + r_hi;
  if (!(root_sum > 0.0)) return kInfinity;
  const double rise = 0.5 * L * (slope_lo + slope_hi) / root_sum;
  if (c2 == 0.0) return 2.0 * L / root_sum;
  if (c2 > 0.0) {
    const double g = std::sqrt(c2);
    const double p_lo = 0.5 * slope_lo + g * r_lo;
    if (!(p_lo > 0.0)) return kInfinity;
    return std::log1p(g * (g * L + rise) / p_lo) / g;
  }
  const double k = std::sqrt(-c2);
  const double sine = 0.5 * slope_lo * rise + (-c2) * L * r_lo;
  const double cosine = (-c2) * r_lo * r_hi + 0.25 * slope_lo * slope_hi;
  return std::atan2(k * sine, cosine) / k;
}

// A quadratic cell b(sigma) = b0 + c1 sigma + c2 sigma^2 on [0, h] through b0, bm, b1.
struct QuadraticCell {
  double h, b0, b1, c1, c2, d1;  // d1 = b'(h)

  QuadraticCell(double b0_in, double bm, double b1_in, double h_in)
      : h(h_in),
        b0(b0_in),
        b1(b1_in),
        c1((-3.0 * b0_in + 4.0 * bm - b1_in) / h_in),
        c2(2.0 * (b0_in - 2.0 * bm + b1_in) / (h_in * h_in)),
        d1((b0_in - 4.0 * bm + 3.0 * b1_in) / h_in) {}

  // b and b' expanded about the nearer end, so that near an end where b = 0 the value keeps its
  // relative accuracy instead of carrying the rounding of the far end's b.
  double B(double sigma) const {
    if (sigma <= 0.5 * h) return std::max(0.0, b0 + sigma * (c1 + c2 * sigma));
    const double back = sigma - h;  // exact for sigma in [h/2, h] (Sterbenz)
    return std::max(0.0, b1 + back * (d1 + c2 * back));
  }
  double Slope(double sigma) const { return sigma <= 0.5 * h ? c1 + 2.0 * c2 * sigma : d1 + 2.0 * c2 * (sigma - h); }

  // b at the extremum of b when b' changes sign strictly inside the cell (c1 and d1 of opposite
  // signs), from the end with the smaller slope (less cancellation in b - b'^2 / (4 c2)); NaN when
  // b is monotone on the cell.
  double VertexValue() const {
    if (!((c1 < 0.0 && d1 > 0.0) || (c1 > 0.0 && d1 < 0.0))) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    return std::abs(c1) <= std::abs(d1) ? b0 - c1 * c1 / (4.0 * c2) : b1 - d1 * d1 / (4.0 * c2);
  }

  // Time from sigma = 0 to sigma (clamped to [0, h]): the cell is reflected or split at the
  // extremum of b into pieces on which b rises, each timed by RisingTime. Infinite when b reaches
  // 0 with zero slope (or drops below 0) inside.
  double Time(double sigma) const {
    if (!(sigma > 0.0)) return 0.0;
    const double L = std::min(sigma, h);
    const double bL = sigma >= h ? b1 : B(L);
    const double dL = sigma >= h ? d1 : Slope(L);
    if (c1 >= 0.0 && dL >= 0.0) return RisingTime(b0, bL, c1, dL, L);
    if (c1 <= 0.0 && dL <= 0.0) return RisingTime(bL, b0, -dL, -c1, L);
    // b' changes sign inside, so c2 != 0; the extremum lies -c1 / (2 c2) after the start and
    // dL / (2 c2) before the end. Slopes carry the rounding of the b values they come from
    // (~eps b / h), so these two need not add up to L when c2 is small: the one from the smaller
    // slope is used, the other is what is left of L, and the extremum's b comes from that end too.
    const bool from_start = std::abs(c1) <= std::abs(dL);
    const double to_vertex = from_start ? -c1 / (2.0 * c2) : L - dL / (2.0 * c2);
    const double from_vertex = L - to_vertex;
    const double bv = from_start ? b0 - c1 * c1 / (4.0 * c2) : bL - dL * dL / (4.0 * c2);
    if (c2 > 0.0) {  // a minimum
      if (!(bv > 0.0)) return kInfinity;
      return RisingTime(bv, b0, 0.0, -c1, to_vertex) + RisingTime(bv, bL, 0.0, dL, from_vertex);
    }
    // a maximum
    return RisingTime(b0, bv, c1, 0.0, to_vertex) + RisingTime(bL, bv, -dL, 0.0, from_vertex);
  }

  // The sigma in [0, h] reached after time tau in [0, duration] (duration = Time(h)): Newton on
  // Time(sigma) = tau, whose derivative is 1 / sqrt(b), kept inside a shrinking bracket and
  // replaced by bisection when it would leave it. The start is the constant-acceleration guess
  // sqrt(b0) tau + b'(0) tau^2 / 4. It stops when the step is below a few ulps of sigma or the
  // residual below a few ulps of tau: Time itself is only that accurate.
  double Sigma(double tau, double duration) const {
    if (!(tau > 0.0)) return 0.0;
    if (tau >= duration) return h;
    double lo = 0.0, hi = h;
    double sigma = std::clamp(std::sqrt(b0) * tau + 0.25 * c1 * tau * tau, 0.0, h);
    // Bisection alone needs ~60 halvings to reach an ulp of h (more for sigma near 0), Newton a
    // handful; 200 is a bound never reached on valid cells.
    for (int iteration = 0; iteration < 200; ++iteration) {
      const double residual = Time(sigma) - tau;
      if (residual == 0.0) return sigma;
      if (residual < 0.0) {
        lo = sigma;
      } else {
        hi = sigma;
      }
      double next = sigma - residual * std::sqrt(B(sigma));
      const bool newton = next > lo && next < hi;
      if (!newton) next = 0.5 * (lo + hi);
      if (std::abs(residual) <= 2.0 * kEps * tau) return newton ? next : sigma;
      if (std::abs(next - sigma) <= 4.0 * kEps * next || next == lo || next == hi) return next;
      sigma = next;
    }
    return sigma;
  }
};

// A rest cell of length L (see the header): with w in [0, 1] the fraction of the cell's time
// from its rest point, s - s_rest = +-L w^3 and b = w^4 q(w) with q = alpha + beta w linear, so that
// w has a constant second derivative: w' = sqrt(q) / (3 L). alpha and beta follow from b at the
// cell's middle in s (w^3 = 1/2) and at its far end: q(2^(-1/3)) = 2^(4/3) b_mid, q(1) = b_far.
// beta = 0 is a constant s-jerk; alpha = q at the rest point may be 0 (the cell starts with zero
// s-jerk).
struct RestCell {
  double alpha = 0.0, beta = 0.0, L = 0.0;
  static constexpr double kMiddleW = 0.7937005259840998;  // 2^(-1/3)
  RestCell(double b_mid, double b_far, double length) : L(length) {
    alpha = TemporalProfile::RestAlpha(b_mid, b_far);
    beta = b_far - alpha;
    // Rounding of an alpha = 0 cell (relative to b_far) is not a negative alpha.
    if (alpha < 0.0 && alpha > -1e-12 * b_far) alpha = 0.0;
  }
  double Q(double w) const { return std::max(0.0, alpha + beta * w); }
  // Time from the rest point to w: 3 L times the integral of 1 / sqrt(q), in a form free of
  // cancellation as beta -> 0.
  double TimeTo(double w) const { return 6.0 * L * w / (std::sqrt(Q(w)) + std::sqrt(alpha)); }
  // Time between w and the far end (w = 1).
  double TimeFrom(double w, double one_minus_w) const {
    return 6.0 * L * one_minus_w / (std::sqrt(Q(1.0)) + std::sqrt(Q(w)));
  }
  double Duration() const { return TimeTo(1.0); }
  // w reached a time tau after the rest point: sqrt(q) = sqrt(alpha) + beta tau / (6 L).
  double WAfter(double tau) const {
    return std::clamp(tau * (2.0 * std::sqrt(alpha) + beta * tau / (6.0 * L)) / (6.0 * L), 0.0, 1.0);
  }
  // 1 - w a time tau after the far end (towards the rest point), for a rest-end cell.
  double OneMinusWAfterFar(double tau) const {
    const double t1 = Duration();
    return std::clamp(tau * (2.0 * std::sqrt(alpha) + beta * (2.0 * t1 - tau) / (6.0 * L)) / (6.0 * L), 0.0, 1.0);
  }
  // The state at w: sdot = w^2 sqrt(q), sddot = +-w (4 alpha + 5 beta w) / (6 L) (braking towards a
  // rest end), sdddot = (4 alpha + 10 beta w) sqrt(q) / (18 L^2) (the same sign for both ends).
  void State(bool start, double w, TemporalProfile::Point* p) const {
    const double root = std::sqrt(Q(w));
    p->sdot = w * w * root;
    p->sddot = (start ? 1.0 : -1.0) * w * (4.0 * alpha + 5.0 * beta * w) / (6.0 * L);
    p->sdddot = (4.0 * alpha + 10.0 * beta * w) * root / (18.0 * L * L);
  }
};

// A ramp cell [s0, s0 + len] (see the header): with omega = |w - w0| the distance in w from the
// cell's start along the path (w = w0 + eps omega, eps = +1 after a rest start, -1 before a rest
// end), q is the quadratic cell of length |w1 - w0| in omega through q_j = b_j / w_j^4, and the
// time is 3 times that cell's (dw/dt = eps sqrt(q) / 3).
struct RampCell {
  CellShape shape;
  double s0, len, w0, w1, eps;
  QuadraticCell q;
  RampCell(CellShape shape_in, double s0_in, double len_in, double b0, double bm, double b1)
      : shape(shape_in),
        s0(s0_in),
        len(len_in),
        w0(TemporalProfile::RampW(shape_in, s0_in)),
        w1(TemporalProfile::RampW(shape_in, s0_in + len_in)),
        eps(shape_in == CellShape::kRampStart ? 1.0 : -1.0),
        q(b0 / Pow4(w0), bm / Pow4(0.5 * (w0 + w1)), b1 / Pow4(w1), std::abs(w1 - w0)) {}
  static double Pow4(double w) { return (w * w) * (w * w); }
  double Omega(double sigma) const {
    return std::clamp(std::abs(TemporalProfile::RampW(shape, s0 + std::clamp(sigma, 0.0, len)) - w0), 0.0, q.h);
  }
  // sigma (from the cell's start, in s) at omega.
  double Sigma(double omega) const {
    return std::clamp(TemporalProfile::RampS(shape, w0 + eps * omega) - s0, 0.0, len);
  }
  double Time(double sigma) const { return 3.0 * q.Time(Omega(sigma)); }
  double Duration() const { return 3.0 * q.Time(q.h); }
  void State(double omega, TemporalProfile::Point* p) const {
    const double w = w0 + eps * omega;
    const double Q = q.B(omega), root = std::sqrt(Q);
    const double qw = eps * q.Slope(omega), qww = 2.0 * q.c2;
    p->sdot = w * w * root;
    p->sddot = eps * w * (4.0 * Q + w * qw) / 6.0;
    p->sdddot = root * (4.0 * Q + 6.0 * w * qw + w * w * qww) / 18.0;
  }
};

// w^4 at a rest cell's middle in s (w^3 = 1/2).
constexpr double kMiddleW4 = RestCell::kMiddleW * RestCell::kMiddleW * RestCell::kMiddleW * RestCell::kMiddleW;

RampCell RampOf(const TemporalProfile& p, int piece, int k) {
  return RampCell(p.shape(piece, k), p.CellStart(piece, k), p.CellLength(piece, k), p.half_b(piece, 2 * k),
                  p.half_b(piece, 2 * k + 1), p.half_b(piece, 2 * k + 2));
}

std::string CellName(size_t piece, int k) { return "cell " + std::to_string(k) + " of piece " + std::to_string(piece); }

}  // namespace

TemporalProfile::TemporalProfile(std::vector<std::vector<double>> b) : b_(std::move(b)) {
  if (b_.empty()) throw std::invalid_argument("TemporalProfile: expected at least 1 piece");
  const size_t points = b_.front().size();
  if (points < 2) throw std::invalid_argument("TemporalProfile: expected K >= 1 (2 grid points)");
  cells_per_piece_ = static_cast<int>(points) - 1;
  const double ds = 1.0 / cells_per_piece_;
  cell_start_.reserve(b_.size() * static_cast<size_t>(cells_per_piece_) + 1);
  cell_start_.push_back(0.0);
  for (size_t i = 0; i < b_.size(); ++i) {
    if (b_[i].size() != points) {
      throw std::invalid_argument("TemporalProfile: piece " + std::to_string(i) + " has " +
                                  std::to_string(b_[i].size()) + " grid values, expected " + std::to_string(points));
    }
    for (size_t k = 0; k < points; ++k) {
      if (!(b_[i][k] >= 0.0) || !std::isfinite(b_[i][k])) {
        throw std::invalid_argument("TemporalProfile: b of piece " + std::to_string(i) + " at grid point " +
                                    std::to_string(k) + " must be finite and >= 0");
      }
    }
    for (int k = 0; k < cells_per_piece_; ++k) {
      const double root = std::sqrt(b_[i][k]) + std::sqrt(b_[i][k + 1]);
      if (!(root > 0.0)) {
        throw std::invalid_argument("TemporalProfile: cell " + std::to_string(k) + " of piece " + std::to_string(i) +
                                    " has zero speed at both ends");
      }
      cell_start_.push_back(cell_start_.back() + 2.0 * ds / root);
    }
  }
}

TemporalProfile TemporalProfile::TimeScaled(double factor) const {
  if (!std::isfinite(factor) || !(factor > 0.0)) {
    throw std::invalid_argument("TemporalProfile::TimeScaled: expected a positive finite factor, got " +
                                std::to_string(factor));
  }
  TemporalProfile scaled = *this;
  const double b_factor = 1.0 / (factor * factor);
  for (std::vector<double>& piece : scaled.b_) {
    for (double& b : piece) b *= b_factor;
  }
  for (std::vector<double>& piece : scaled.half_b_) {
    for (double& b : piece) b *= b_factor;
  }
  // Rebuilt by its constructor from the scaled values, so that a profile equals the one its values
  // make (a trajectory file read back samples to the bit what was written); the times multiplied
  // instead only if the scaled values make no profile (underflow at an extreme factor).
  try {
    if (jerk_limited()) return JerkLimited(scaled.half_b_, shapes_, edges_);
    return TemporalProfile(scaled.b_);
  } catch (const std::invalid_argument&) {
    for (double& t : scaled.cell_start_) t *= factor;
    return scaled;
  }
}

double TemporalProfile::RestAlpha(double b_mid, double b_far) {
  // q(w_mid) = b_mid / w_mid^4 = alpha (1 - w_mid) + b_far w_mid.
  return (b_mid / kMiddleW4 - RestCell::kMiddleW * b_far) / (1.0 - RestCell::kMiddleW);
}

double TemporalProfile::RestMiddle(double alpha, double b_far) {
  return kMiddleW4 * (alpha * (1.0 - RestCell::kMiddleW) + b_far * RestCell::kMiddleW);
}

double TemporalProfile::RampW(CellShape shape, double s) {
  return std::cbrt(std::max(0.0, shape == CellShape::kRampEnd ? 1.0 - s : s));
}

double TemporalProfile::RampS(CellShape shape, double w) {
  const double cube = w * w * w;
  return shape == CellShape::kRampEnd ? 1.0 - cube : cube;
}

double TemporalProfile::RampMiddleS(CellShape shape, double s0, double s1) {
  return RampS(shape, 0.5 * (RampW(shape, s0) + RampW(shape, s1)));
}

TemporalProfile TemporalProfile::JerkLimited(std::vector<std::vector<double>> half_b,
                                             std::vector<std::vector<CellShape>> shapes,
                                             std::vector<std::vector<double>> cell_edges) {
  const std::string where = "TemporalProfile::JerkLimited: ";
  if (half_b.empty()) throw std::invalid_argument(where + "expected at least 1 piece");
  if (shapes.size() != half_b.size()) {
    throw std::invalid_argument(where + "expected shapes for " + std::to_string(half_b.size()) + " pieces, got " +
                                std::to_string(shapes.size()));
  }
  const size_t points = half_b.front().size();
  if (points < 3 || points % 2 == 0) {
    throw std::invalid_argument(where + "expected 2K + 1 half-grid values with K >= 1, got " + std::to_string(points));
  }
  TemporalProfile p;
  p.cells_per_piece_ = static_cast<int>(points / 2);
  const int K = p.cells_per_piece_;
  if (!cell_edges.empty()) {
    if (cell_edges.size() != half_b.size()) {
      throw std::invalid_argument(where + "expected cell edges for " + std::to_string(half_b.size()) + " pieces, got " +
                                  std::to_string(cell_edges.size()));
    }
    for (size_t i = 0; i < cell_edges.size(); ++i) {
      const std::vector<double>& e = cell_edges[i];
      bool ok = e.size() == static_cast<size_t>(K) + 1 && e.front() == 0.0 && e.back() == 1.0;
      for (size_t k = 0; ok && k + 1 < e.size(); ++k) ok = e[k] < e[k + 1];
      if (!ok) {
        throw std::invalid_argument(where + "the cell edges of piece " + std::to_string(i) +
                                    " must be K + 1 increasing values from 0 to 1");
      }
    }
    p.edges_ = std::move(cell_edges);
  }
  p.cell_start_.reserve(half_b.size() * static_cast<size_t>(K) + 1);
  p.cell_start_.push_back(0.0);
  for (size_t i = 0; i < half_b.size(); ++i) {
    std::vector<double>& h = half_b[i];
    if (h.size() != points) {
      throw std::invalid_argument(where + "piece " + std::to_string(i) + " has " + std::to_string(h.size()) +
                                  " half-grid values, expected " + std::to_string(points));
    }
    if (shapes[i].size() != static_cast<size_t>(K)) {
      throw std::invalid_argument(where + "piece " + std::to_string(i) + " has " + std::to_string(shapes[i].size()) +
                                  " cell shapes, expected " + std::to_string(K));
    }
    for (size_t j = 0; j < points; ++j) {
      if (!(h[j] >= 0.0) || !std::isfinite(h[j])) {
        throw std::invalid_argument(where + "b of piece " + std::to_string(i) + " at half point " + std::to_string(j) +
                                    " (cell " + std::to_string(std::min<size_t>(j / 2, K - 1)) +
                                    ") must be finite and >= 0");
      }
    }
    for (int k = 0; k < K; ++k) {
      const double b0 = h[2 * k], b1 = h[2 * k + 2];
      const double ds = p.CellLength(static_cast<int>(i), k);
      double duration = 0.0;
      switch (shapes[i][k]) {
        case CellShape::kLinear:
          throw std::invalid_argument(where + CellName(i, k) +
                                      " is linear; a jerk-limited profile takes quadratic, "
                                      "rest and ramp cells");
        case CellShape::kRestStart:
        case CellShape::kRestEnd: {
          const bool start = shapes[i][k] == CellShape::kRestStart;
          const double b_rest = start ? b0 : b1, b_far = start ? b1 : b0;
          if (b_rest != 0.0 || !(b_far > 0.0)) {
            throw std::invalid_argument(where + CellName(i, k) +
                                        (start ? " starts at rest: expected b = 0 at its start and b > 0 at its end"
                                               : " ends at rest: expected b > 0 at its start and b = 0 at its end"));
          }
          const RestCell cell(h[2 * k + 1], b_far, ds);
          if (!(cell.alpha >= 0.0)) {
            throw std::invalid_argument(where + CellName(i, k) + (start ? " starts" : " ends") +
                                        " at rest: b in its middle must be at least 2^(-5/3) times b at its far "
                                        "end (q at the rest point >= 0)");
          }
          duration = cell.Duration();
          break;
        }
        case CellShape::kRampStart:
        case CellShape::kRampEnd: {
          const bool start = shapes[i][k] == CellShape::kRampStart;
          const double s0 = p.CellStart(static_cast<int>(i), k);
          if ((start && !(s0 > 0.0)) || (!start && !(s0 + ds < 1.0))) {
            throw std::invalid_argument(where + CellName(i, k) + " is a ramp cell at its piece's " +
                                        (start ? "start" : "end") + ": a ramp lies after a rest cell");
          }
          if (!(b0 > 0.0) || !(h[2 * k + 1] > 0.0) || !(b1 > 0.0)) {
            throw std::invalid_argument(where + CellName(i, k) +
                                        " is a ramp cell: expected b > 0 at its three half points");
          }
          const RampCell cell(shapes[i][k], s0, ds, b0, h[2 * k + 1], b1);
          if (cell.q.VertexValue() < 0.0) {
            throw std::invalid_argument(where + CellName(i, k) + ": the ramp cell's q = b / w^4 drops below 0 inside");
          }
          duration = cell.Duration();
          if (!std::isfinite(duration) || !(duration > 0.0)) {
            throw std::invalid_argument(where + CellName(i, k) + ": the ramp cell would take forever");
          }
          break;
        }
        case CellShape::kQuadratic: {
          const QuadraticCell cell(b0, h[2 * k + 1], b1, ds);
          if (cell.VertexValue() < 0.0) {
            throw std::invalid_argument(where + CellName(i, k) + ": the quadratic b = sdot^2 drops below 0 inside");
          }
          duration = cell.Time(ds);
          if (!std::isfinite(duration) || !(duration > 0.0)) {
            throw std::invalid_argument(where + CellName(i, k) +
                                        ": b = sdot^2 reaches 0 with zero slope (at an end or "
                                        "inside), so the cell would take forever");
          }
          break;
        }
        default:
          throw std::invalid_argument(where + CellName(i, k) + " has an unknown shape");
      }
      p.cell_start_.push_back(p.cell_start_.back() + duration);
    }
    std::vector<double> grid(static_cast<size_t>(K) + 1);
    for (int k = 0; k <= K; ++k) grid[k] = h[2 * k];
    p.b_.push_back(std::move(grid));
  }
  p.half_b_ = std::move(half_b);
  p.shapes_ = std::move(shapes);
  return p;
}

double TemporalProfile::a(int piece, int k) const {
  if (!edges_.empty()) return (b_[piece][k + 1] - b_[piece][k]) * 0.5 / CellLength(piece, k);
  return (b_[piece][k + 1] - b_[piece][k]) * 0.5 * cells_per_piece_;
}

double TemporalProfile::half_b(int piece, int j) const {
  if (jerk_limited()) return half_b_[piece][j];
  return j % 2 == 0 ? b_[piece][j / 2] : 0.5 * (b_[piece][j / 2] + b_[piece][j / 2 + 1]);
}

CellShape TemporalProfile::shape(int piece, int k) const {
  return jerk_limited() ? shapes_[piece][k] : CellShape::kLinear;
}

std::vector<double> TemporalProfile::piece_durations() const {
  std::vector<double> out(b_.size());
  for (size_t i = 0; i < b_.size(); ++i) {
    out[i] = cell_start_[(i + 1) * cells_per_piece_] - cell_start_[i * cells_per_piece_];
  }
  return out;
}

double TemporalProfile::TimeAt(int piece, int k) const {
  return cell_start_[static_cast<size_t>(piece) * cells_per_piece_ + k];
}

double TemporalProfile::CellStart(int piece, int k) const {
  return edges_.empty() ? k * (1.0 / cells_per_piece_) : edges_[piece][k];
}

double TemporalProfile::CellLength(int piece, int k) const {
  return edges_.empty() ? 1.0 / cells_per_piece_ : edges_[piece][k + 1] - edges_[piece][k];
}

void TemporalProfile::Locate(int piece, double s, int* k, double* sigma) const {
  s = std::clamp(std::isnan(s) ? 0.0 : s, 0.0, 1.0);
  if (edges_.empty()) {
    const double ds = 1.0 / cells_per_piece_;
    *k = std::min(static_cast<int>(s * cells_per_piece_), cells_per_piece_ - 1);
    *sigma = std::clamp(s - *k * ds, 0.0, ds);
    return;
  }
  const std::vector<double>& e = edges_[piece];
  *k = static_cast<int>(std::upper_bound(e.begin(), e.end(), s) - e.begin()) - 1;
  *k = std::clamp(*k, 0, cells_per_piece_ - 1);
  *sigma = std::clamp(s - e[*k], 0.0, e[*k + 1] - e[*k]);
}

double TemporalProfile::TimeInCell(int piece, int k, double sigma) const {
  const double ds = CellLength(piece, k);
  if (!(sigma > 0.0)) return 0.0;
  switch (shape(piece, k)) {
    case CellShape::kLinear: {
      const double b0 = b_[piece][k];
      const double b_sigma = std::max(0.0, b0 + 2.0 * a(piece, k) * sigma);
      return 2.0 * sigma / (std::sqrt(b0) + std::sqrt(b_sigma));
    }
    case CellShape::kQuadratic:
      return QuadraticCell(half_b_[piece][2 * k], half_b_[piece][2 * k + 1], half_b_[piece][2 * k + 2], ds).Time(sigma);
    case CellShape::kRestStart:
      return RestCell(half_b_[piece][2 * k + 1], b_[piece][k + 1], ds).TimeTo(std::cbrt(std::min(sigma / ds, 1.0)));
    case CellShape::kRestEnd: {
      // 1 - w with w^3 = 1 - sigma / ds, without cancellation for small sigma.
      const double x = std::min(sigma / ds, 1.0);
      const double one_minus_w = -std::expm1(std::log1p(-x) / 3.0);
      return RestCell(half_b_[piece][2 * k + 1], b_[piece][k], ds).TimeFrom(1.0 - one_minus_w, one_minus_w);
    }
    case CellShape::kRampStart:
    case CellShape::kRampEnd:
      return RampOf(*this, piece, k).Time(sigma);
  }
  return 0.0;
}

TemporalProfile::Point TemporalProfile::StateInCell(int piece, int k, double sigma) const {
  const double ds = CellLength(piece, k);
  sigma = std::clamp(sigma, 0.0, ds);
  Point p;
  p.piece = piece;
  p.s = std::min(CellStart(piece, k) + sigma, 1.0);
  switch (shape(piece, k)) {
    case CellShape::kLinear:
      p.sddot = a(piece, k);
      p.sdot = std::sqrt(std::max(0.0, b_[piece][k] + 2.0 * p.sddot * sigma));
      break;
    case CellShape::kQuadratic: {
      const QuadraticCell cell(half_b_[piece][2 * k], half_b_[piece][2 * k + 1], half_b_[piece][2 * k + 2], ds);
      p.sdot = std::sqrt(cell.B(sigma));
      p.sddot = 0.5 * cell.Slope(sigma);
      p.sdddot = cell.c2 * p.sdot;
      break;
    }
    case CellShape::kRestStart:
      RestCell(half_b_[piece][2 * k + 1], b_[piece][k + 1], ds).State(true, std::cbrt(sigma / ds), &p);
      break;
    case CellShape::kRestEnd:
      RestCell(half_b_[piece][2 * k + 1], b_[piece][k], ds).State(false, std::cbrt((ds - sigma) / ds), &p);
      break;
    case CellShape::kRampStart:
    case CellShape::kRampEnd: {
      const RampCell cell = RampOf(*this, piece, k);
      cell.State(cell.Omega(sigma), &p);
      break;
    }
  }
  return p;
}

void TemporalProfile::InCellSamples(int piece, int k, int n, Point* out) const {
  if (shape(piece, k) != CellShape::kQuadratic) {
    for (int j = 0; j <= n; ++j) out[j] = StateInCell(piece, k, (static_cast<double>(j) / n) * CellLength(piece, k));
    return;
  }
  // StateInCell's quadratic case with the cell formed once (the dense check's samples).
  const double ds = CellLength(piece, k), start = CellStart(piece, k);
  const QuadraticCell cell(half_b_[piece][2 * k], half_b_[piece][2 * k + 1], half_b_[piece][2 * k + 2], ds);
  for (int j = 0; j <= n; ++j) {
    const double sigma = std::clamp((static_cast<double>(j) / n) * ds, 0.0, ds);
    Point& p = out[j];
    p.piece = piece;
    p.s = std::min(start + sigma, 1.0);
    p.sdot = std::sqrt(cell.B(sigma));
    p.sddot = 0.5 * cell.Slope(sigma);
    p.sdddot = cell.c2 * p.sdot;
  }
}

double TemporalProfile::TimeAtS(int piece, double s) const {
  int k = 0;
  double sigma = 0.0;
  Locate(piece, s, &k, &sigma);
  const size_t cell = static_cast<size_t>(piece) * cells_per_piece_ + k;
  if (sigma >= CellLength(piece, k)) return cell_start_[cell + 1];
  return cell_start_[cell] + TimeInCell(piece, k, sigma);
}

TemporalProfile::Point TemporalProfile::AtS(int piece, double s) const {
  int k = 0;
  double sigma = 0.0;
  Locate(piece, s, &k, &sigma);
  return StateInCell(piece, k, sigma);
}

TemporalProfile::Point TemporalProfile::AtTime(double t) const {
  Point p;
  if (b_.empty()) return p;
  const double T = total_time();
  t = std::clamp(std::isnan(t) ? 0.0 : t, 0.0, T);
  // Last cell whose start time is <= t.
  auto it = std::upper_bound(cell_start_.begin(), cell_start_.end(), t);
  size_t cell = static_cast<size_t>(std::distance(cell_start_.begin(), it));
  cell = cell == 0 ? 0 : cell - 1;
  const size_t num_cells = cell_start_.size() - 1;
  if (cell >= num_cells) cell = num_cells - 1;
  const int piece = static_cast<int>(cell / cells_per_piece_);
  const int k = static_cast<int>(cell % cells_per_piece_);
  const double duration = cell_start_[cell + 1] - cell_start_[cell];
  const double tau = std::min(t - cell_start_[cell], duration);
  const double ds = CellLength(piece, k);
  switch (shape(piece, k)) {
    case CellShape::kLinear: {
      const double v0 = std::sqrt(b_[piece][k]);
      const double acc = a(piece, k);
      p.piece = piece;
      p.sddot = acc;
      p.sdot = std::max(0.0, v0 + acc * tau);
      p.s = std::clamp(k * ds + v0 * tau + 0.5 * acc * tau * tau, k * ds, (k + 1) * ds);
      return p;
    }
    case CellShape::kQuadratic: {
      const QuadraticCell q(half_b_[piece][2 * k], half_b_[piece][2 * k + 1], half_b_[piece][2 * k + 2], ds);
      // The cell's own time, not the difference of the cumulative sums, so that tau = duration
      // lands on sigma = ds.
      return StateInCell(piece, k, q.Sigma(tau, q.Time(ds)));
    }
    case CellShape::kRestStart: {
      // sigma = ds w^3 with w from tau in closed form.
      const RestCell cell(half_b_[piece][2 * k + 1], b_[piece][k + 1], ds);
      const double w = cell.WAfter(tau);
      p = StateInCell(piece, k, ds * w * w * w);
      cell.State(true, w, &p);
      return p;
    }
    case CellShape::kRestEnd: {
      // w is the fraction of the cell's time left; ds - sigma = ds w^3, so sigma =
      // ds (1 - w) (1 + w + w^2), free of cancellation near the start.
      const RestCell cell(half_b_[piece][2 * k + 1], b_[piece][k], ds);
      const double one_minus_w = cell.OneMinusWAfterFar(tau), w = 1.0 - one_minus_w;
      p = StateInCell(piece, k, ds * one_minus_w * (1.0 + w + w * w));
      cell.State(false, w, &p);
      return p;
    }
    case CellShape::kRampStart:
    case CellShape::kRampEnd: {
      // omega from the quadratic cell of q in w (a third of the time), then s from w.
      const RampCell cell = RampOf(*this, piece, k);
      const double omega = cell.q.Sigma(tau / 3.0, cell.q.Time(cell.q.h));
      p = StateInCell(piece, k, cell.Sigma(omega));
      cell.State(omega, &p);
      return p;
    }
  }
  return p;
}

}  // namespace timeopt
