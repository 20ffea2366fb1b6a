#include "timeopt/conic/cbf.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../common/random_socp.h"
#include "timeopt/conic/problem_builder.h"
#include "timeopt/conic/solver.h"

namespace timeopt::conic {
namespace {

using ::testing::HasSubstr;

CbfModel Read(const std::string& text) {
  std::istringstream in(text);
  return ReadCbf(in);
}

void ExpectReadError(const std::string& text, const std::string& message) {
  try {
    Read(text);
    FAIL() << "expected std::invalid_argument containing \"" << message << "\"";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr(message));
  }
}

// Dense copies compare values and positions regardless of how the sparse storage was built.
void ExpectSameProblem(const Problem& a, const Problem& b) {
  EXPECT_EQ(a.c, b.c);
  EXPECT_EQ(a.b, b.b);
  EXPECT_EQ(a.h, b.h);
  EXPECT_EQ(Eigen::MatrixXd(a.A), Eigen::MatrixXd(b.A));
  EXPECT_EQ(Eigen::MatrixXd(a.G), Eigen::MatrixXd(b.G));
  EXPECT_EQ(a.cones.num_nonnegative, b.cones.num_nonnegative);
  EXPECT_EQ(a.cones.soc_dims, b.cones.soc_dims);
  EXPECT_EQ(a.cones.rotated_dims, b.cones.rotated_dims);
}

// Every kind of block our problems have: equalities, orthant rows, second-order and rotated cones
// (including one of dimension 2 and a large one), with random values that need all 17 digits.
TEST(Cbf, WriteThenReadGivesTheSameNumbersBitForBit) {
  Problem p = test_support::RandomPathSocp(60, 7);
  ASSERT_GT(p.num_equalities(), 0);
  ProblemBuilder builder;
  builder.AddVariables(4);
  builder.SetObjectiveCoefficient(1, 1.0 / 3.0);
  builder.AddEquality({{0, std::sqrt(2.0)}, {3, -1e-300}}, std::acos(-1.0));
  builder.AddLessEqual({{2, 0.1}}, 7e22);
  builder.AddLessEqual({{1, 4.9e-324}}, 2.2250738585072009e-308);  // subnormal numbers
  builder.AddRotatedCone({AffineExpr{{{0, 1.0}}, 0.0}, AffineExpr{{{1, 2.0}}, 0.5}});
  builder.AddSecondOrderCone({AffineExpr{{{3, 1.0}}, 1.0}, AffineExpr{{{0, -1.0}}, 0.0}, AffineExpr{{}, 2.0}});
  std::vector<AffineExpr> big(40);
  for (int i = 0; i < 40; ++i) big[static_cast<size_t>(i)] = AffineExpr{{{i % 4, 1.0 + i}}, -0.25 * i};
  builder.AddRotatedCone(big);
  for (const Problem& problem : {p, builder.Build()}) {
    std::ostringstream out;
    WriteCbf(problem, out);
    const CbfModel model = Read(out.str());
    EXPECT_FALSE(model.maximize);
    EXPECT_EQ(model.objective_constant, 0.0);
    ExpectSameProblem(model.problem, problem);
  }
}

// maximize 5 - x0 + x3 with x1 = 2, x2 = 3, 2 x0 x1 >= x2^2, x3 <= 0 (a variable domain), and three
// rows that do not bind: x0 - 1 >= 0, |x0 - 2| <= 4 and x0 - 10 <= 0 (each would bind, or make the
// problem infeasible, with the wrong sign). The optimum is x0 = 9/4, x3 = 0, value
// 5 - 9/4 = 2.75 exactly; 1e-7 is the solver's tolerance of 1e-8 with room for the 1/x0 scaling.
TEST(Cbf, ReadsDomainsSenseAndConstantAndSolvesToTheClosedForm) {
  const std::string text = R"(# a comment
VER
3

OBJSENSE
MAX

VAR
4 2
F 3
L- 1

CON
9 5
L= 2
QR 3
L+ 1
Q 2
L- 1

OBJACOORD
2
0 -1
3 1

OBJBCOORD
5

ACOORD
8
0 1 1
1 2 1
2 0 1
3 1 1
4 2 1
5 0 1
7 0 1
8 0 1

BCOORD
6
0 -2
1 -3
5 -1
6 4
7 -2
8 -10
)";
  const CbfModel model = Read(text);
  EXPECT_TRUE(model.maximize);
  EXPECT_EQ(model.objective_constant, 5.0);
  EXPECT_EQ(model.problem.num_variables(), 4);
  EXPECT_EQ(model.problem.num_equalities(), 2);
  EXPECT_EQ(model.problem.cones.num_nonnegative, 3);  // the L+ and L- rows and the L- variable
  const Result r = Solver().Solve(model.problem);
  ASSERT_EQ(r.status, Status::kOptimal) << r.message;
  EXPECT_FALSE(r.reduced_accuracy);
  EXPECT_NEAR(model.FileObjective(r.primal_objective), 2.75, 1e-7);
  EXPECT_NEAR(r.x[0], 2.25, 1e-7);
  EXPECT_NEAR(r.x[3], 0.0, 1e-7);
}

