#include "timeopt/conic/solver.h"

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "timeopt/conic/problem_builder.h"
#include "../common/random_socp.h"

namespace timeopt::conic {
namespace {

using ::testing::HasSubstr;

AffineExpr Var(int v, double coef = 1.0, double constant = 0.0) { return AffineExpr{{{v, coef}}, constant}; }
AffineExpr Const(double value) { return AffineExpr{{}, value}; }

// ------------------------------------------------------------------------------------------------
// Problems with known optimal values, each with an independent (closed-form) answer.

struct Example {
  std::string name;
  std::function<Problem()> make;
  double optimal_value;
  Eigen::VectorXd optimal_x;  // empty if x is not unique or not checked
};

std::vector<Example> Examples() {
  std::vector<Example> examples;
  // LP: max x + y s.t. x + 2y <= 4, 3x + y <= 6, x, y >= 0. Vertex (1.6, 1.2), value -2.8.
  examples.push_back({"lp_vertex",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(2);
                        b.SetObjectiveCoefficient(0, -1.0);
                        b.SetObjectiveCoefficient(1, -1.0);
                        b.AddLessEqual({{0, 1.0}, {1, 2.0}}, 4.0);
                        b.AddLessEqual({{0, 3.0}, {1, 1.0}}, 6.0);
                        b.AddNonnegative(Var(0));
                        b.AddNonnegative(Var(1));
                        return b.Build();
                      },
                      -2.8, Eigen::Vector2d(1.6, 1.2)});
  // LP on the simplex: min x0 + 2 x1 + 3 x2, sum x = 1, x >= 0 -> x = e0.
  examples.push_back({"lp_simplex",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(3);
                        for (int i = 0; i < 3; ++i) {
                          b.SetObjectiveCoefficient(i, i + 1.0);
                          b.AddNonnegative(Var(i));
                        }
                        b.AddEquality({{0, 1.0}, {1, 1.0}, {2, 1.0}}, 1.0);
                        return b.Build();
                      },
                      1.0, Eigen::Vector3d(1.0, 0.0, 0.0)});
  // LP with a free variable: min t s.t. t >= |x - 3|, x <= 1 -> x = 1, t = 2.
  examples.push_back({"lp_absolute_value",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(2);  // t, x
                        b.SetObjectiveCoefficient(0, 1.0);
                        b.AddNonnegative(AffineExpr{{{0, 1.0}, {1, -1.0}}, 3.0});  // t - x + 3 >= 0
                        b.AddNonnegative(AffineExpr{{{0, 1.0}, {1, 1.0}}, -3.0});  // t + x - 3 >= 0
                        b.AddLessEqual({{1, 1.0}}, 1.0);
                        return b.Build();
                      },
                      2.0, Eigen::Vector2d(2.0, 1.0)});
  // SOC: distance from (1, 2) to the line x + y = 1 is |1 + 2 - 1| / sqrt(2) = sqrt(2).
  examples.push_back({"soc_distance_to_line",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(3);  // t, x, y
                        b.SetObjectiveCoefficient(0, 1.0);
                        b.AddEquality({{1, 1.0}, {2, 1.0}}, 1.0);
                        b.AddSecondOrderCone({Var(0), Var(1, 1.0, -1.0), Var(2, 1.0, -2.0)});
                        return b.Build();
                      },
                      std::sqrt(2.0), Eigen::Vector3d(std::sqrt(2.0), 0.0, 1.0)});
  // Optimum on the boundary of the unit disc: min x + y, ||(x, y)|| <= 1 -> x = y = -1/sqrt(2).
  examples.push_back({"soc_boundary_of_disc",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(2);
                        b.SetObjectiveCoefficient(0, 1.0);
                        b.SetObjectiveCoefficient(1, 1.0);
                        b.AddSecondOrderCone({Const(1.0), Var(0), Var(1)});
                        return b.Build();
                      },
                      -std::sqrt(2.0), Eigen::Vector2d(-std::sqrt(0.5), -std::sqrt(0.5))});
  // A large cone (dimension 11, sparse expansion by default): min sum x s.t. ||x|| <= 1 -> -sqrt(10).
  examples.push_back({"soc_large_ball",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(10);
                        std::vector<AffineExpr> rows = {Const(1.0)};
                        for (int i = 0; i < 10; ++i) {
                          b.SetObjectiveCoefficient(i, 1.0);
                          rows.push_back(Var(i));
                        }
                        b.AddSecondOrderCone(rows);
                        return b.Build();
                      },
                      -std::sqrt(10.0), Eigen::VectorXd::Constant(10, -1.0 / std::sqrt(10.0))});
  // Fermat point of the equilateral triangle (0,0), (1,0), (1/2, sqrt3/2): the centroid, each
  // distance 1/sqrt3, total sqrt3.
  examples.push_back({"soc_fermat_point",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(5);  // px, py, t0, t1, t2
                        const double pts[3][2] = {{0, 0}, {1, 0}, {0.5, std::sqrt(3.0) / 2}};
                        for (int k = 0; k < 3; ++k) {
                          b.SetObjectiveCoefficient(2 + k, 1.0);
                          b.AddSecondOrderCone({Var(2 + k), Var(0, 1.0, -pts[k][0]), Var(1, 1.0, -pts[k][1])});
                        }
                        return b.Build();
                      },
                      std::sqrt(3.0), Eigen::VectorXd()});
  // Rotated cone: min t s.t. t u >= x^2 with u = 2, x = 3, i.e. 2 t (u/2) >= x^2 -> t = 4.5.
  examples.push_back({"rotated_t_u_x2",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(3);  // t, u, x
                        b.SetObjectiveCoefficient(0, 1.0);
                        b.AddEquality({{1, 1.0}}, 2.0);
                        b.AddEquality({{2, 1.0}}, 3.0);
                        b.AddRotatedCone({Var(0), Var(1, 0.5), Var(2)});
                        return b.Build();
                      },
                      4.5, Eigen::Vector3d(4.5, 2.0, 3.0)});
  // Hyperbolic constraint: min x + y s.t. x y >= 1 -> x = y = 1 (rotated cone (x, y, sqrt2)).
  examples.push_back({"rotated_hyperbola",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(2);
                        b.SetObjectiveCoefficient(0, 1.0);
                        b.SetObjectiveCoefficient(1, 1.0);
                        b.AddRotatedCone({Var(0), Var(1), Const(std::sqrt(2.0))});
                        return b.Build();
                      },
                      2.0, Eigen::Vector2d(1.0, 1.0)});
  // Least squares as an SOC: min ||M x - q||; the answer from the normal equations (dense QR).
  {
    Eigen::MatrixXd M(5, 3);
    M << 1, 2, 0, 0, 1, 1, 3, 0, 1, 1, 1, 1, 2, -1, 0;
    Eigen::VectorXd q(5);
    q << 1, -2, 3, 0.5, 4;
    const Eigen::VectorXd xs = M.colPivHouseholderQr().solve(q);
    Eigen::VectorXd expected(4);
    expected << (M * xs - q).norm(), xs;
    examples.push_back({"least_squares",
                        [M, q] {
                          ProblemBuilder b;
                          b.AddVariables(4);  // t, x0..x2
                          b.SetObjectiveCoefficient(0, 1.0);
                          std::vector<AffineExpr> rows = {Var(0)};
                          for (int i = 0; i < 5; ++i) {
                            AffineExpr e{{}, -q[i]};
                            for (int j = 0; j < 3; ++j) e.terms.push_back({1 + j, M(i, j)});
                            rows.push_back(e);
                          }
                          b.AddSecondOrderCone(rows);
                          return b.Build();
                        },
                        expected[0], expected});
  }
  // Minimum-variance portfolio: min x' S x s.t. 1'x = 1, x >= 0, with S = L L' diagonally dominant
  // so that the unconstrained answer S^{-1} 1 / (1' S^{-1} 1) is positive (the bounds are inactive).
  // Variance as t with the rotated cone 2 t (1/2) >= ||L' x||^2.
  {
    Eigen::MatrixXd S(4, 4);
    S << 4, 1, 0.5, 0.2, 1, 3, 0.3, 0.1, 0.5, 0.3, 2, 0.4, 0.2, 0.1, 0.4, 5;
    const Eigen::MatrixXd L = S.llt().matrixL();
    const Eigen::VectorXd w = S.ldlt().solve(Eigen::VectorXd::Ones(4));
    const double variance = 1.0 / w.sum();
    Eigen::VectorXd expected(5);
    expected << variance, w * variance;
    examples.push_back({"portfolio_min_variance",
                        [L] {
                          ProblemBuilder b;
                          b.AddVariables(5);  // t, x0..x3
                          b.SetObjectiveCoefficient(0, 1.0);
                          std::vector<Term> budget;
                          for (int i = 0; i < 4; ++i) {
                            budget.push_back({1 + i, 1.0});
                            b.AddNonnegative(Var(1 + i));
                          }
                          b.AddEquality(budget, 1.0);
                          std::vector<AffineExpr> rows = {Var(0), Const(0.5)};
                          for (int j = 0; j < 4; ++j) {  // (L' x)_j = sum_i L(i, j) x_i
                            AffineExpr e;
                            for (int i = j; i < 4; ++i) e.terms.push_back({1 + i, L(i, j)});
                            rows.push_back(e);
                          }
                          b.AddRotatedCone(rows);
                          return b.Build();
                        },
                        variance, expected});
  }
  // Optimum at the apex of a cone: min t s.t. t >= ||(x, y)||, x + y >= 1... shifted: x + y = 0 and
  // x >= 0, y >= 0 force x = y = 0, so t = 0 at the apex.
  examples.push_back({"soc_apex",
                      [] {
                        ProblemBuilder b;
                        b.AddVariables(3);
                        b.SetObjectiveCoefficient(0, 1.0);
                        b.AddEquality({{1, 1.0}, {2, 1.0}}, 0.0);
                        b.AddNonnegative(Var(1));
                        b.AddNonnegative(Var(2));
                        b.AddSecondOrderCone({Var(0), Var(1), Var(2)});
                        return b.Build();
                      },
                      0.0, Eigen::Vector3d::Zero()});
  return examples;
}

