// The trajectory file and the exports (timeopt/io/trajectory_io.h), the yaw
// (timeopt/trajectory/yaw.h) and the polynomial segments (timeopt/trajectory/polynomial_segments.h),
// each checked against the trajectory itself: the samples of a file read back, the ENU samples
// under the stated NED conversion, finite differences of the yaw, the segments at 1 kHz.

#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../common/fixtures.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/io/trajectory_io.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = 3.14159265358979323846;

// The shipped example's waypoints, minimum-jerk, timed with and without a jerk limit.
Trajectory Solved(bool jerk_limited, int K = 20) {
  Waypoints w(3, 5);
  w << 0, 2, 4, 1, -1,    //
      0, 0.5, 2.5, 6, 9,  //
      1, 1.2, 1.5, 1.8, 2;
  TemporalProblem problem;
  problem.curve = MinimumJerkSpline(w);
  problem.limits.max_velocity = Eigen::Vector3d::Constant(2.0);
  problem.limits.max_acceleration = Eigen::Vector3d::Constant(2.0);
  if (jerk_limited) problem.limits.max_jerk = Eigen::Vector3d::Constant(10.0);
  problem.cells_per_piece = K;
  const TemporalResult result = MakeTemporalSolver(TemporalBackend::kSocp)->Solve(problem);
  EXPECT_TRUE(result.is_success()) << result.message;
  return Trajectory(problem.curve, result.profile);
}

std::vector<std::vector<double>> CsvRows(const std::string& text, std::string* header) {
  std::istringstream in(text);
  std::string line;
  std::getline(in, *header);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) row.push_back(std::strtod(field.c_str(), nullptr));
    rows.push_back(row);
  }
  return rows;
}

// Written and read back, a trajectory samples to the bit what the solver's did (the file holds the
// profile's own values at full precision, and the profile is rebuilt by the same constructor).
TEST(TrajectoryFile, ReadBackSamplesToTheBit) {
  for (const bool jerk : {false, true}) {
    const Trajectory original = Solved(jerk);
    const Trajectory back = ParseTrajectoryJson(TrajectoryToJson(original));
    EXPECT_EQ(back.duration(), original.duration());
    EXPECT_EQ(back.profile().jerk_limited(), jerk);
    const auto a = original.Sample(250.0), b = back.Sample(250.0);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].t, b[i].t);
      ASSERT_EQ(a[i].position, b[i].position) << i;
      ASSERT_EQ(a[i].velocity, b[i].velocity) << i;
      ASSERT_EQ(a[i].acceleration, b[i].acceleration) << i;
      ASSERT_EQ(a[i].jerk, b[i].jerk) << i;
    }
  }
}

// f() throws std::invalid_argument whose message contains `message`.
template <typename F>
void ExpectInvalid(F f, const std::string& message) {
  try {
    f();
    FAIL() << "expected std::invalid_argument containing \"" << message << "\"";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr(message));
  }
}

void ExpectRefused(const std::string& text, const std::string& message) {
  ExpectInvalid([&] { ParseTrajectoryJson(text, "t.json"); }, message);
}

TEST(TrajectoryFile, BadFilesAreRefusedNamingTheField) {
  const std::string good = TrajectoryToJson(Solved(true, 8));
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };
  ExpectRefused("{", "t.json: malformed JSON");
  ExpectRefused(replaced("\"timeopt-trajectory\"", "\"other\""), "t.json.format: expected \"timeopt-trajectory\"");
  ExpectRefused(replaced("\"version\": 1", "\"version\": 2"), "t.json.version: 2 is not supported");
  ExpectRefused(replaced("\"frame\": \"ENU\"", "\"frame\": \"NED\""), "t.json.frame: expected \"ENU\"");
  ExpectRefused(replaced("\"duration\": ", "\"duration\": 1"), "t.json.duration:");
  ExpectRefused(replaced("\"cells_per_piece\": 8", "\"cells_per_piece\": 9"),
                "t.json.profile.half_b[0]: expected 19 numbers");
  ExpectRefused(replaced("\"quadratic\"", "\"resting\""), "t.json.profile.shapes[0][0]: expected");
  ExpectRefused(replaced("\"profile\": {", "\"profile\": {\"extra\": 1, "), "t.json.profile.extra: unknown key");
  ExpectRefused(replaced("\"half_b\": [", "\"b\": [[1]], \"half_b\": ["), "either \"b\"");
  // A profile value that makes no profile: the constructor's message, under the field.
  ExpectRefused(replaced("\"quadratic\"", "\"rest_end\""), "t.json.profile: TemporalProfile::JerkLimited:");
}

