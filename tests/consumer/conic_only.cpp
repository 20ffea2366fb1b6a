// Uses only the installed conic solver (timeopt::conic, Eigen and nothing else): minimizes t
// subject to t >= ||(3, 4)||, whose optimum is exactly 5.
#include <cmath>
#include <cstdio>

#include <timeopt/conic/problem_builder.h>
#include <timeopt/conic/solver.h>

int main() {
  using namespace timeopt::conic;
  ProblemBuilder builder;
  const int t = builder.AddVariables(1);
  builder.SetObjectiveCoefficient(t, 1.0);
  builder.AddSecondOrderCone({AffineExpr{{{t, 1.0}}, 0.0}, AffineExpr{{}, 3.0}, AffineExpr{{}, 4.0}});
  Solver solver;
  const Result result = solver.Solve(builder.Build());
  std::printf("conic-only consumer: %s, t = %.12g\n", ToString(result.status), result.x[t]);
  // The solver's default relative gap tolerance is 1e-8; 1e-6 leaves room for rounding.
  return result.is_success() && std::abs(result.x[t] - 5.0) < 1e-6 ? 0 : 1;
}
