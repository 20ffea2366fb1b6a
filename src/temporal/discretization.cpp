#include "discretization.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "discretization_internal.h"
#include "timeopt/core/enum_strings.h"

namespace timeopt {

const char* ToString(JointType type) {
  switch (type) {
    case JointType::kC1:
      return "C1";
    case JointType::kG1:
      return "G1";
    case JointType::kStop:
      return "stop";
  }
  return "unknown";
}

bool FromString(const std::string& text, JointType* type) { return EnumFromString(text, kJointTypes, type); }

namespace {

using namespace internal;

constexpr double kInf = std::numeric_limits<double>::infinity();
// The variable scale's cap over the squared speed the largest acceleration limit reaches over the
// whole path (AssignGridValues). A squared speed along the path is at most sqrt(3) times that one
// (the per-axis limits together allow sqrt(3) times the largest along the path), so a cap of 4
// times it never takes effect where the velocity limit can bind. It had been 1e6: a 1.2 cm minimum-jerk piece under
// speed limits of about 500 m/s (it reaches 0.8 m/s) had its unknowns near 1e-6, and both the structured path and the
// conic solver failed ("no step keeps the iterate inside the cones"; the property sweep, seed 3, problem 9450); now the
// structured path answers in 11 iterations, T within 1e-9 of Ipopt's.
constexpr double kUnreachableSpeedShare = 4;

}  // namespace

double TemporalDiscretization::GridB(int g, const std::vector<double>& x) const {
  const GridValue& v = grid[static_cast<size_t>(g)];
  return v.var < 0 ? v.fixed : v.scale * x[static_cast<size_t>(v.var)];
}

double TemporalDiscretization::Objective(const std::vector<double>& x, double* total_time) const {
  double time = 0.0, reg = 0.0;
  for (const Cell& c : cells) {
    if (c.time_weight == 0.0 && rho == 0.0) continue;  // no time, no regularization (a rest cell's half)
    const double b0 = std::max(0.0, GridB(c.first_grid, x));
    const double b1 = std::max(0.0, GridB(c.first_grid + 1, x));
    const double root = std::sqrt(b0) + std::sqrt(b1);
    time += root > 0.0 ? c.time_weight * 2.0 * c.ds / root : std::numeric_limits<double>::infinity();
    const double a = (b1 - b0) / (2.0 * c.ds);
    reg += a * a * c.ds;
  }
  if (total_time) *total_time = time;
  return time + rho * reg;
}

double CubicRow::Value(const std::array<double, 3>& b) const {
  double value = 0.0;
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 3; ++k) {
      for (int l = 0; l < 3; ++l) value += coef[static_cast<size_t>(9 * j + 3 * k + l)] * b[j] * b[k] * b[l];
    }
  }
  return value;
}

Eigen::Vector3d ConeRow::NormPart(const std::vector<double>& b) const {
  Eigen::Vector3d v = norm_constant;
  for (size_t j = 0; j < grid.size(); ++j) v += norm[j] * b[j];
  return v;
}

double ConeRow::BoundPart(const std::vector<double>& b) const {
  double t = bound_constant;
  for (size_t j = 0; j < grid.size(); ++j) t += bound[j] * b[j];
  return t;
}

double TemporalDiscretization::MaxViolation(const std::vector<double>& x) const {
  double worst = 0.0;
  for (size_t v = 0; v < var_upper.size(); ++v) {
    worst = std::max(worst, -x[v]);
    if (std::isfinite(var_upper[v])) worst = std::max(worst, x[v] - var_upper[v]);
  }
  for (const LinearRow& r : rows) {
    double value = 0.0;
    for (const auto& t : r.terms) value += t.second * x[static_cast<size_t>(t.first)];
    if (std::isfinite(r.lower)) worst = std::max(worst, r.lower - value);
    if (std::isfinite(r.upper)) worst = std::max(worst, value - r.upper);
  }
  for (const CubicRow& r : cubic_rows) {
    const std::array<double, 3> b = {GridB(r.grid[0], x), GridB(r.grid[1], x), GridB(r.grid[2], x)};
    worst = std::max(worst, r.Value(b) - 1.0);
  }
  std::vector<double> b;
  for (const ConeRow& r : cone_rows) {
    b.clear();
    for (int g : r.grid) b.push_back(GridB(g, x));
    worst = std::max(worst, r.NormPart(b).norm() - r.BoundPart(b));
  }
  return worst;
}

namespace internal {

// Of the rows coef * x_v <= upper with coef > 0 (upper bounds on one variable; certified mode makes one
// per grid point in each of the two cells around it, and fixed neighbours make more) keeps the
// tightest per variable, in place of the first; the others are implied by it.
void KeepTightestUpperBounds(TemporalDiscretization* d) {
  std::vector<int> kept(static_cast<size_t>(d->num_vars), -1);  // row index per variable
  std::vector<LinearRow>& rows = d->rows;
  std::vector<bool> drop(rows.size(), false);
  for (size_t r = 0; r < rows.size(); ++r) {
    const LinearRow& row = rows[r];
    if (row.terms.size() != 1 || !(row.terms[0].second > 0.0) || std::isfinite(row.lower)) continue;
    int& k = kept[static_cast<size_t>(row.terms[0].first)];
    if (k < 0) {
      k = static_cast<int>(r);
      continue;
    }
    const LinearRow& other = rows[static_cast<size_t>(k)];
    // Bound upper / coef, compared without dividing: row is tighter iff upper * c_other < u_other * c.
    if (row.upper * other.terms[0].second < other.upper * row.terms[0].second) {
      drop[static_cast<size_t>(k)] = true;
      k = static_cast<int>(r);
    } else {
      drop[r] = true;
    }
  }
  size_t out = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (!drop[r]) {
      if (out != r) rows[out] = std::move(rows[r]);
      ++out;
    }
  }
  rows.resize(out);
}