struct ExampleCase {
  Example example;
  int sparse_cone_min_dimension;
  KktMethod kkt_method;
};

// A case prints as its problem's name (gtest would dump its bytes, a heap address among them,
// into every ctest name, which then changed from build to build; the method and the cones'
// expansion are in the test's name already).
void PrintTo(const ExampleCase& c, std::ostream* os) { *os << c.example.name; }

class KnownOptimumTest : public ::testing::TestWithParam<ExampleCase> {};

TEST_P(KnownOptimumTest, ReachesTheClosedFormOptimum) {
  const ExampleCase& param = GetParam();
  Solver::Options options;
  options.sparse_cone_min_dimension = param.sparse_cone_min_dimension;
  options.kkt_method = param.kkt_method;
  Solver solver(options);
  const Problem problem = param.example.make();
  const Result result = solver.Solve(problem);
  ASSERT_EQ(result.status, Status::kOptimal) << result.BriefReport();
  // The stopping rule bounds the duality gap and the residuals by 1e-8 (relative, or absolute below 1):
  // the objective is then within ~1e-8 of the optimum; 1e-7 leaves a factor 10 for rounding.
  const double scale = std::max(1.0, std::abs(param.example.optimal_value));
  EXPECT_NEAR(result.primal_objective, param.example.optimal_value, 1e-7 * scale) << result.BriefReport();
  EXPECT_NEAR(result.dual_objective, param.example.optimal_value, 1e-7 * scale) << result.BriefReport();
  // The solver stops on its residuals in internal coordinates, where the first two rows of every
  // rotated cone are turned by 45 degrees; turned back, an infinity norm can grow by up to sqrt(2).
  EXPECT_LE(result.primal_residual, std::sqrt(2.0) * 1e-8);
  EXPECT_LE(result.dual_residual, 1e-8);
  if (param.example.optimal_x.size() > 0) {
    // These optima are unique and the problems well conditioned (strict complementarity), so x is
    // Lipschitz in the gap: 1e-6 is a safe margin over the observed ~1e-9.
    EXPECT_LT((result.x - param.example.optimal_x).lpNorm<Eigen::Infinity>(), 1e-6) << result.x.transpose();
  }
  EXPECT_TRUE(result.x.allFinite() && result.y.allFinite() && result.z.allFinite() && result.s.allFinite());
  EXPECT_LE(result.iterations, 30);
}

