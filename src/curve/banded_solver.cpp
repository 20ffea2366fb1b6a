#include "banded_solver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace timeopt::internal {

BandedSystem::BandedSystem(int n, int kl, int ku)
    : n_(n),
      kl_(kl),
      ku_(ku),
      width_(2 * kl + ku + 1),
      storage_(static_cast<size_t>(n) * static_cast<size_t>(2 * kl + ku + 1), 0.0) {
  if (n < 1 || kl < 0 || ku < 0) throw std::logic_error("BandedSystem: bad dimensions");
}

double& BandedSystem::At(std::vector<double>& storage, int i, int j) const {
  const int offset = j - i + kl_;
  if (i < 0 || i >= n_ || j < 0 || j >= n_ || offset < 0 || offset >= width_) {
    throw std::logic_error("BandedSystem: entry (" + std::to_string(i) + ", " + std::to_string(j) +
                           ") outside the band");
  }
  return storage[static_cast<size_t>(i) * static_cast<size_t>(width_) + static_cast<size_t>(offset)];
}

void BandedSystem::Add(int i, int j, double value) {
  if (j - i > ku_) throw std::logic_error("BandedSystem::Add: entry above the band");
  At(storage_, i, j) += value;
}

Eigen::MatrixXd BandedSystem::Solve(const Eigen::MatrixXd& rhs, double singular_tolerance) const {
  if (rhs.rows() != n_) throw std::logic_error("BandedSystem::Solve: rhs has the wrong size");
  std::vector<double> a = storage_;
  Eigen::MatrixXd x = rhs;
  double scale = 0.0;
  for (double v : a) scale = std::max(scale, std::abs(v));
  const double tiny = singular_tolerance * std::max(scale, 1e-300);

  for (int k = 0; k < n_; ++k) {
    const int last_row = std::min(n_ - 1, k + kl_);
    const int last_col = std::min(n_ - 1, k + kl_ + ku_);
    int pivot = k;
    for (int i = k + 1; i <= last_row; ++i) {
      if (std::abs(At(a, i, k)) > std::abs(At(a, pivot, k))) pivot = i;
    }
    if (std::abs(At(a, pivot, k)) <= tiny) {
      throw std::runtime_error("banded solve: the system is singular at unknown " + std::to_string(k));
    }
    if (pivot != k) {
      for (int j = k; j <= last_col; ++j) std::swap(At(a, k, j), At(a, pivot, j));
      x.row(k).swap(x.row(pivot));
    }
    const double diag = At(a, k, k);
    for (int i = k + 1; i <= last_row; ++i) {
      const double factor = At(a, i, k) / diag;
      if (factor == 0.0) continue;
      At(a, i, k) = 0.0;
      for (int j = k + 1; j <= last_col; ++j) At(a, i, j) -= factor * At(a, k, j);
      x.row(i) -= factor * x.row(k);
    }
  }
  for (int k = n_ - 1; k >= 0; --k) {
    const int last_col = std::min(n_ - 1, k + kl_ + ku_);
    for (int j = k + 1; j <= last_col; ++j) x.row(k) -= At(a, k, j) * x.row(j);
    x.row(k) /= At(a, k, k);
  }
  return x;
}

}  // namespace timeopt::internal