// Boundary grid value from a given velocity and the tangent there; a free value gets `scale`.
GridValue BoundaryValue(const Eigen::Vector3d& velocity, const Eigen::Vector3d& tangent, const TemporalProblem& p,
                        const std::string& field, double scale, int* next_var) {
  GridValue g;
  const double tn = tangent.norm();
  const double vn = velocity.norm();
  if (tn <= p.zero_tangent_tolerance) {
    if (vn != 0.0) {
      throw std::invalid_argument(field +
                                  ": the curve's tangent vanishes there, so only a zero "
                                  "velocity is possible");
    }
    g.var = (*next_var)++;  // v = f' sqrt(b) = 0 for any b: b is free
    g.scale = scale;
    return g;
  }
  if (vn == 0.0) {
    g.fixed = 0.0;
    return g;
  }
  const double angle = Angle(velocity, tangent);
  if (angle > p.parallel_tolerance) {
    std::ostringstream ss;
    ss << field << ": must be parallel to the curve's tangent (" << tangent.transpose() << "), the angle is " << angle
       << " rad";
    throw std::invalid_argument(ss.str());
  }
  g.fixed = (vn / tn) * (vn / tn);
  return g;
}

// ---- the stages of Discretize, in the order it runs them ----

// The type of every joint between pieces (C1, G1 with its speed ratio, or a stop).
void ClassifyJoints(const TemporalProblem& problem, TemporalDiscretization* out) {
  TemporalDiscretization& d = *out;
  const PiecewiseCurve& curve = problem.curve;
  const int m = curve.num_pieces();
  for (int i = 0; i + 1 < m; ++i) {
    const Eigen::Vector3d t0 = curve.Evaluate(i, 1.0, 1), t1 = curve.Evaluate(i + 1, 0.0, 1);
    JointInfo j;
    j.joint = i;
    const double n0 = t0.norm(), n1 = t1.norm();
    if (n0 <= problem.zero_tangent_tolerance || n1 <= problem.zero_tangent_tolerance) {
      j.type = JointType::kStop;
      j.speed_ratio = 0.0;
      j.angle = 0.0;
      std::ostringstream why;
      why << "the tangent vanishes at the "
          << (n0 <= problem.zero_tangent_tolerance ? "end of piece " : "start of piece ")
          << (n0 <= problem.zero_tangent_tolerance ? i : i + 1) << " (" << std::min(n0, n1)
          << " m per unit s, at most zero_tangent_tolerance " << problem.zero_tangent_tolerance << ")";
      j.reason = why.str();
    } else {
      j.angle = Angle(t0, t1);
      j.speed_ratio = n0 / n1;
      if (j.angle > problem.parallel_tolerance) {
        j.type = JointType::kStop;
        std::ostringstream why;
        why << "the tangents turn by " << j.angle << " rad (above parallel_tolerance " << problem.parallel_tolerance
            << ")";
        j.reason = why.str();
      } else if (std::abs(j.speed_ratio - 1.0) <= 1e-12) {
        // Equal up to rounding: eq. 43 exactly.
        j.type = JointType::kC1;
        j.speed_ratio = 1.0;
      } else {
        j.type = JointType::kG1;
      }
    }
    d.joints.push_back(j);
  }
}

namespace {

// Whether an interior piece may be short enough to be tied, from the coefficients alone (no
// evaluation; most curves end here): its chord |f(1) - f(0)| is at most its length, and every
// length at most sum k |c_k|, the largest |f'|. Loose by 4 x, as PieceLengthEstimate is an estimate.
bool MayHaveShortPiece(const PiecewiseCurve& curve) {
  const int m = curve.num_pieces();
  if (m < 3) return false;
  double upper = 0.0, shortest_chord = std::numeric_limits<double>::infinity();
  for (int i = 0; i < m; ++i) {
    const PolynomialPiece::Coefficients& c = curve.piece(i).coefficients();
    Eigen::Vector3d chord = Eigen::Vector3d::Zero();
    for (int k = 1; k < c.cols(); ++k) {
      chord += c.col(k);
      upper += k * c.col(k).norm();
    }
    if (i > 0 && i + 1 < m) shortest_chord = std::min(shortest_chord, chord.norm());
  }
  return !(shortest_chord > 4.0 * kTiedPieceShare * upper);
}

// The pieces that would be tied (TemporalDiscretization::tied) but for rounding: interior, between
// joints that are not stops, at most kTiedPieceShare of the longest piece within two of it, the
// tangent nowhere vanishing; their lengths in `length` (all pieces), and with a jerk limit the length
// below which rounding in b makes no profile on a piece trustworthy in `rounding_length`. With a
// jerk limit, a piece of length l carries b ~ (v / l)^2 per unit s, and rounding in b (eps b per
// value) makes a jerk of the order of eps v^3 (2 K)^2 / l^2 along its cells of 1 / (2 K): where
// that is above kJerkRoundingRatio times the jerk limit. v: the fastest speed the limits and the
// path allow.
std::vector<char> TieCandidates(const TemporalProblem& problem, const std::vector<JointInfo>& joints,
                                std::vector<double>* length, double* rounding_length) {
  const PiecewiseCurve& curve = problem.curve;
  const int m = curve.num_pieces();
  std::vector<char> candidate(static_cast<size_t>(m), 0);
  *rounding_length = 0.0;
  length->assign(static_cast<size_t>(m), 0.0);
  if (problem.limits.max_acceleration_change || !MayHaveShortPiece(curve)) return candidate;
  double path = 0.0;
  for (int i = 0; i < m; ++i) {
    (*length)[static_cast<size_t>(i)] = PieceLengthEstimate(curve, i);
    path += (*length)[static_cast<size_t>(i)];
  }
  const TemporalLimits& limits = problem.limits;
  if (limits.max_jerk) {
    double v = 0.0, a = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      if (std::isfinite(limits.max_velocity(axis))) v = std::max(v, limits.max_velocity(axis));
      if (std::isfinite(limits.max_acceleration(axis))) a = std::max(a, limits.max_acceleration(axis));
    }
    if (limits.max_speed) v = std::max(v, *limits.max_speed);
    if (limits.max_acceleration_norm) a = std::max(a, *limits.max_acceleration_norm);
    const double boundary =
        std::max(problem.boundary.start_velocity.squaredNorm(), problem.boundary.end_velocity.squaredNorm());
    const double reach = std::sqrt(boundary + 2.0 * a * path);
    if (a > 0.0) v = v > 0.0 ? std::min(v, reach) : reach;
    const double cells = 2.0 * problem.cells_per_piece, j = limits.max_jerk->minCoeff();
    *rounding_length =
        std::sqrt(std::numeric_limits<double>::epsilon() * v * v * v * cells * cells / (kJerkRoundingRatio * j));
  }
  for (int i = 1; i + 1 < m; ++i) {
    if (joints[static_cast<size_t>(i - 1)].type == JointType::kStop ||
        joints[static_cast<size_t>(i)].type == JointType::kStop) {
      continue;
    }
    // Short against the longest piece within two of it (a run of short pieces ties as a whole).
    double around = 0.0;
    for (int n = std::max(0, i - 2); n <= std::min(m - 1, i + 2); ++n) {
      if (n != i) around = std::max(around, (*length)[static_cast<size_t>(n)]);
    }
    if (!((*length)[static_cast<size_t>(i)] <= kTiedPieceShare * around)) continue;
    // Its tangent must not vanish inside either (its values are scaled by it).
    bool moving = true;
    for (int k = 0; k <= 16 && moving; ++k) {
      moving = curve.Evaluate(i, k / 16.0, 1).norm() > problem.zero_tangent_tolerance;
    }
    candidate[static_cast<size_t>(i)] = moving ? 1 : 0;
  }
  return candidate;
}

