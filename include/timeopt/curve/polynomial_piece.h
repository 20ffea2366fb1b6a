#pragma once

// One polynomial piece of a spatial curve in R^3.
//
//   f(s) = sum_{j=0}^{n} c_j s^j,   c_j in R^3,   s in [0, 1]
//
// Coefficients are stored per axis in ascending powers: row a of `coefficients()` holds axis a
// (x, y, z), column j the coefficient of s^j. The parameter s is a virtual parameter, not time
// (paper Sect. III): the piece is evaluated on [0, 1], values outside are extrapolated.

#include <Eigen/Core>

namespace timeopt {

class PolynomialPiece {
 public:
  using Coefficients = Eigen::Matrix<double, 3, Eigen::Dynamic>;

  // A constant zero piece of degree 0.
  PolynomialPiece();
  // Throws std::invalid_argument when there is no coefficient or one is not finite.
  explicit PolynomialPiece(Coefficients coefficients);

  int degree() const { return static_cast<int>(coefficients_.cols()) - 1; }
  const Coefficients& coefficients() const { return coefficients_; }

  // The `derivative`-th derivative with respect to s at s (derivative >= 0; orders above the
  // degree give zero). Throws std::invalid_argument for a negative order.
  Eigen::Vector3d Evaluate(double s, int derivative = 0) const;

  // Value and derivatives 0..max_derivative at s, column d holding order d.
  Eigen::Matrix<double, 3, Eigen::Dynamic> EvaluateAll(double s, int max_derivative) const;

  // The piece of the `order`-th derivative (degree lowered by `order`, at least degree 0).
  PolynomialPiece Derivative(int order = 1) const;

  // The same curve with the degree raised to `degree` (zero coefficients appended).
  PolynomialPiece WithDegree(int degree) const;

  // g(s) = f(scale * s): a piece given in its own parameter tau in [0, h] becomes a unit piece
  // with scale = h (coefficient j is multiplied by h^j).
  PolynomialPiece Reparameterized(double scale) const;

  // Exact integral over s in [0, 1] of |f^(order)(s)|^2 (e.g. order 3: the jerk integral in s,
  // paper eq. 2).
  double SquaredDerivativeIntegral(int order) const;

 private:
  Coefficients coefficients_;
};

}  // namespace timeopt
