#include "spatial_costs.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace timeopt::spatial_internal {
namespace {

// Monomial powers s^0..s^5 and their derivatives of order d at s: entry j is d^d/ds^d s^j.
Eigen::Matrix<double, 6, 1> MonomialDerivatives(double s, int derivative) {
  Eigen::Matrix<double, 6, 1> m = Eigen::Matrix<double, 6, 1>::Zero();
  for (int j = derivative; j < 6; ++j) {
    double factor = 1.0;
    for (int i = 0; i < derivative; ++i) factor *= (j - i);
    m(j) = factor * std::pow(s, j - derivative);
  }
  return m;
}

}  // namespace

QuinticHermite::QuinticHermite() {
  // Rows: the six end conditions (value, first, second derivative at s = 0 and at s = 1) applied
  // to the monomials; the Hermite basis is its inverse.
  Eigen::Matrix<double, 6, 6> conditions;
  for (int d = 0; d < 3; ++d) {
    conditions.row(d) = MonomialDerivatives(0.0, d).transpose();
    conditions.row(3 + d) = MonomialDerivatives(1.0, d).transpose();
  }
  monomials_ = conditions.inverse();
}

const QuinticHermite& QuinticHermite::Get() {
  static const QuinticHermite instance;
  return instance;
}

Eigen::Matrix<double, 6, 1> QuinticHermite::Basis(double s, int derivative) const {
  return monomials_.transpose() * MonomialDerivatives(s, derivative);
}

Eigen::Matrix<double, 6, 6> QuinticHermite::Gram(int derivative) const {
  // integral_0^1 m^(d)(s) m^(d)(s)^T ds in monomials, exact, then mapped to the basis.
  Eigen::Matrix<double, 6, 6> monomial_gram = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = derivative; i < 6; ++i) {
    for (int j = derivative; j < 6; ++j) {
      double fi = 1.0, fj = 1.0;
      for (int k = 0; k < derivative; ++k) {
        fi *= (i - k);
        fj *= (j - k);
      }
      monomial_gram(i, j) = fi * fj / (i + j - 2 * derivative + 1);
    }
  }
  return monomials_.transpose() * monomial_gram * monomials_;
}

Eigen::MatrixXd QuinticHermite::Factor(int derivative) const {
  // G is positive semi-definite of rank 6 - derivative (the derivative of a quintic spans
  // polynomials of degree 5 - derivative); keep the eigenpairs above round-off.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(Gram(derivative));
  const double largest = eig.eigenvalues().maxCoeff();
  std::vector<Eigen::RowVectorXd> rows;
  for (int k = 0; k < 6; ++k) {
    const double lambda = eig.eigenvalues()(k);
    if (lambda > 1e-12 * largest) rows.push_back(std::sqrt(lambda) * eig.eigenvectors().col(k).transpose());
  }
  Eigen::MatrixXd factor(static_cast<int>(rows.size()), 6);
  for (size_t r = 0; r < rows.size(); ++r) factor.row(static_cast<int>(r)) = rows[r];
  // Entries that are zero in exact arithmetic come out at ~1e-15 (e.g. a row orthogonal to the
  // positions): make them exact zeros so that the residuals ignore what the integral ignores.
  const double tiny = 1e-12 * factor.cwiseAbs().maxCoeff();
  factor = factor.unaryExpr([tiny](double v) { return std::abs(v) < tiny ? 0.0 : v; });
  return factor;
}

Eigen::Matrix<double, 6, 1> PieceScale(double duration) {
  Eigen::Matrix<double, 6, 1> s;
  s << 1.0, duration, duration * duration, 1.0, duration, duration * duration;
  return s;
}

Eigen::Matrix<double, 3, 6> PieceData(const double* joint0, const double* joint1,
                                      const Eigen::Matrix<double, 6, 1>& scale) {
  Eigen::Matrix<double, 3, 6> q;
  for (int k = 0; k < 3; ++k) {
    for (int a = 0; a < 3; ++a) {
      q(a, k) = joint0[3 * k + a] * scale(k);
      q(a, 3 + k) = joint1[3 * k + a] * scale(3 + k);
    }
  }
  return q;
}

void GaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  if (n < 1 || n > 64) throw std::invalid_argument("Gauss-Legendre order must be in [1, 64]");
  // Golub-Welsch: nodes are the eigenvalues of the Jacobi matrix of the Legendre recurrence.
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int i = 1; i < n; ++i) {
    const double b = i / std::sqrt(4.0 * i * i - 1.0);
    jacobi(i, i - 1) = jacobi(i - 1, i) = b;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(jacobi);
  nodes->resize(n);
  weights->resize(n);
  for (int i = 0; i < n; ++i) {
    (*nodes)[i] = 0.5 * (eig.eigenvalues()(i) + 1.0);  // [-1, 1] -> [0, 1]
    const double v = eig.eigenvectors()(0, i);
    (*weights)[i] = v * v;  // 2 v^2 on [-1, 1], halved for [0, 1]
  }
}

// ---- QuadraticFormCost ----

QuadraticFormCost::QuadraticFormCost(const Eigen::MatrixXd& factor, const Eigen::Matrix<double, 6, 1>& scale,
                                     double weight)
    : scaled_factor_(std::sqrt(weight) * factor * scale.asDiagonal()) {
  set_num_residuals(3 * static_cast<int>(factor.rows()));
  mutable_parameter_block_sizes()->assign({kJointSize, kJointSize});
}

bool QuadraticFormCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int rows = static_cast<int>(scaled_factor_.rows());
  const Eigen::Matrix<double, 3, 6> q = PieceData(parameters[0], parameters[1], Eigen::Matrix<double, 6, 1>::Ones());
  Eigen::Map<Eigen::MatrixXd> r(residuals, rows, 3);  // column a: axis a
  r.noalias() = scaled_factor_ * q.transpose();
  if (jacobians == nullptr) return true;
  for (int block = 0; block < 2; ++block) {
    if (jacobians[block] == nullptr) continue;
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, kJointSize, Eigen::RowMajor>> j(jacobians[block], 3 * rows,
                                                                                     kJointSize);
    j.setZero();
    for (int a = 0; a < 3; ++a) {
      for (int k = 0; k < 3; ++k) {
        j.block(a * rows, 3 * k + a, rows, 1) = scaled_factor_.col(3 * block + k);
      }
    }
  }
  return true;
}

// ---- CollisionCost ----

double CollisionPenalty::Value(double distance, double* derivative) const {
  if (!(distance < safe_distance)) {
    *derivative = 0.0;
    return 0.0;
  }
  const double exponent = (safe_distance - distance) / decay_length;
  if (exponent > max_exponent) {
    *derivative = 0.0;  // flat beyond the clamp (only reached deep inside obstacles)
    return std::exp(max_exponent) - 1.0;
  }
  const double e = std::exp(exponent);
  *derivative = -e / decay_length;
  return e - 1.0;
}

CollisionCost::CollisionCost(const DistanceField* field, const CollisionPenalty& penalty, int samples,
                             const Eigen::Matrix<double, 6, 1>& scale, double weight, double tangent_epsilon)
    : field_(field), penalty_(penalty), scale_(scale), tangent_epsilon_(tangent_epsilon) {
  std::vector<double> weights;
  GaussLegendre(samples, &nodes_, &weights);
  sqrt_weights_.resize(samples);
  for (int k = 0; k < samples; ++k) {
    sqrt_weights_[k] = std::sqrt(weight * weights[k]);
    basis0_.push_back(QuinticHermite::Get().Basis(nodes_[k], 0));
    basis1_.push_back(QuinticHermite::Get().Basis(nodes_[k], 1));
  }
  set_num_residuals(samples);
  mutable_parameter_block_sizes()->assign({kJointSize, kJointSize});
}

