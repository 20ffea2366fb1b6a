// The augmented KKT method: the full quasi-definite system in (x, y, z), plus two rows per expanded
// cone, ordered once by AMD and factorized by SparseLdl into a fixed pattern.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

#include "kkt_system.h"
#include "sparse_ldl.h"

namespace timeopt::conic::internal {

namespace {

class AugmentedKkt final : public KktSystem {
 public:
  AugmentedKkt(const InternalProblem& problem, const Cones& cones, std::int64_t max_factor_bytes)
      : problem_(problem), cones_(cones), max_factor_bytes_(max_factor_bytes) {
    Analyze();
  }

  KktMethod method() const override { return KktMethod::kAugmentedSparse; }
  void LoadData() override;
  void SetStaticRegularization(double delta) override;
  int Factor(const SolverOptions& options) override;
  void Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol) override;
  void Solve2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a, const Eigen::VectorXd& rhs_b,
              Eigen::VectorXd& sol_b) override;
  int Refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const RefinementSettings& settings) override;
  int size() const override { return problem_.num_kkt; }
  long long num_nonzeros() const override { return static_cast<long long>(k_idx.size()); }
  long long num_factor_nonzeros() const override { return ldl.num_factor_nonzeros(); }

 private:
  void Analyze();
  // The scaled entries: -W'W - delta on the z block, the expansion of large cones.
  void UpdateScaling(double delta);
  void MultiplyUnregularized(const double* v, double* out) const;  // permuted space

  const InternalProblem& problem_;
  const Cones& cones_;
  std::int64_t max_factor_bytes_ = 0;  // 0: no limit
  std::vector<int> perm, pinv;         // perm[new] = old, pinv[old] = new
  std::vector<int> k_ptr, k_idx;       // permuted upper triangle, diagonal last in each column
  std::vector<double> k_val;
  std::vector<signed char> k_sign;    // expected pivot sign (permuted)
  std::vector<double> k_reg;          // static regularization on the diagonal (permuted)
  std::vector<int> diag_slot;         // unpermuted index -> slot of its diagonal
  std::vector<int> a_slot, g_slot;    // per internal A / G entry -> slot of (col, row) entry
  std::vector<int> dense_slots;       // per dense cone: strict upper triangle slots, row-major
  std::vector<int> u_slots, v_slots;  // per expanded cone: slot of (z_i, u-row), (z_i, v-row)
  SparseLdl ldl;
  Eigen::VectorXd perm_rhs, perm_sol, perm_res, perm_corr;
};

