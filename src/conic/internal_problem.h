#pragma once
// The solver's internal copy of a Problem (private to the conic module): A and G in compressed
// columns with a fixed pattern, and the first two rows of every rotated cone turned by 45 degrees,
// t0 = (s0 + s1) / sqrt(2), t1 = (s0 - s1) / sqrt(2), which maps 2 s0 s1 >= ||s2..||^2 onto the
// standard cone t0 >= ||(t1, s2..)||. The pattern is analyzed once; the values are reloaded by every
// Solve().

#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include "cones.h"
#include "timeopt/conic/problem.h"

namespace timeopt::conic::internal {

inline double NormInf(const double* v, int n) {
  return n > 0 ? Eigen::Map<const Eigen::VectorXd>(v, n).lpNorm<Eigen::Infinity>() : 0.0;
}

// Compressed sparse column matrix with a fixed pattern.
struct Csc {
  int rows = 0;
  int cols = 0;
  std::vector<int> ptr;
  std::vector<int> idx;
  std::vector<double> val;

  // out = M v (out has `rows` entries).
  void Multiply(const double* v, double* out) const {
    std::fill(out, out + rows, 0.0);
    for (int j = 0; j < cols; ++j) {
      const double vj = v[j];
      if (vj == 0.0) continue;
      for (int p = ptr[j]; p < ptr[j + 1]; ++p) out[idx[p]] += val[p] * vj;
    }
  }
  // out = M' v (out has `cols` entries).
  void MultiplyTransposed(const double* v, double* out) const {
    for (int j = 0; j < cols; ++j) {
      double sum = 0.0;
      for (int p = ptr[j]; p < ptr[j + 1]; ++p) sum += val[p] * v[idx[p]];
      out[j] = sum;
    }
  }
};

struct InternalProblem {
  int n = 0, p = 0, m = 0;
  // Size of the augmented KKT system: n + p + m + 2 per expanded cone (see Cones::Layout).
  int num_kkt = 0;
  Csc A;                    // p x n
  Csc G;                    // m x n, rotated rows transformed
  Eigen::VectorXd c, b, h;  // h transformed

  // Pattern signature of the user's problem (what must match for reuse).
  ConeSpec spec;
  std::vector<int> sig_a_ptr, sig_a_idx, sig_g_ptr, sig_g_idx;
  // For every stored entry of the user's G (in InnerIterator order): where it goes in G.val, with
  // which coefficient (target1 = -1 if only one target).
  std::vector<int> g_target0, g_target1;
  std::vector<double> g_coef0, g_coef1;

  // True if `problem` has the sizes, cones and A and G patterns analyzed last.
  bool SamePattern(const Problem& problem) const;
  // Takes the pattern of `problem`, whose cones are laid out in `cones` (with num_kkt its KKT size).
  void Analyze(const Problem& problem, const Cones& cones, int kkt_size);
  // Copies the values of `problem` (same pattern) in the internal coordinates.
  void LoadValues(const Problem& problem, const Cones& cones);
};

}  // namespace timeopt::conic::internal