// PX4 rows are the ENU samples under x north = y, y east = x, z down = -z, yaw = pi/2 - yaw_ENU,
// yawspeed = -yaw_rate, timestamps the times in whole microseconds.
TEST(Exports, Px4RowsAreTheEnuSamplesInNed) {
  const Trajectory trajectory = Solved(true);
  const HeadedSamples samples = SampleWithYaw(trajectory, 100.0, YawOptions());
  std::string h1, h2;
  const auto enu = CsvRows(ExportCsv(samples), &h1), ned = CsvRows(ExportPx4Csv(samples), &h2);
  EXPECT_EQ(h1, "t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz,yaw,yaw_rate");
  EXPECT_EQ(h2, "timestamp_us,x,y,z,vx,vy,vz,ax,ay,az,yaw,yawspeed");
  ASSERT_EQ(enu.size(), ned.size());
  ASSERT_EQ(enu.size(), trajectory.Sample(100.0).size());
  for (size_t i = 0; i < enu.size(); ++i) {
    const std::vector<double>& e = enu[i];
    const std::vector<double>& n = ned[i];
    ASSERT_EQ(e.size(), 15u);
    ASSERT_EQ(n.size(), 12u);
    EXPECT_EQ(n[0], std::round(e[0] * 1e6));
    for (int k = 0; k < 3; ++k) {  // position, velocity, acceleration
      EXPECT_NEAR(n[1 + 3 * k], e[2 + 3 * k], 1e-6);
      EXPECT_NEAR(n[2 + 3 * k], e[1 + 3 * k], 1e-6);
      EXPECT_NEAR(n[3 + 3 * k], -e[3 + 3 * k], 1e-6);
    }
    EXPECT_NEAR(n[10], kPi / 2 - e[13], 1e-6);
    EXPECT_NEAR(n[11], -e[14], 1e-6);
  }
}

// The yaw holds its rate limit, its rate column is its finite difference, and it is continuous;
// along a straight horizontal line it points along the motion.
TEST(Yaw, RateLimitedContinuousAndItsRateIsTheFiniteDifference) {
  const Trajectory trajectory = Solved(true);
  for (const double max_rate : {0.3, 1.0, 5.0}) {
    for (const YawMode mode : {YawMode::kVelocity, YawMode::kGoal}) {
      YawOptions options;
      options.mode = mode;
      options.max_rate = max_rate;
      const HeadedSamples s = SampleWithYaw(trajectory, 100.0, options);
      for (size_t i = 0; i + 1 < s.yaw.t.size(); ++i) {
        const double dt = s.yaw.t[i + 1] - s.yaw.t[i];
        const double difference = (s.yaw.yaw[i + 1] - s.yaw.yaw[i]) / dt;
        // Rounding of yaw (|yaw| < 10 rad) over dt >= 1e-8 s: well below 1e-6 rad/s.
        EXPECT_NEAR(difference, s.yaw.rate[i], 1e-6) << i;
        EXPECT_LE(std::abs(difference), max_rate * (1 + 1e-9) + 1e-6) << i;
        EXPECT_LE(std::abs(s.yaw.rate[i]), max_rate);
      }
      EXPECT_EQ(s.yaw.rate.back(), 0.0);
    }
  }
  // A line along (1, 2, 0.5): the heading is atan2(2, 1) throughout (the start faces it too).
  TemporalProblem line = test_support::LineProblem(1.0, 20);
  line.curve = test_support::Segment(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(4, 7, 2.5));
  const TemporalResult result = MakeTemporalSolver(TemporalBackend::kSocp)->Solve(line);
  ASSERT_TRUE(result.is_success());
  const Trajectory straight(line.curve, result.profile);
  for (const YawMode mode : {YawMode::kVelocity, YawMode::kGoal}) {
    YawOptions options;
    options.mode = mode;
    const HeadedSamples s = SampleWithYaw(straight, 50.0, options);
    for (const double yaw : s.yaw.yaw) EXPECT_NEAR(yaw, std::atan2(2.0, 1.0), 1e-9);
  }
  YawOptions fixed;
  fixed.mode = YawMode::kFixed;
  fixed.fixed_yaw = -2.0;
  for (const double yaw : SampleWithYaw(straight, 50.0, fixed).yaw.yaw) EXPECT_EQ(yaw, -2.0);
}