void AugmentedKkt::Analyze() {
  const int n = problem_.n, p = problem_.p, m = problem_.m, num_kkt = problem_.num_kkt;
  const Csc& A = problem_.A;
  const Csc& G = problem_.G;
  const std::vector<SocBlock>& socs = cones_.socs;
  int dense_count = 0, expanded_count = 0;
  for (const SocBlock& blk : socs) {
    if (blk.expanded) {
      expanded_count += blk.dim;
    } else {
      dense_count += blk.dim * (blk.dim - 1) / 2;
    }
  }

  // ---- KKT pattern (unpermuted upper triangle) ----
  std::vector<std::pair<int, int>> entries;  // (row, col), row <= col
  entries.reserve(num_kkt + A.idx.size() + G.idx.size() + 3 * m);
  std::vector<int> diag_entry(num_kkt);
  for (int k = 0; k < num_kkt; ++k) {
    diag_entry[k] = static_cast<int>(entries.size());
    entries.emplace_back(k, k);
  }
  std::vector<int> a_entry(A.idx.size()), g_entry(G.idx.size());
  for (int j = 0; j < n; ++j) {
    for (int q = A.ptr[j]; q < A.ptr[j + 1]; ++q) {
      a_entry[q] = static_cast<int>(entries.size());
      entries.emplace_back(j, n + A.idx[q]);
    }
    for (int q = G.ptr[j]; q < G.ptr[j + 1]; ++q) {
      g_entry[q] = static_cast<int>(entries.size());
      entries.emplace_back(j, n + p + G.idx[q]);
    }
  }
  std::vector<int> dense_entry(dense_count), u_entry(expanded_count), v_entry(expanded_count);
  const int z0 = n + p;
  for (const SocBlock& blk : socs) {
    if (blk.expanded) {
      for (int i = 0; i < blk.dim; ++i) {
        v_entry[blk.slot_offset + i] = static_cast<int>(entries.size());
        entries.emplace_back(z0 + blk.start + i, blk.ext);
        u_entry[blk.slot_offset + i] = static_cast<int>(entries.size());
        entries.emplace_back(z0 + blk.start + i, blk.ext + 1);
      }
    } else {
      int t = blk.slot_offset;
      for (int i = 0; i < blk.dim; ++i) {
        for (int j = i + 1; j < blk.dim; ++j) {
          dense_entry[t++] = static_cast<int>(entries.size());
          entries.emplace_back(z0 + blk.start + i, z0 + blk.start + j);
        }
      }
    }
  }

  // ---- fill-reducing ordering ----
  {
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(entries.size());
    for (const auto& e : entries) triplets.emplace_back(e.first, e.second, 1.0);
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> pattern(num_kkt, num_kkt);
    pattern.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::AMDOrdering<int> amd;
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> ordering;
    amd(pattern, ordering);
    perm.assign(num_kkt, 0);
    pinv.assign(num_kkt, 0);
    for (int k = 0; k < num_kkt; ++k) {
      perm[k] = ordering.indices()[k];
      pinv[perm[k]] = k;
    }
  }

  // ---- permuted upper triangle in CSC, diagonal last in each column ----
  std::vector<int> count(num_kkt + 1, 0);
  std::vector<std::pair<int, int>> permuted(entries.size());  // (row, col) permuted
  for (std::size_t e = 0; e < entries.size(); ++e) {
    int r = pinv[entries[e].first], c2 = pinv[entries[e].second];
    if (r > c2) std::swap(r, c2);
    permuted[e] = {r, c2};
    ++count[c2 + 1];
  }
  k_ptr.assign(num_kkt + 1, 0);
  for (int k = 0; k < num_kkt; ++k) k_ptr[k + 1] = k_ptr[k] + count[k + 1];
  std::vector<int> order(entries.size());
  {
    std::vector<int> next(k_ptr.begin(), k_ptr.end() - 1);
    for (std::size_t e = 0; e < entries.size(); ++e) order[next[permuted[e].second]++] = static_cast<int>(e);
  }
  std::vector<int> slot_of_entry(entries.size());
  k_idx.assign(entries.size(), 0);
  for (int k = 0; k < num_kkt; ++k) {
    std::sort(order.begin() + k_ptr[k], order.begin() + k_ptr[k + 1],
              [&](int a, int b2) { return permuted[a].first < permuted[b2].first; });
    for (int q = k_ptr[k]; q < k_ptr[k + 1]; ++q) {
      slot_of_entry[order[q]] = q;
      k_idx[q] = permuted[order[q]].first;
    }
  }
  k_val.assign(entries.size(), 0.0);
  diag_slot.resize(num_kkt);
  for (int k = 0; k < num_kkt; ++k) diag_slot[k] = slot_of_entry[diag_entry[k]];
  a_slot.resize(a_entry.size());
  for (std::size_t q = 0; q < a_entry.size(); ++q) a_slot[q] = slot_of_entry[a_entry[q]];
  g_slot.resize(g_entry.size());
  for (std::size_t q = 0; q < g_entry.size(); ++q) g_slot[q] = slot_of_entry[g_entry[q]];
  dense_slots.resize(dense_count);
  for (int q = 0; q < dense_count; ++q) dense_slots[q] = slot_of_entry[dense_entry[q]];
  u_slots.resize(expanded_count);
  v_slots.resize(expanded_count);
  for (int q = 0; q < expanded_count; ++q) {
    u_slots[q] = slot_of_entry[u_entry[q]];
    v_slots[q] = slot_of_entry[v_entry[q]];
  }

  // ---- expected pivot signs ----
  k_sign.assign(num_kkt, -1);
  for (int j = 0; j < n; ++j) k_sign[pinv[j]] = 1;
  for (const SocBlock& blk : socs) {
    if (blk.expanded) k_sign[pinv[blk.ext + 1]] = 1;  // the u-row has +1 on the diagonal
  }
  k_reg.assign(num_kkt, 0.0);

  // The factor's size with its fill-in, before any of it is allocated: a few hundred bytes of
  // input can have a factor of gigabytes (cones over scattered variables fill in).
  const long long nonzeros = SparseLdl::CountFactorNonzeros(num_kkt, k_ptr, k_idx);
  const double bytes = static_cast<double>(nonzeros) * SolverOptions::kFactorBytesPerNonzero;
  if (nonzeros > std::numeric_limits<int>::max() ||
      (max_factor_bytes_ > 0 && bytes > static_cast<double>(max_factor_bytes_))) {
    std::ostringstream m;
    m << "the KKT factor of " << num_kkt << " rows has " << nonzeros << " non-zeros with its fill-in (about "
      << static_cast<long long>(bytes / (1 << 20)) << " MiB), ";
    if (nonzeros > std::numeric_limits<int>::max())
      m << "more than 32-bit indices address";
    else
      m << "above the memory budget of " << max_factor_bytes_ / (1 << 20) << " MiB for it";
    throw std::invalid_argument(m.str());
  }
  ldl.Analyze(num_kkt, k_ptr, k_idx);
  for (Eigen::VectorXd* v : {&perm_rhs, &perm_sol, &perm_res, &perm_corr}) v->setZero(num_kkt);
}

