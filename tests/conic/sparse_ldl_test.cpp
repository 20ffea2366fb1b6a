#include "conic/sparse_ldl.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

namespace timeopt::conic {
namespace {

// A random sparse quasi-definite matrix [[H, B'], [B, -E]] (H, E positive definite diagonal-dominant)
// under a random symmetric permutation: the LDL' without pivoting must exist and solve it.
TEST(SparseLdlTest, SolvesRandomQuasiDefiniteSystems) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int n1 = 5 + trial, n2 = 3 + trial / 2, n = n1 + n2;
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i) K(i, i) = i < n1 ? 4.0 : -4.0;
    for (int e = 0; e < 2 * n; ++e) {
      const int i = static_cast<int>(rng() % n), j = static_cast<int>(rng() % n);
      if (i == j) continue;
      const bool same_block = (i < n1) == (j < n1);
      const double v = same_block ? 0.3 * uni(rng) : uni(rng);
      K(i, j) = K(j, i) = v;
    }
    std::vector<int> perm(n);
    for (int i = 0; i < n; ++i) perm[i] = i;
    std::shuffle(perm.begin(), perm.end(), rng);
    Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, n);  // permuted matrix Kp(a, b) = K(perm a, perm b)
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) P(a, b) = K(perm[a], perm[b]);
    }
    std::vector<int> col_ptr(n + 1, 0), row_idx;
    std::vector<double> values;
    std::vector<signed char> signs(n);
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < j; ++i) {
        if (P(i, j) != 0.0) {
          row_idx.push_back(i);
          values.push_back(P(i, j));
        }
      }
      row_idx.push_back(j);
      values.push_back(P(j, j));
      col_ptr[j + 1] = static_cast<int>(row_idx.size());
      signs[j] = perm[j] < n1 ? 1 : -1;
    }
    SparseLdl ldl;
    ldl.Analyze(n, col_ptr, row_idx);
    EXPECT_EQ(ldl.Factor(values.data(), signs.data(), 1e-13, 1e-7), 0);
    Eigen::VectorXd rhs = Eigen::VectorXd::NullaryExpr(n, [&] { return uni(rng); });
    Eigen::VectorXd x = rhs;
    ldl.Solve(x.data());
    // Residual relative to the data (entries O(1), diagonal 4): a backward-stable solve gives ~1e-15.
    EXPECT_LT((P * x - rhs).lpNorm<Eigen::Infinity>(), 1e-12) << "trial " << trial;
    // Refactor with new numbers on the same pattern.
    for (double& v : values) v *= 2.0;
    ldl.Factor(values.data(), signs.data(), 1e-13, 1e-7);
    x = rhs;
    ldl.Solve(x.data());
    EXPECT_LT((2.0 * P * x - rhs).lpNorm<Eigen::Infinity>(), 1e-12) << "trial " << trial;
  }
}

TEST(SparseLdlTest, ReplacesPivotsOfTheWrongSign) {
  // [[1, 1], [1, 1]] is singular: the second pivot is 0 and is replaced by +1e-7 (expected sign +1).
  std::vector<int> col_ptr = {0, 1, 3}, row_idx = {0, 0, 1};
  std::vector<double> values = {1.0, 1.0, 1.0};
  std::vector<signed char> signs = {1, 1};
  SparseLdl ldl;
  ldl.Analyze(2, col_ptr, row_idx);
  EXPECT_EQ(ldl.Factor(values.data(), signs.data(), 1e-13, 1e-7), 1);
  double x[2] = {1.0, 1.0};  // consistent right-hand side: any solution of x0 + x1 = 1 is fine
  ldl.Solve(x);
  EXPECT_TRUE(std::isfinite(x[0]) && std::isfinite(x[1]));
  EXPECT_NEAR(x[0] + x[1], 1.0, 1e-9);  // the regularized pivot leaves the consistent part exact
}

// The factor's non-zeros counted without building it equal those of Analyze and those of a dense
// symbolic elimination (brute force: eliminating pivot k fills (i, j) wherever (i, k) and (j, k)
// are non-zero), on random patterns from nearly diagonal to heavily filled.
TEST(SparseLdlTest, CountsTheFactorsNonZerosBeforeBuildingIt) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const int n = 2 + trial;
    std::vector<std::vector<char>> nonzero(n, std::vector<char>(n, 0));
    for (int e = 0; e < (trial % 5 + 1) * n / 2; ++e) {
      const int i = static_cast<int>(rng() % n), j = static_cast<int>(rng() % n);
      nonzero[std::min(i, j)][std::max(i, j)] = 1;
    }
    std::vector<int> col_ptr(n + 1, 0), row_idx;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < j; ++i) {
        if (nonzero[i][j]) row_idx.push_back(i);
      }
      row_idx.push_back(j);
      col_ptr[j + 1] = static_cast<int>(row_idx.size());
    }
    // Brute force: a dense symmetric pattern, eliminated pivot by pivot.
    std::vector<std::vector<char>> filled(n, std::vector<char>(n, 0));
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) filled[i][j] = filled[j][i] = nonzero[i][j];
    }
    long long expected = 0;
    for (int k = 0; k < n; ++k) {
      for (int i = k + 1; i < n; ++i) {
        if (!filled[i][k]) continue;
        ++expected;
        for (int j = k + 1; j < n; ++j) {
          if (filled[j][k]) filled[i][j] = filled[j][i] = 1;
        }
      }
    }
    SparseLdl ldl;
    ldl.Analyze(n, col_ptr, row_idx);
    EXPECT_EQ(SparseLdl::CountFactorNonzeros(n, col_ptr, row_idx), expected) << "trial " << trial;
    EXPECT_EQ(ldl.num_factor_nonzeros(), expected) << "trial " << trial;
  }
}

}  // namespace
}  // namespace timeopt::conic
