// The cells of the jerk-limited grid (jerk_grid.h).

#include "jerk_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "discretization_internal.h"

namespace timeopt::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
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
// A rest point on a curve (a rest cell that RestCellSize halves, or a curved one longer than a
// nominal cell) gets ramp cells (CellShape::kRampStart / kRampEnd): with the rest cell, n cells
// uniform in w = s^(1/3) over kRampLengthFactor times the ramp from rest (RampLength, at most
// kLargestRestCell), n = kRampCellsPerNominal S K rounded (S that length; at least kMinRampCells
// and at most K / 3, so none below K = 9; the last ramp cell is then about 3 / kRampCellsPerNominal
// nominal cells long), followed by cells growing by kRampGrading up to the nominal cell. In a ramp
// cell a constant s-jerk from rest is exact and its s-jerk is not tied to sdot (a regular cell's is
// proportional to sdot, so along a ramp it holds the jerk below its limit at each cell's start; the
// geometric cells that made up for that took up to K / 3 cells per end). Against the time-domain
// reference on the 12 rest-to-rest curves (time_domain_reference_test.cpp), at K = 50 / 100 / 200
// the worst curve went from +0.73 / +0.42 / +0.30% (geometric cells, kRestGrading) to +0.48 / +0.24
// / +0.13%, all 12 within 0.5% at K = 50 (9 before). The worst curve at K = 50 for other choices
// (length factor, cells per nominal cell): with grading 1.5, (1.5, 3) +0.54%, (2, 3) +0.52%, (2, 4)
// +0.49%, (2.5, 4) +0.49%, (2.5, 5) +0.48%, (3, 4) +0.51%, (3, 5) +0.53%, (3, 6) +0.53%; without it
// (2, 4) +0.48%, (2.5, 4) +0.53%.
constexpr double kRampLengthFactor = 2.0;
constexpr double kRampCellsPerNominal = 5.0;
constexpr int kMinRampCells = 3;
// Ramp cells only where they number at most kMaxRampCells (a ramp region of at most 20 nominal
// cells; beyond, the geometric cells above). On the reference curve whose start is halved most, K =
// 1000 has 229 of them and K = 2000 458: there the structured path did not answer (the general path
// did, in 5 s and 217 MB against 0.08 s and 41 MB with geometric cells); with at most 100 of
// them and the region cut to fit, or fewer and longer cells, K = 2000-5000 failed too.
constexpr int kMaxRampCells = 100;
constexpr double kRampGrading = 1.5;
// The smallest rest cell, relative to the nominal cell 1 / K, and the largest, in s.
constexpr double kSmallestRestCell = 1.0 / 64.0;
constexpr double kLargestRestCell = 0.25;

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

}  // namespace

// The rest cell at the start (end = false) or end of piece i: the ramp from rest (RampLength),
// halved (at most 5 times) until a constant s-jerk over it keeps at least kRestJerkShare of the
// jerk limit at the rest point (on a curve the terms of f'' and f''' grow through the cell) and
// nowhere less than kRestJerkSlack of its largest value (where they fall, the optimum's s-jerk
// grows).
RestSize RestCellSize(const TemporalProblem& p, int piece, bool end, bool rest_to_rest) {
  RestSize r;
  r.cell = RampLength(p, piece, end, rest_to_rest);
  r.ramp = r.cell;
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

std::vector<double> CellEdges(int K, const RestSize& rest_start, const RestSize& rest_end, int (*ramp_cells)[2],
                              bool ramp_degree_fits) {
  const double ds = 1.0 / K;
  if (ramp_cells != nullptr) (*ramp_cells)[0] = (*ramp_cells)[1] = 0;
  // The cells of one end, from the rest point on. A rest cell halved below its ramp (RestSize), or
  // one on a curve longer than a nominal cell and cut to one, is followed by cells whose edges grow
  // by kRestGrading up to the nominal cell, which carry on the ramp (sdot grows like the time
  // squared there, and a cell whose ends differ much in sdot holds its jerk well below the limit at
  // its start). Otherwise, a ramp of at least half a nominal cell gets one rest cell of its length
  // (at most a quarter of the piece); a shorter one h, h, 2 h, ..., 2^(n-1) h with the last one
  // widened so that they sum to ds. At most K / 3 cells per end.
  const auto graded = [&](const RestSize& rest, int* ramp) {
    std::vector<double> g;
    double h = rest.cell;
    if (!(h > 0.0) || K < 4) return g;
    const double ramp_region = std::min(kRampLengthFactor * rest.ramp, kLargestRestCell);
    if (ramp != nullptr && ramp_degree_fits && !rest.braking && K / 3 >= kMinRampCells &&
        kSmallestRestCell * ds < 0.5 * ramp_region && kRampCellsPerNominal * ramp_region * K <= kMaxRampCells &&
        (rest.halved || (rest.curved && h > ds))) {
      // A curved start: a rest cell and ramp cells, uniform in w = s^(1/3) over kRampLengthFactor
      // ramps, then cells growing by kRampGrading up to the nominal cell.
      const double S = ramp_region;
      const int n = std::clamp(static_cast<int>(std::lround(kRampCellsPerNominal * S * K)), kMinRampCells, K / 3);
      // The rest cell at least kSmallestRestCell of the nominal cell (uniform in w it would be S /
      // n^3, 3e-6 of the piece at K = 100), the ramp cells uniform in w from its end to S.
      const double first = std::max(S / (n * n * n), kSmallestRestCell * ds);
      const double w1 = std::cbrt(first / S);
      double previous = 0.0;
      for (int j = 0; j < n; ++j) {
        const double w = j == 0 ? w1 : w1 + (1.0 - w1) * j / (n - 1.0);
        const double edge = j + 1 == n ? S : S * w * w * w;
        g.push_back(edge - previous);
        previous = edge;
      }
      *ramp = n - 1;
      for (double next = S * (kRampGrading - 1.0); next < ds && static_cast<int>(g.size()) < K / 3;
           next *= kRampGrading) {
        g.push_back(next);
      }
      return g;
    }
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
  std::vector<double> head = graded(rest_start, ramp_cells ? &(*ramp_cells)[0] : nullptr),
                      tail = graded(rest_end, ramp_cells ? &(*ramp_cells)[1] : nullptr);
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

}  // namespace timeopt::internal
