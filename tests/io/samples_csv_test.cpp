#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "timeopt/io/temporal_io.h"

namespace timeopt {
namespace {

using ::testing::HasSubstr;

void ExpectParseError(const std::string& text, const std::string& message) {
  try {
    ParseSamplesCsv(text, "s.csv");
    FAIL() << "expected std::invalid_argument containing \"" << message << "\"";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr(message));
  }
}

// SamplesToCsv writes 17 significant digits, so parsing gives back every value exactly.
TEST(SamplesCsv, RoundTripIsExact) {
  std::vector<TrajectoryState> samples(3);
  for (int k = 0; k < 3; ++k) {
    samples[k].t = 0.1 * k;
    samples[k].position = Eigen::Vector3d(std::sqrt(2.0) * k, -1.0 / 3.0, 1e-300);
    samples[k].velocity = Eigen::Vector3d(k, 2.0 * k, std::acos(-1.0));
    samples[k].acceleration = Eigen::Vector3d(-k, 0.5, 7e22);
    samples[k].jerk = Eigen::Vector3d(1.0 / 7.0, k, -2.5);
  }
  const std::vector<TrajectoryState> back = ParseSamplesCsv(SamplesToCsv(samples), "s.csv");
  ASSERT_EQ(back.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(back[k].t, samples[k].t);
    EXPECT_EQ(back[k].position, samples[k].position);
    EXPECT_EQ(back[k].velocity, samples[k].velocity);
    EXPECT_EQ(back[k].acceleration, samples[k].acceleration);
    EXPECT_EQ(back[k].jerk, samples[k].jerk);
  }
}

// Without jerk columns the jerk is the forward difference quotient of the acceleration.
TEST(SamplesCsv, JerkFromAccelerationWhenAbsent) {
  const auto s = ParseSamplesCsv(
      "# from another planner\r\nt, x, y, z, vx, vy, vz, ax, ay, az\r\n"
      "0,0,0,0,0,0,0,1,0,0\r\n0.5,0.125,0,0,0.5,0,0,2,0,-1\r\n1.5,1,0,0,2,0,0,2,0,0\r\n",
      "s.csv");
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].jerk, Eigen::Vector3d(2.0, 0.0, -2.0));  // (2 - 1) / 0.5, (-1 - 0) / 0.5
  EXPECT_EQ(s[1].jerk, Eigen::Vector3d(0.0, 0.0, 1.0));   // (0 - -1) / 1
  EXPECT_EQ(s[2].jerk, Eigen::Vector3d::Zero());
}

TEST(SamplesCsv, RejectsBadInputNamingTheLine) {
  const std::string header = "t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz\n";
  const std::string row0 = "0,0,0,0,0,0,0,0,0,0,0,0,0\n";
  ExpectParseError("", "no header");
  ExpectParseError("t,x,y,z\n", "s.csv line 1: expected the header");
  ExpectParseError(header + row0, "expected at least 2 samples, got 1");
  ExpectParseError(header + row0 + "0,1,1,1,0,0,0,0,0,0,0,0,0\n", "s.csv line 3: t must increase strictly (0 after 0)");
  ExpectParseError(header + row0 + "1,1,1,1,0,0,0,0,0,0,0,0\n", "s.csv line 3: expected 13 values, got 12");
  ExpectParseError(header + row0 + "1,1,1,1,0,0,0,0,0,0,0,0,x\n", "'x' is not a number");
  ExpectParseError(header + row0 + "1,1,1,1,0,0,0,0,0,0,0,0,nan\n", "'nan' is not finite");
}

}  // namespace
}  // namespace timeopt
