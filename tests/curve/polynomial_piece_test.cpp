#include "timeopt/curve/polynomial_piece.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "timeopt/curve/bernstein.h"
#include "timeopt/curve/piecewise_curve.h"

namespace timeopt {
namespace {

PolynomialPiece RandomPiece(std::mt19937& rng, int degree) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  PolynomialPiece::Coefficients c(3, degree + 1);
  for (int j = 0; j <= degree; ++j) {
    for (int a = 0; a < 3; ++a) c(a, j) = u(rng);
  }
  return PolynomialPiece(c);
}

TEST(PolynomialPiece, DerivativesMatchCentralDifferences) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const PolynomialPiece p = RandomPiece(rng, 7);
    for (double s : {0.1, 0.37, 0.5, 0.83}) {
      for (int d = 1; d <= 4; ++d) {
        // Central difference of the (d-1)-th derivative with h = 1e-5: truncation error
        // h^2/6 |f^(d+2)| <= ~1e-10 * 7^4 * 2 and rounding ~1e-16/h * |f| ~ 1e-10; 1e-5 covers
        // both with margin for coefficients up to 2 and degree 7.
        const double h = 1e-5;
        const Eigen::Vector3d fd = (p.Evaluate(s + h, d - 1) - p.Evaluate(s - h, d - 1)) / (2.0 * h);
        EXPECT_LT((fd - p.Evaluate(s, d)).norm(), 1e-5 * (1.0 + fd.norm())) << "order " << d << " at s=" << s;
      }
    }
  }
}

TEST(PolynomialPiece, DerivativePieceAgreesWithEvaluate) {
  std::mt19937 rng(3);
  const PolynomialPiece p = RandomPiece(rng, 5);
  for (int d = 0; d <= 6; ++d) {
    const PolynomialPiece q = p.Derivative(d);
    for (double s : {0.0, 0.25, 1.0}) {
      // Same arithmetic in a different order: agreement to a few ulps of the values (<= ~1e3).
      EXPECT_LT((q.Evaluate(s) - p.Evaluate(s, d)).norm(), 1e-10);
    }
  }
  EXPECT_EQ(p.Evaluate(0.3, 6), Eigen::Vector3d::Zero());
}

TEST(PolynomialPiece, ReparameterizationComposes) {
  std::mt19937 rng(11);
  const PolynomialPiece p = RandomPiece(rng, 5);
  const double h = 2.5;
  const PolynomialPiece q = p.Reparameterized(h);
  // g(s) = f(h s), g'(s) = h f'(h s): exact up to rounding of values of size ~h^5 * 2.
  for (double s : {0.0, 0.2, 0.7, 1.0}) {
    EXPECT_LT((q.Evaluate(s) - p.Evaluate(h * s)).norm(), 1e-10);
    EXPECT_LT((q.Evaluate(s, 1) - h * p.Evaluate(h * s, 1)).norm(), 1e-9);
  }
}

TEST(PolynomialPiece, SquaredDerivativeIntegralMatchesQuadrature) {
  std::mt19937 rng(5);
  const PolynomialPiece p = RandomPiece(rng, 5);
  // Composite Simpson with 2000 panels on a degree-4 integrand (|f'''|^2 of a quintic) is exact
  // up to h^4 |f''''| / 180 ~ 1e-14 relative: compare to 1e-9 relative.
  const int n = 2000;
  double sum = 0.0;
  for (int k = 0; k <= n; ++k) {
    const double s = static_cast<double>(k) / n;
    const double w = (k == 0 || k == n) ? 1.0 : (k % 2 == 1 ? 4.0 : 2.0);
    sum += w * p.Evaluate(s, 3).squaredNorm();
  }
  sum /= 3.0 * n;
  EXPECT_NEAR(p.SquaredDerivativeIntegral(3), sum, 1e-9 * sum);
}

TEST(PolynomialPiece, RejectsBadInput) {
  PolynomialPiece::Coefficients c = PolynomialPiece::Coefficients::Zero(3, 3);
  c(1, 2) = std::numeric_limits<double>::quiet_NaN();
  try {
    PolynomialPiece p(c);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("coefficient 2 of axis y"), std::string::npos) << e.what();
  }
  EXPECT_THROW(PolynomialPiece(PolynomialPiece::Coefficients(3, 0)), std::invalid_argument);
  EXPECT_THROW(PolynomialPiece().Evaluate(0.5, -1), std::invalid_argument);
}

