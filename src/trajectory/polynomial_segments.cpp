#include "timeopt/trajectory/polynomial_segments.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "timeopt/curve/bernstein.h"

namespace timeopt {

void PolynomialFitOptions::Validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string("polynomial segments: ") + name + " must be a positive finite number");
    }
  };
  positive(max_position_error, "max_position_error");
  positive(max_velocity_error, "max_velocity_error");
  positive(max_acceleration_error, "max_acceleration_error");
  positive(check_rate_hz, "check_rate_hz");
  if (!(max_comparisons >= 1.0)) throw std::invalid_argument("polynomial segments: max_comparisons must be at least 1");
  if (max_segments < 1) throw std::invalid_argument("polynomial segments: max_segments must be at least 1");
}

Eigen::Vector3d EvaluateSegment(const PolynomialSegment& segment, double tau, int derivative) {
  const Eigen::Matrix<double, 3, Eigen::Dynamic>& c = segment.coefficients;
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
  for (int j = static_cast<int>(c.cols()) - 1; j >= derivative; --j) {
    double factor = 1.0;
    for (int k = 0; k < derivative; ++k) factor *= j - k;
    value = value * tau + c.col(j) * factor;
  }
  return value;
}

namespace {

using Coefficients = Eigen::Matrix<double, 3, Eigen::Dynamic>;

// The least number of checked times a segment gets, and the largest.
constexpr int kMinChecks = 8;
constexpr int kMaxChecks = 100000;
// Share of the tolerance the h^2 / 8 term may take.
constexpr double kCurvatureShare = 0.05;
// Halvings of one cell at most.
constexpr int kMaxDepth = 40;

// Bounds of |acceleration| and |jerk| per axis of the trajectory over one cell.
struct CellBounds {
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();
  Eigen::Vector3d jerk = Eigen::Vector3d::Zero();
};

// max |g(u)| over u in [0, 1] bounded by the largest Bernstein coefficient.
double BernsteinBound(const Eigen::VectorXd& power) {
  if (power.size() == 0) return 0.0;
  return PowerToBernstein(power).cwiseAbs().maxCoeff();
}

CellBounds BoundCell(const Trajectory& trajectory, int piece, int k) {
  const TemporalProfile& profile = trajectory.profile();
  const PolynomialPiece& f = trajectory.curve().piece(piece);
  const double s0 = profile.CellStart(piece, k), L = profile.CellLength(piece, k);
  // f's derivatives of order 1..3 over [s0, s0 + L], as polynomials in u in [0, 1] (Taylor at s0).
  const int n = f.degree();
  const Eigen::Matrix<double, 3, Eigen::Dynamic> all = f.EvaluateAll(s0, std::max(n, 3));
  Eigen::Vector3d F[4];
  for (int order = 1; order <= 3; ++order) {
    for (int a = 0; a < 3; ++a) {
      const int size = std::max(n - order + 1, 1);
      Eigen::VectorXd g(size);
      double power = 1.0, factorial = 1.0;
      for (int j = 0; j < size; ++j) {
        if (j > 0) {
          power *= L;
          factorial *= j;
        }
        g(j) = order + j <= std::max(n, 3) ? all(a, order + j) * power / factorial : 0.0;
      }
      F[order](a) = BernsteinBound(g);
    }
  }
  // sdot, |sddot|, |sdddot| over the cell from its shape.
  double bmax = 0.0, sdd = 0.0, sddd = 0.0;
  const CellShape shape = profile.shape(piece, k);
  if (shape == CellShape::kLinear) {
    bmax = std::max(profile.b(piece, k), profile.b(piece, k + 1));
    sdd = std::abs(profile.a(piece, k));
  } else if (shape == CellShape::kQuadratic) {
    const double b0 = profile.half_b(piece, 2 * k), bm = profile.half_b(piece, 2 * k + 1);
    const double b1 = profile.half_b(piece, 2 * k + 2);
    bmax = std::max({b0, 2.0 * bm - 0.5 * (b0 + b1), b1});
    const double c1 = (-3.0 * b0 + 4.0 * bm - b1) / L, c2 = 2.0 * (b0 - 2.0 * bm + b1) / (L * L);
    sdd = 0.5 * std::max(std::abs(c1), std::abs(c1 + 2.0 * c2 * L));
    sddd = std::abs(c2) * std::sqrt(std::max(bmax, 0.0));
  } else if (IsRampShape(shape)) {
    // b = w^4 q(w) with q quadratic in w through q_j = b_j / w_j^4 (temporal_profile.h): bounds from
    // the largest w on the cell and q's Bernstein coefficients and slopes in w.
    const double wa = TemporalProfile::RampW(shape, s0), wb = TemporalProfile::RampW(shape, s0 + L);
    const double w = std::max(wa, wb), h = std::abs(wb - wa), wm = 0.5 * (wa + wb);
    const double q0 = profile.half_b(piece, 2 * k) / (wa * wa * wa * wa);
    const double qm = profile.half_b(piece, 2 * k + 1) / (wm * wm * wm * wm);
    const double q1 = profile.half_b(piece, 2 * k + 2) / (wb * wb * wb * wb);
    const double qmax = std::max({q0, 2.0 * qm - 0.5 * (q0 + q1), q1, 0.0});
    const double c1 = (-3.0 * q0 + 4.0 * qm - q1) / h, c2 = 2.0 * (q0 - 2.0 * qm + q1) / (h * h);
    const double slope = std::max(std::abs(c1), std::abs(c1 + 2.0 * c2 * h));
    bmax = w * w * w * w * qmax;
    sdd = w * (4.0 * qmax + w * slope) / 6.0;
    sddd = std::sqrt(qmax) * (4.0 * qmax + 6.0 * w * slope + w * w * 2.0 * std::abs(c2)) / 18.0;
  } else {
    const bool start = shape == CellShape::kRestStart;
    const double bm = profile.half_b(piece, 2 * k + 1);
    const double far = profile.half_b(piece, start ? 2 * k + 2 : 2 * k);
    const double alpha = TemporalProfile::RestAlpha(bm, far), beta = far - alpha;
    const double qmax = std::max({alpha, far, 0.0});
    bmax = qmax;
    sdd = (4.0 * std::abs(alpha) + 5.0 * std::abs(beta)) / (6.0 * L);
    sddd = (4.0 * std::abs(alpha) + 10.0 * std::abs(beta)) * std::sqrt(qmax) / (18.0 * L * L);
  }
  const double sd = std::sqrt(std::max(bmax, 0.0));
  CellBounds out;
  out.acceleration = F[2] * sd * sd + F[1] * sdd;
  out.jerk = F[3] * sd * sd * sd + 3.0 * F[2] * sd * sdd + F[1] * sddd;
  return out;
}

// f(s(tau)) for s(tau) = s0 + v tau + a tau^2 / 2: the composition, by Horner's scheme on
// polynomials in tau.
Coefficients Compose(const PolynomialPiece& f, double s0, double v, double a) {
  const int n = f.degree();
  Coefficients result = Coefficients::Zero(3, 2 * n + 1);
  result.col(0) = f.coefficients().col(n);
  int size = 1;
  for (int j = n - 1; j >= 0; --j) {
    // result = result * (s0 + v tau + a/2 tau^2) + c_j
    Coefficients next = Coefficients::Zero(3, 2 * n + 1);
    for (int i = 0; i < size; ++i) {
      next.col(i) += result.col(i) * s0;
      next.col(i + 1) += result.col(i) * v;
      next.col(i + 2) += result.col(i) * (0.5 * a);
    }
    next.col(0) += f.coefficients().col(j);
    result = next;
    size += 2;
  }
  return result;
}

// The degree-7 polynomial on [0, h] through p, v, a, j at both ends.
Coefficients Hermite7(const TrajectoryState& x0, const TrajectoryState& x1, double h) {
  // With d_k = c_k h^k for k = 4..7, the end conditions are M d = r (see below).
  static const Eigen::Matrix4d inverse = [] {
    Eigen::Matrix4d m;
    m << 1, 1, 1, 1, 4, 5, 6, 7, 12, 20, 30, 42, 24, 60, 120, 210;
    return Eigen::Matrix4d(m.inverse());
  }();
  Coefficients c = Coefficients::Zero(3, 8);
  c.col(0) = x0.position;
  c.col(1) = x0.velocity;
  c.col(2) = x0.acceleration / 2.0;
  c.col(3) = x0.jerk / 6.0;
  for (int a = 0; a < 3; ++a) {
    const double c0 = c(a, 0), c1 = c(a, 1), c2 = c(a, 2), c3 = c(a, 3);
    Eigen::Vector4d r;
    r(0) = x1.position(a) - (c0 + h * (c1 + h * (c2 + h * c3)));
    r(1) = (x1.velocity(a) - (c1 + h * (2.0 * c2 + h * 3.0 * c3))) * h;
    r(2) = (x1.acceleration(a) - (2.0 * c2 + 6.0 * c3 * h)) * h * h;
    r(3) = (x1.jerk(a) - 6.0 * c3) * h * h * h;
    const Eigen::Vector4d d = inverse * r;
    double power = h * h * h * h;
    for (int k = 4; k <= 7; ++k) {
      c(a, k) = d(k - 4) / power;
      power *= h;
    }
  }
  return c;
}

// max |derivative of order `order`| of the segment per axis, over its whole duration.
Eigen::Vector3d SegmentBound(const Coefficients& c, double h, int order) {
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  const int size = static_cast<int>(c.cols()) - order;
  if (size <= 0) return out;
  for (int a = 0; a < 3; ++a) {
    Eigen::VectorXd g(size);
    for (int j = 0; j < size; ++j) {
      double factor = 1.0;
      for (int k = 0; k < order; ++k) factor *= j + order - k;
      g(j) = c(a, j + order) * factor * std::pow(h, j);
    }
    out(a) = BernsteinBound(g);
  }
  return out;
}

struct Checked {
  bool ok = false;
  double position = 0.0, velocity = 0.0, acceleration = 0.0, gap = 0.0;
};

class Fitter {
 public:
  Fitter(const Trajectory& trajectory, const PolynomialFitOptions& options)
      : trajectory_(trajectory), profile_(trajectory.profile()), options_(options) {}