std::vector<ExampleCase> AllCases() {
  // Every problem through both KKT methods, each with dense blocks for small cones (6, the default)
  // and with every cone expanded (1): four independent computations of the same optimum.
  std::vector<ExampleCase> cases;
  for (const Example& e : Examples()) {
    for (KktMethod method : {KktMethod::kAugmentedSparse, KktMethod::kReducedBanded}) {
      cases.push_back({e, 6, method});
      cases.push_back({e, 1, method});
    }
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Examples, KnownOptimumTest, ::testing::ValuesIn(AllCases()),
                         [](const ::testing::TestParamInfo<ExampleCase>& info) {
                           return info.param.example.name + "_" + ToString(info.param.kkt_method) +
                                  (info.param.sparse_cone_min_dimension == 1 ? "_expanded" : "_default");
                         });

// Options forcing each KKT method, for the tests below that must hold for both.
std::vector<Solver::Options> BothKktMethods() {
  std::vector<Solver::Options> all(2);
  all[0].kkt_method = KktMethod::kAugmentedSparse;
  all[1].kkt_method = KktMethod::kReducedBanded;
  return all;
}

// Solves `problem` with each KKT method forced and runs check(result) on each, traced by method.
template <typename Check>
void ForBothKktMethods(const Problem& problem, Check check) {
  for (const Solver::Options& options : BothKktMethods()) {
    SCOPED_TRACE(ToString(options.kkt_method));
    Solver solver(options);
    check(solver.Solve(problem));
  }
}

// ------------------------------------------------------------------------------------------------
// The two KKT methods on a path-shaped problem (the temporal stage's structure): the automatic choice
// takes the reduced banded method, and both methods reach the same optimum.

// Minimum-time-like SOCP over N cells: b_k <= u_k, |b_{k+1} - b_k| <= 2 ds amax, c_k^2 <= b_k,
// d_k (c_k + c_{k+1}) >= 1, b_0 and b_N fixed by equalities, and a large rotated cone for
// rho * sum ((b_{k+1} - b_k) / (2 ds))^2 ds.
Problem PathProblem(int cells) {
  ProblemBuilder builder;
  const int b0 = builder.AddVariables(cells + 1);
  const int c0 = builder.AddVariables(cells + 1);
  const int d0 = builder.AddVariables(cells);
  const int t = builder.AddVariables(1);
  const double ds = 1.0 / cells, amax = 2.0, rho = 0.1;
  for (int k = 0; k <= cells; ++k) {
    builder.AddRotatedCone({Var(b0 + k), Const(0.5), Var(c0 + k)});
    builder.AddLessEqual({{b0 + k, 1.0}}, 4.0 + std::sin(0.3 * k));
  }
  for (int k = 0; k < cells; ++k) {
    builder.SetObjectiveCoefficient(d0 + k, 2.0 * ds);
    builder.AddRotatedCone({Var(d0 + k), AffineExpr{{{c0 + k, 1.0}, {c0 + k + 1, 1.0}}, 0.0}, Const(std::sqrt(2.0))});
    builder.AddLessEqual({{b0 + k + 1, 1.0}, {b0 + k, -1.0}}, 2.0 * ds * amax);
    builder.AddLessEqual({{b0 + k + 1, -1.0}, {b0 + k, 1.0}}, 2.0 * ds * amax);
  }
  builder.AddEquality({{b0, 1.0}}, 0.04);
  builder.AddEquality({{b0 + cells, 1.0}}, 0.04);
  std::vector<AffineExpr> rows = {Var(t), Const(0.5)};
  for (int k = 0; k < cells; ++k) rows.push_back(AffineExpr{{{b0 + k + 1, 0.5 / ds}, {b0 + k, -0.5 / ds}}, 0.0});
  builder.AddRotatedCone(rows);
  builder.SetObjectiveCoefficient(t, rho * ds);
  return builder.Build();
}

TEST(KktMethodTest, PathProblemTakesTheReducedMethodAndBothAgree) {
  const Problem problem = PathProblem(200);
  Solver automatic;
  const Result reduced = automatic.Solve(problem);
  ASSERT_EQ(reduced.status, Status::kOptimal) << reduced.BriefReport();
  EXPECT_EQ(reduced.kkt_method, KktMethod::kReducedBanded);
  // The automatic rule: at most 16 stored entries per row on average (the border rows excepted).
  EXPECT_LE(reduced.factor_nonzeros, 16LL * reduced.kkt_size);
  Solver::Options options;
  options.kkt_method = KktMethod::kAugmentedSparse;
  Solver augmented_solver(options);
  const Result augmented = augmented_solver.Solve(problem);
  ASSERT_EQ(augmented.status, Status::kOptimal) << augmented.BriefReport();
  EXPECT_EQ(augmented.kkt_method, KktMethod::kAugmentedSparse);
  // Both stop at a relative gap of 1e-8 around the same optimum: objectives within 2e-8 relative,
  // checked at 1e-7. The objective is strictly convex in b through the rho term, so b is unique; its
  // error grows like the square root of the gap, hence 1e-4.
  EXPECT_NEAR(reduced.primal_objective, augmented.primal_objective, 1e-7 * std::abs(augmented.primal_objective));
  EXPECT_LT((reduced.x.head(201) - augmented.x.head(201)).lpNorm<Eigen::Infinity>(), 1e-4);
  // A re-solve of the same pattern reuses the reduced analysis.
  const Result again = automatic.Solve(problem);
  EXPECT_TRUE(again.reused_symbolic);
  EXPECT_EQ(again.kkt_method, KktMethod::kReducedBanded);
  EXPECT_EQ(again.iterations, reduced.iterations);
}

// ------------------------------------------------------------------------------------------------
// Infeasible and unbounded problems: the certificates are checked against their definitions.

void ExpectInCone(const Eigen::VectorXd& v, const ConeSpec& cones, double tol) {
  int r = 0;
  for (; r < cones.num_nonnegative; ++r) EXPECT_GE(v[r], -tol);
  for (int d : cones.soc_dims) {
    EXPECT_GE(v[r] - v.segment(r + 1, d - 1).norm(), -tol);
    r += d;
  }
  for (int d : cones.rotated_dims) {
    EXPECT_GE(v[r], -tol);
    EXPECT_GE(v[r + 1], -tol);
    EXPECT_GE(2.0 * v[r] * v[r + 1] - v.segment(r + 2, d - 2).squaredNorm(), -tol);
    r += d;
  }
}

void ExpectPrimalInfeasibilityCertificate(const Problem& problem, const Result& result) {
  ASSERT_EQ(result.status, Status::kPrimalInfeasible) << result.BriefReport();
  // Normalization b'y + h'z = -1 is exact up to rounding.
  EXPECT_NEAR(problem.b.dot(result.y) + problem.h.dot(result.z), -1.0, 1e-12);
  // A'y + G'z = 0 to the infeasibility tolerance 1e-8 (data entries are O(1)).
  const Eigen::VectorXd r = problem.A.transpose() * result.y + problem.G.transpose() * result.z;
  EXPECT_LE(r.lpNorm<Eigen::Infinity>(), 1e-8);
  ExpectInCone(result.z, problem.cones, 1e-12);  // iterates are strictly interior
  EXPECT_TRUE(result.y.allFinite() && result.z.allFinite());
}

void ExpectDualInfeasibilityCertificate(const Problem& problem, const Result& result) {
  ASSERT_EQ(result.status, Status::kDualInfeasible) << result.BriefReport();
  EXPECT_NEAR(problem.c.dot(result.x), -1.0, 1e-12);
  EXPECT_LE((problem.A * result.x).lpNorm<Eigen::Infinity>(), 1e-8);
  EXPECT_LE((problem.G * result.x + result.s).lpNorm<Eigen::Infinity>(), 1e-8);
  ExpectInCone(result.s, problem.cones, 1e-12);
  EXPECT_TRUE(result.x.allFinite() && result.s.allFinite());
}

TEST(InfeasibilityTest, PrimalInfeasibleLp) {
  ProblemBuilder b;
  b.AddVariables(2);
  b.SetObjectiveCoefficient(0, 1.0);
  b.AddNonnegative(Var(0, 1.0, -1.0));  // x >= 1
  b.AddLessEqual({{0, 1.0}}, 0.0);      // x <= 0
  b.AddEquality({{1, 1.0}}, 2.0);
  const Problem problem = b.Build();
  ForBothKktMethods(problem, [&](const Result& result) { ExpectPrimalInfeasibilityCertificate(problem, result); });
}

TEST(InfeasibilityTest, PrimalInfeasibleSocAndRotated) {
  ProblemBuilder b;
  b.AddVariables(3);
  b.SetObjectiveCoefficient(0, 1.0);
  b.AddSecondOrderCone({Const(1.0), Var(0), Var(1)});  // ||(x, y)|| <= 1
  b.AddNonnegative(Var(0, 1.0, -2.0));                 // x >= 2
  b.AddRotatedCone({Var(2), Var(2), Const(1.0)});      // 2 w^2 >= 1, feasible by itself
  const Problem problem = b.Build();
  for (int min_dim : {6, 1}) {
    for (Solver::Options options : BothKktMethods()) {
      SCOPED_TRACE(std::string(ToString(options.kkt_method)) + " min_dim " + std::to_string(min_dim));
      options.sparse_cone_min_dimension = min_dim;
      Solver solver(options);
      ExpectPrimalInfeasibilityCertificate(problem, solver.Solve(problem));
    }
  }
}

TEST(InfeasibilityTest, DualInfeasibleLp) {
  // min -x s.t. x >= 0, y = 1: unbounded along x.
  ProblemBuilder b;
  b.AddVariables(2);
  b.SetObjectiveCoefficient(0, -1.0);
  b.AddNonnegative(Var(0));
  b.AddEquality({{1, 1.0}}, 1.0);
  const Problem problem = b.Build();
  ForBothKktMethods(problem, [&](const Result& result) { ExpectDualInfeasibilityCertificate(problem, result); });
}

TEST(InfeasibilityTest, DualInfeasibleSoc) {
  // min y - 0.5 t s.t. t >= ||y||: along t = -y -> infinity the objective falls like -1.5 t.
  ProblemBuilder b;
  b.AddVariables(2);  // t, y
  b.SetObjectiveCoefficient(0, -0.5);
  b.SetObjectiveCoefficient(1, 1.0);
  b.AddSecondOrderCone({Var(0), Var(1)});
  b.AddRotatedCone({Var(0), Const(1.0), Const(0.5)});  // 2 t >= 1/4
  const Problem problem = b.Build();
  ForBothKktMethods(problem, [&](const Result& result) { ExpectDualInfeasibilityCertificate(problem, result); });
}

// ------------------------------------------------------------------------------------------------
// Degenerate problems end with a clear status and finite numbers.

void ExpectFinite(const Result& result) {
  EXPECT_TRUE(result.x.allFinite() && result.y.allFinite() && result.z.allFinite() && result.s.allFinite());
  EXPECT_TRUE(std::isfinite(result.primal_objective) && std::isfinite(result.dual_objective));
  EXPECT_NE(result.status, Status::kNotSolved);
}

TEST(DegenerateTest, RedundantEqualities) {
  ProblemBuilder b;
  b.AddVariables(3);
  for (int i = 0; i < 3; ++i) {
    b.SetObjectiveCoefficient(i, i + 1.0);
    b.AddNonnegative(Var(i));
  }
  b.AddEquality({{0, 1.0}, {1, 1.0}, {2, 1.0}}, 1.0);
  b.AddEquality({{0, 1.0}, {1, 1.0}, {2, 1.0}}, 1.0);  // duplicate
  b.AddEquality({{0, 2.0}, {1, 2.0}, {2, 2.0}}, 2.0);  // multiple
  const Problem problem = b.Build();
  ForBothKktMethods(problem, [&](const Result& result) {
    ExpectFinite(result);
    ASSERT_EQ(result.status, Status::kOptimal) << result.BriefReport();
    EXPECT_NEAR(result.primal_objective, 1.0, 1e-7);  // same answer as lp_simplex
  });
}

TEST(DegenerateTest, AllZeroRows) {
  ProblemBuilder b;
  b.AddVariables(3);  // the last variable appears nowhere
  b.SetObjectiveCoefficient(0, 1.0);
  b.AddNonnegative(Var(0, 1.0, -2.0));  // x >= 2
  b.AddNonnegative(Const(1.0));         // 1 >= 0: a zero row of G
  b.AddEquality({}, 0.0);               // 0 = 0: a zero row of A
  b.AddSecondOrderCone({Const(1.0), Const(0.0), Var(1)});
  const Problem problem = b.Build();
  ForBothKktMethods(problem, [&](const Result& result) {
    ExpectFinite(result);
    ASSERT_EQ(result.status, Status::kOptimal) << result.BriefReport();
    EXPECT_NEAR(result.primal_objective, 2.0, 1e-7);
  });
}

TEST(DegenerateTest, ConesWithoutInterior) {
  // x >= 0 and x <= 0 (the orthant part has no interior), t >= ||(x, u)|| with t = 0 (the SOC has no
  // interior), minimize y subject to y >= 1 + x. Optimum 1.
  ProblemBuilder b;
  b.AddVariables(4);  // x, y, t, u
  b.SetObjectiveCoefficient(1, 1.0);
  b.AddNonnegative(Var(0));
  b.AddLessEqual({{0, 1.0}}, 0.0);
  b.AddNonnegative(AffineExpr{{{1, 1.0}, {0, -1.0}}, -1.0});
  b.AddEquality({{2, 1.0}}, 0.0);
  b.AddSecondOrderCone({Var(2), Var(0), Var(3)});
  const Problem problem = b.Build();
  ForBothKktMethods(problem, [&](const Result& result) {
    ExpectFinite(result);
    // No interior means no strictly feasible point: the method still converges, but the achievable
    // accuracy is about sqrt(tolerance), so only a clear status and a close objective are required.
    EXPECT_TRUE(result.status == Status::kOptimal || result.status == Status::kNumericalError ||
                result.status == Status::kIterationLimit)
        << result.BriefReport();
    EXPECT_NEAR(result.primal_objective, 1.0, 1e-4) << result.BriefReport();
  });
}

TEST(DegenerateTest, EmptyProblemAndNoCones) {
  // Only equalities: min x0 s.t. x0 + x1 = 1, x1 = 3 -> x0 = -2.
  ProblemBuilder b;
  b.AddVariables(2);
  b.SetObjectiveCoefficient(0, 1.0);
  b.AddEquality({{0, 1.0}, {1, 1.0}}, 1.0);
  b.AddEquality({{1, 1.0}}, 3.0);
  const Problem problem = b.Build();
  ForBothKktMethods(problem, [&](const Result& result) {
    ExpectFinite(result);
    ASSERT_EQ(result.status, Status::kOptimal) << result.BriefReport();
    EXPECT_NEAR(result.primal_objective, -2.0, 1e-7);
  });
}

// ------------------------------------------------------------------------------------------------
// Bad input and options.

TEST(BadInputTest, ThrowsBeforeAnyIteration) {
  ProblemBuilder b;
  b.AddVariables(2);
  b.AddNonnegative(Var(0));
  b.AddSecondOrderCone({Var(0), Var(1)});
  Problem problem = b.Build();
  int callbacks = 0;
  Solver::Options options;
  options.callback = [&](const IterationInfo&) { ++callbacks; };
  Solver solver(options);

  Problem bad = problem;
  bad.cones.soc_dims = {3};
  try {
    solver.Solve(bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("G has 3 rows but the cones need 4"));
  }
  bad = problem;
  bad.c[1] = std::numeric_limits<double>::quiet_NaN();
  try {
    solver.Solve(bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("c has NaN at 1"));
  }
  EXPECT_EQ(callbacks, 0);
  EXPECT_EQ(solver.Solve(problem).status, Status::kOptimal);  // the solver is still usable (c = 0)
  EXPECT_GT(callbacks, 0);
}

TEST(BadInputTest, InvalidOptions) {
  Solver::Options options;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error));
  options.step_fraction = 1.5;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_THAT(error, HasSubstr("step_fraction"));
  EXPECT_THROW(Solver{options}, std::invalid_argument);
  options = Solver::Options();
  options.feasibility_tolerance = -1.0;
  EXPECT_FALSE(options.IsValid(nullptr));
  options = Solver::Options();
  options.refinement_mu_factor = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_THAT(error, HasSubstr("refinement_mu_factor"));
}

