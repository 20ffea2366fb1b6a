#include "timeopt/curve/bernstein.h"

#include <stdexcept>
#include <string>

namespace timeopt {
namespace {

double Binomial(int n, int k) {
  if (k < 0 || k > n) return 0.0;
  double value = 1.0;
  for (int i = 1; i <= k; ++i) value = value * (n - k + i) / i;
  return value;
}

}  // namespace

// Power to Bernstein: p_k = sum_{j <= k} C(k, j) / C(n, j) a_j.
Eigen::VectorXd PowerToBernstein(const Eigen::VectorXd& a) {
  if (a.size() < 1) throw std::invalid_argument("PowerToBernstein: expected at least 1 coefficient");
  const int n = static_cast<int>(a.size()) - 1;
  Eigen::VectorXd p = Eigen::VectorXd::Zero(n + 1);
  for (int k = 0; k <= n; ++k) {
    for (int j = 0; j <= k; ++j) p(k) += Binomial(k, j) / Binomial(n, j) * a(j);
  }
  return p;
}

// Bernstein to power: a_j = C(n, j) sum_{k <= j} (-1)^(j - k) C(j, k) p_k.
Eigen::VectorXd BernsteinToPower(const Eigen::VectorXd& p) {
  if (p.size() < 1) throw std::invalid_argument("BernsteinToPower: expected at least 1 control value");
  const int n = static_cast<int>(p.size()) - 1;
  Eigen::VectorXd a = Eigen::VectorXd::Zero(n + 1);
  for (int j = 0; j <= n; ++j) {
    double sum = 0.0;
    for (int k = 0; k <= j; ++k) sum += ((j - k) % 2 == 0 ? 1.0 : -1.0) * Binomial(j, k) * p(k);
    a(j) = Binomial(n, j) * sum;
  }
  return a;
}

Eigen::Matrix<double, 3, Eigen::Dynamic> ToBernstein(const PolynomialPiece& piece) {
  Eigen::Matrix<double, 3, Eigen::Dynamic> out(3, piece.degree() + 1);
  for (int axis = 0; axis < 3; ++axis) {
    out.row(axis) = PowerToBernstein(piece.coefficients().row(axis).transpose()).transpose();
  }
  return out;
}

PolynomialPiece FromBernstein(const Eigen::Matrix<double, 3, Eigen::Dynamic>& control_points) {
  if (control_points.cols() < 1) {
    throw std::invalid_argument("FromBernstein: expected at least 1 control point, got 0");
  }
  PolynomialPiece::Coefficients c(3, control_points.cols());
  for (int axis = 0; axis < 3; ++axis) {
    c.row(axis) = BernsteinToPower(control_points.row(axis).transpose()).transpose();
  }
  return PolynomialPiece(std::move(c));
}

}  // namespace timeopt
