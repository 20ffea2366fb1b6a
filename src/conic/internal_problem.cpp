#include "internal_problem.h"

#include <algorithm>

#include <Eigen/SparseCore>

namespace timeopt::conic::internal {

bool InternalProblem::SamePattern(const Problem& problem) const {
  if (problem.num_variables() != n || problem.num_equalities() != p || problem.num_cone_rows() != m) {
    return false;
  }
  if (problem.cones.num_nonnegative != spec.num_nonnegative || problem.cones.soc_dims != spec.soc_dims ||
      problem.cones.rotated_dims != spec.rotated_dims) {
    return false;
  }
  auto same = [](const Eigen::SparseMatrix<double>& M, const std::vector<int>& ptr, const std::vector<int>& idx) {
    std::size_t q = 0;
    for (int j = 0; j < M.outerSize(); ++j) {
      if (ptr[j] != static_cast<int>(q)) return false;
      for (Eigen::SparseMatrix<double>::InnerIterator it(M, j); it; ++it, ++q) {
        if (q >= idx.size() || idx[q] != it.row()) return false;
      }
    }
    return q == idx.size();
  };
  return same(problem.A, sig_a_ptr, sig_a_idx) && same(problem.G, sig_g_ptr, sig_g_idx);
}

void InternalProblem::Analyze(const Problem& problem, const Cones& cones, int kkt_size) {
  n = problem.num_variables();
  p = problem.num_equalities();
  m = problem.num_cone_rows();
  spec = problem.cones;
  num_kkt = kkt_size;
  auto signature = [](const Eigen::SparseMatrix<double>& M, std::vector<int>& ptr, std::vector<int>& idx) {
    ptr.assign(M.outerSize() + 1, 0);
    idx.clear();
    for (int j = 0; j < M.outerSize(); ++j) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(M, j); it; ++it) idx.push_back(it.row());
      ptr[j + 1] = static_cast<int>(idx.size());
    }
  };
  signature(problem.A, sig_a_ptr, sig_a_idx);
  signature(problem.G, sig_g_ptr, sig_g_idx);

  // ---- A (copy of the pattern) ----
  A.rows = p;
  A.cols = n;
  A.ptr = sig_a_ptr;
  A.idx = sig_a_idx;
  A.val.assign(A.idx.size(), 0.0);

  // ---- G with rotated rows transformed: pattern and contribution map ----
  G.rows = m;
  G.cols = n;
  G.ptr.assign(n + 1, 0);
  G.idx.clear();
  std::vector<int> mark(m, -1), position(m, 0);
  const std::size_t g_nnz = sig_g_idx.size();
  g_target0.assign(g_nnz, -1);
  g_target1.assign(g_nnz, -1);
  g_coef0.assign(g_nnz, 0.0);
  g_coef1.assign(g_nnz, 0.0);
  for (int j = 0; j < n; ++j) {
    const int begin = static_cast<int>(G.idx.size());
    for (int q = sig_g_ptr[j]; q < sig_g_ptr[j + 1]; ++q) {
      const int r = sig_g_idx[q];
      const int r0 = cones.row_kind[r] == 2 ? r - 1 : r;
      const int count = cones.row_kind[r] == 0 ? 1 : 2;
      for (int t = 0; t < count; ++t) {
        if (mark[r0 + t] != j) {
          mark[r0 + t] = j;
          G.idx.push_back(r0 + t);
        }
      }
    }
    std::sort(G.idx.begin() + begin, G.idx.end());
    for (int q = begin; q < static_cast<int>(G.idx.size()); ++q) position[G.idx[q]] = q;
    for (int q = sig_g_ptr[j]; q < sig_g_ptr[j + 1]; ++q) {
      const int r = sig_g_idx[q];
      if (cones.row_kind[r] == 0) {
        g_target0[q] = position[r];
        g_coef0[q] = 1.0;
      } else {
        // t0 = (s0 + s1)/sqrt2, t1 = (s0 - s1)/sqrt2.
        const int r0 = cones.row_kind[r] == 1 ? r : r - 1;
        g_target0[q] = position[r0];
        g_coef0[q] = kSqrtHalf;
        g_target1[q] = position[r0 + 1];
        g_coef1[q] = cones.row_kind[r] == 1 ? kSqrtHalf : -kSqrtHalf;
      }
    }
    G.ptr[j + 1] = static_cast<int>(G.idx.size());
  }
  G.val.assign(G.idx.size(), 0.0);
}

void InternalProblem::LoadValues(const Problem& problem, const Cones& cones) {
  c = problem.c;
  b = problem.b;
  h = problem.h;
  for (const SocBlock& blk : cones.socs) {
    if (!blk.rotated) continue;
    const double h0 = problem.h[blk.start], h1 = problem.h[blk.start + 1];
    h[blk.start] = kSqrtHalf * (h0 + h1);
    h[blk.start + 1] = kSqrtHalf * (h0 - h1);
  }
  int q = 0;
  for (int j = 0; j < problem.A.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(problem.A, j); it; ++it) A.val[q++] = it.value();
  }
  std::fill(G.val.begin(), G.val.end(), 0.0);
  q = 0;
  for (int j = 0; j < problem.G.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(problem.G, j); it; ++it, ++q) {
      G.val[g_target0[q]] += g_coef0[q] * it.value();
      if (g_target1[q] >= 0) G.val[g_target1[q]] += g_coef1[q] * it.value();
    }
  }
}

}  // namespace timeopt::conic::internal