// The tuning heuristics that were literals inside the solve: every one is checked, and its message
// names it.
TEST(BadInputTest, InvalidHeuristicOptions) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<std::string, std::function<void(Solver::Options&)>>> cases = {
      {"reduced_max_expanded_cones", [](Solver::Options& o) { o.reduced_max_expanded_cones = -1; }},
      {"reduced_max_profile_per_row", [](Solver::Options& o) { o.reduced_max_profile_per_row = 0; }},
      {"slow_phase_stall_factor", [](Solver::Options& o) { o.slow_phase_stall_factor = 0; }},
      {"max_regularization_boosts", [](Solver::Options& o) { o.max_regularization_boosts = -1; }},
      {"regularization_boost_factor", [](Solver::Options& o) { o.regularization_boost_factor = 1.0; }},
      {"regularization_boost_factor", [&](Solver::Options& o) { o.regularization_boost_factor = nan; }},
      {"max_step_trials", [](Solver::Options& o) { o.max_step_trials = 0; }},
      {"lookback_merit", [](Solver::Options& o) { o.lookback_merit = -1.0; }},
      {"lookback_merit", [&](Solver::Options& o) { o.lookback_merit = nan; }},
      {"lookback_min_step", [](Solver::Options& o) { o.lookback_min_step = 1.5; }},
      {"divergence_merit_factor", [](Solver::Options& o) { o.divergence_merit_factor = 1.0; }},
      {"divergence_merit_factor", [&](Solver::Options& o) { o.divergence_merit_factor = nan; }},
  };
  for (const auto& [name, mutate] : cases) {
    SCOPED_TRACE(name);
    Solver::Options options;
    mutate(options);
    std::string error;
    EXPECT_FALSE(options.IsValid(&error));
    EXPECT_THAT(error, HasSubstr(name));
    EXPECT_THROW(Solver{options}, std::invalid_argument);
  }
  // The boundary values are valid: no boosts, lookback disabled.
  Solver::Options options;
  options.max_regularization_boosts = 0;
  options.lookback_merit = 0.0;
  options.lookback_min_step = 1.0;
  options.reduced_max_expanded_cones = 0;
  EXPECT_TRUE(options.IsValid(nullptr));
}