// TieCandidates of a problem whose joints are not classified yet (outside a discretization).
std::vector<char> TieCandidates(const TemporalProblem& problem, std::vector<double>* length, double* rounding_length) {
  TemporalDiscretization d;
  ClassifyJoints(problem, &d);
  return TieCandidates(problem, d.joints, length, rounding_length);
}

}  // namespace

// A tied piece gives up its own profile: without a jerk limit it is crossed at the speed it is
// entered with, with one at the tangential acceleration it is entered with (its s-jerk 0). On a
// piece of length l entered at v with acceleration a that costs at most about l / v times the
// relative change a jerk or an acceleration would have made over it: T within 1e-4 of the straight
// line's optimum at a share of 2e-3 (measured, reliability_test.cpp).
void MarkTiedPieces(const TemporalProblem& problem, TemporalDiscretization* d) {
  std::vector<double> length;
  double rounding_length = 0.0;
  d->tied = TieCandidates(problem, d->joints, &length, &rounding_length);
  for (size_t i = 0; i < d->tied.size(); ++i) {
    if (d->tied[i] && !(length[i] > rounding_length)) d->tied[i] = 0;
  }
}

std::optional<std::string> TiedPieceTooShortForItsSpeed(const TemporalProblem& problem,
                                                        const TemporalProfile& profile) {
  if (!problem.limits.max_jerk || profile.num_pieces() != problem.curve.num_pieces() ||
      !MayHaveShortPiece(problem.curve)) {
    return std::nullopt;
  }
  std::vector<double> length;
  double rounding_length = 0.0;
  const std::vector<char> candidate = TieCandidates(problem, &length, &rounding_length);
  double path = 0.0;
  for (double l : length) path += l;
  const double cells = 2.0 * problem.cells_per_piece, j = problem.limits.max_jerk->minCoeff();
  for (size_t i = 0; i < candidate.size(); ++i) {
    if (!candidate[i] || !(length[i] > rounding_length)) continue;
    const int piece = static_cast<int>(i);
    const double v = std::max(profile.AtS(piece, 0.0).sdot * problem.curve.Evaluate(piece, 0.0, 1).norm(),
                              profile.AtS(piece, 1.0).sdot * problem.curve.Evaluate(piece, 1.0, 1).norm());
    const double ratio =
        std::numeric_limits<double>::epsilon() * v * v * v * cells * cells / (length[i] * length[i] * j);
    if (!(ratio > kTiedRoundingCheck)) continue;
    std::ostringstream why;
    why << "piece " << i << " (" << length[i] / path << " of the curve's length) is too short for a jerk-limited "
        << "profile at K = " << problem.cells_per_piece
        << " at the speed it is crossed: rounding in its b could move its jerk rows; merge it into a neighbour, or use "
           "a smaller K";
    return why.str();
  }
  return std::nullopt;
}

std::optional<std::string> TiedPieceMayBeTooShort(const TemporalProblem& problem) {
  if (!problem.limits.max_jerk || !MayHaveShortPiece(problem.curve)) return std::nullopt;
  std::vector<double> length;
  double rounding_length = 0.0;
  const std::vector<char> candidate = TieCandidates(problem, &length, &rounding_length);
  // The estimate goes as 1 / l^2: kTiedRoundingCheck with the limits' fastest speed is reached at
  // this length.
  const double check_length = rounding_length * std::sqrt(kJerkRoundingRatio / kTiedRoundingCheck);
  for (size_t i = 0; i < candidate.size(); ++i) {
    if (!candidate[i] || !(length[i] <= check_length)) continue;
    std::ostringstream why;
    why << "piece " << i << " (" << length[i]
        << " m) may be too short for a jerk-limited profile at K = " << problem.cells_per_piece
        << " at the speeds the limits allow: merge it into a neighbour, or use a smaller K";
    return why.str();
  }
  return std::nullopt;
}

