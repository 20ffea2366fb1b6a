#include "timeopt/conic/problem_builder.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace timeopt::conic {
namespace {

using ::testing::HasSubstr;

// Expects that f() throws std::invalid_argument whose message contains `text`.
template <typename F>
void ExpectInvalid(F f, const std::string& text) {
  try {
    f();
    FAIL() << "expected std::invalid_argument containing \"" << text << "\"";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr(text));
  }
}

TEST(ProblemBuilderTest, OrdersRowsAsTheConeSpecRequires) {
  ProblemBuilder builder;
  const int x = builder.AddVariables(3);
  EXPECT_EQ(x, 0);
  EXPECT_EQ(builder.AddVariables(0), 3);
  // Added out of order: rotated, then SOC, then an orthant row.
  builder.AddRotatedCone({AffineExpr{{{0, 1.0}}, 0.0}, AffineExpr{{}, 0.5}, AffineExpr{{{1, 2.0}}, 0.0}});
  builder.AddSecondOrderCone({AffineExpr{{{2, 1.0}}, 1.0}, AffineExpr{{{0, 3.0}}, 0.0}});
  builder.AddLessEqual({{1, 4.0}, {1, 1.0}}, 7.0);  // repeated terms are summed: 5 x1 <= 7
  builder.AddEquality({{0, 1.0}, {2, -1.0}}, 2.0);
  builder.SetObjectiveCoefficient(2, 1.5);
  builder.SetObjectiveCoefficient(2, 0.5);
  const Problem problem = builder.Build();
  EXPECT_NO_THROW(problem.Validate());

  EXPECT_EQ(problem.cones.num_nonnegative, 1);
  EXPECT_EQ(problem.cones.soc_dims, std::vector<int>({2}));
  EXPECT_EQ(problem.cones.rotated_dims, std::vector<int>({3}));
  EXPECT_EQ(problem.cones.NumRows(), 6);
  EXPECT_EQ(problem.cones.Degree(), 3);
  ASSERT_EQ(problem.G.rows(), 6);
  const Eigen::MatrixXd G(problem.G);
  Eigen::MatrixXd expected_G(6, 3);
  // s = h - G x: the orthant row 7 - 5 x1, the SOC (1 + x2, 3 x0), the rotated cone (x0, 0.5, 2 x1).
  expected_G << 0, 5, 0,  //
      0, 0, -1,           //
      -3, 0, 0,           //
      -1, 0, 0,           //
      0, 0, 0,            //
      0, -2, 0;
  EXPECT_EQ(G, expected_G);  // exact: only copies and sign changes
  EXPECT_EQ(problem.h, Eigen::VectorXd((Eigen::VectorXd(6) << 7, 1, 0, 0, 0.5, 0).finished()));
  EXPECT_EQ(Eigen::MatrixXd(problem.A), Eigen::MatrixXd((Eigen::MatrixXd(1, 3) << 1, 0, -1).finished()));
  EXPECT_EQ(problem.b, Eigen::VectorXd::Constant(1, 2.0));
  EXPECT_EQ(problem.c, Eigen::Vector3d(0, 0, 2.0));
}

TEST(ProblemBuilderTest, RejectsUnknownVariablesAndBadSizes) {
  ProblemBuilder builder;
  builder.AddVariables(2);
  ExpectInvalid([&] { builder.AddEquality({{2, 1.0}}, 0.0); }, "variable 2 does not exist");
  ExpectInvalid([&] { builder.SetObjectiveCoefficient(-1, 1.0); }, "variable -1 does not exist");
  ExpectInvalid([&] { builder.AddSecondOrderCone({}); }, "rows is empty");
  ExpectInvalid([&] { builder.AddRotatedCone({AffineExpr{}}); }, "rows has 1 entries, expected >= 2");
  ExpectInvalid([&] { builder.AddVariables(-3); }, "n is -3");
}

Problem SmallProblem() {
  ProblemBuilder builder;
  builder.AddVariables(3);
  builder.AddEquality({{0, 1.0}}, 1.0);
  builder.AddLessEqual({{1, 1.0}}, 1.0);
  builder.AddSecondOrderCone({AffineExpr{{{2, 1.0}}, 0.0}, AffineExpr{{{0, 1.0}}, 0.0}});
  return builder.Build();
}

TEST(ProblemValidateTest, NamesTheMismatch) {
  {
    Problem p = SmallProblem();
    p.cones.num_nonnegative = 2;
    ExpectInvalid([&] { p.Validate(); }, "G has 3 rows but the cones need 4");
  }
  {
    Problem p = SmallProblem();
    p.h.resize(2);
    ExpectInvalid([&] { p.Validate(); }, "h has 2 entries but the cones need 3");
  }
  {
    Problem p = SmallProblem();
    p.c[2] = std::numeric_limits<double>::quiet_NaN();
    ExpectInvalid([&] { p.Validate(); }, "c has NaN at 2");
  }
  {
    Problem p = SmallProblem();
    p.G.coeffRef(1, 2) = std::numeric_limits<double>::infinity();
    ExpectInvalid([&] { p.Validate(); }, "G has Inf at (1, 2)");
  }
  {
    Problem p = SmallProblem();
    p.b.resize(2);
    ExpectInvalid([&] { p.Validate(); }, "A has 1 rows but b has 2 entries");
  }
  {
    Problem p = SmallProblem();
    p.c.resize(4);
    ExpectInvalid([&] { p.Validate(); }, "A has 3 columns but c has 4 entries");
  }
  {
    Problem p = SmallProblem();
    p.cones.soc_dims = {0};
    ExpectInvalid([&] { p.Validate(); }, "soc_dims[0] is 0, expected >= 1");
  }
  {
    Problem p = SmallProblem();
    p.cones.soc_dims = {};
    p.cones.rotated_dims = {2};
    EXPECT_NO_THROW(p.Validate());
    p.cones.rotated_dims = {1};
    p.cones.num_nonnegative = 2;
    ExpectInvalid([&] { p.Validate(); }, "rotated_dims[0] is 1, expected >= 2");
  }
  {
    Problem p = SmallProblem();
    p.h[0] = -std::numeric_limits<double>::infinity();
    ExpectInvalid([&] { p.Validate(); }, "h has Inf at 0");
  }
}

}  // namespace
}  // namespace timeopt::conic