// The band limit of the automatic method decides it: the random path SOCP (a window of 30 columns per
// row) is too wide for the default 16 entries per row and goes to the augmented method; with the limit
// raised it goes to the reduced one, and the change forces a new analysis on the next Solve(). Both
// reach the same optimum (1e-6 relative: two methods, each to the 1e-8 tolerances).
TEST(KktMethodTest, BandLimitDecidesAutomaticMethod) {
  const Problem problem = test_support::RandomPathSocp(200, 3);
  Solver solver;
  const Result augmented = solver.Solve(problem);
  ASSERT_TRUE(augmented.is_success()) << augmented.BriefReport();
  EXPECT_EQ(augmented.kkt_method, KktMethod::kAugmentedSparse);
  Solver::Options options;
  options.reduced_max_profile_per_row = 1000000;
  solver.set_options(options);
  const Result banded = solver.Solve(problem);
  ASSERT_TRUE(banded.is_success()) << banded.BriefReport();
  EXPECT_FALSE(banded.reused_symbolic);
  EXPECT_EQ(banded.kkt_method, KktMethod::kReducedBanded);
  EXPECT_NEAR(banded.primal_objective, augmented.primal_objective, 1e-6 * std::abs(augmented.primal_objective));
}

TEST(StatusTest, NamesAndReport) {
  EXPECT_STREQ(ToString(Status::kOptimal), "optimal");
  EXPECT_STREQ(ToString(Status::kPrimalInfeasible), "primal_infeasible");
  EXPECT_STREQ(ToString(Status::kDualInfeasible), "dual_infeasible");
  EXPECT_STREQ(ToString(Status::kIterationLimit), "iteration_limit");
  EXPECT_STREQ(ToString(Status::kNumericalError), "numerical_error");
  EXPECT_STREQ(ToString(Status::kNotSolved), "not_solved");
  Result result;
  EXPECT_FALSE(result.is_success());
  EXPECT_THAT(result.BriefReport(), HasSubstr("not_solved"));
}

