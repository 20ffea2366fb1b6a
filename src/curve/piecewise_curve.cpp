#include "timeopt/curve/piecewise_curve.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace timeopt {

int ContinuityReport::ContinuousUpTo(double tolerance) const {
  int order = -1;
  for (size_t d = 0; d < jump.size(); ++d) {
    if (jump[d] > tolerance) break;
    order = static_cast<int>(d);
  }
  return order;
}

PiecewiseCurve::PiecewiseCurve(std::vector<PolynomialPiece> pieces) : pieces_(std::move(pieces)) {
  if (pieces_.empty()) {
    throw std::invalid_argument("PiecewiseCurve: expected at least 1 piece, got 0");
  }
}

const PolynomialPiece& PiecewiseCurve::piece(int i) const {
  if (i < 0 || i >= num_pieces()) {
    throw std::out_of_range("PiecewiseCurve: piece index " + std::to_string(i) + " outside [0, " +
                            std::to_string(num_pieces()) + ")");
  }
  return pieces_[static_cast<size_t>(i)];
}

int PiecewiseCurve::max_degree() const {
  int n = 0;
  for (const auto& p : pieces_) n = std::max(n, p.degree());
  return n;
}

Eigen::Vector3d PiecewiseCurve::Evaluate(int piece_index, double s, int derivative) const {
  return piece(piece_index).Evaluate(s, derivative);
}

Eigen::Vector3d PiecewiseCurve::EvaluateGlobal(double sigma, int derivative) const {
  if (empty()) throw std::logic_error("PiecewiseCurve::EvaluateGlobal on an empty curve");
  if (std::isnan(sigma)) throw std::invalid_argument("PiecewiseCurve::EvaluateGlobal: sigma is NaN");
  const int m = num_pieces();
  if (sigma <= 0.0) return pieces_.front().Evaluate(0.0, derivative);
  if (sigma >= m) return pieces_.back().Evaluate(1.0, derivative);
  const int i = std::min(static_cast<int>(std::floor(sigma)), m - 1);
  return pieces_[static_cast<size_t>(i)].Evaluate(sigma - i, derivative);
}

ContinuityReport PiecewiseCurve::Continuity(int max_order) const {
  if (max_order < 0) {
    throw std::invalid_argument("PiecewiseCurve::Continuity: max_order must be >= 0, got " + std::to_string(max_order));
  }
  ContinuityReport report;
  report.jump.assign(static_cast<size_t>(max_order) + 1, 0.0);
  report.worst_joint.assign(static_cast<size_t>(max_order) + 1, -1);
  for (int i = 0; i + 1 < num_pieces(); ++i) {
    for (int d = 0; d <= max_order; ++d) {
      const double jump = (pieces_[i + 1].Evaluate(0.0, d) - pieces_[i].Evaluate(1.0, d)).norm();
      if (report.worst_joint[d] < 0 || jump > report.jump[d]) {
        report.jump[d] = jump;
        report.worst_joint[d] = i;
      }
    }
  }
  return report;
}

namespace {

// Adaptive Simpson on g over [a, b]; whole = Simpson estimate over [a, b].
template <typename F>
double AdaptiveSimpson(const F& g, double a, double b, double fa, double fm, double fb, double whole, double tolerance,
                       int depth, long* budget) {
  const double m = 0.5 * (a + b);
  *budget -= 2;
  const double lm = 0.5 * (a + m), rm = 0.5 * (m + b);
  const double flm = g(lm), frm = g(rm);
  const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
  const double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
  const double delta = left + right - whole;
  // The depth limit bounds the work for pathological input; at depth 40 the interval is 1e-12
  // of a piece, far below any tolerance a caller can ask for in double precision.
  // The evaluation budget bounds the whole recursion (2^40 leaves would be a hang): past it, each
  // interval keeps its extrapolated estimate.
  if (depth >= 40 || *budget <= 0 || std::abs(delta) <= 15.0 * tolerance) {
    return left + right + delta / 15.0;  // Richardson extrapolation
  }
  return AdaptiveSimpson(g, a, m, fa, flm, fm, left, 0.5 * tolerance, depth + 1, budget) +
         AdaptiveSimpson(g, m, b, fm, frm, fb, right, 0.5 * tolerance, depth + 1, budget);
}

}  // namespace

double PiecewiseCurve::ArcLength(double tolerance) const {
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) {
    throw std::invalid_argument("PiecewiseCurve::ArcLength: tolerance must be positive, got " +
                                std::to_string(tolerance));
  }
  double total = 0.0;
  const double per_piece = tolerance / std::max(1, num_pieces());
  for (const auto& p : pieces_) {
    const auto speed = [&p](double s) { return p.Evaluate(s, 1).norm(); };
    // Start from four panels so that a symmetric integrand cannot fool the first estimate.
    const int panels = 4;
    double fa[panels], fm[panels], fb[panels], whole[panels], estimate = 0.0;
    for (int k = 0; k < panels; ++k) {
      const double a = static_cast<double>(k) / panels, b = static_cast<double>(k + 1) / panels;
      fa[k] = speed(a);
      fb[k] = speed(b);
      fm[k] = speed(0.5 * (a + b));
      whole[k] = (b - a) / 6.0 * (fa[k] + 4.0 * fm[k] + fb[k]);
      estimate += whole[k];
    }
    if (!std::isfinite(estimate)) {
      // |f'| overflows double precision (coordinates near 1e154 m and beyond).
      throw std::invalid_argument("PiecewiseCurve::ArcLength: the derivative of piece " +
                                  std::to_string(&p - pieces_.data()) +
                                  " is not finite (coordinates too large for double precision)");
    }
    // Not below 1e-13 of the piece's length: there the differences are the rounding of |f'| (on a
    // curve 1e8 m long a 1e-9 m tolerance was never met, and the recursion went 2^40 wide: a hang).
    const double piece_tolerance = std::max(per_piece, 1e-13 * std::abs(estimate));
    // At most ~2^20 evaluations per piece (a few ms): far more than a smooth piece needs.
    long budget = 1L << 20;
    for (int k = 0; k < panels; ++k) {
      const double a = static_cast<double>(k) / panels, b = static_cast<double>(k + 1) / panels;
      total += AdaptiveSimpson(speed, a, b, fa[k], fm[k], fb[k], whole[k], piece_tolerance / panels, 0, &budget);
    }
  }
  return total;
}

double PiecewiseCurve::SquaredDerivativeIntegral(int order) const {
  double total = 0.0;
  for (const auto& p : pieces_) total += p.SquaredDerivativeIntegral(order);
  return total;
}

}  // namespace timeopt