  PolynomialSegments Run() {
    const int m = profile_.num_pieces(), K = profile_.cells_per_piece();
    const int cells = m * K;
    const auto start_of = [&](int c) { return profile_.TimeAt(c / K, c % K); };
    const auto end_of = [&](int c) { return c + 1 < cells ? start_of(c + 1) : profile_.total_time(); };
    std::vector<CellBounds> bounds(static_cast<size_t>(cells));
    for (int c = 0; c < cells; ++c) bounds[static_cast<size_t>(c)] = BoundCell(trajectory_, c / K, c % K);
    // The state at the start of cell c (its own right limit) and at the end of cell c (its left one).
    const auto first_state = [&](int c) {
      return trajectory_.AtPoint(profile_.InCell(c / K, c % K, 0.0), start_of(c));
    };
    const auto last_state = [&](int c) {
      return trajectory_.AtPoint(profile_.InCell(c / K, c % K, profile_.CellLength(c / K, c % K)), end_of(c));
    };
    for (int c = 0; c < cells;) {
      const int i = c / K, k = c % K;
      if (!(end_of(c) > start_of(c))) {
        ++c;
        continue;
      }
      if (profile_.shape(i, k) == CellShape::kLinear) {
        const double v = std::sqrt(profile_.b(i, k)), a = profile_.a(i, k);
        PolynomialSegment segment;
        segment.start = start_of(c);
        segment.duration = end_of(c) - segment.start;
        segment.coefficients = Compose(trajectory_.curve().piece(i), profile_.CellStart(i, k), v, a);
        segment.exact = true;
        const Checked checked = Check(segment, bounds[static_cast<size_t>(c)], first_state(c), last_state(c));
        if (checked.ok) {
          Accept(std::move(segment), checked);
          ++c;
          continue;
        }
        Fit(first_state(c), last_state(c), bounds[static_cast<size_t>(c)], 0);
        ++c;
        continue;
      }
      // Cells that are not polynomial in time: one fit over as many consecutive such cells as
      // meet the tolerances (spans doubled from one cell while they do), so that the segments are
      // few; a single cell that does not is halved in time (Fit).
      const TrajectoryState x0 = first_state(c);
      int run = 1;
      while (c + run < cells && profile_.shape((c + run) / K, (c + run) % K) != CellShape::kLinear) ++run;
      int best = 0;
      PolynomialSegment best_segment;
      Checked best_checked;
      CellBounds span_bounds = bounds[static_cast<size_t>(c)];
      int covered = 1;
      for (int span = 1; span <= run; span *= 2) {
        for (; covered < span; ++covered) {
          span_bounds.acceleration =
              span_bounds.acceleration.cwiseMax(bounds[static_cast<size_t>(c + covered)].acceleration);
          span_bounds.jerk = span_bounds.jerk.cwiseMax(bounds[static_cast<size_t>(c + covered)].jerk);
        }
        const TrajectoryState x1 = last_state(c + span - 1);
        PolynomialSegment segment;
        segment.start = x0.t;
        segment.duration = x1.t - x0.t;
        segment.coefficients = Hermite7(x0, x1, segment.duration);
        const Checked checked = Check(segment, span_bounds, x0, x1);
        if (!checked.ok) break;
        best = span;
        best_segment = std::move(segment);
        best_checked = checked;
      }
      if (best == 0) {
        Fit(x0, last_state(c), bounds[static_cast<size_t>(c)], 0);
        ++c;
      } else {
        Accept(std::move(best_segment), best_checked);
        c += best;
      }
    }
    return std::move(out_);
  }