TEST(IterationLimitTest, StopsWithLastIterate) {
  Solver::Options options;
  options.max_iterations = 2;
  Solver solver(options);
  const Result result = solver.Solve(Examples()[0].make());
  EXPECT_EQ(result.status, Status::kIterationLimit);
  EXPECT_EQ(result.iterations, 2);
  ExpectFinite(result);
}

// ------------------------------------------------------------------------------------------------
// Random strictly feasible problems: optimality is certified from the returned vectors themselves
// (weak duality): primal and dual feasibility plus a vanishing gap, recomputed here from the data.

Problem RandomFeasibleProblem(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const int n = 10 + static_cast<int>(rng() % 30);
  const int p = static_cast<int>(rng() % 4);
  Problem problem;
  problem.cones.num_nonnegative = static_cast<int>(rng() % 10);
  for (int k = 0, count = static_cast<int>(rng() % 5); k < count; ++k) {
    problem.cones.soc_dims.push_back(1 + static_cast<int>(rng() % 8));
  }
  for (int k = 0, count = static_cast<int>(rng() % 4); k < count; ++k) {
    problem.cones.rotated_dims.push_back(2 + static_cast<int>(rng() % 8));
  }
  const int m = problem.cones.NumRows();
  std::vector<Eigen::Triplet<double>> ta, tg;
  for (int i = 0; i < p; ++i) {
    for (int q = 0; q < 4; ++q) ta.emplace_back(i, static_cast<int>(rng() % n), uni(rng));
  }
  for (int i = 0; i < m; ++i) {
    for (int q = 0; q < 3; ++q) tg.emplace_back(i, static_cast<int>(rng() % n), uni(rng));
  }
  // Every variable in some cone row keeps the problem bounded (c = -A'y0 - G'z0 with z0 interior).
  for (int j = 0; j < n && m > 0; ++j) tg.emplace_back(static_cast<int>(rng() % m), j, uni(rng));
  problem.A.resize(p, n);
  problem.A.setFromTriplets(ta.begin(), ta.end());
  problem.G.resize(m, n);
  problem.G.setFromTriplets(tg.begin(), tg.end());
  // Interior points of K: the identity element plus a small perturbation.
  auto interior = [&] {
    Eigen::VectorXd v = 0.3 * Eigen::VectorXd::NullaryExpr(m, [&] { return uni(rng); });
    int r = problem.cones.num_nonnegative;
    for (int i = 0; i < r; ++i) v[i] = 1.0 + std::abs(v[i]);
    for (int d : problem.cones.soc_dims) {
      v[r] = 1.0 + v.segment(r + 1, d - 1).norm();
      r += d;
    }
    for (int d : problem.cones.rotated_dims) {
      v[r] = v[r + 1] = 1.0 + v.segment(r + 2, d - 2).norm();
      r += d;
    }
    return v;
  };
  const Eigen::VectorXd x0 = Eigen::VectorXd::NullaryExpr(n, [&] { return uni(rng); });
  const Eigen::VectorXd y0 = Eigen::VectorXd::NullaryExpr(p, [&] { return uni(rng); });
  problem.h = problem.G * x0 + interior();
  problem.b = problem.A * x0;
  problem.c = -(problem.A.transpose() * y0) - problem.G.transpose() * interior();
  return problem;
}

