// Cost functions of the spatial optimizer: analytic Jacobians against Ceres' gradient checker and
// cost values against independent computations (PolynomialPiece's exact integrals, quadrature).

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "../../src/spatial/spatial_costs.h"
#include "timeopt/curve/polynomial_piece.h"

namespace timeopt {
namespace {

using spatial_internal::kJointSize;

// A smooth analytic field: distance to a sphere (gradient exact, no interpolation kinks).
class SphereField final : public DistanceField {
 public:
  SphereField(Eigen::Vector3d centre, double radius) : centre_(centre), radius_(radius) {}
  double Distance(const Eigen::Vector3d& p) const override { return (p - centre_).norm() - radius_; }
  double DistanceAndGradient(const Eigen::Vector3d& p, Eigen::Vector3d* g) const override {
    *g = (p - centre_).normalized();
    return Distance(p);
  }

 private:
  Eigen::Vector3d centre_;
  double radius_;
};

std::vector<double> RandomJoint(std::mt19937* rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<double> x(kJointSize);
  for (double& v : x) v = u(*rng);
  return x;
}

// Probes the cost at several random joint pairs. The checker differentiates by Ridders' method;
// its first step is lowered from 1e-2 to 1e-4 relative so that it does not jump over the kinks of
// |v| and max(0, .) in the penalties (Ridders extrapolates to ~1e-10 on smooth functions).
// Relative precision 1e-5: far above that accuracy, far below any real Jacobian error.
void CheckGradient(const ceres::CostFunction& cost, double scale, int seed) {
  std::mt19937 rng(seed);
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::NumericDiffOptions numeric;
  numeric.ridders_relative_initial_step_size = 1e-4;
  ceres::GradientChecker checker(&cost, no_manifolds, numeric);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<double> x0 = RandomJoint(&rng, scale), x1 = RandomJoint(&rng, scale);
    const double* parameters[] = {x0.data(), x1.data()};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(parameters, 1e-5, &results)) << results.error_log;
  }
}

TEST(QuinticHermite, InterpolatesEndData) {
  const auto& h = spatial_internal::QuinticHermite::Get();
  for (int d = 0; d < 3; ++d) {
    const Eigen::Matrix<double, 6, 1> at0 = h.Basis(0.0, d), at1 = h.Basis(1.0, d);
    for (int k = 0; k < 6; ++k) {
      // Exact rational arithmetic up to the 6x6 inverse: 1e-12.
      EXPECT_NEAR(at0(k), k == d ? 1.0 : 0.0, 1e-12) << "d " << d << " k " << k;
      EXPECT_NEAR(at1(k), k == 3 + d ? 1.0 : 0.0, 1e-12) << "d " << d << " k " << k;
    }
  }
}

TEST(QuadraticFormCost, JerkResidualsSquareToTheExactIntegral) {
  std::mt19937 rng(3);
  const auto& h = spatial_internal::QuinticHermite::Get();
  for (double duration : {1.0, 0.7, 2.5}) {
    const Eigen::Matrix<double, 6, 1> scale = spatial_internal::PieceScale(duration);
    const spatial_internal::QuadraticFormCost jerk(h.Factor(3), scale, 2.0);
    const spatial_internal::QuadraticFormCost length(h.Factor(1), scale, 3.0);
    std::vector<double> x0 = RandomJoint(&rng, 2.0), x1 = RandomJoint(&rng, 2.0);
    const double* parameters[] = {x0.data(), x1.data()};
    const PolynomialPiece piece(PolynomialPiece::Coefficients(spatial_internal::PieceData(x0.data(), x1.data(), scale) *
                                                              h.monomials().transpose()));
    std::vector<double> r(jerk.num_residuals());
    ASSERT_TRUE(jerk.Evaluate(parameters, r.data(), nullptr));
    double sum = 0.0;
    for (double v : r) sum += v * v;
    // Both sides are exact integrals of the same polynomial: round-off only (1e-9 relative).
    EXPECT_NEAR(sum, 2.0 * piece.SquaredDerivativeIntegral(3), 1e-9 * (1.0 + sum));
    r.assign(length.num_residuals(), 0.0);
    ASSERT_TRUE(length.Evaluate(parameters, r.data(), nullptr));
    sum = 0.0;
    for (double v : r) sum += v * v;
    EXPECT_NEAR(sum, 3.0 * piece.SquaredDerivativeIntegral(1), 1e-9 * (1.0 + sum));
    CheckGradient(jerk, 2.0, 11);
    CheckGradient(length, 2.0, 12);
  }
}