 private:
  void Accept(PolynomialSegment segment, const Checked& checked) {
    if (static_cast<int>(out_.segments.size()) >= options_.max_segments) {
      throw std::invalid_argument("polynomial segments: more than max_segments (" +
                                  std::to_string(options_.max_segments) + ") segments needed for these tolerances");
    }
    out_.degree = std::max(out_.degree, static_cast<int>(segment.coefficients.cols()) - 1);
    out_.max_position_error = std::max(out_.max_position_error, checked.position);
    out_.max_velocity_error = std::max(out_.max_velocity_error, checked.velocity);
    out_.max_acceleration_error = std::max(out_.max_acceleration_error, checked.acceleration);
    out_.largest_checked_gap = std::max(out_.largest_checked_gap, checked.gap);
    out_.segments.push_back(std::move(segment));
  }

  // Fits [x0.t, x1.t] (inside one cell) and halves it until it meets the tolerances.
  void Fit(const TrajectoryState& x0, const TrajectoryState& x1, const CellBounds& bounds, int depth) {
    PolynomialSegment segment;
    segment.start = x0.t;
    segment.duration = x1.t - x0.t;
    segment.coefficients = Hermite7(x0, x1, segment.duration);
    const Checked checked = Check(segment, bounds, x0, x1);
    if (checked.ok) {
      Accept(std::move(segment), checked);
      return;
    }
    const double middle = x0.t + 0.5 * segment.duration;
    if (depth >= kMaxDepth || !(segment.duration > 1e-9 * profile_.total_time()) || !(middle > x0.t && middle < x1.t)) {
      std::ostringstream message;
      message << "polynomial segments: the tolerances (" << options_.max_position_error << " m, "
              << options_.max_velocity_error << " m/s, " << options_.max_acceleration_error
              << " m/s^2) cannot be met at t = " << x0.t << " s (error bounds " << checked.position << " m, "
              << checked.velocity << " m/s, " << checked.acceleration << " m/s^2 on a segment of " << segment.duration
              << " s)";
      throw std::invalid_argument(message.str());
    }
    const TrajectoryState xm = trajectory_.Evaluate(middle);
    Fit(x0, xm, bounds, depth + 1);
    Fit(xm, x1, bounds, depth + 1);
  }