std::optional<std::string> JerkPieceTooShort(const TemporalProblem& problem) {
  if (!problem.limits.max_jerk || !MayHaveShortPiece(problem.curve)) return std::nullopt;
  std::vector<double> length;
  double rounding_length = 0.0;
  const std::vector<char> candidate = TieCandidates(problem, &length, &rounding_length);
  for (size_t i = 0; i < candidate.size(); ++i) {
    if (!candidate[i] || length[i] > rounding_length) continue;
    std::ostringstream why;
    why << "piece " << i << " is " << length[i] << " m long between pieces of " << length[i - 1] << " and "
        << length[i + 1] << " m: too short for a jerk-limited profile at K = " << problem.cells_per_piece
        << " (rounding in its b would exceed the jerk limit below about " << rounding_length
        << " m); merge it into a neighbour, or use a smaller K";
    return why.str();
  }
  return std::nullopt;
}

// One grid value per grid point: a scaled free variable, a fixed value (boundary speeds, stops),
// or a value shared with the previous piece at a smooth joint. Returns the tangent f'(k ds) at
// every grid point, also used by the paper's velocity rows.
std::vector<Eigen::Vector3d> AssignGridValues(const TemporalProblem& problem, TemporalDiscretization* out,
                                              FreeBoundaries* free) {
  TemporalDiscretization& d = *out;
  const PiecewiseCurve& curve = problem.curve;
  const int m = curve.num_pieces();
  const int K = problem.cells_per_piece;
  const double ds = 1.0 / K;
  const TemporalLimits& limits = problem.limits;
  // A new variable of piece i is x = b / S_i with S_i = vref^2 / T_i^2, T_i the piece's largest
  // tangent length on the grid and vref the largest velocity limit: x is then about the squared
  // speed relative to the limit. Unscaled b spans 1 to 1e4 on curves with short, slow pieces (a time
  // allocation's last piece), and the conic solver stalled on such problems.
  // The tangent f'(k ds) at every grid point, also used by the paper's velocity rows below.
  std::vector<Eigen::Vector3d> grid_tangent(d.grid.size());
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k <= K; ++k) grid_tangent[static_cast<size_t>(d.GridIndex(i, k))] = curve.Evaluate(i, k * ds, 1);
  }
  // (The largest finite one: per-axis limits may be absent, +infinity, when max_speed is given.)
  double vref = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (std::isfinite(limits.max_velocity(a))) vref = std::max(vref, limits.max_velocity(a));
  }
  if (limits.max_speed) vref = std::max(vref, *limits.max_speed);
  if (!(vref > 0.0)) vref = 1.0;
  // With a jerk limit the speed a piece can reach may be far below vref (a 1 cm curve at limits of
  // 1e4: ~0.4 m/s against 2e4), and x of 1e-9 stalled the solvers. There S_i is the smallest of
  // the squared speeds each limit alone allows along a length of about T_i: vref^2, aref T_i
  // (accelerating over it) and (jref T_i^2)^(2/3) (a jerk ramp over it); aref and jref are the
  // largest finite acceleration and jerk limits. Without a jerk limit the scale stays vref's,
  // which the paper's and certified rows were measured with.
  double aref = 0.0, jref = 0.0;
  if (limits.max_jerk) {
    for (int a = 0; a < 3; ++a) {
      if (std::isfinite(limits.max_acceleration(a))) aref = std::max(aref, limits.max_acceleration(a));
      if (std::isfinite((*limits.max_jerk)(a))) jref = std::max(jref, (*limits.max_jerk)(a));
    }
    if (limits.max_acceleration_norm) aref = std::max(aref, *limits.max_acceleration_norm);
  }
  // A velocity limit far above any speed the acceleration limits can reach on this path (1e300
  // m/s, say) cannot bind, but its square overflowed the scale and the rows ("G has Inf"). The
  // scale is capped at kUnreachableSpeedShare times the squared speed that the largest finite
  // acceleration limit reaches over the whole path from the faster boundary speed: ordinary
  // problems keep vref's scale.
  double reach2 = kInf;
  {
    double accel = aref;
    for (int a = 0; a < 3; ++a) {
      if (std::isfinite(limits.max_acceleration(a))) accel = std::max(accel, limits.max_acceleration(a));
    }
    if (limits.max_acceleration_norm) accel = std::max(accel, *limits.max_acceleration_norm);
    if (limits.max_thrust) accel = std::max(accel, *limits.max_thrust + limits.gravity);
    double path = 0.0;
    for (int i = 0; i < m; ++i) {
      for (int k = 0; k < K; ++k) path += grid_tangent[static_cast<size_t>(d.GridIndex(i, k))].norm() / K;
    }
    const double boundary2 =
        std::max(problem.boundary.start_velocity.squaredNorm(), problem.boundary.end_velocity.squaredNorm());
    // (The grid's tangents can all vanish, a minimum-jerk piece at K = 1: no length, no cap.)
    if (accel > 0.0 && std::isfinite(accel) && std::isfinite(path) && boundary2 + path > 0.0) {
      reach2 = kUnreachableSpeedShare * (boundary2 + 2.0 * accel * path);
    }
  }
  // The largest tangent of each piece on its grid, or, where every grid tangent vanishes (a
  // minimum-jerk piece at K = 1), at its cell middles.
  std::vector<double> piece_tangent(static_cast<size_t>(m), 0.0);
  for (int i = 0; i < m; ++i) {
    double& t_max = piece_tangent[static_cast<size_t>(i)];
    for (int k = 0; k <= K; ++k) t_max = std::max(t_max, grid_tangent[static_cast<size_t>(d.GridIndex(i, k))].norm());
    for (int k = 0; k < K && !(t_max > problem.zero_tangent_tolerance); ++k) {
      t_max = std::max(t_max, curve.Evaluate(i, (k + 0.5) / K, 1).norm());
    }
  }
  std::vector<double> piece_scale(static_cast<size_t>(m), 1.0);
  for (int i = 0; i < m; ++i) {
    const double t_max = piece_tangent[static_cast<size_t>(i)];
    if (!(t_max > problem.zero_tangent_tolerance)) continue;
    double speed2 = std::min(vref * vref, reach2);
    if (aref > 0.0) speed2 = std::min(speed2, aref * t_max);
    if (jref > 0.0) speed2 = std::min(speed2, std::cbrt(jref * jref * t_max * t_max * t_max * t_max));
    piece_scale[static_cast<size_t>(i)] = speed2 / (t_max * t_max);
  }
  int next_var = 0;
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k <= K; ++k) {
      GridValue& g = d.grid[static_cast<size_t>(d.GridIndex(i, k))];
      if ((i == 0 && k == 0) || (i == m - 1 && k == K)) {
        const int end = i == 0 && k == 0 ? 0 : 1;
        const double scale = end == 0 ? piece_scale.front() : piece_scale.back();
        g = BoundaryValue(end == 0 ? problem.boundary.start_velocity : problem.boundary.end_velocity,
                          curve.Evaluate(i, end == 0 ? 0.0 : 1.0, 1), problem,
                          end == 0 ? "boundary.start_velocity" : "boundary.end_velocity", scale, &next_var);
        if (free != nullptr && g.var < 0 && g.fixed > 0.0) {
          // Free below the given speed.
          free->var[end] = next_var;
          free->given_b[end] = g.fixed;
          free->scale[end] = scale;
          g = GridValue{next_var++, scale, 0.0};
        }
      } else if (k == 0) {
        const JointInfo& j = d.joints[static_cast<size_t>(i - 1)];
        const GridValue& prev = d.grid[static_cast<size_t>(d.GridIndex(i - 1, K))];
        if (j.type == JointType::kStop) {
          g = GridValue{};
        } else {
          // The last point of a piece that ends at a non-stop joint is always free (see below).
          if (prev.var < 0) throw std::logic_error("Discretize: fixed value before a G1 joint");
          g = prev;
          g.scale = prev.scale * j.speed_ratio * j.speed_ratio;
        }
      } else if (k == K && i + 1 < m && d.joints[static_cast<size_t>(i)].type == JointType::kStop) {
        g = GridValue{};  // fixed 0: the vehicle stops at the kink
      } else if (!limits.max_jerk && !d.tied.empty() && d.tied[static_cast<size_t>(i)]) {
        // A tied piece: the speed it is entered with, all across it (b |f'|^2 constant).
        const GridValue& first = d.grid[static_cast<size_t>(d.GridIndex(i, 0))];
        const double ratio = grid_tangent[static_cast<size_t>(d.GridIndex(i, 0))].norm() /
                             grid_tangent[static_cast<size_t>(d.GridIndex(i, k))].norm();
        g = first;
        g.scale = first.scale * ratio * ratio;
      } else {
        g.var = next_var++;
        g.scale = piece_scale[static_cast<size_t>(i)];
      }
    }
  }
  d.num_vars = next_var;
  d.var_upper.assign(static_cast<size_t>(next_var), std::numeric_limits<double>::infinity());
  if (!limits.max_jerk) {
    for (int i = 0; i < m; ++i) {
      const double t_max = piece_tangent[static_cast<size_t>(i)];
      for (int k = 0; k <= K; ++k) {
        const int g = d.GridIndex(i, k);
        const int var = d.grid[static_cast<size_t>(g)].var;
        if (var < 0 || !(grid_tangent[static_cast<size_t>(g)].norm() < kSlowTangentShare * t_max)) continue;
        double& upper = d.var_upper[static_cast<size_t>(var)];
        upper = std::min(upper, kSlowTangentCap);
      }
    }
  }
  if (free != nullptr) {
    for (int e = 0; e < 2; ++e) {
      if (free->var[e] >= 0) d.var_upper[static_cast<size_t>(free->var[e])] = free->given_b[e] / free->scale[e];
    }
  }

  return grid_tangent;
}

