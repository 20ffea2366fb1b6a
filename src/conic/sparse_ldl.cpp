#include "sparse_ldl.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace timeopt::conic {

namespace {

// The elimination tree of the upper triangle (col_ptr, row_idx): parent[i] = -1 at a root.
std::vector<int> EliminationTree(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx) {
  std::vector<int> parent(n, -1), ancestor(n, -1);
  for (int k = 0; k < n; ++k) {
    for (int p = col_ptr[k]; p < col_ptr[k + 1]; ++p) {
      int i = row_idx[p];
      while (i != -1 && i < k) {
        const int next = ancestor[i];
        ancestor[i] = k;
        if (next == -1) {
          parent[i] = k;
          break;
        }
        i = next;
      }
    }
  }
  return parent;
}

}  // namespace

long long SparseLdl::CountFactorNonzeros(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx) {
  if (n < 0 || static_cast<int>(col_ptr.size()) != n + 1) {
    throw std::invalid_argument("SparseLdl::CountFactorNonzeros: col_ptr has " + std::to_string(col_ptr.size()) +
                                " entries, expected " + std::to_string(n + 1));
  }
  const std::vector<int> parent = EliminationTree(n, col_ptr, row_idx);
  std::vector<int> mark(n, -1);
  long long count = 0;
  for (int k = 0; k < n; ++k) {
    mark[k] = k;
    for (int p = col_ptr[k]; p < col_ptr[k + 1]; ++p) {
      for (int i = row_idx[p]; i != -1 && i < k && mark[i] != k; i = parent[i]) {
        mark[i] = k;
        ++count;
      }
    }
  }
  return count;
}

void SparseLdl::Analyze(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx) {
  if (n < 0 || static_cast<int>(col_ptr.size()) != n + 1) {
    throw std::invalid_argument("SparseLdl::Analyze: col_ptr has " + std::to_string(col_ptr.size()) +
                                " entries, expected " + std::to_string(n + 1));
  }
  n_ = n;
  a_col_ptr_ = col_ptr;
  a_row_ = row_idx;

  // Elimination tree (with path-compressed ancestors) and the pattern of every row of L: row k of L
  // holds the nodes met when walking up the tree from each i < k in column k of the upper triangle,
  // stopping at nodes already visited for k.
  const std::vector<int> parent = EliminationTree(n, col_ptr, row_idx);
  std::vector<int> mark(n, -1);
  row_ptr_.assign(n + 1, 0);
  row_col_.clear();
  std::vector<int> col_count(n, 0);
  for (int k = 0; k < n; ++k) {
    mark[k] = k;
    const std::size_t start = row_col_.size();
    for (int p = col_ptr[k]; p < col_ptr[k + 1]; ++p) {
      for (int i = row_idx[p]; i != -1 && i < k && mark[i] != k; i = parent[i]) {
        mark[i] = k;
        row_col_.push_back(i);
        ++col_count[i];
      }
    }
    std::sort(row_col_.begin() + static_cast<std::ptrdiff_t>(start), row_col_.end());
    row_ptr_[k + 1] = static_cast<int>(row_col_.size());
  }
  l_col_ptr_.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) l_col_ptr_[i + 1] = l_col_ptr_[i] + col_count[i];
  l_row_.assign(row_col_.size(), 0);
  l_val_.assign(row_col_.size(), 0.0);
  row_slot_.assign(row_col_.size(), 0);
  std::vector<int> fill(l_col_ptr_.begin(), l_col_ptr_.end() - 1);
  flops_ = 0;
  for (int k = 0; k < n; ++k) {
    for (int q = row_ptr_[k]; q < row_ptr_[k + 1]; ++q) {
      const int i = row_col_[q];
      const int slot = fill[i]++;
      l_row_[slot] = k;
      row_slot_[q] = slot;
      flops_ += slot - l_col_ptr_[i] + 1;
    }
  }
  d_.assign(n, 0.0);
  inv_d_.assign(n, 0.0);
  l_row_val_.assign(row_col_.size(), 0.0);
  work_.assign(n, 0.0);
  regularized_.assign(n, 0);
  num_regularized_ = 0;
}

int SparseLdl::Factor(const double* values, const signed char* signs, double threshold, double replacement) {
  int regularized = 0;
  double* work = work_.data();
  double* lx = l_val_.data();
  const int* li = l_row_.data();
  double* rv = l_row_val_.data();  // L in row order (row_col_), written as it is computed
  for (int k = 0; k < n_; ++k) {
    const int a_end = a_col_ptr_[k + 1];
    for (int p = a_col_ptr_[k]; p < a_end; ++p) work[a_row_[p]] = values[p];
    double d = work[k];
    work[k] = 0.0;
    const int q_end = row_ptr_[k + 1];
    for (int q = row_ptr_[k]; q < q_end; ++q) {
      const int i = row_col_[q];
      const double yi = work[i];
      work[i] = 0.0;
      const int slot = row_slot_[q];
      for (int p = l_col_ptr_[i]; p < slot; ++p) work[li[p]] -= lx[p] * yi;
      const double lki = yi / d_[i];
      lx[slot] = lki;
      rv[q] = lki;  // row-wise copy for the forward solve
      d -= lki * yi;
    }
    if (!(signs[k] * d > threshold)) {  // also catches NaN
      d = signs[k] * replacement;
      regularized_[regularized++] = k;
    }
    d_[k] = d;
    inv_d_[k] = 1.0 / d;
  }
  num_regularized_ = regularized;
  return regularized;
}

void SparseLdl::Solve(double* x) const {
  // Forward by rows of L (a gather per row, from the row-wise copy), backward by columns of L (a
  // gather per column): no scattered writes.
  const double* lx = l_val_.data();
  const int* li = l_row_.data();
  const double* rv = l_row_val_.data();
  const int* rc = row_col_.data();
  for (int k = 0; k < n_; ++k) {
    double sum = x[k];
    for (int q = row_ptr_[k]; q < row_ptr_[k + 1]; ++q) sum -= rv[q] * x[rc[q]];
    x[k] = sum;
  }
  for (int i = n_ - 1; i >= 0; --i) {
    double xi = x[i] * inv_d_[i];
    for (int p = l_col_ptr_[i]; p < l_col_ptr_[i + 1]; ++p) xi -= lx[p] * x[li[p]];
    x[i] = xi;
  }
}

void SparseLdl::Solve2(double* x1, double* x2) const {
  const double* lx = l_val_.data();
  const int* li = l_row_.data();
  const double* rv = l_row_val_.data();
  const int* rc = row_col_.data();
  for (int k = 0; k < n_; ++k) {
    double sum1 = x1[k], sum2 = x2[k];
    for (int q = row_ptr_[k]; q < row_ptr_[k + 1]; ++q) {
      const int c = rc[q];
      sum1 -= rv[q] * x1[c];
      sum2 -= rv[q] * x2[c];
    }
    x1[k] = sum1;
    x2[k] = sum2;
  }
  for (int i = n_ - 1; i >= 0; --i) {
    double xi1 = x1[i] * inv_d_[i], xi2 = x2[i] * inv_d_[i];
    for (int p = l_col_ptr_[i]; p < l_col_ptr_[i + 1]; ++p) {
      const int r = li[p];
      xi1 -= lx[p] * x1[r];
      xi2 -= lx[p] * x2[r];
    }
    x1[i] = xi1;
    x2[i] = xi2;
  }
}

}  // namespace timeopt::conic
