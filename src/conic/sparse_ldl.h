#pragma once
// Sparse signed LDL' factorization with a fixed pattern, for quasi-definite matrices.
//
// The matrix is given as its upper triangle (diagonal included, every diagonal entry present) in
// compressed column form, already in elimination order (the caller applies any fill-reducing
// permutation). Analyze() computes the elimination tree, the non-zero pattern of every row of L and the
// slot of every entry of L once; Factor() then runs an up-looking LDL' without pivoting into the
// preallocated arrays, with no allocation, so repeated factorizations of matrices with the same pattern
// cost only the numeric work. Quasi-definite matrices (positive definite block, negative definite block)
// have such a factorization for every symmetric ordering (Vanderbei 1995); a pivot whose sign differs
// from the expected sign, or whose magnitude is below a threshold, is replaced by a small value of the
// expected sign (dynamic regularization) and counted.

#include <vector>

namespace timeopt::conic {

class SparseLdl {
 public:
  /// Symbolic analysis. col_ptr has n+1 entries, row_idx the row of each stored entry; in every column
  /// the rows are < = the column, sorted increasingly, and the last one is the diagonal.
  void Analyze(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx);
  /// The non-zeros of L strictly below the diagonal that Analyze would give the same pattern
  /// (the elimination tree walked row by row, nothing stored: O(n) memory, O(nnz(L)) time), so
  /// that a caller can refuse a factor before allocating it.
  static long long CountFactorNonzeros(int n, const std::vector<int>& col_ptr, const std::vector<int>& row_idx);

  /// Numeric factorization of the matrix whose values (in the order of row_idx) are `values`.
  /// `signs[k]` (+1 or -1) is the expected sign of pivot k. Returns the number of regularized pivots.
  int Factor(const double* values, const signed char* signs, double threshold, double replacement);

  /// Solves L D L' x = rhs in place (x holds rhs on entry).
  void Solve(double* x) const;
  /// Solves two systems in one sweep over the factor (x1, x2 hold the right-hand sides on entry).
  void Solve2(double* x1, double* x2) const;

  int size() const { return n_; }
  /// Pivots (in elimination order) replaced by the last Factor(): the first num_regularized() entries.
  const std::vector<int>& regularized_pivots() const { return regularized_; }
  int num_regularized() const { return num_regularized_; }
  /// Non-zeros of L strictly below the diagonal.
  long long num_factor_nonzeros() const { return static_cast<long long>(l_row_.size()); }
  /// Multiply-adds of one factorization (a measure of its cost).
  long long num_factor_flops() const { return flops_; }

 private:
  int n_ = 0;
  std::vector<int> a_col_ptr_;
  std::vector<int> a_row_;
  std::vector<int> l_col_ptr_;  // column pointers of L (strictly lower part)
  std::vector<int> l_row_;      // row index of each entry of L
  std::vector<double> l_val_;
  std::vector<double> d_;
  std::vector<double> inv_d_;
  std::vector<double> l_row_val_;  // values of L in the order of row_col_ (row-wise copy)
  std::vector<int> row_ptr_;       // row k of L: pattern row_col_[row_ptr_[k] .. row_ptr_[k+1])
  std::vector<int> row_col_;       // columns i < k with L(k, i) != 0, increasing (a topological order)
  std::vector<int> row_slot_;      // slot of L(k, i) in l_val_
  mutable std::vector<double> work_;
  std::vector<int> regularized_;
  int num_regularized_ = 0;
  long long flops_ = 0;
};

}  // namespace timeopt::conic