// The cells, and the verdict on a piece of one cell that must start and end at rest.
void MakeCells(const TemporalProblem& problem, TemporalDiscretization* out) {
  TemporalDiscretization& d = *out;
  const int m = problem.curve.num_pieces();
  const int K = problem.cells_per_piece;
  const double ds = 1.0 / K;
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k < K; ++k) d.cells.push_back(Cell{i, d.GridIndex(i, k), ds});
  }
  for (const Cell& c : d.cells) {
    if (d.grid[c.first_grid].var < 0 && d.grid[c.first_grid].fixed == 0.0 && d.grid[c.first_grid + 1].var < 0 &&
        d.grid[c.first_grid + 1].fixed == 0.0) {
      std::ostringstream ss;
      ss << "piece " << c.piece << " must start and end at rest (zero speed at both ends of a "
         << "single cell): it cannot be traversed with K = " << K << "; use K >= 2";
      if (!d.infeasible_reason) d.infeasible_reason = ss.str();
    }
  }
}

// Velocity at grid points (paper mode, eq. 41): f'_axis(s_k)^2 b_k <= vmax^2.
void AddPaperVelocityRows(const TemporalProblem& problem, const std::vector<Eigen::Vector3d>& grid_tangent,
                          RowBuilder& row, TemporalDiscretization* out) {
  TemporalDiscretization& d = *out;
  const int m = problem.curve.num_pieces();
  const int K = problem.cells_per_piece;
  const double ds = 1.0 / K;
  const auto vmax2 = problem.limits.max_velocity.cwiseProduct(problem.limits.max_velocity);
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k <= K; ++k) {
      const int g = d.GridIndex(i, k);
      const GridValue& v = d.grid[static_cast<size_t>(g)];
      const Eigen::Vector3d& t = grid_tangent[static_cast<size_t>(g)];
      if (problem.limits.max_speed && t.norm() > problem.zero_tangent_tolerance) {
        // The quadrotor's speed: |f'|^2 b <= max_speed^2.
        const double speed2 = *problem.limits.max_speed * *problem.limits.max_speed;
        if (v.var >= 0) {
          double& ub = d.var_upper[static_cast<size_t>(v.var)];
          ub = std::min(ub, speed2 / (t.squaredNorm() * v.scale));
        } else {
          row.Add(g, t.squaredNorm());
          row.Finish(LinearRow::Kind::kVelocity, -std::numeric_limits<double>::infinity(), speed2,
                     [&] { return "squared speed at piece " + std::to_string(i) + " s=" + std::to_string(k * ds); });
        }
      }
      for (int a = 0; a < 3; ++a) {
        // A tangent component that vanishes up to rounding (e.g. 1e-15 on an axis the curve
        // does not move along) bounds nothing but would put a huge number (vmax^2 / 1e-30) into
        // the problem data.
        if (std::abs(t(a)) <= problem.zero_tangent_tolerance) continue;
        if (!std::isfinite(vmax2(a))) continue;  // no limit on this axis
        const double t2 = t(a) * t(a);
        if (v.var >= 0) {
          double& ub = d.var_upper[static_cast<size_t>(v.var)];
          ub = std::min(ub, vmax2(a) / (t2 * v.scale));
        } else {
          row.Add(g, t2);
          row.Finish(LinearRow::Kind::kVelocity, -std::numeric_limits<double>::infinity(), vmax2(a), [&] {
            return std::string("squared velocity on axis ") + kAxisNames[a] + " at piece " + std::to_string(i) +
                   " s=" + std::to_string(k * ds);
          });
        }
      }
    }
  }
  // A grid point where the tangent vanishes bounds nothing. A cell whose two grid points both do
  // (a minimum-jerk piece at K = 1) gets the velocity at its middle, f'(mid)^2 (b^k + b^{k+1}) / 2
  // <= vmax^2 (b is linear on the cell): on a straight piece, whose f'' vanishes at the middle,
  // nothing else bounded b and T had no minimum (Ipopt answered 0.7 ms for a metre).
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k < K; ++k) {
      const int g0 = d.GridIndex(i, k);
      if (grid_tangent[static_cast<size_t>(g0)].norm() > problem.zero_tangent_tolerance ||
          grid_tangent[static_cast<size_t>(g0 + 1)].norm() > problem.zero_tangent_tolerance) {
        continue;
      }
      const Eigen::Vector3d t = problem.curve.Evaluate(i, (k + 0.5) * ds, 1);
      const auto add = [&](double t2, double bound, const char* what, int axis) {
        row.Add(g0, 0.5 * t2);
        row.Add(g0 + 1, 0.5 * t2);
        row.Finish(LinearRow::Kind::kVelocity, -std::numeric_limits<double>::infinity(), bound, [&] {
          return std::string(what) + (axis >= 0 ? std::string(" on axis ") + kAxisNames[axis] : std::string()) +
                 " at piece " + std::to_string(i) + " s=" + std::to_string((k + 0.5) * ds);
        });
      };
      if (problem.limits.max_speed && t.norm() > problem.zero_tangent_tolerance) {
        add(t.squaredNorm(), *problem.limits.max_speed * *problem.limits.max_speed, "squared speed", -1);
      }
      for (int a = 0; a < 3; ++a) {
        if (std::abs(t(a)) <= problem.zero_tangent_tolerance || !std::isfinite(vmax2(a))) continue;
        add(t(a) * t(a), vmax2(a), "squared velocity", a);
      }
    }
  }
}