TEST(CollisionCost, MatchesADenseQuadratureOfTheLineIntegral) {
  const SphereField field(Eigen::Vector3d(0.5, 0.2, 0.0), 0.3);
  spatial_internal::CollisionPenalty penalty;
  penalty.safe_distance = 0.6;
  penalty.decay_length = 0.2;
  const Eigen::Matrix<double, 6, 1> scale = spatial_internal::PieceScale(1.0);
  const spatial_internal::CollisionCost cost(&field, penalty, 16, scale, 1.5, 1e-6);
  // A piece passing near the sphere: from (-0.5, 0, 0) to (1.5, 0, 0) with non-zero end tangents.
  std::vector<double> x0 = {-0.5, 0, 0, 2, 0.3, 0, 0, 0, 0};
  std::vector<double> x1 = {1.5, 0, 0, 2, -0.2, 0, 0, 0, 0};
  const double* parameters[] = {x0.data(), x1.data()};
  std::vector<double> r(cost.num_residuals());
  ASSERT_TRUE(cost.Evaluate(parameters, r.data(), nullptr));
  double sum = 0.0;
  for (double v : r) sum += v * v;
  // Independent: composite Simpson with 20000 intervals on the same curve.
  const auto& h = spatial_internal::QuinticHermite::Get();
  const Eigen::Matrix<double, 3, 6> q = spatial_internal::PieceData(x0.data(), x1.data(), scale);
  const int n = 20000;
  double simpson = 0.0;
  for (int k = 0; k <= n; ++k) {
    const double s = static_cast<double>(k) / n;
    double unused;
    const double g = penalty.Value(field.Distance(q * h.Basis(s, 0)), &unused);
    const double f = g * g * (q * h.Basis(s, 1)).norm();
    simpson += f * (k == 0 || k == n ? 1.0 : (k % 2 == 1 ? 4.0 : 2.0));
  }
  simpson *= 1.5 / (3.0 * n);
  // 16 Gauss nodes on an integrand whose penalty has a kink in its second derivative where the
  // curve enters the safety band: agreement to 2% (the figure is a cost, not a measurement).
  EXPECT_NEAR(sum, simpson, 0.02 * simpson);
  EXPECT_GT(simpson, 0.1);  // the piece really enters the band
}

TEST(CollisionCost, GradientCheck) {
  // The sphere is far from the probed curves: the distance's curvature (1 / |p - c|) stays small,
  // so central differences stay accurate; the safety distance puts every node inside the band
  // (the smooth branch of the penalty is probed, not its kink at d_safe).
  const SphereField field(Eigen::Vector3d(6.0, 5.0, 4.0), 0.5);
  spatial_internal::CollisionPenalty penalty;
  penalty.safe_distance = 12.0;
  penalty.decay_length = 2.0;
  for (double duration : {1.0, 1.7}) {
    const spatial_internal::CollisionCost cost(&field, penalty, 8, spatial_internal::PieceScale(duration), 2.0, 1e-3);
    CheckGradient(cost, 1.0, 21);
  }
}

TEST(DynamicPenaltyCost, GradientCheck) {
  // Limits of 1e-6 put every sample above them: the only kinks left are sign changes of an axis
  // velocity or acceleration, which a random probe hits with probability ~0.
  const spatial_internal::DynamicPenaltyCost cost(0.8, 1e-6, 1e-6, 6, 3.0);
  CheckGradient(cost, 1.0, 31);
}

TEST(GaussLegendre, IntegratesPolynomialsExactly) {
  std::vector<double> nodes, weights;
  spatial_internal::GaussLegendre(6, &nodes, &weights);
  for (int degree = 0; degree <= 11; ++degree) {
    double sum = 0.0;
    for (size_t k = 0; k < nodes.size(); ++k) sum += weights[k] * std::pow(nodes[k], degree);
    // Exact for degree <= 2n - 1 = 11, up to the eigen solver's round-off.
    EXPECT_NEAR(sum, 1.0 / (degree + 1), 1e-13) << "degree " << degree;
  }
}

}  // namespace
}  // namespace timeopt
