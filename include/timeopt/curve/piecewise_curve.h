#pragma once

// A piecewise polynomial curve f(s) in R^3 made of m pieces, piece i on its own unit parameter
// s in [0, 1]. The global parameter sigma in [0, m] addresses piece floor(sigma) at
// s = sigma - floor(sigma) (sigma = m is the end of the last piece).

#include <vector>

#include <Eigen/Core>

#include "timeopt/curve/polynomial_piece.h"

namespace timeopt {

// The largest jump at the joints for each derivative order: jump[d] is the largest Euclidean norm
// of f_{i+1}^(d)(0) - f_i^(d)(1) over all joints, for d = 0..max_order. A single piece has no
// joints and reports zeros; worst_joint[d] is the joint index (between piece j and j+1) where
// the largest jump occurs, or -1 when there is no joint.
struct ContinuityReport {
  std::vector<double> jump;
  std::vector<int> worst_joint;
  // Largest order d such that every jump of order 0..d is at most `tolerance`, or -1.
  int ContinuousUpTo(double tolerance) const;
};

class PiecewiseCurve {
 public:
  PiecewiseCurve() = default;
  // Throws std::invalid_argument when `pieces` is empty.
  explicit PiecewiseCurve(std::vector<PolynomialPiece> pieces);

  int num_pieces() const { return static_cast<int>(pieces_.size()); }
  bool empty() const { return pieces_.empty(); }
  const PolynomialPiece& piece(int i) const;
  const std::vector<PolynomialPiece>& pieces() const { return pieces_; }
  // Highest degree of any piece.
  int max_degree() const;

  // Derivative of order `derivative` in the piece's own s (not time) at (piece, s).
  // Throws std::out_of_range for a piece index outside [0, m).
  Eigen::Vector3d Evaluate(int piece, double s, int derivative = 0) const;
  // Same at the global parameter sigma in [0, m]; values outside are clamped into the range
  // (sigma < 0 evaluates the first piece at s = 0, sigma > m the last piece at s = 1).
  Eigen::Vector3d EvaluateGlobal(double sigma, int derivative = 0) const;

  // Jumps at the joints for derivative orders 0..max_order (default 4).
  ContinuityReport Continuity(int max_order = 4) const;

  // Arc length integral of |f'(s)| over all pieces, by adaptive Simpson quadrature with the given
  // absolute tolerance (metres), or 1e-13 of each piece's length (the rounding of doubles) where
  // that is larger.
  // Throws std::invalid_argument for a tolerance that is not positive and finite, and for a piece
  // whose derivative overflows double precision; its work is bounded (about 2^20 evaluations of
  // |f'| per piece), so pathological pieces end with the best estimate reached.
  double ArcLength(double tolerance = 1e-9) const;

  // Sum over pieces of the exact integral of |f^(order)(s)|^2 ds.
  double SquaredDerivativeIntegral(int order) const;

 private:
  std::vector<PolynomialPiece> pieces_;
};

}  // namespace timeopt