// The largest acceleration norm the quadrotor's limits allow (infinite without any):
// max_acceleration_norm, and max_thrust + gravity (||acc|| <= ||acc + g e3|| + g).
double QuadrotorAccelerationCap(const TemporalLimits& limits) {
  double cap = std::numeric_limits<double>::infinity();
  if (limits.max_acceleration_norm) cap = std::min(cap, *limits.max_acceleration_norm);
  if (limits.max_thrust) cap = std::min(cap, *limits.max_thrust + limits.gravity);
  return cap;
}

void AddQuadrotorAccelerationRows(const TemporalLimits& limits, const std::vector<int>& grid,
                                  const std::vector<Eigen::Vector3d>& coef, const std::function<std::string()>& where,
                                  RowBuilder& row, TemporalDiscretization* d) {
  const double g = limits.gravity;
  const auto add_cone = [&](ConeRow::Kind kind, double scale, const Eigen::Vector3d& constant,
                            const Eigen::Vector3d& mask, double bound_per_z, const char* what) {
    ConeRow r;
    r.kind = kind;
    r.grid = grid;
    r.norm_constant = constant.cwiseProduct(mask) / scale;
    r.bound_constant = 1.0;
    for (const Eigen::Vector3d& c : coef) {
      r.norm.push_back(c.cwiseProduct(mask) / scale);
      r.bound.push_back(bound_per_z * c(2) / scale);
    }
    // All values fixed: a constant row, decided here.
    bool constant_row = true;
    std::vector<double> b;
    for (int v : grid) {
      const GridValue& gv = d->grid[static_cast<size_t>(v)];
      constant_row = constant_row && gv.var < 0;
      b.push_back(gv.fixed);
    }
    if (constant_row) {
      if (r.NormPart(b).norm() > r.BoundPart(b) + kConstantRowSlack && !d->infeasible_reason) {
        d->infeasible_reason = std::string(what) + " at " + where() + " is exceeded whatever the time allocation";
      }
      return;
    }
    d->cone_rows.push_back(std::move(r));
  };
  const Eigen::Vector3d all(1.0, 1.0, 1.0), horizontal(1.0, 1.0, 0.0), up(0.0, 0.0, g);
  if (limits.max_acceleration_norm) {
    add_cone(ConeRow::Kind::kAccelerationNorm, *limits.max_acceleration_norm, Eigen::Vector3d::Zero(), all, 0.0,
             "limits.max_acceleration_norm");
  }
  if (limits.max_thrust) {
    add_cone(ConeRow::Kind::kThrust, *limits.max_thrust, up, all, 0.0, "limits.max_thrust");
  }
  const auto add_vertical = [&](double lower, const char* what) {
    // acc_z >= lower.
    for (size_t j = 0; j < grid.size(); ++j) row.Add(grid[j], coef[j](2));
    row.Finish(LinearRow::Kind::kAcceleration, lower, std::numeric_limits<double>::infinity(),
               [&] { return std::string(what) + " at " + where(); });
  };
  if (limits.max_tilt) {
    // ||acc_xy|| <= tan(tilt) (acc_z + g), scaled by tan(tilt) g; and acc_z + g >= 0 (the cone
    // implies it; the Ipopt backend's smooth form needs it written).
    const double tan_tilt = std::tan(*limits.max_tilt);
    add_cone(ConeRow::Kind::kTilt, tan_tilt * g, Eigen::Vector3d::Zero(), horizontal, tan_tilt, "limits.max_tilt");
    add_vertical(-g, "thrust pointing up (limits.max_tilt)");
  }
  if (limits.min_thrust) add_vertical(*limits.min_thrust - g, "limits.min_thrust (acc_z + gravity)");
}