TEST(RandomProblemTest, OptimalityCertifiedByTheReturnedVectors) {
  int reduced = 0, reduced_kkt = 0;
  for (unsigned trial = 0; trial < 180; ++trial) {
    // Each problem with the automatic choice and with each method forced.
    const unsigned seed = trial / 3;
    const KktMethod method = trial % 3 == 0   ? KktMethod::kAutomatic
                             : trial % 3 == 1 ? KktMethod::kAugmentedSparse
                                              : KktMethod::kReducedBanded;
    const Problem problem = RandomFeasibleProblem(seed);
    Solver::Options options;
    options.sparse_cone_min_dimension = seed % 2 == 0 ? 6 : 1;
    options.kkt_method = method;
    Solver solver(options);
    const Result r = solver.Solve(problem);
    ASSERT_EQ(r.status, Status::kOptimal) << "seed " << seed << ": " << r.BriefReport();
    if (r.reduced_accuracy) ++reduced;
    if (r.kkt_method == KktMethod::kReducedBanded) ++reduced_kkt;
    ExpectInCone(r.s, problem.cones, 1e-12);
    ExpectInCone(r.z, problem.cones, 1e-12);
    // Full accuracy: relative residuals and gap 1e-8 (checked at 1e-7 against this simpler scale);
    // reduced accuracy (see SolverOptions): 1e-6 residuals, 1e-5 gap.
    const double tol_res = r.reduced_accuracy ? 1e-6 : 1e-7;
    const double tol_gap = r.reduced_accuracy ? 1e-5 : 1e-7;
    const double scale = 1.0 + std::max(problem.b.size() ? problem.b.lpNorm<Eigen::Infinity>() : 0.0,
                                        problem.h.lpNorm<Eigen::Infinity>());
    EXPECT_LE((problem.G * r.x + r.s - problem.h).lpNorm<Eigen::Infinity>(), tol_res * scale) << seed;
    if (problem.b.size() > 0) {
      EXPECT_LE((problem.A * r.x - problem.b).lpNorm<Eigen::Infinity>(), tol_res * scale) << seed;
    }
    const Eigen::VectorXd dual = problem.c + problem.A.transpose() * r.y + problem.G.transpose() * r.z;
    EXPECT_LE(dual.lpNorm<Eigen::Infinity>(), tol_res * (1.0 + problem.c.lpNorm<Eigen::Infinity>())) << seed;
    // Weak duality: c'x - (-b'y - h'z) = s'z up to residuals; both small certify optimality of x.
    const double objective_scale = std::max(1.0, std::abs(r.primal_objective));
    EXPECT_LE(std::abs(r.primal_objective - r.dual_objective), tol_gap * objective_scale) << seed;
    EXPECT_LE(r.s.dot(r.z), tol_gap * objective_scale) << seed;
    EXPECT_LE(r.iterations, 40) << seed;
  }
  // Known weakness: a few of these end one step short of the 1e-8 tolerances (the last Newton
  // directions lose accuracy) and are accepted with reduced accuracy. Currently 3 of 180, all with the
  // augmented method forced (it was 5 before the reduced method learnt to hand over to the augmented
  // one when its direction is spoiled; seed 15 ended at a gap of 3e-6 that way).
  EXPECT_LE(reduced, 6);
  // The reduced method is defined on the problems whose G has at least as many rows as columns (48 of
  // the 180 solves with these seeds, by both the automatic choice and forcing): the check above must
  // really cover it.
  EXPECT_GE(reduced_kkt, 40);
}