void AugmentedKkt::LoadData() {
  const Csc& A = problem_.A;
  const Csc& G = problem_.G;
  for (std::size_t e = 0; e < A.val.size(); ++e) k_val[a_slot[e]] = A.val[e];
  for (std::size_t e = 0; e < G.val.size(); ++e) k_val[g_slot[e]] = G.val[e];
}

void AugmentedKkt::SetStaticRegularization(double delta) {
  const int n = problem_.n, p = problem_.p, m = problem_.m;
  static_reg_ = delta;
  const std::vector<SocBlock>& socs = cones_.socs;
  // Constant KKT entries.
  for (int j = 0; j < n; ++j) {
    k_val[diag_slot[j]] = delta;
    k_reg[pinv[j]] = delta;
  }
  for (int i = 0; i < p; ++i) {
    k_val[diag_slot[n + i]] = -delta;
    k_reg[pinv[n + i]] = -delta;
  }
  for (int i = 0; i < m; ++i) k_reg[pinv[n + p + i]] = -delta;
  for (const SocBlock& blk : socs) {
    if (!blk.expanded) continue;
    k_val[diag_slot[blk.ext]] = -1.0;
    k_val[diag_slot[blk.ext + 1]] = 1.0;
  }
}

int AugmentedKkt::Factor(const SolverOptions& options) {
  UpdateScaling(static_reg_);
  return ldl.Factor(k_val.data(), k_sign.data(), options.dynamic_regularization_threshold,
                    options.dynamic_regularization);
}

