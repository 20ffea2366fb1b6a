// The temporal profile against constant-acceleration kinematics written here independently: on a
// cell of length ds the speed goes from v0 = sqrt(b^k) to v1 = sqrt(b^{k+1}) at a constant rate.

#include "timeopt/trajectory/temporal_profile.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace timeopt {
namespace {

using Grid = std::vector<std::vector<double>>;

// Two pieces of K = 4 cells from rest to rest: accelerating, cruising (equal b: zero
// acceleration), braking, with the joint value shared as the temporal stage shares it.
Grid HandMadeB() { return {{0.0, 0.36, 1.44, 1.44, 1.0}, {1.0, 0.81, 0.25, 0.04, 0.0}}; }

// One cell by the textbook: v1^2 = v0^2 + 2 a ds gives the acceleration, and the time is the speed
// change over the acceleration, or ds / v0 when the speed is constant.
struct Cell {
  double v0 = 0.0, acceleration = 0.0, duration = 0.0;
};
Cell Kinematics(double b0, double b1, double ds) {
  Cell c;
  c.v0 = std::sqrt(b0);
  const double v1 = std::sqrt(b1);
  c.acceleration = (v1 * v1 - c.v0 * c.v0) / (2.0 * ds);
  c.duration = c.acceleration == 0.0 ? ds / c.v0 : (v1 - c.v0) / c.acceleration;
  return c;
}

// Times of order 1 s from two algebraically equal formulas: they round differently, (v1 - v0) / a
// with cancellation up to v / |v1 - v0| <= 10 here, so 1e-13 s (a few hundred ulps).
constexpr double kTimeTolerance = 1e-13;

TEST(TemporalProfile, CellTimesFollowConstantAccelerationKinematics) {
  const Grid b = HandMadeB();
  const TemporalProfile profile(b);
  ASSERT_EQ(profile.num_pieces(), 2);
  ASSERT_EQ(profile.cells_per_piece(), 4);
  const double ds = 0.25;
  EXPECT_EQ(profile.CellLength(0, 0), ds);
  double t = 0.0;
  for (int i = 0; i < 2; ++i) {
    const double piece_start = t;
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(profile.TimeAt(i, k), t, kTimeTolerance) << "piece " << i << " point " << k;
      const Cell cell = Kinematics(b[i][k], b[i][k + 1], ds);
      // (b1 - b0) / (2 ds) from b of order 1: rounding only.
      EXPECT_NEAR(profile.a(i, k), cell.acceleration, 1e-15) << "piece " << i << " cell " << k;
      t += cell.duration;
    }
    EXPECT_NEAR(profile.piece_durations()[i], t - piece_start, kTimeTolerance) << "piece " << i;
  }
  EXPECT_NEAR(profile.total_time(), t, kTimeTolerance);
}

// Inside a cell s(t) = s_k + v0 tau + a tau^2 / 2; here the other way round: for a given s the time
// is the root of that quadratic, tau = 2 (s - s_k) / (v0 + sqrt(v0^2 + 2 a (s - s_k))) (the form
// without cancellation), and AtTime at that time must give back s, the speed sqrt(v0^2 + 2 a (s -
// s_k)) and the cell's acceleration: the t <-> s map both ways.
TEST(TemporalProfile, AtTimeInvertsTheTimeOfEveryS) {
  const Grid b = HandMadeB();
  const TemporalProfile profile(b);
  const double ds = profile.CellLength(0, 0);
  int checked = 0;
  for (int i = 0; i < 2; ++i) {
    for (int k = 0; k < 4; ++k) {
      const Cell cell = Kinematics(b[i][k], b[i][k + 1], ds);
      for (double fraction : {0.1, 0.37, 0.5, 0.82, 0.97}) {
        const double travelled = fraction * ds;
        const double speed = std::sqrt(cell.v0 * cell.v0 + 2.0 * cell.acceleration * travelled);
        const double tau = 2.0 * travelled / (cell.v0 + speed);
        const TemporalProfile::Point p = profile.AtTime(profile.TimeAt(i, k) + tau);
        // s, sdot of order 1 through a square root and a quadratic: rounding only, 1e-13. The
        // acceleration is the cell's own value, compared exactly with a(i, k).
        EXPECT_EQ(p.piece, i);
        EXPECT_NEAR(p.s, k * ds + travelled, 1e-13) << "piece " << i << " cell " << k;
        EXPECT_NEAR(p.sdot, speed, 1e-13) << "piece " << i << " cell " << k;
        EXPECT_EQ(p.sddot, profile.a(i, k));
        ++checked;
      }
      // At the grid times: the grid point, with the speed sqrt(b).
      const TemporalProfile::Point g = profile.AtTime(profile.TimeAt(i, k));
      EXPECT_EQ(g.piece, i);
      EXPECT_NEAR(g.s, k * ds, 1e-13);
      EXPECT_NEAR(g.sdot, std::sqrt(b[i][k]), 1e-13);
    }
  }
  EXPECT_EQ(checked, 40);
}

TEST(TemporalProfile, TimesOutsideTheProfileAreClampedToItsEnds) {
  const TemporalProfile profile(HandMadeB());
  const double T = profile.total_time();
  for (double t : {-1.0, -1e-300, std::numeric_limits<double>::quiet_NaN()}) {
    const TemporalProfile::Point p = profile.AtTime(t);
    EXPECT_EQ(p.piece, 0);
    EXPECT_EQ(p.s, 0.0);
    EXPECT_EQ(p.sdot, 0.0);
  }
  for (double t : {T, T + 1e-9, 2.0 * T}) {
    const TemporalProfile::Point p = profile.AtTime(t);
    EXPECT_EQ(p.piece, 1);
    // The last cell brakes from sqrt(0.04) = 0.2 to rest: its end is s = 1 with zero speed, up to
    // the rounding of T (sums of 8 cell times of order 1 s).
    EXPECT_NEAR(p.s, 1.0, 1e-13);
    EXPECT_NEAR(p.sdot, 0.0, 1e-13);
  }
}

TEST(TemporalProfile, InvalidGridsAreRejected) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(TemporalProfile(Grid{}), std::invalid_argument);
  EXPECT_THROW(TemporalProfile(Grid{{1.0}}), std::invalid_argument);                        // K = 0
  EXPECT_THROW(TemporalProfile(Grid{{1.0, 1.0}, {1.0, 1.0, 1.0}}), std::invalid_argument);  // K differs
  EXPECT_THROW(TemporalProfile(Grid{{1.0, -1e-9}}), std::invalid_argument);
  EXPECT_THROW(TemporalProfile(Grid{{1.0, nan}}), std::invalid_argument);
  EXPECT_THROW(TemporalProfile(Grid{{1.0, inf}}), std::invalid_argument);
  EXPECT_THROW(TemporalProfile(Grid{{1.0, 0.0, 0.0, 1.0}}), std::invalid_argument);  // a cell at rest
  EXPECT_NO_THROW(TemporalProfile(Grid{{0.0, 1e-12, 0.0}}));  // at rest on grid points only: allowed
}

}  // namespace
}  // namespace timeopt
