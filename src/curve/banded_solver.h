#pragma once

// Gaussian elimination with partial pivoting for a banded system A X = B, A of size n x n with kl
// sub-diagonals and ku super-diagonals. Storage and work are O(n (2 kl + ku + 1)), so fitting a
// curve through m waypoints costs time linear in m. Private to the library.

#include <vector>

#include <Eigen/Core>

namespace timeopt::internal {

class BandedSystem {
 public:
  BandedSystem(int n, int kl, int ku);

  int size() const { return n_; }
  // Adds `value` to A(i, j); |i - j| must lie inside the band (throws std::logic_error otherwise).
  void Add(int i, int j, double value);

  // Solves A X = B in place of a copy of A; throws std::runtime_error when A is singular (a pivot
  // below `singular_tolerance` times the largest entry of A).
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& rhs, double singular_tolerance = 1e-13) const;

 private:
  double& At(std::vector<double>& storage, int i, int j) const;
  int n_, kl_, ku_, width_;
  std::vector<double> storage_;  // row i holds columns [i - kl, i + kl + ku]
};

}  // namespace timeopt::internal
