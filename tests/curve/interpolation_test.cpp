#include "timeopt/curve/interpolation.h"

#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace timeopt {
namespace {

Waypoints RandomWaypoints(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  Waypoints w(3, count);
  for (int i = 0; i < count; ++i) w.col(i) = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return w;
}

// Values of size ~10 after a banded solve: 1e-10 is ~1e5 ulps, far above rounding and far below
// any real error.
constexpr double kTol = 1e-10;

TEST(NaturalCubicSpline, InterpolatesIsC2AndNatural) {
  std::mt19937 rng(1);
  for (int count : {2, 3, 7, 40}) {
    const Waypoints w = RandomWaypoints(rng, count);
    const PiecewiseCurve c = NaturalCubicSpline(w);
    ASSERT_EQ(c.num_pieces(), count - 1);
    for (int i = 0; i < count - 1; ++i) {
      EXPECT_LT((c.Evaluate(i, 0.0) - w.col(i)).norm(), kTol);
      EXPECT_LT((c.Evaluate(i, 1.0) - w.col(i + 1)).norm(), kTol);
    }
    const ContinuityReport r = c.Continuity(2);
    EXPECT_LT(r.jump[1], kTol);
    EXPECT_LT(r.jump[2], kTol);
    EXPECT_LT(c.Evaluate(0, 0.0, 2).norm(), kTol);
    EXPECT_LT(c.Evaluate(c.num_pieces() - 1, 1.0, 2).norm(), kTol);
  }
}

TEST(MinimumJerkSpline, InterpolatesAndHonorsEnds) {
  std::mt19937 rng(2);
  const Waypoints w = RandomWaypoints(rng, 9);
  EndDerivatives ends;
  ends.start_velocity = Eigen::Vector3d(1, -2, 0.5);
  ends.start_acceleration = Eigen::Vector3d(0, 0.3, 0);
  ends.end_velocity = Eigen::Vector3d(0, 0, -1);
  ends.end_acceleration = Eigen::Vector3d(2, 0, 0);
  const PiecewiseCurve c = MinimumJerkSpline(w, ends);
  for (int i = 0; i < 8; ++i) {
    EXPECT_LT((c.Evaluate(i, 0.0) - w.col(i)).norm(), kTol);
    EXPECT_LT((c.Evaluate(i, 1.0) - w.col(i + 1)).norm(), kTol);
  }
  EXPECT_LT((c.Evaluate(0, 0.0, 1) - *ends.start_velocity).norm(), kTol);
  EXPECT_LT((c.Evaluate(0, 0.0, 2) - *ends.start_acceleration).norm(), kTol);
  EXPECT_LT((c.Evaluate(7, 1.0, 1) - *ends.end_velocity).norm(), kTol);
  EXPECT_LT((c.Evaluate(7, 1.0, 2) - *ends.end_acceleration).norm(), kTol);
  // Optimality makes the curve C4 at interior waypoints (jerk and snap continuous).
  const ContinuityReport r = c.Continuity(4);
  for (int d = 0; d <= 4; ++d) EXPECT_LT(r.jump[d], 1e-8) << "order " << d;
}

// Perturbation that keeps a curve admissible (through the waypoints, C2, same end derivatives):
// move the velocity/acceleration at interior knots by re-fitting Hermite pieces, and add a bump
// s^3 (1-s)^3 q(s) inside each piece, which vanishes with its first two derivatives at both ends.
PiecewiseCurve Perturb(const PiecewiseCurve& c, std::mt19937& rng, double size) {
  std::normal_distribution<double> n(0.0, size);
  const int m = c.num_pieces();
  std::vector<Eigen::Vector3d> dv(m + 1, Eigen::Vector3d::Zero()), da(m + 1, Eigen::Vector3d::Zero());
  for (int i = 1; i < m; ++i) {
    dv[i] = Eigen::Vector3d(n(rng), n(rng), n(rng));
    da[i] = Eigen::Vector3d(n(rng), n(rng), n(rng));
  }
  std::vector<PolynomialPiece> pieces;
  for (int i = 0; i < m; ++i) {
    // Quintic Hermite correction with zero position change at both ends.
    Eigen::Matrix<double, 6, 6> h;
    h << 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0.5, 0, 0, 0, -10, -6, -1.5, 10, -4, 0.5, 15, 8, 1.5, -15, 7, -1, -6,
        -3, -0.5, 6, -3, 0.5;
    Eigen::Matrix<double, 6, 3> ends = Eigen::Matrix<double, 6, 3>::Zero();
    ends.row(1) = dv[i].transpose();
    ends.row(2) = da[i].transpose();
    ends.row(4) = dv[i + 1].transpose();
    ends.row(5) = da[i + 1].transpose();
    PolynomialPiece::Coefficients coeff = c.piece(i).WithDegree(7).coefficients();
    coeff.leftCols(6) += (h * ends).transpose();
    // bump: s^3 (1 - s)^3 (b0 + b1 s) = s^3 - 3 s^4 + 3 s^5 - s^6 times (b0 + b1 s)
    const Eigen::Vector3d b0(n(rng), n(rng), n(rng)), b1(n(rng), n(rng), n(rng));
    const double base[4] = {1, -3, 3, -1};
    for (int k = 0; k < 4; ++k) {
      coeff.col(3 + k) += base[k] * b0;
      coeff.col(4 + k) += base[k] * b1;
    }
    pieces.emplace_back(coeff);
  }
  return PiecewiseCurve(pieces);
}

TEST(MinimumJerkSpline, RandomAdmissiblePerturbationsNeverLowerTheJerkIntegral) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 5; ++trial) {
    const Waypoints w = RandomWaypoints(rng, 6);
    for (const EndDerivatives& ends : {EndDerivatives::RestToRest(), EndDerivatives{}}) {
      const PiecewiseCurve best = MinimumJerkSpline(w, ends);
      const double j0 = best.SquaredDerivativeIntegral(3);
      for (int k = 0; k < 50; ++k) {
        for (double size : {1e-3, 1e-1, 1.0}) {
          // Free ends: perturbing the end derivatives too would be admissible; the interior ones
          // suffice to probe the stationarity conditions, and the bump probes everything else.
          const PiecewiseCurve other = Perturb(best, rng, size);
          // Relative 1e-12 covers rounding in the exact integrals of values up to ~1e4.
          EXPECT_GE(other.SquaredDerivativeIntegral(3), j0 * (1.0 - 1e-12));
        }
      }
    }
  }
}

