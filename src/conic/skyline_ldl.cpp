#include "skyline_ldl.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace timeopt::conic {

void SkylineLdl::Analyze(const std::vector<int>& first) {
  n_ = static_cast<int>(first.size());
  first_ = first;
  row_ptr_.assign(n_ + 1, 0);
  flops_ = 0;
  for (int i = 0; i < n_; ++i) {
    if (first[i] < 0 || first[i] > i) {
      throw std::invalid_argument("SkylineLdl::Analyze: first column of row " + std::to_string(i) + " is " +
                                  std::to_string(first[i]) + ", expected 0.." + std::to_string(i));
    }
    row_ptr_[i + 1] = row_ptr_[i] + (i - first[i] + 1);
    // Row i: for every stored j < i, a dot product over the overlap with row j.
    for (int j = first[i]; j < i; ++j) flops_ += j - std::max(first[i], first[j]) + 1;
  }
  val_.assign(row_ptr_[n_], 0.0);
  inv_d_.assign(n_, 0.0);
}

void SkylineLdl::SetZero() { std::fill(val_.begin(), val_.end(), 0.0); }

int SkylineLdl::Factor(const signed char* signs, double threshold, double replacement) {
  int regularized = 0;
  double* v = val_.data();
  for (int i = 0; i < n_; ++i) {
    const int fi = first_[i];
    double* row = v + row_ptr_[i] - fi;  // row[j] is entry (i, j)
    // Crout order: row[j] becomes L(i, j) D(j) = a(i, j) - sum_{k < j} L(i, k) D(k) L(j, k).
    for (int j = fi; j < i; ++j) {
      const int lo = std::max(fi, first_[j]);
      const double* lj = v + row_ptr_[j] - first_[j];
      double sum = 0.0;
      for (int k = lo; k < j; ++k) sum += row[k] * lj[k];
      row[j] -= sum;
    }
    double d = row[i];
    for (int j = fi; j < i; ++j) {
      const double w = row[j];
      const double l = w * inv_d_[j];
      row[j] = l;
      d -= l * w;
    }
    if (!(signs[i] * d > threshold)) {  // also catches NaN
      d = signs[i] * replacement;
      ++regularized;
    }
    row[i] = d;
    inv_d_[i] = 1.0 / d;
  }
  return regularized;
}

void SkylineLdl::Solve(double* x) const {
  const double* v = val_.data();
  for (int i = 0; i < n_; ++i) {
    const int fi = first_[i];
    const double* row = v + row_ptr_[i] - fi;
    double sum = 0.0;
    for (int k = fi; k < i; ++k) sum += row[k] * x[k];
    x[i] -= sum;
  }
  for (int i = 0; i < n_; ++i) x[i] *= inv_d_[i];
  for (int i = n_ - 1; i >= 0; --i) {
    const int fi = first_[i];
    const double* row = v + row_ptr_[i] - fi;
    const double xi = x[i];
    for (int k = fi; k < i; ++k) x[k] -= row[k] * xi;
  }
}

void SkylineLdl::Solve2(double* x1, double* x2) const {
  const double* v = val_.data();
  for (int i = 0; i < n_; ++i) {
    const int fi = first_[i];
    const double* row = v + row_ptr_[i] - fi;
    double sum1 = 0.0, sum2 = 0.0;
    for (int k = fi; k < i; ++k) {
      sum1 += row[k] * x1[k];
      sum2 += row[k] * x2[k];
    }
    x1[i] -= sum1;
    x2[i] -= sum2;
  }
  for (int i = 0; i < n_; ++i) {
    x1[i] *= inv_d_[i];
    x2[i] *= inv_d_[i];
  }
  for (int i = n_ - 1; i >= 0; --i) {
    const int fi = first_[i];
    const double* row = v + row_ptr_[i] - fi;
    const double a = x1[i], b = x2[i];
    for (int k = fi; k < i; ++k) {
      x1[k] -= row[k] * a;
      x2[k] -= row[k] * b;
    }
  }
}

}  // namespace timeopt::conic