// The vehicle starts and ends in its boundary states: their accelerations must meet the
// quadrotor's limits (a hover with min_thrust above gravity cannot), or nothing can.
void CheckBoundaryAccelerations(const TemporalProblem& problem, TemporalDiscretization* d) {
  const TemporalLimits& l = problem.limits;
  if (!l.HasNormLimits()) return;
  const auto check = [&](const Eigen::Vector3d& acc, const char* field) {
    const Eigen::Vector3d thrust = ThrustVector(acc, l.gravity);
    std::ostringstream ss;
    if (l.min_thrust && thrust(2) < *l.min_thrust - kConstantRowSlack * std::max(1.0, *l.min_thrust)) {
      ss << "limits.min_thrust (" << *l.min_thrust << " m/s^2) cannot hold at " << field << " (" << acc.transpose()
         << " m/s^2: vertical thrust " << thrust(2) << ")";
    } else if (l.max_thrust && thrust.norm() > *l.max_thrust * (1.0 + kConstantRowSlack)) {
      ss << "limits.max_thrust (" << *l.max_thrust << " m/s^2) is exceeded at " << field << " (thrust " << thrust.norm()
         << ")";
    } else if (l.max_acceleration_norm && acc.norm() > *l.max_acceleration_norm * (1.0 + kConstantRowSlack)) {
      ss << "limits.max_acceleration_norm (" << *l.max_acceleration_norm << ") is exceeded at " << field << " ("
         << acc.norm() << ")";
    } else if (l.max_tilt && Tilt(thrust) > *l.max_tilt * (1.0 + kConstantRowSlack)) {
      ss << "limits.max_tilt (" << *l.max_tilt << " rad) is exceeded at " << field << " (tilt " << Tilt(thrust)
         << " rad)";
    } else {
      return;
    }
    if (!d->infeasible_reason) d->infeasible_reason = ss.str();
  };
  check(problem.boundary.start_acceleration, "boundary.start_acceleration");
  check(problem.boundary.end_acceleration, "boundary.end_acceleration");
  // From rest the vehicle must speed up along the tangent u (into rest: slow down, an acceleration
  // along -u). With max_thrust T the largest acceleration along a unit direction w is
  // -g w_z + sqrt(T^2 - g^2 (1 - w_z^2)): 0 for a level or climbing w when T = g (a hover at full
  // thrust), where the conic solver could only run out of iterations.
  if (!l.max_thrust) return;
  const int m = problem.curve.num_pieces();
  for (const bool end : {false, true}) {
    const Eigen::Vector3d v = end ? problem.boundary.end_velocity : problem.boundary.start_velocity;
    if (!v.isZero(0.0)) continue;
    const Eigen::Vector3d f1 = problem.curve.Evaluate(end ? m - 1 : 0, end ? 1.0 : 0.0, 1);
    if (!(f1.norm() > problem.zero_tangent_tolerance)) continue;
    const Eigen::Vector3d w = (end ? -1.0 : 1.0) * f1.normalized();
    const double g = l.gravity, T = *l.max_thrust;
    const double room = T * T - g * g * (1.0 - w(2) * w(2));
    const double largest = room >= 0.0 ? -g * w(2) + std::sqrt(room) : -1.0;
    if (largest <= 1e-9 * std::max(g, 1.0)) {
      std::ostringstream ss;
      ss << "limits.max_thrust (" << T << " m/s^2) leaves no acceleration along the path at its "
         << (end ? "end" : "start") << " (a hover takes " << g << " m/s^2 and the path's direction there, "
         << (end ? -w : w).transpose() << ", is not " << (end ? "upward" : "downward") << "), so the vehicle cannot "
         << (end ? "come to rest there" : "leave rest");
      if (!d->infeasible_reason) d->infeasible_reason = ss.str();
      return;
    }
  }
}