TEST(MinimumJerkSpline, FreeEndsSatisfyNaturalConditions) {
  std::mt19937 rng(6);
  const Waypoints w = RandomWaypoints(rng, 5);
  const PiecewiseCurve c = MinimumJerkSpline(w, EndDerivatives{});
  // Free velocity: snap vanishes at the end; free acceleration: jerk vanishes (variational
  // boundary terms). Values of jerk are ~1e3 here, so 1e-8 absolute is tight.
  EXPECT_LT(c.Evaluate(0, 0.0, 3).norm(), 1e-8);
  EXPECT_LT(c.Evaluate(0, 0.0, 4).norm(), 1e-8);
  EXPECT_LT(c.Evaluate(3, 1.0, 3).norm(), 1e-8);
  EXPECT_LT(c.Evaluate(3, 1.0, 4).norm(), 1e-8);
}

TEST(Interpolation, RejectsBadInput) {
  EXPECT_THROW(NaturalCubicSpline(Waypoints(3, 1)), std::invalid_argument);
  Waypoints w = Waypoints::Zero(3, 3);
  w(2, 1) = std::numeric_limits<double>::infinity();
  try {
    MinimumJerkSpline(w);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("waypoint 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(MinimumJerkSpline(Waypoints::Random(3, 2), EndDerivatives{}), std::invalid_argument);
}

// Coincident waypoints (within 1e-6 of the extent) are dropped, the last one replacing a kept one
// it coincides with. Truth: the waypoints written without the duplicates, and the straight line's
// length. Through the duplicate itself, the minimum-jerk spline loops back around it (a 2 m line
// through (0, 1, 1 + 1e-9, 2) m is 2.35 m long), which is why it is dropped.
TEST(MergeCoincidentWaypoints, DropsRepeatsAndKeepsTheEnds) {
  Waypoints w(3, 4);
  w << 0, 1, 1 + 1e-9, 2, 0, 0, 0, 0, 0, 0, 0, 0;
  int merged = -1;
  Waypoints out = MergeCoincidentWaypoints(w, kCoincidentWaypointFraction, &merged);
  EXPECT_EQ(merged, 1);
  ASSERT_EQ(out.cols(), 3);
  EXPECT_EQ(out.col(0), w.col(0));
  EXPECT_EQ(out.col(1), w.col(1));
  EXPECT_EQ(out.col(2), w.col(3));
  // The straight line: its length is the chord, 2 m, to the quadrature's 1e-9.
  EXPECT_NEAR(MinimumJerkSpline(out).ArcLength(1e-12), 2.0, 1e-9);
  EXPECT_GT(MinimumJerkSpline(w).ArcLength(1e-12), 2.3);
  // A goal that repeats the waypoint before it replaces that waypoint; exact repeats too.
  Waypoints end(3, 5);
  end << 0, 1, 1, 2, 2 + 1e-9, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0;
  out = MergeCoincidentWaypoints(end, kCoincidentWaypointFraction, &merged);
  EXPECT_EQ(merged, 2);
  ASSERT_EQ(out.cols(), 3);
  EXPECT_EQ(out.col(2), end.col(4));
  // Steps above the tolerance stay (1e-5 of a 2 m extent), and fraction 0 keeps all but exact repeats.
  Waypoints near(3, 3);
  near << 0, 2e-5, 2, 0, 0, 0, 0, 0, 0;
  EXPECT_EQ(MergeCoincidentWaypoints(near).cols(), 3);
  EXPECT_EQ(MergeCoincidentWaypoints(end, 0.0).cols(), 4);
  // Nothing to fly: every waypoint coincides; a fraction out of range.
  try {
    MergeCoincidentWaypoints(Waypoints::Ones(3, 4));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("all 4 waypoints coincide"), std::string::npos) << e.what();
  }
  // Waypoints whose extent overflows a double (+-1e308) are two distinct waypoints, not one.
  Waypoints huge(3, 2);
  huge << -1e308, 1e308, 0, 0, 0, 0;
  EXPECT_EQ(MergeCoincidentWaypoints(huge).cols(), 2);
  EXPECT_THROW(MergeCoincidentWaypoints(near, 1.0), std::invalid_argument);
  EXPECT_THROW(MergeCoincidentWaypoints(near, -1.0), std::invalid_argument);
}

// A curve 1e8 m long: the 1e-9 m default tolerance is below the rounding of |f'| there. The
// quadrature stops at 1e-13 of each piece's length (it used to recurse 2^40 wide: a hang) and
// agrees with composite Simpson on 2e5 panels per piece to 1e-9 relative.
TEST(PiecewiseCurveArcLength, HugeCurvesTerminateAndAreAccurate) {
  Waypoints w(3, 3);
  w << 0, 1e8, 2e8, 0, 1e8, 0, 0, 0, 1e8;
  const PiecewiseCurve c = MinimumJerkSpline(w);
  double reference = 0.0;
  constexpr int kPanels = 200000;
  for (int i = 0; i < c.num_pieces(); ++i) {
    const double h = 1.0 / kPanels;
    for (int k = 0; k < kPanels; ++k) {
      const double a = k * h;
      reference +=
          h / 6.0 *
          (c.Evaluate(i, a, 1).norm() + 4.0 * c.Evaluate(i, a + 0.5 * h, 1).norm() + c.Evaluate(i, a + h, 1).norm());
    }
  }
  EXPECT_NEAR(c.ArcLength(1e-9), reference, 1e-9 * reference);
}

// Two waypoints 1e154 m apart: |f'|^2 overflows, so the length is refused with a message (it
// recursed without end on inf and NaN); 1e150 m still has a length, the chord (a straight line).
TEST(PiecewiseCurveArcLength, OverflowingCurvesAreRefusedNotHung) {
  Waypoints w(3, 2);
  w << 0, 1e154, 0, 0, 0, 0;
  EXPECT_THROW(MinimumJerkSpline(w).ArcLength(), std::invalid_argument);
  w << 0, 1e150, 0, 0, 0, 0;
  EXPECT_NEAR(MinimumJerkSpline(w).ArcLength(), 1e150, 1e-12 * 1e150);
}

}  // namespace
}  // namespace timeopt