// A heading that turns round and round stays continuous (unwrapped): a circle flown twice.
TEST(Yaw, IsUnwrappedOnACircle) {
  Waypoints w(3, 17);
  for (int i = 0; i < 17; ++i) w.col(i) = Eigen::Vector3d(5 * std::cos(i * kPi / 4), 5 * std::sin(i * kPi / 4), 1);
  TemporalProblem p = test_support::WalkProblem(MinimumJerkSpline(w), 10);
  const TemporalResult result = MakeTemporalSolver(TemporalBackend::kSocp)->Solve(p);
  ASSERT_TRUE(result.is_success()) << result.message;
  YawOptions options;
  options.max_rate = 3.0;
  const HeadedSamples s = SampleWithYaw(Trajectory(p.curve, result.profile), 100.0, options);
  // Two turns counter-clockwise: the heading gains 4 pi less what the start and the end leave out
  // (the minimum-jerk spline starts and stops along the chords to its neighbours, pi / 8 off the
  // circle's tangent each), with no jump of 2 pi anywhere.
  const double gain = s.yaw.yaw.back() - s.yaw.yaw.front();
  EXPECT_GT(gain, 4 * kPi - kPi / 2);
  EXPECT_LT(gain, 4 * kPi);
  for (size_t i = 0; i + 1 < s.yaw.yaw.size(); ++i) EXPECT_LT(std::abs(s.yaw.yaw[i + 1] - s.yaw.yaw[i]), 0.031);
}

TEST(Yaw, BadOptionsAreRefused) {
  const Trajectory trajectory = Solved(false, 8);
  YawOptions bad;
  bad.max_rate = 0.0;
  EXPECT_THROW(PlanYaw(trajectory, {0.0, 1.0}, bad), std::invalid_argument);
  EXPECT_THROW(PlanYaw(trajectory, {1.0, 1.0}, YawOptions()), std::invalid_argument);
  EXPECT_THROW(PlanYaw(trajectory, {}, YawOptions()), std::invalid_argument);
}