// Per cell and axis, the acceleration at the cell middle (eq. 40) as coefficients on
// (b^k, b^{k+1}): f' (b1 - b0) / (2 ds) + f'' (b0 + b1) / 2. Used by the paper's acceleration
// rows and by the acceleration-change rows in both modes. Also sets acceleration_norm_scale.
std::vector<Eigen::Matrix<double, 3, 2>> MidCellAccelerations(const TemporalProblem& problem,
                                                              TemporalDiscretization* out) {
  TemporalDiscretization& d = *out;
  const PiecewiseCurve& curve = problem.curve;
  const double ds = 1.0 / problem.cells_per_piece;
  const TemporalLimits& limits = problem.limits;
  std::vector<Eigen::Matrix<double, 3, 2>> mid_acc(d.cells.size());
  std::vector<double> caps;  // for acceleration_norm_scale
  caps.reserve(d.cells.size());
  for (size_t ci = 0; ci < d.cells.size(); ++ci) {
    const Cell& c = d.cells[ci];
    const int k = c.first_grid - d.GridIndex(c.piece, 0);
    const double s_mid = (k + 0.5) * ds;
    const Eigen::Vector3d f1 = curve.Evaluate(c.piece, s_mid, 1);
    const Eigen::Vector3d f2 = curve.Evaluate(c.piece, s_mid, 2);
    mid_acc[ci].col(0) = -f1 / (2.0 * ds) + f2 / 2.0;
    mid_acc[ci].col(1) = f1 / (2.0 * ds) + f2 / 2.0;
    double cap = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (f1(a) != 0.0) cap = std::min(cap, limits.max_acceleration(a) / std::abs(f1(a)));
    }
    const double norm_cap = QuadrotorAccelerationCap(limits);
    if (f1.norm() > 0.0) cap = std::min(cap, norm_cap / f1.norm());
    if (std::isfinite(cap)) caps.push_back(cap);
  }
  if (!caps.empty()) {
    // sqrt(count) times the median cap: near a vanishing tangent (the ends of a rest-to-rest
    // minimum-jerk curve) the cap grows without bound, and a root-sum-square was then set by those
    // few cells alone. Measured on 240 rho > 0 problems (natural cubics and rest-to-rest quintics,
    // m 2..50, K 30..100, rho 0.01..10): the root-sum-square ended 32 with reduced accuracy (the
    // rho cone held the first steps to ~0.05, then rounding spoiled the end), the median none,
    // with 13% fewer iterations in all.
    auto middle = caps.begin() + static_cast<std::ptrdiff_t>(caps.size() / 2);
    std::nth_element(caps.begin(), middle, caps.end());
    const double scale = std::sqrt(static_cast<double>(caps.size())) * *middle;
    if (scale > 0.0 && std::isfinite(scale)) d.acceleration_norm_scale = scale;
  }

  return mid_acc;
}

// Acceleration change (eqs. 44-45) between neighbouring cells and against the boundary
// accelerations (eqs. 48-49), when max_acceleration_change is set.
void AddAccelerationChangeRows(const TemporalProblem& problem, const std::vector<Eigen::Matrix<double, 3, 2>>& mid_acc,
                               RowBuilder& row, TemporalDiscretization* out) {
  TemporalDiscretization& d = *out;
  const TemporalLimits& limits = problem.limits;
  if (!limits.max_acceleration_change) return;
  const double lambda = *limits.max_acceleration_change;
  for (int a = 0; a < 3; ++a) {
    for (size_t ci = 0; ci + 1 < d.cells.size(); ++ci) {
      row.Add(d.cells[ci + 1].first_grid, mid_acc[ci + 1](a, 0));
      row.Add(d.cells[ci + 1].first_grid + 1, mid_acc[ci + 1](a, 1));
      row.Add(d.cells[ci].first_grid, -mid_acc[ci](a, 0));
      row.Add(d.cells[ci].first_grid + 1, -mid_acc[ci](a, 1));
      row.Finish(LinearRow::Kind::kAccelerationChange, -lambda, lambda,
                 [&] { return std::string("acceleration change on axis ") + kAxisNames[a]; });
    }
    const size_t last = d.cells.size() - 1;
    const double a0 = problem.boundary.start_acceleration(a);
    const double af = problem.boundary.end_acceleration(a);
    row.Add(d.cells[0].first_grid, mid_acc[0](a, 0));
    row.Add(d.cells[0].first_grid + 1, mid_acc[0](a, 1));
    row.Finish(LinearRow::Kind::kBoundaryAcceleration, a0 - lambda, a0 + lambda,
               [&] { return std::string("first cell's acceleration on axis ") + kAxisNames[a]; });
    row.Add(d.cells[last].first_grid, mid_acc[last](a, 0));
    row.Add(d.cells[last].first_grid + 1, mid_acc[last](a, 1));
    row.Finish(LinearRow::Kind::kBoundaryAcceleration, af - lambda, af + lambda,
               [&] { return std::string("last cell's acceleration on axis ") + kAxisNames[a]; });
  }
}

}  // namespace internal

TemporalDiscretization Discretize(const TemporalProblem& problem) {
  return internal::DiscretizeWithFreeBoundaries(problem, nullptr);
}

TemporalDiscretization internal::DiscretizeWithFreeBoundaries(const TemporalProblem& problem, FreeBoundaries* free) {
  using namespace internal;
  problem.Validate();
  const int m = problem.curve.num_pieces();
  const int K = problem.cells_per_piece;
  TemporalDiscretization d;
  d.num_pieces = m;
  d.cells_per_piece = K;
  d.rho = problem.rho;
  d.grid.resize(static_cast<size_t>(m) * static_cast<size_t>(K + 1));

  ClassifyJoints(problem, &d);
  MarkTiedPieces(problem, &d);
  CheckBoundaryAccelerations(problem, &d);
  const std::vector<Eigen::Vector3d> grid_tangent = AssignGridValues(problem, &d, free);
  MakeCells(problem, &d);
  RowBuilder row(d);
  if (problem.constraint_mode == ConstraintMode::kPaper) {
    AddPaperVelocityRows(problem, grid_tangent, row, &d);
  }
  const std::vector<Eigen::Matrix<double, 3, 2>> mid_acc = MidCellAccelerations(problem, &d);
  AddCellRows(problem, mid_acc, row, &d);
  if (problem.prune_redundant_rows) KeepTightestUpperBounds(&d);
  AddAccelerationChangeRows(problem, mid_acc, row, &d);
  return d;
}
}  // namespace timeopt
