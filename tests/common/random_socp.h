// A random sparse SOCP generator shared by the conic tests and benchmark (one definition, so that the
// test exercises exactly the problems the benchmark measures).
#ifndef TIMEOPT_TESTS_COMMON_RANDOM_SOCP_H_
#define TIMEOPT_TESTS_COMMON_RANDOM_SOCP_H_

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Sparse>

#include "timeopt/conic/problem.h"

namespace timeopt::test_support {

// A random sparse SOCP with n variables, strictly feasible primal and dual (so it has an optimum):
// n/4 equalities with 3 non-zeros each, n orthant rows and n/2 three-dimensional cones (3n/2 rows)
// with 2-3 non-zeros per row. Column indices are drawn near the row's position along the variables
// (a window of 30), as in problems discretized along a path; purely random patterns have fill that
// grows faster than linearly under any ordering.
inline timeopt::conic::Problem RandomPathSocp(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::uniform_int_distribution<int> window(-15, 15);
  auto near = [&](int center) { return std::min(n - 1, std::max(0, center + window(rng))); };
  const int p = n / 4, num_lin = n, num_soc = n / 2, m = num_lin + 3 * num_soc;
  std::vector<Eigen::Triplet<double>> ta, tg;
  for (int i = 0; i < p; ++i) {
    const int center = static_cast<int>(static_cast<long long>(i) * n / p);
    for (int q = 0; q < 3; ++q) ta.emplace_back(i, near(center), uni(rng));
  }
  for (int i = 0; i < m; ++i) {
    const int center = static_cast<int>(static_cast<long long>(i) * n / m);
    const int nz = 2 + static_cast<int>(rng() % 2);
    for (int q = 0; q < nz; ++q) tg.emplace_back(i, near(center), uni(rng));
  }
  timeopt::conic::Problem problem;
  problem.A.resize(p, n);
  problem.A.setFromTriplets(ta.begin(), ta.end());
  problem.G.resize(m, n);
  problem.G.setFromTriplets(tg.begin(), tg.end());
  problem.cones.num_nonnegative = num_lin;
  problem.cones.soc_dims.assign(num_soc, 3);
  // Interior points s0, z0 of K, a point x0 and duals y0: h = G x0 + s0, b = A x0, c = -A'y0 - G'z0.
  Eigen::VectorXd x0 = Eigen::VectorXd::NullaryExpr(n, [&] { return uni(rng); });
  Eigen::VectorXd y0 = Eigen::VectorXd::NullaryExpr(p, [&] { return uni(rng); });
  Eigen::VectorXd s0(m), z0(m);
  for (int i = 0; i < num_lin; ++i) {
    s0[i] = 1.0 + uni(rng);
    z0[i] = 1.0 + uni(rng);
  }
  for (int k = 0; k < num_soc; ++k) {
    const int r = num_lin + 3 * k;
    for (Eigen::VectorXd* v : {&s0, &z0}) {
      (*v)[r + 1] = uni(rng);
      (*v)[r + 2] = uni(rng);
      (*v)[r] = std::hypot((*v)[r + 1], (*v)[r + 2]) + 0.5 + 0.5 * std::abs(uni(rng));
    }
  }
  problem.h = problem.G * x0 + s0;
  problem.b = problem.A * x0;
  problem.c = -(problem.A.transpose() * y0) - problem.G.transpose() * z0;
  return problem;
}

}  // namespace timeopt::test_support

#endif  // TIMEOPT_TESTS_COMMON_RANDOM_SOCP_H_
