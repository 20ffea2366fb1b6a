#include "timeopt/io/curve_io.h"

#include <cstdio>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace timeopt {
namespace {

using ::testing::HasSubstr;

std::string ErrorOf(const std::string& json) {
  try {
    ParseCurveJson(json);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(CurveJson, RoundTripIsBitExact) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  std::vector<PolynomialPiece> pieces;
  for (int i = 0; i < 4; ++i) {
    PolynomialPiece::Coefficients c(3, 3 + i);
    for (int j = 0; j < c.cols(); ++j)
      for (int a = 0; a < 3; ++a) c(a, j) = u(rng);
    pieces.emplace_back(c);
  }
  const PiecewiseCurve curve(pieces);
  const CurveFile back = ParseCurveJson(CurveToJson(curve));
  ASSERT_EQ(back.curve.num_pieces(), 4);
  EXPECT_FALSE(back.durations.has_value());
  for (int i = 0; i < 4; ++i) {
    // nlohmann::json prints doubles with round-trip precision: exact equality is the contract.
    EXPECT_EQ(back.curve.piece(i).coefficients(), curve.piece(i).coefficients());
  }
}

TEST(CurveJson, DurationsRescaleToUnitPieces) {
  // x(tau) = tau on [0, 2]: as a unit piece x(s) = 2 s.
  const CurveFile f = ParseCurveJson(R"({"pieces": [{"x": [0, 1], "y": [0, 0], "z": [1, 0]}], "durations": [2.0]})");
  ASSERT_TRUE(f.durations.has_value());
  EXPECT_EQ((*f.durations)[0], 2.0);
  EXPECT_EQ(f.curve.Evaluate(0, 1.0), Eigen::Vector3d(2, 0, 1));
}

// A constant axis may be given as one coefficient: the missing ones are zero, so the piece is the
// same as with every axis written out.
TEST(CurveJson, ShorterAxesArePaddedWithZeros) {
  const CurveFile short_axes = ParseCurveJson(R"({"pieces": [{"x": [0, 10, 0.5], "y": [2], "z": [1, 3]}]})");
  const CurveFile full = ParseCurveJson(R"({"pieces": [{"x": [0, 10, 0.5], "y": [2, 0, 0], "z": [1, 3, 0]}]})");
  EXPECT_EQ(short_axes.curve.piece(0).coefficients(), full.curve.piece(0).coefficients());
}

TEST(CurveJson, BadInputNamesTheField) {
  EXPECT_THAT(ErrorOf("{\"pieces\": [ {\"x\": [1"), HasSubstr("malformed JSON"));
  // Text above 64 MiB is refused before parsing (its tree would take ~1 GB, and a parse that runs
  // out of memory aborts the process); one byte below the cap is parsed (here: an empty object).
  EXPECT_THAT(ErrorOf(std::string((size_t{64} << 20) - 2, ' ') + "{}}"),
              HasSubstr("67108865 bytes of JSON, above the 67108864 supported"));
  EXPECT_THAT(ErrorOf(std::string((size_t{64} << 20) - 2, ' ') + "{}"), HasSubstr("curve.pieces: missing"));
  EXPECT_THAT(ErrorOf(R"({"pieces": []})"), HasSubstr("curve.pieces: expected at least 1 piece"));
  EXPECT_THAT(ErrorOf(R"({"peaces": []})"), HasSubstr("curve.pieces: missing"));
  EXPECT_THAT(ErrorOf(R"({"pieces": [{"x": [1, 2], "y": [], "z": [0, 0]}]})"),
              HasSubstr("curve.pieces[0].y: expected at least 1 coefficient"));
  EXPECT_THAT(ErrorOf(R"({"pieces": [{"x": [1], "y": [1], "z": [0]}, {"x": [1], "y": ["a"], "z": [0]}]})"),
              HasSubstr("curve.pieces[1].y[0]: expected a number"));
  EXPECT_THAT(ErrorOf(R"({"pieces": [{"x": [1], "y": [1]}]})"), HasSubstr("curve.pieces[0].z: missing"));
  EXPECT_THAT(ErrorOf(R"({"pieces": [{"x": [], "y": [], "z": []}]})"),
              HasSubstr("curve.pieces[0].x: expected at least 1 coefficient"));
  EXPECT_THAT(ErrorOf(R"({"pieces": [{"x": [1e999], "y": [0], "z": [0]}]})"), HasSubstr("1e999"));
  EXPECT_THAT(ErrorOf(R"({"pieces": [{"x": [1], "y": [0], "z": [0]}], "durations": [0]})"),
              HasSubstr("curve.durations[0]: expected a positive duration"));
  EXPECT_THAT(ErrorOf(R"({"pieces": [{"x": [1], "y": [0], "z": [0]}], "durations": [1, 2]})"),
              HasSubstr("curve.durations: expected 1 numbers, got 2"));
}

TEST(CurveJson, UnreadableFileIsAFileError) {
  EXPECT_THROW(ReadCurveJson("/nonexistent/dir/curve.json"), FileError);
  EXPECT_THROW(WriteCurveJson(PiecewiseCurve({PolynomialPiece()}), "/nonexistent/dir/c.json"), FileError);
}

TEST(WaypointsCsv, ParsesHeaderCommentsAndRows) {
  const Waypoints w = ParseWaypointsCsv("x,y,z\n# comment\n0,0,0\n\n1.5, 2, -3\r\n");
  ASSERT_EQ(w.cols(), 2);
  EXPECT_EQ(w.col(1), Eigen::Vector3d(1.5, 2, -3));
}

TEST(WaypointsCsv, BadRowsNameTheLine) {
  try {
    ParseWaypointsCsv("0,0,0\n1,2\n", "w.csv");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("w.csv line 2: expected 3 values"));
  }
  try {
    ParseWaypointsCsv("0,0,0\n1,2,abc\n", "w.csv");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("w.csv line 2: 'abc' is not a number"));
  }
  EXPECT_THROW(ParseWaypointsCsv("0,0,0\n1,2,nan\n"), std::invalid_argument);
  // The cap: 1e6 waypoints are read, one more is refused naming its line.
  std::string rows;
  for (int i = 0; i < 1'000'000; ++i) rows += "0,0,0\n";
  EXPECT_EQ(ParseWaypointsCsv(rows, "w.csv").cols(), 1'000'000);
  try {
    ParseWaypointsCsv(rows + "1,1,1\n", "w.csv");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("w.csv line 1000001: more than 1000000 waypoints"));
  }
  EXPECT_THROW(ParseWaypointsCsv("0,0,0\n"), std::invalid_argument);
}

}  // namespace
}  // namespace timeopt
