#pragma once
// Signed LDL' factorization of a symmetric matrix stored by its skyline (variable-band profile).
//
// Row i of the lower triangle is stored densely from its first structural non-zero column first(i) to
// the diagonal. A factorization without pivoting creates no fill outside this profile, so the storage
// is fixed by Analyze() and Factor() only does arithmetic on contiguous memory: the right tool for
// matrices ordered to a small bandwidth (path-like problems), where it beats a general sparse LDL' by
// avoiding indirect addressing. A few full-width rows at the end (a border, e.g. from a low-rank term)
// cost one dot product with every earlier row's stored part.
//
// Quasi-definite matrices have such a factorization in every symmetric order; a pivot whose sign
// differs from the expected sign, or whose magnitude is below a threshold, is replaced by a small value
// of the expected sign (dynamic regularization) and counted, as in SparseLdl.

#include <vector>

namespace timeopt::conic {

class SkylineLdl {
 public:
  /// Sets the profile: first[i] <= i is the first stored column of row i. Throws
  /// std::invalid_argument if a first column is out of range.
  void Analyze(const std::vector<int>& first);

  /// Offset of entry (i, j), first(i) <= j <= i, in values().
  int Slot(int i, int j) const { return row_ptr_[i] + (j - first_[i]); }
  /// The lower triangle in skyline order; the caller fills it, then calls Factor().
  double* values() { return val_.data(); }
  const double* values() const { return val_.data(); }
  void SetZero();

  /// Factorizes in place. signs[i] (+1 or -1) is the expected sign of pivot i. Returns the number
  /// of replaced pivots. The matrix values are overwritten by L (strictly lower part) and D.
  int Factor(const signed char* signs, double threshold, double replacement);

  /// Solves L D L' x = rhs in place (x holds rhs on entry).
  void Solve(double* x) const;
  /// Two right-hand sides in one sweep over the factor.
  void Solve2(double* x1, double* x2) const;

  int size() const { return n_; }
  int first(int i) const { return first_[i]; }
  /// Stored entries of the lower triangle (diagonal included).
  long long num_stored() const { return static_cast<long long>(val_.size()); }
  /// Multiply-adds of one factorization.
  long long num_factor_flops() const { return flops_; }

 private:
  int n_ = 0;
  std::vector<int> first_;
  std::vector<int> row_ptr_;  // row i occupies [row_ptr_[i], row_ptr_[i + 1]), diagonal last
  std::vector<double> val_;
  std::vector<double> inv_d_;
  long long flops_ = 0;
};

}  // namespace timeopt::conic