// A large random SOCP (10,000 variables, 25,000 cone rows; the benchmark's BM_RandomSocp/10000). Near
// the optimum its scaling spans ~20 orders of magnitude and the LDL' of the augmented system broke
// down one iteration before the tolerances (3,000 pivots replaced, a non-finite direction): the solve
// ended with reduced accuracy (relative gap 1.4e-8). The solver now raises the static regularization
// and refactors, and the strict tolerances are met. Certified from the returned vectors as above.
TEST(RandomProblemTest, LargePathSocpReachesFullAccuracy) {
  const Problem problem = timeopt::test_support::RandomPathSocp(10000, 2);
  Solver solver;
  const Result r = solver.Solve(problem);
  ASSERT_EQ(r.status, Status::kOptimal) << r.BriefReport();
  EXPECT_FALSE(r.reduced_accuracy) << r.BriefReport();
  ExpectInCone(r.s, problem.cones, 1e-12);
  ExpectInCone(r.z, problem.cones, 1e-12);
  // The stopping test is 1e-8 relative in the solver's own scaling; 1e-7 against these simpler
  // scales leaves room for the difference of scales, not for a lost digit of the optimum.
  const double scale = 1.0 + std::max(problem.b.lpNorm<Eigen::Infinity>(), problem.h.lpNorm<Eigen::Infinity>());
  EXPECT_LE((problem.G * r.x + r.s - problem.h).lpNorm<Eigen::Infinity>(), 1e-7 * scale);
  EXPECT_LE((problem.A * r.x - problem.b).lpNorm<Eigen::Infinity>(), 1e-7 * scale);
  const Eigen::VectorXd dual = problem.c + problem.A.transpose() * r.y + problem.G.transpose() * r.z;
  EXPECT_LE(dual.lpNorm<Eigen::Infinity>(), 1e-7 * (1.0 + problem.c.lpNorm<Eigen::Infinity>()));
  const double objective_scale = std::max(1.0, std::abs(r.primal_objective));
  EXPECT_LE(std::abs(r.primal_objective - r.dual_objective), 1e-8 * objective_scale);
  EXPECT_LE(r.s.dot(r.z), 1e-8 * objective_scale);
}

// ------------------------------------------------------------------------------------------------
// Re-solving with the same pattern and new numbers.

// A random sparse problem of fixed pattern whose numbers depend on `seed` (the pattern does not):
// min c'x s.t. ||x - x0||_inf-box ... i.e. l <= x <= u, a few SOCs on pairs and one rotated cone.
Problem PatternProblem(unsigned seed) {
  std::srand(seed);
  auto r = [] { return 0.5 + static_cast<double>(std::rand()) / RAND_MAX; };
  const int n = 12;
  ProblemBuilder b;
  b.AddVariables(n + 1);
  for (int i = 0; i < n; ++i) {
    b.SetObjectiveCoefficient(i, r() - 1.0);
    b.AddLessEqual({{i, r()}}, 2.0 * r());
    b.AddNonnegative(AffineExpr{{{i, r()}}, 3.0 * r()});
  }
  b.AddEquality({{0, r()}, {3, r()}, {5, -r()}}, r());
  for (int i = 0; i + 2 < n; i += 3) b.AddSecondOrderCone({Const(2.0 * r()), Var(i, r()), Var(i + 1, r())});
  std::vector<AffineExpr> rows = {Var(n), Const(0.5)};
  for (int i = 0; i < n; ++i) rows.push_back(Var(i, r()));
  b.AddRotatedCone(rows);  // x_n >= ||D x||^2
  b.SetObjectiveCoefficient(n, 0.1 * r());
  return b.Build();
}

TEST(ResolveTest, SamePatternGivesTheSameAsAFreshSolver) {
  Solver reused;
  const Result first = reused.Solve(PatternProblem(1));
  ASSERT_EQ(first.status, Status::kOptimal) << first.BriefReport();
  EXPECT_FALSE(first.reused_symbolic);
  const Problem second_problem = PatternProblem(2);
  const Result second = reused.Solve(second_problem);
  EXPECT_TRUE(second.reused_symbolic);
  Solver fresh;
  const Result reference = fresh.Solve(second_problem);
  ASSERT_EQ(reference.status, Status::kOptimal) << reference.BriefReport();
  EXPECT_EQ(second.status, reference.status);
  EXPECT_EQ(second.iterations, reference.iterations);
  // Same arithmetic in the same order: identical to the last bit, checked with a tiny margin.
  EXPECT_LT((second.x - reference.x).lpNorm<Eigen::Infinity>(), 1e-14);
  EXPECT_NEAR(second.primal_objective, reference.primal_objective, 1e-14);
  EXPECT_NE(first.primal_objective, second.primal_objective);

  // A different pattern triggers a new analysis.
  const Result other = reused.Solve(Examples()[3].make());
  EXPECT_FALSE(other.reused_symbolic);
  EXPECT_EQ(other.status, Status::kOptimal);
}

// max_factor_bytes counts the sparse factor's fill-in before allocating it: a budget below the
// factor the solve reports (its non-zeros x kFactorBytesPerNonzero) is refused with a message
// naming the factor, one at it solves, and a refused solver solves again once the budget allows.
TEST(KktMethodTest, TheSparseFactorIsRefusedAboveItsBudgetBeforeItIsBuilt) {
  const Problem problem = PathProblem(200);
  Solver::Options options;
  options.kkt_method = KktMethod::kAugmentedSparse;
  const Result free_solve = Solver(options).Solve(problem);
  ASSERT_EQ(free_solve.status, Status::kOptimal) << free_solve.BriefReport();
  const std::int64_t needed = free_solve.factor_nonzeros * SolverOptions::kFactorBytesPerNonzero;
  options.max_factor_bytes = needed - 1;
  Solver tight(options);
  try {
    tight.Solve(problem);
    ADD_FAILURE() << "a factor of " << needed << " bytes solved under a budget of " << needed - 1;
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(),
                ::testing::HasSubstr(std::to_string(free_solve.factor_nonzeros) + " non-zeros with its fill-in"));
  }
  options.max_factor_bytes = needed;
  tight.set_options(options);
  const Result at_budget = tight.Solve(problem);
  ASSERT_EQ(at_budget.status, Status::kOptimal) << at_budget.BriefReport();
  EXPECT_EQ(at_budget.primal_objective, free_solve.primal_objective);
  options.max_factor_bytes = -1;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_THAT(why, ::testing::HasSubstr("max_factor_bytes"));
}

}  // namespace
}  // namespace timeopt::conic