bool CollisionCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Matrix<double, 3, 6> q = PieceData(parameters[0], parameters[1], scale_);
  const int n = static_cast<int>(nodes_.size());
  const double eps2 = tangent_epsilon_ * tangent_epsilon_;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p = q * basis0_[k];
    const Eigen::Vector3d tangent = q * basis1_[k];
    Eigen::Vector3d gradient;
    const double d = field_->DistanceAndGradient(p, &gradient);
    if (!std::isfinite(d)) return false;
    double dg = 0.0;
    const double g = penalty_.Value(d, &dg);
    const double t2 = tangent.squaredNorm() + eps2;
    const double length_factor = std::pow(t2, 0.25);
    residuals[k] = sqrt_weights_[k] * length_factor * g;
    if (jacobians == nullptr) continue;
    // d r / d p = sw L g'(d) grad d;  d r / d f' = sw g dL/df' with dL/df' = f' (t2)^(-3/4) / 2.
    const Eigen::Vector3d dr_dp = sqrt_weights_[k] * length_factor * dg * gradient;
    const Eigen::Vector3d dr_dt = sqrt_weights_[k] * g * 0.5 * std::pow(t2, -0.75) * tangent;
    for (int block = 0; block < 2; ++block) {
      if (jacobians[block] == nullptr) continue;
      double* row = jacobians[block] + k * kJointSize;
      for (int j = 0; j < 3; ++j) {
        const int b = 3 * block + j;
        const double h0 = basis0_[k](b) * scale_(b), h1 = basis1_[k](b) * scale_(b);
        for (int a = 0; a < 3; ++a) row[3 * j + a] = dr_dp(a) * h0 + dr_dt(a) * h1;
      }
    }
  }
  return true;
}

// ---- DynamicPenaltyCost ----

DynamicPenaltyCost::DynamicPenaltyCost(double duration, double max_velocity, double max_acceleration, int samples,
                                       double weight)
    : scale_(PieceScale(duration)),
      inverse_duration_(1.0 / duration),
      max_velocity_(max_velocity),
      max_acceleration_(max_acceleration),
      sqrt_weight_(std::sqrt(weight)) {
  for (int k = 0; k < samples; ++k) {
    const double s = (k + 0.5) / samples;
    basis1_.push_back(QuinticHermite::Get().Basis(s, 1));
    basis2_.push_back(QuinticHermite::Get().Basis(s, 2));
  }
  set_num_residuals(6 * samples);
  mutable_parameter_block_sizes()->assign({kJointSize, kJointSize});
}

bool DynamicPenaltyCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Matrix<double, 3, 6> q = PieceData(parameters[0], parameters[1], scale_);
  const int n = static_cast<int>(basis1_.size());
  if (jacobians != nullptr) {
    for (int block = 0; block < 2; ++block) {
      if (jacobians[block] != nullptr) {
        std::fill(jacobians[block], jacobians[block] + 6 * n * kJointSize, 0.0);
      }
    }
  }
  for (int k = 0; k < n; ++k) {
    for (int order = 1; order <= 2; ++order) {
      const Eigen::Matrix<double, 6, 1>& basis = order == 1 ? basis1_[k] : basis2_[k];
      const double time_factor = order == 1 ? inverse_duration_ : inverse_duration_ * inverse_duration_;
      const double limit = order == 1 ? max_velocity_ : max_acceleration_;
      const Eigen::Vector3d value = time_factor * (q * basis);
      for (int a = 0; a < 3; ++a) {
        const int r = 6 * k + 3 * (order - 1) + a;
        const double excess = std::abs(value(a)) - limit;
        residuals[r] = excess > 0.0 ? sqrt_weight_ * excess : 0.0;
        if (jacobians == nullptr || excess <= 0.0) continue;
        const double sign = value(a) >= 0.0 ? 1.0 : -1.0;
        for (int block = 0; block < 2; ++block) {
          if (jacobians[block] == nullptr) continue;
          for (int j = 0; j < 3; ++j) {
            const int b = 3 * block + j;
            jacobians[block][r * kJointSize + 3 * j + a] = sqrt_weight_ * sign * time_factor * basis(b) * scale_(b);
          }
        }
      }
    }
  }
  return true;
}

}  // namespace timeopt::spatial_internal