  // The segment's error bounds against the trajectory (see the header comment).
  // x0 and x1: the trajectory's states at the segment's ends, as its own cells give them (one-sided
  // where the acceleration steps between cells).
  Checked Check(const PolynomialSegment& segment, const CellBounds& bounds, const TrajectoryState& x0,
                const TrajectoryState& x1) const {
    const double h = segment.duration;
    const Eigen::Vector3d s_position = SegmentBound(segment.coefficients, h, 2) + bounds.acceleration;
    const Eigen::Vector3d s_velocity = SegmentBound(segment.coefficients, h, 3) + bounds.jerk;
    // Checks: the rate, at least kMinChecks, and a spacing whose slack terms are small: gap^2 / 8
    // times the second derivative's bound for position and velocity, gap / 2 times the first
    // derivative's for the acceleration (the trajectory's jerk may step, so no second order there).
    double count = std::max({static_cast<double>(kMinChecks), std::ceil(h * options_.check_rate_hz)});
    const auto spacing_for = [&](double curvature, double tolerance) {
      return curvature > 0.0 ? std::sqrt(8.0 * kCurvatureShare * tolerance / curvature) : h;
    };
    const double spacing_a =
        s_velocity.norm() > 0.0 ? 2.0 * kCurvatureShare * options_.max_acceleration_error / s_velocity.norm() : h;
    const double finest = std::min({spacing_for(s_position.norm(), options_.max_position_error),
                                    spacing_for(s_velocity.norm(), options_.max_velocity_error), spacing_a});
    count = std::max(count, std::ceil(h / finest));
    Checked out;
    if (!(count <= kMaxChecks)) {
      out.position = out.velocity = out.acceleration = std::numeric_limits<double>::infinity();
      return out;
    }
    const int n = static_cast<int>(count);
    comparisons_ += n + 1;
    if (comparisons_ > options_.max_comparisons) {
      std::ostringstream message;
      message << "polynomial segments: more than " << options_.max_comparisons
              << " comparisons with the trajectory for these tolerances (" << options_.max_position_error << " m, "
              << options_.max_velocity_error << " m/s, " << options_.max_acceleration_error << " m/s^2); loosen them";
      throw std::invalid_argument(message.str());
    }
    const double gap = h / n;
    Eigen::Vector3d prev_p = Eigen::Vector3d::Zero(), prev_v = Eigen::Vector3d::Zero(),
                    prev_a = Eigen::Vector3d::Zero();
    const Eigen::Vector3d slack_p = s_position * (gap * gap / 8.0), slack_v = s_velocity * (gap * gap / 8.0);
    const Eigen::Vector3d slack_a = s_velocity * (gap / 2.0);
    for (int j = 0; j <= n; ++j) {
      const double tau = j == n ? h : j * gap;
      const TrajectoryState x = j == 0 ? x0 : j == n ? x1 : trajectory_.Evaluate(segment.start + tau);
      const Eigen::Vector3d e_p = (EvaluateSegment(segment, tau, 0) - x.position).cwiseAbs();
      const Eigen::Vector3d e_v = (EvaluateSegment(segment, tau, 1) - x.velocity).cwiseAbs();
      const Eigen::Vector3d e_a = (EvaluateSegment(segment, tau, 2) - x.acceleration).cwiseAbs();
      if (j > 0) {
        out.position = std::max(out.position, (prev_p.cwiseMax(e_p) + slack_p).norm());
        out.velocity = std::max(out.velocity, (prev_v.cwiseMax(e_v) + slack_v).norm());
        out.acceleration = std::max(out.acceleration, (prev_a.cwiseMax(e_a) + slack_a).norm());
      }
      prev_p = e_p;
      prev_v = e_v;
      prev_a = e_a;
    }
    out.gap = gap;
    out.ok = out.position <= options_.max_position_error && out.velocity <= options_.max_velocity_error &&
             out.acceleration <= options_.max_acceleration_error;
    return out;
  }

  const Trajectory& trajectory_;
  const TemporalProfile& profile_;
  const PolynomialFitOptions& options_;
  PolynomialSegments out_;
  mutable double comparisons_ = 0.0;
};

}  // namespace

PolynomialSegments FitPolynomialSegments(const Trajectory& trajectory, const PolynomialFitOptions& options) {
  options.Validate();
  return Fitter(trajectory, options).Run();
}

}  // namespace timeopt
