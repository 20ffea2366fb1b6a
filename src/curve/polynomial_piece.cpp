#include "timeopt/curve/polynomial_piece.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace timeopt {
namespace {

// n! / (n - k)!: the factor that differentiating s^n k times produces.
double FallingFactorial(int n, int k) {
  double value = 1.0;
  for (int i = 0; i < k; ++i) value *= static_cast<double>(n - i);
  return value;
}

}  // namespace

PolynomialPiece::PolynomialPiece() : coefficients_(Coefficients::Zero(3, 1)) {}

PolynomialPiece::PolynomialPiece(Coefficients coefficients) : coefficients_(std::move(coefficients)) {
  if (coefficients_.cols() < 1) {
    throw std::invalid_argument("PolynomialPiece: expected at least 1 coefficient per axis, got 0");
  }
  for (int j = 0; j < coefficients_.cols(); ++j) {
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(coefficients_(a, j))) {
        throw std::invalid_argument("PolynomialPiece: coefficient " + std::to_string(j) + " of axis " + "xyz"[a] +
                                    " is not finite");
      }
    }
  }
}

Eigen::Vector3d PolynomialPiece::Evaluate(double s, int derivative) const {
  if (derivative < 0) {
    throw std::invalid_argument("PolynomialPiece::Evaluate: derivative order must be >= 0, got " +
                                std::to_string(derivative));
  }
  const int n = degree();
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
  // Horner on the differentiated coefficients.
  for (int j = n; j >= derivative; --j) {
    value = value * s + coefficients_.col(j) * FallingFactorial(j, derivative);
  }
  return value;
}

Eigen::Matrix<double, 3, Eigen::Dynamic> PolynomialPiece::EvaluateAll(double s, int max_derivative) const {
  if (max_derivative < 0) {
    throw std::invalid_argument("PolynomialPiece::EvaluateAll: max_derivative must be >= 0, got " +
                                std::to_string(max_derivative));
  }
  Eigen::Matrix<double, 3, Eigen::Dynamic> out(3, max_derivative + 1);
  for (int d = 0; d <= max_derivative; ++d) out.col(d) = Evaluate(s, d);
  return out;
}

PolynomialPiece PolynomialPiece::Derivative(int order) const {
  if (order < 0) {
    throw std::invalid_argument("PolynomialPiece::Derivative: order must be >= 0, got " + std::to_string(order));
  }
  const int n = degree();
  if (order > n) return PolynomialPiece();
  Coefficients result(3, n - order + 1);
  for (int j = order; j <= n; ++j) {
    result.col(j - order) = coefficients_.col(j) * FallingFactorial(j, order);
  }
  return PolynomialPiece(std::move(result));
}

PolynomialPiece PolynomialPiece::WithDegree(int new_degree) const {
  if (new_degree < degree()) {
    throw std::invalid_argument("PolynomialPiece::WithDegree: cannot lower degree " + std::to_string(degree()) +
                                " to " + std::to_string(new_degree));
  }
  Coefficients result = Coefficients::Zero(3, new_degree + 1);
  result.leftCols(coefficients_.cols()) = coefficients_;
  return PolynomialPiece(std::move(result));
}

PolynomialPiece PolynomialPiece::Reparameterized(double scale) const {
  if (!std::isfinite(scale)) {
    throw std::invalid_argument("PolynomialPiece::Reparameterized: scale is not finite");
  }
  Coefficients result = coefficients_;
  double power = 1.0;
  for (int j = 0; j < result.cols(); ++j) {
    result.col(j) *= power;
    power *= scale;
  }
  return PolynomialPiece(std::move(result));
}

double PolynomialPiece::SquaredDerivativeIntegral(int order) const {
  const PolynomialPiece d = Derivative(order);
  const Coefficients& c = d.coefficients();
  // integral_0^1 s^(i+j) ds = 1 / (i + j + 1), summed over the axes.
  double total = 0.0;
  for (int i = 0; i < c.cols(); ++i) {
    for (int j = 0; j < c.cols(); ++j) {
      total += c.col(i).dot(c.col(j)) / static_cast<double>(i + j + 1);
    }
  }
  return total;
}

}  // namespace timeopt
