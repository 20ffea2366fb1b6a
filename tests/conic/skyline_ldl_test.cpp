#include "conic/skyline_ldl.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

namespace timeopt::conic {
namespace {

// Loads the lower triangle of a dense symmetric matrix into the skyline storage.
void Load(const Eigen::MatrixXd& K, SkylineLdl& ldl) {
  ldl.SetZero();
  for (int i = 0; i < K.rows(); ++i) {
    for (int j = ldl.first(i); j <= i; ++j) ldl.values()[ldl.Slot(i, j)] = K(i, j);
  }
}

// A random quasi-definite matrix (positive definite block, negative definite block, interleaved as an
// interior-point KKT system is after a bandwidth ordering) with a variable band, plus full-width border
// rows at the end like the ones a low-rank term adds: the factorization without pivoting must exist,
// stay inside the profile, and solve the system to rounding, compared with the dense matrix.
TEST(SkylineLdlTest, SolvesBandedQuasiDefiniteSystemsWithABorder) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int band = 1 + trial % 6, core = 30 + 7 * trial, border = trial % 3, n = core + border;
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
    std::vector<int> first(n);
    std::vector<signed char> signs(n);
    for (int i = 0; i < core; ++i) {
      signs[i] = i % 4 == 3 ? -1 : 1;
      first[i] = std::max(0, i - 1 - static_cast<int>(rng() % band));
      K(i, i) = 4.0 * signs[i];
      for (int j = first[i]; j < i; ++j) {
        const bool same = signs[i] == signs[j];
        K(i, j) = K(j, i) = (same ? 0.3 : 1.0) * uni(rng);
      }
    }
    for (int i = core; i < n; ++i) {
      // Border rows: a positive one, then a negative one, each coupled to the whole core weakly.
      signs[i] = (i - core) % 2 == 0 ? 1 : -1;
      first[i] = 0;
      K(i, i) = 4.0 * signs[i] * core;
      for (int j = 0; j < i; ++j) K(i, j) = K(j, i) = uni(rng);
    }
    SkylineLdl ldl;
    ldl.Analyze(first);
    Load(K, ldl);
    EXPECT_EQ(ldl.Factor(signs.data(), 1e-13, 1e-7), 0) << "trial " << trial;
    const Eigen::VectorXd rhs = Eigen::VectorXd::NullaryExpr(n, [&] { return uni(rng); });
    Eigen::VectorXd x = rhs;
    ldl.Solve(x.data());
    // Entries O(1) against diagonals >= 4: a backward-stable solve leaves ~1e-15; 1e-11 allows the
    // border's larger entries.
    EXPECT_LT((K * x - rhs).lpNorm<Eigen::Infinity>(), 1e-11) << "trial " << trial;
    // Two right-hand sides in one sweep give the same answers as two single solves.
    Eigen::VectorXd x1 = rhs, x2 = 2.0 * rhs + Eigen::VectorXd::Ones(n);
    ldl.Solve2(x1.data(), x2.data());
    Eigen::VectorXd y2 = 2.0 * rhs + Eigen::VectorXd::Ones(n);
    ldl.Solve(y2.data());
    EXPECT_LT((x1 - x).lpNorm<Eigen::Infinity>(), 1e-14);
    EXPECT_LT((x2 - y2).lpNorm<Eigen::Infinity>(), 1e-14);
  }
}

TEST(SkylineLdlTest, StoredProfileAndCost) {
  SkylineLdl ldl;
  ldl.Analyze({0, 0, 1, 1, 0});
  // Row widths 1, 2, 2, 3, 5.
  EXPECT_EQ(ldl.num_stored(), 13);
  EXPECT_EQ(ldl.Slot(3, 1), 5 + 0);
  EXPECT_EQ(ldl.Slot(4, 4), 12);
}

TEST(SkylineLdlTest, ReplacesPivotsOfTheWrongSign) {
  // [[1, 1], [1, 1]] is singular: the second pivot is 0 and is replaced by +1e-7 (expected sign +1);
  // then the solve is finite.
  SkylineLdl ldl;
  ldl.Analyze({0, 0});
  Eigen::MatrixXd K(2, 2);
  K << 1.0, 1.0, 1.0, 1.0;
  Load(K, ldl);
  const signed char signs[2] = {1, 1};
  EXPECT_EQ(ldl.Factor(signs, 1e-13, 1e-7), 1);
  double x[2] = {1.0, 2.0};
  ldl.Solve(x);
  EXPECT_TRUE(std::isfinite(x[0]) && std::isfinite(x[1]));
  // A negative pivot where a positive one is expected is replaced too.
  K << -1.0, 0.0, 0.0, 1.0;
  Load(K, ldl);
  EXPECT_EQ(ldl.Factor(signs, 1e-13, 1e-7), 1);
}

TEST(SkylineLdlTest, RejectsAFirstColumnBeyondTheDiagonal) {
  SkylineLdl ldl;
  EXPECT_THROW(ldl.Analyze({0, 2}), std::invalid_argument);
  EXPECT_THROW(ldl.Analyze({-1}), std::invalid_argument);
}

}  // namespace
}  // namespace timeopt::conic
