#pragma once

// Private to the library (and its tests): the quintic Hermite parameterization of one unit piece
// and the Ceres cost functions of the spatial optimizer.
//
// A joint state is 9 numbers [p(3), f'(3), f''(3)] (position and first/second derivative of the
// curve at the joint, axis-major inside each group). Piece i is the quintic on s in [0, 1] with
// the states of joints i and i + 1 at its ends:
//   f_i(s) = sum_k H_k(s) q_k,  q = (p0, f'0, f''0, p1, f'1, f''1) per axis,
// with H_k the quintic Hermite basis. Neighbouring pieces share a joint, so the curve is C2 by
// construction and every residual touches exactly two parameter blocks.
//
// Time-coupled baseline: a piece may carry a duration T (seconds). The joint then stores time
// derivatives (m/s, m/s^2) and the piece's s-data is q_s = S q with S = diag(1, T, T^2, 1, T, T^2)
// per axis (f'(s) = T v(t), f''(s) = T^2 a(t) for s = t / T). Spatial pieces have T = 1 and S = I.

#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>

#include "timeopt/map/distance_field.h"

namespace timeopt::spatial_internal {

constexpr int kJointSize = 9;

// The quintic Hermite basis on [0, 1] in the order (p0, f'0, f''0, p1, f'1, f''1).
class QuinticHermite {
 public:
  static const QuinticHermite& Get();

  // Column k: monomial coefficients (ascending powers) of H_k.
  const Eigen::Matrix<double, 6, 6>& monomials() const { return monomials_; }
  // The six basis values of derivative order `derivative` (0..5) at s.
  Eigen::Matrix<double, 6, 1> Basis(double s, int derivative) const;
  // G(d) = integral_0^1 h^(d)(s) h^(d)(s)^T ds, exact.
  Eigen::Matrix<double, 6, 6> Gram(int derivative) const;
  // A factor R (rank(G) x 6) with R^T R = G(d): the quadratic form q^T G q is |R q|^2, so the
  // exact integral becomes linear least-squares residuals.
  Eigen::MatrixXd Factor(int derivative) const;

 private:
  QuinticHermite();
  Eigen::Matrix<double, 6, 6> monomials_;
};

// The per-piece scale S (6 entries, see the file comment) for a piece of duration T (1: spatial).
Eigen::Matrix<double, 6, 1> PieceScale(double duration);

// Gathers the piece's s-data (3 x 6, column k = q_k) from two joint states and a scale.
Eigen::Matrix<double, 3, 6> PieceData(const double* joint0, const double* joint1,
                                      const Eigen::Matrix<double, 6, 1>& scale);

// sqrt(weight) * R * q per axis: residual a * rows + i. Exact for quadratic forms such as the jerk
// integral (R = Factor(3)) or the integral of |f'|^2 (R = Factor(1)).
class QuadraticFormCost final : public ceres::CostFunction {
 public:
  QuadraticFormCost(const Eigen::MatrixXd& factor, const Eigen::Matrix<double, 6, 1>& scale, double weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::MatrixXd scaled_factor_;  // sqrt(weight) * R * diag(S)
};

// Parameters of the collision penalty c(d) = g(d)^2 with
//   g(d) = exp((d_safe - d) / decay) - 1  for d < d_safe,  0 otherwise,
// an exponential penalty that vanishes at the safety distance with a continuous derivative of c.
struct CollisionPenalty {
  double safe_distance = 0.5;  // metres
  double decay_length = 0.2;   // metres
  double max_exponent = 30.0;  // the exponent is clamped here (no overflow deep inside obstacles)
  // g and dg/dd at d.
  double Value(double distance, double* derivative) const;
};

// The collision line integral of one piece, C = integral_0^1 c(d(f(s))) |f'(s)| ds, by
// Gauss-Legendre quadrature (nodes s_k, weights w_k): residual k is
//   sqrt(weight * w_k) * (|f'(s_k)|^2 + eps^2)^(1/4) * g(d(f(s_k))),
// so the sum of squares is weight * C (with |f'| regularized by eps so that the square root is
// differentiable where the tangent vanishes).
class CollisionCost final : public ceres::CostFunction {
 public:
  CollisionCost(const DistanceField* field, const CollisionPenalty& penalty, int samples,
                const Eigen::Matrix<double, 6, 1>& scale, double weight, double tangent_epsilon);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const DistanceField* field_;
  CollisionPenalty penalty_;
  Eigen::Matrix<double, 6, 1> scale_;
  double tangent_epsilon_;
  std::vector<double> nodes_, sqrt_weights_;
  std::vector<Eigen::Matrix<double, 6, 1>> basis0_, basis1_;  // H and H' at the nodes
};

// Time-coupled baseline only: soft limits on velocity and acceleration in time at `samples`
// evenly spaced interior points of a piece of duration T. Residuals per sample: 3 velocity axes,
// then 3 acceleration axes, each sqrt(weight) * max(0, |value| - limit).
class DynamicPenaltyCost final : public ceres::CostFunction {
 public:
  DynamicPenaltyCost(double duration, double max_velocity, double max_acceleration, int samples, double weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Matrix<double, 6, 1> scale_;
  double inverse_duration_;
  double max_velocity_, max_acceleration_, sqrt_weight_;
  std::vector<Eigen::Matrix<double, 6, 1>> basis1_, basis2_;
};

// Gauss-Legendre nodes and weights on [0, 1] (n from 1 to 16).
void GaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights);

}  // namespace timeopt::spatial_internal