void AugmentedKkt::UpdateScaling(double delta) {
  const int n = problem_.n, p = problem_.p;
  const int num_orthant = cones_.num_orthant;
  const std::vector<SocBlock>& socs = cones_.socs;
  const Eigen::VectorXd& w_orthant = cones_.w_orthant;
  const Eigen::VectorXd& wbar = cones_.wbar;
  const std::vector<double>& eta = cones_.eta;
  const int z0 = n + p;
  for (int i = 0; i < num_orthant; ++i) {
    k_val[diag_slot[z0 + i]] = -w_orthant[i] * w_orthant[i] - delta;
  }
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    const double* w = wbar.data() + blk.start;
    const double e2 = eta[k] * eta[k];
    const int d = blk.dim;
    if (!blk.expanded) {
      // W'W = eta^2 (2 w w' - J).
      k_val[diag_slot[z0 + blk.start]] = -e2 * (2.0 * w[0] * w[0] - 1.0) - delta;
      for (int i = 1; i < d; ++i) k_val[diag_slot[z0 + blk.start + i]] = -e2 * (2.0 * w[i] * w[i] + 1.0) - delta;
      int t = blk.slot_offset;
      for (int i = 0; i < d; ++i) {
        for (int j = i + 1; j < d; ++j) k_val[dense_slots[t++]] = -2.0 * e2 * w[i] * w[j];
      }
    } else {
      // W'W = eta^2 (D + u u' - v v') (see ExpandCone).
      const ExpandedCone x = ExpandCone(w[0]);
      const double d0 = x.d0, u0 = x.u0, u1 = x.u1, v1 = x.v1;
      const double et = eta[k];
      k_val[diag_slot[z0 + blk.start]] = -e2 * d0 - delta;
      k_val[u_slots[blk.slot_offset]] = et * u0;
      k_val[v_slots[blk.slot_offset]] = 0.0;
      for (int i = 1; i < d; ++i) {
        k_val[diag_slot[z0 + blk.start + i]] = -e2 - delta;
        k_val[u_slots[blk.slot_offset + i]] = et * u1 * w[i];
        k_val[v_slots[blk.slot_offset + i]] = et * v1 * w[i];
      }
    }
  }
}

void AugmentedKkt::MultiplyUnregularized(const double* v, double* out) const {
  const int num_kkt = problem_.num_kkt;
  std::fill(out, out + num_kkt, 0.0);
  for (int j = 0; j < num_kkt; ++j) {
    const double vj = v[j];
    double sum = 0.0;
    const int end = k_ptr[j + 1] - 1;  // diagonal is last
    for (int q = k_ptr[j]; q < end; ++q) {
      const int i = k_idx[q];
      out[i] += k_val[q] * vj;
      sum += k_val[q] * v[i];
    }
    out[j] += sum + (k_val[end] - k_reg[j]) * vj;
  }
}

void AugmentedKkt::Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol) {
  const int num_kkt = problem_.num_kkt;
  for (int k = 0; k < num_kkt; ++k) perm_sol[k] = rhs[perm[k]];
  ldl.Solve(perm_sol.data());
  for (int k = 0; k < num_kkt; ++k) sol[perm[k]] = perm_sol[k];
}

void AugmentedKkt::Solve2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a, const Eigen::VectorXd& rhs_b,
                          Eigen::VectorXd& sol_b) {
  const int num_kkt = problem_.num_kkt;
  for (int k = 0; k < num_kkt; ++k) {
    perm_sol[k] = rhs_a[perm[k]];
    perm_corr[k] = rhs_b[perm[k]];
  }
  ldl.Solve2(perm_sol.data(), perm_corr.data());
  for (int k = 0; k < num_kkt; ++k) {
    sol_a[perm[k]] = perm_sol[k];
    sol_b[perm[k]] = perm_corr[k];
  }
}

int AugmentedKkt::Refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const RefinementSettings& settings) {
  const int num_kkt = problem_.num_kkt;
  for (int k = 0; k < num_kkt; ++k) {
    perm_rhs[k] = rhs[perm[k]];
    perm_sol[k] = sol[perm[k]];
  }
  int steps = 0;
  const bool changed = RefineSolution(
      perm_rhs, perm_sol, perm_res, perm_corr, num_kkt, settings,
      [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { MultiplyUnregularized(v.data(), out.data()); },
      [&](const Eigen::VectorXd& r, Eigen::VectorXd& out) {
        out = r;
        ldl.Solve(out.data());
      },
      &steps);
  if (changed) {
    for (int k = 0; k < num_kkt; ++k) sol[perm[k]] = perm_sol[k];
  }
  return steps;
}

}  // namespace

std::unique_ptr<KktSystem> MakeAugmentedKkt(const InternalProblem& problem, const Cones& cones,
                                            std::int64_t max_factor_bytes) {
  return std::make_unique<AugmentedKkt>(problem, cones, max_factor_bytes);
}

}  // namespace timeopt::conic::internal