// The segments against the trajectory at 1 kHz and at every segment's edges: within the bounds
// they report, which are within the tolerances. Linear cells are composed exactly (rounding only);
// the fitted jerk-limited segments join with continuous position, velocity and acceleration.
TEST(PolynomialSegments, WithinTheirBoundsOfTheTrajectoryAt1kHz) {
  for (const bool jerk : {false, true}) {
    const Trajectory trajectory = Solved(jerk);
    const PolynomialSegments fit = FitPolynomialSegments(trajectory);
    EXPECT_LE(fit.max_position_error, 1e-3);
    EXPECT_LE(fit.max_velocity_error, 1e-2);
    EXPECT_LE(fit.max_acceleration_error, 2e-2);
    EXPECT_EQ(fit.degree, jerk ? 7 : 10);  // 2 x 5 for a quintic composed with a quadratic s(t)
    ASSERT_FALSE(fit.segments.empty());
    EXPECT_EQ(fit.segments.front().start, 0.0);
    const PolynomialSegment& last = fit.segments.back();
    EXPECT_NEAR(last.start + last.duration, trajectory.duration(), 1e-12 * trajectory.duration());
    size_t segment = 0;
    double worst_p = 0.0, worst_v = 0.0, worst_a = 0.0;
    for (double t = 0.0; t <= trajectory.duration(); t += 1e-3) {
      while (segment + 1 < fit.segments.size() && fit.segments[segment + 1].start <= t) ++segment;
      const PolynomialSegment& s = fit.segments[segment];
      const TrajectoryState x = trajectory.Evaluate(t);
      worst_p = std::max(worst_p, (EvaluateSegment(s, t - s.start, 0) - x.position).norm());
      worst_v = std::max(worst_v, (EvaluateSegment(s, t - s.start, 1) - x.velocity).norm());
      worst_a = std::max(worst_a, (EvaluateSegment(s, t - s.start, 2) - x.acceleration).norm());
    }
    EXPECT_LE(worst_a, fit.max_acceleration_error);
    EXPECT_LE(worst_p, fit.max_position_error);
    EXPECT_LE(worst_v, fit.max_velocity_error);
    if (!jerk) {
      EXPECT_LT(worst_p, 1e-9);  // composed exactly: rounding of ~10 m positions
      EXPECT_LT(worst_v, 1e-8);
    }
    for (size_t i = 0; i + 1 < fit.segments.size(); ++i) {
      const PolynomialSegment& a = fit.segments[i];
      const PolynomialSegment& b = fit.segments[i + 1];
      EXPECT_NEAR(a.start + a.duration, b.start, 1e-12);
      EXPECT_LT((EvaluateSegment(a, a.duration, 0) - EvaluateSegment(b, 0.0, 0)).norm(), 1e-9);
      EXPECT_LT((EvaluateSegment(a, a.duration, 1) - EvaluateSegment(b, 0.0, 1)).norm(), 1e-8);
      // A jerk-limited trajectory's acceleration is continuous, and the fit keeps it so; without
      // a jerk limit it steps between cells, as the trajectory's does.
      if (jerk) {
        EXPECT_LT((EvaluateSegment(a, a.duration, 2) - EvaluateSegment(b, 0.0, 2)).norm(), 1e-6);
      }
    }
  }
}

// Tighter tolerances give more segments and still hold; an unreachable one is refused by name.
TEST(PolynomialSegments, TighterTolerancesSplitAndUnreachableOnesAreRefused) {
  const Trajectory trajectory = Solved(true, 5);
  PolynomialFitOptions loose, tight;
  tight.max_position_error = 1e-9;
  tight.max_velocity_error = 1e-8;
  tight.max_acceleration_error = 1e-3;
  const PolynomialSegments a = FitPolynomialSegments(trajectory, loose), b = FitPolynomialSegments(trajectory, tight);
  EXPECT_GT(b.segments.size(), a.segments.size());
  EXPECT_LE(b.max_position_error, 1e-9);
  EXPECT_LE(b.max_velocity_error, 1e-8);
  PolynomialFitOptions impossible;
  impossible.max_position_error = 1e-300;
  ExpectInvalid([&] { FitPolynomialSegments(trajectory, impossible); }, "cannot be met");
  // Tolerances that would need minutes of comparisons are refused by the work cap, not run.
  PolynomialFitOptions slow;
  slow.max_acceleration_error = 1e-7;
  slow.max_comparisons = 1e5;  // (the default 2e7 takes seconds to reach)
  ExpectInvalid([&] { FitPolynomialSegments(trajectory, slow); }, "comparisons");
  PolynomialFitOptions bad;
  bad.check_rate_hz = -1;
  EXPECT_THROW(FitPolynomialSegments(trajectory, bad), std::invalid_argument);
}

}  // namespace
}  // namespace timeopt