TEST(Bernstein, RoundTripAndEndpoints) {
  std::mt19937 rng(13);
  for (int degree = 0; degree <= 9; ++degree) {
    const PolynomialPiece p = RandomPiece(rng, degree);
    const auto control = ToBernstein(p);
    ASSERT_EQ(control.cols(), degree + 1);
    // A Bezier curve interpolates its first and last control points.
    EXPECT_LT((control.col(0) - p.Evaluate(0.0)).norm(), 1e-12);
    EXPECT_LT((control.col(degree) - p.Evaluate(1.0)).norm(), 1e-10);
    const PolynomialPiece back = FromBernstein(control);
    // Binomial weights up to C(9,4)=126 amplify rounding: 1e-10 is ~1e6 ulps of O(1) numbers.
    EXPECT_LT((back.coefficients() - p.coefficients()).norm(), 1e-10) << "degree " << degree;
  }
}

TEST(Bernstein, EvaluationByDeCasteljauMatches) {
  std::mt19937 rng(17);
  const PolynomialPiece p = RandomPiece(rng, 6);
  const auto control = ToBernstein(p);
  for (double s : {0.0, 0.3, 0.77, 1.0}) {
    // de Casteljau's algorithm is an independent evaluation of the Bernstein form.
    Eigen::Matrix<double, 3, Eigen::Dynamic> work = control;
    for (int r = 1; r < work.cols(); ++r) {
      for (int i = 0; i < work.cols() - r; ++i) {
        work.col(i) = (1.0 - s) * work.col(i) + s * work.col(i + 1);
      }
    }
    EXPECT_LT((work.col(0) - p.Evaluate(s)).norm(), 1e-12);
  }
}

TEST(PiecewiseCurve, ContinuityReportFindsTheJump) {
  PolynomialPiece::Coefficients a(3, 3), b(3, 3);
  a << 0, 1, 0,  // x = s
      0, 0, 1,   // y = s^2
      0, 0, 0;
  b << 1, 1, 0,  // continues x with the same slope
      1, 3, 0,   // y jumps in slope: 2 -> 3
      0, 0, 0;
  const PiecewiseCurve curve({PolynomialPiece(a), PolynomialPiece(b)});
  const ContinuityReport r = curve.Continuity(4);
  EXPECT_DOUBLE_EQ(r.jump[0], 0.0);
  EXPECT_DOUBLE_EQ(r.jump[1], 1.0);
  EXPECT_DOUBLE_EQ(r.jump[2], 2.0);  // y'' = 2 -> 0
  EXPECT_EQ(r.worst_joint[1], 0);
  EXPECT_EQ(r.ContinuousUpTo(1e-12), 0);
}

TEST(PiecewiseCurve, GlobalParameterAddressesPieces) {
  std::mt19937 rng(19);
  const PiecewiseCurve curve({RandomPiece(rng, 3), RandomPiece(rng, 3), RandomPiece(rng, 3)});
  EXPECT_EQ(curve.EvaluateGlobal(1.25, 1), curve.Evaluate(1, 0.25, 1));
  EXPECT_EQ(curve.EvaluateGlobal(3.0), curve.Evaluate(2, 1.0));
  EXPECT_EQ(curve.EvaluateGlobal(-1.0), curve.Evaluate(0, 0.0));
  EXPECT_THROW(curve.Evaluate(3, 0.5), std::out_of_range);
  EXPECT_THROW(PiecewiseCurve(std::vector<PolynomialPiece>{}), std::invalid_argument);
}

TEST(PiecewiseCurve, ArcLengthOfKnownCurves) {
  // A straight segment of length 5 traversed non-uniformly: x = 3 s^2, y = 4 s^2.
  PolynomialPiece::Coefficients line = PolynomialPiece::Coefficients::Zero(3, 3);
  line(0, 2) = 3.0;
  line(1, 2) = 4.0;
  EXPECT_NEAR(PiecewiseCurve({PolynomialPiece(line)}).ArcLength(1e-12), 5.0, 1e-11);

  // The parabola y = x^2, x in [0, 1]: L = sqrt(5)/2 + asinh(2)/4 (closed form).
  PolynomialPiece::Coefficients parabola = PolynomialPiece::Coefficients::Zero(3, 3);
  parabola(0, 1) = 1.0;
  parabola(1, 2) = 1.0;
  const double exact = std::sqrt(5.0) / 2.0 + std::asinh(2.0) / 4.0;
  // The requested tolerance is absolute; Richardson-extrapolated Simpson usually beats it.
  for (double tol : {1e-4, 1e-8, 1e-11}) {
    EXPECT_NEAR(PiecewiseCurve({PolynomialPiece(parabola)}).ArcLength(tol), exact, tol);
  }
  EXPECT_THROW(PiecewiseCurve({PolynomialPiece(parabola)}).ArcLength(0.0), std::invalid_argument);
}

}  // namespace
}  // namespace timeopt