TEST(Cbf, RejectsWhatItCannotReadNamingTheLine) {
  const std::string head = "VER\n3\nVAR\n2 1\nF 2\n";
  ExpectReadError("", "no VER");
  ExpectReadError("VAR\n2 1\nF 2\n", "CBF line 1: the file must start with VER");
  ExpectReadError("VER\n5\n", "CBF version 5 is not supported");
  ExpectReadError("VER\n3\nVAR\n3 1\nF 2\n", "CBF line 5: VAR cones add up to 2, not 3");
  ExpectReadError("VER\n3\nVAR\n3 1\nEXP 3\n", "cone 'EXP' is not supported");
  ExpectReadError(head + "PSDVAR\n1\n2\n", "CBF line 6: PSDVAR is not supported");
  ExpectReadError(head + "INT\n1\n0\n", "INT is not supported");
  ExpectReadError(head + "FOO\n", "unknown keyword 'FOO'");
  ExpectReadError(head + "OBJACOORD\n1\n2 1.0\n", "variable 2 is out of range [0, 2)");
  ExpectReadError(head + "OBJACOORD\n1\n1 nan\n", "coefficient is not finite");
  ExpectReadError(head + "OBJACOORD\n1\n1 x\n", "expected a number, got 'x'");
  ExpectReadError(head + "OBJACOORD\n2\n1 1.0\n", "the file ends where an OBJACOORD entry was expected");
  ExpectReadError(head + "ACOORD\n1\n0 0 1\n", "ACOORD before CON");
  ExpectReadError(head + "CON\n1 1\nQR 1\n", "a QR cone needs dimension >= 2");
  ExpectReadError(head + "CON\n1 1\nL+ 1\nACOORD\n1\n1 0 1\n", "constraint row 1 is out of range [0, 1)");
  ExpectReadError(head + "OBJSENSE\nUP\n", "OBJSENSE must be MIN or MAX");
  ExpectReadError(head + "OBJSENSE\nMAX\nOBJSENSE\nMIN\n", "CBF line 8: OBJSENSE given twice");
  ExpectReadError(head + "OBJACOORD\n1\n0 1\nOBJACOORD\n1\n0 1\n", "OBJACOORD given twice");
  ExpectReadError(head + "OBJACOORD\n2\n0 1e308\n0 1e308\n", "CBF: c has Inf at 0");
  ExpectReadError(head + "OBJACOORD\n1\n0 1e400\n", "'1e400' is out of the range of a double");
  ExpectReadError("VER\n3\nVAR\n2000000000 1\nF 2000000000\n", "VAR size 2000000000 is out of range");
  ExpectReadError("VER\n3\nVAR\n-1 0\n", "VAR size -1 is out of range");
  // Below the format's own limit but above the solver's cap (2e6): refused before any allocation, where
  // a 62-byte file declaring 9e6 variables once grew the workspace to gigabytes.
  ExpectReadError("VER\n3\nVAR\n9000000 1\nF 9000000\n", "VAR declares 9000000 variables, above the 2000000 supported");
  ExpectReadError(head + "CON\n3000000 1\nL+ 3000000\n", "CON declares 3000000 rows, above the 2000000 supported");
}

TEST(Cbf, WriteRejectsAnInvalidProblem) {
  Problem p = test_support::RandomPathSocp(20, 1);
  p.h[0] = std::nan("");
  std::ostringstream out;
  EXPECT_THROW(WriteCbf(p, out), std::invalid_argument);
}

}  // namespace
}  // namespace timeopt::conic
