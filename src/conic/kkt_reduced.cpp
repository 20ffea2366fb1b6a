// The reduced (banded) KKT method: z eliminated through the cone scaling, leaving
//     [ G' W^{-2} G + delta I   A'       ]
//     [ A                       -delta I ]
// in (x, y), plus two border rows per expanded cone (its low-rank part), ordered by reverse
// Cuthill-McKee to a small profile and factorized by SkylineLdl on contiguous memory. Unknowns of the
// reduced system, unpermuted: x_j -> j, y_i -> n + i, and per expanded cone q two border unknowns
// n + p + 2q (its v-row, pivot +1) and n + p + 2q + 1 (its u-row, pivot -1). Refinement runs on the
// full unreduced system.

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "kkt_system.h"
#include "ordering.h"
#include "skyline_ldl.h"

namespace timeopt::conic::internal {

namespace {

class ReducedKkt final : public KktSystem {
 public:
  ReducedKkt(const InternalProblem& problem, const Cones& cones) : problem_(problem), cones_(cones) {}

  // Builds the ordering and profile; false (the method does not apply, see MakeReducedKkt) otherwise.
  bool Analyze(bool automatic, const SolverOptions& options);

  KktMethod method() const override { return KktMethod::kReducedBanded; }
  // The values are formed with the regularization (SetStaticRegularization).
  void LoadData() override {}
  void SetStaticRegularization(double delta) override {
    static_reg_ = delta;
    LoadConstantValues();
  }
  int Factor(const SolverOptions& options) override;
  void Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol) override;
  void Solve2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a, const Eigen::VectorXd& rhs_b,
              Eigen::VectorXd& sol_b) override;
  int Refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const RefinementSettings& settings) override;
  int size() const override { return nr; }
  long long num_nonzeros() const override { return sky.num_stored(); }
  long long num_factor_nonzeros() const override { return sky.num_stored() - nr; }

 private:
  void BuildRowsOfG();
  // The graph of the reduced matrix, its ordering and profile; false if `automatic` and the profile
  // stores more than max_profile_per_row entries per row on average.
  bool OrderAndProfile(bool automatic, int max_profile_per_row);
  void AssignSlots();
  int Slot(int a, int b) const {  // unpermuted reduced unknowns
    const int i = r_pinv[a], j = r_pinv[b];
    return i >= j ? sky.Slot(i, j) : sky.Slot(j, i);
  }
  void LoadConstantValues();
  void ReducedRhs(const Eigen::VectorXd& rhs, Eigen::VectorXd& red, Eigen::VectorXd& t);
  void ReducedSolution(const Eigen::VectorXd& red, const Eigen::VectorXd& t, Eigen::VectorXd& sol);
  // out = K v for the unregularized full system in (x, y, z) (unpermuted; the expansion entries of
  // out are not touched).
  void FullKktMultiply(const Eigen::VectorXd& v, Eigen::VectorXd& out);

  const InternalProblem& problem_;
  const Cones& cones_;
  int num_expanded_ = 0;
  int nr = 0;
  std::vector<int> r_pinv;          // unpermuted reduced unknown -> skyline row
  std::vector<signed char> r_sign;  // expected pivot sign per skyline row
  SkylineLdl sky;
  std::vector<int> r_diag_slot;  // per unpermuted reduced unknown
  std::vector<int> r_a_slot;     // per internal A entry: slot of (y_i, x_j)
  // G by rows: row r has entries [gr_ptr[r], gr_ptr[r+1]) with column gr_col and index gr_val into G.val.
  std::vector<int> gr_ptr, gr_col, gr_val;
  // Rows scaled by a scalar (orthant rows, rows of expanded cones): slots of the products of their
  // entries e <= f (row-major over the row's entries), starting at pair_ptr[r].
  std::vector<int> pair_ptr, pair_slot;
  std::vector<double> pair_coef;       // g_e g_f per pair (constant while the data are)
  std::vector<double> cone_pair_coef;  // per dense-cone pair (a, b): (Gc' J Gc)_ab, constant
  std::vector<double> r_constant;      // skyline values that do not change: A, +-delta, border +-1
  // Small (dense) and expanded cones: the union of the columns of their rows (cone_var_ptr per entry of
  // socs), each row entry's position in that union (gr_local), the slots of the union's pairs a <= b
  // (dense cones, from cone_pair_ptr) and the border slots (expanded cones, one per union column).
  std::vector<int> cone_var_ptr, cone_var, gr_local, cone_pair_ptr, cone_pair_slot, border_u_slot, border_v_slot;
  std::vector<double> local_g;                    // dense scratch of one cone
  Eigen::VectorXd red1, red2;                     // skyline-ordered vectors of size nr
  Eigen::VectorXd red_t1, red_t2, red_m1, red_n;  // sizes m, m, m, n
  Eigen::VectorXd full_res, full_corr;            // size num_kkt
};

bool ReducedKkt::Analyze(bool automatic, const SolverOptions& options) {
  const int n = problem_.n;
  const int m = problem_.m;
  const Csc& G = problem_.G;
  num_expanded_ = cones_.num_expanded();
  // The x block G' W^{-2} G is singular (up to the regularization) unless G has full column rank, for
  // which m >= n and no empty column are necessary: otherwise the elimination meets pivots of size
  // delta and the factor overflows. Border rows are full width; beyond a few of them the augmented
  // system is the better choice.
  if (m < n || (automatic && num_expanded_ > options.reduced_max_expanded_cones)) return false;
  for (int j = 0; j < n; ++j) {
    if (G.ptr[j] == G.ptr[j + 1]) return false;
  }
  BuildRowsOfG();
  if (!OrderAndProfile(automatic, options.reduced_max_profile_per_row)) return false;
  AssignSlots();
  full_res.setZero(problem_.num_kkt);
  full_corr.setZero(problem_.num_kkt);
  return true;
}

void ReducedKkt::BuildRowsOfG() {
  const int n = problem_.n;
  const int m = problem_.m;
  const Csc& G = problem_.G;
  const std::vector<SocBlock>& socs = cones_.socs;
  // ---- G by rows ----
  gr_ptr.assign(m + 1, 0);
  for (int q : G.idx) ++gr_ptr[q + 1];
  for (int r = 0; r < m; ++r) gr_ptr[r + 1] += gr_ptr[r];
  gr_col.assign(G.idx.size(), 0);
  gr_val.assign(G.idx.size(), 0);
  {
    std::vector<int> next(gr_ptr.begin(), gr_ptr.end() - 1);
    for (int j = 0; j < n; ++j) {
      for (int q = G.ptr[j]; q < G.ptr[j + 1]; ++q) {
        const int slot = next[G.idx[q]]++;
        gr_col[slot] = j;
        gr_val[slot] = q;
      }
    }
  }
  // Union of the columns of every cone's rows, and each row entry's position in it.
  gr_local.assign(G.idx.size(), -1);
  cone_var_ptr.assign(socs.size() + 1, 0);
  cone_var.clear();
  {
    std::vector<int> where(n, -1);
    for (std::size_t k = 0; k < socs.size(); ++k) {
      const SocBlock& blk = socs[k];
      const int begin = static_cast<int>(cone_var.size());
      for (int r = blk.start; r < blk.start + blk.dim; ++r) {
        for (int q = gr_ptr[r]; q < gr_ptr[r + 1]; ++q) {
          const int j = gr_col[q];
          if (where[j] < begin) {
            where[j] = static_cast<int>(cone_var.size());
            cone_var.push_back(j);
          }
          gr_local[q] = where[j] - begin;
        }
      }
      cone_var_ptr[k + 1] = static_cast<int>(cone_var.size());
    }
  }
}

bool ReducedKkt::OrderAndProfile(bool automatic, int max_profile_per_row) {
  const int n = problem_.n;
  const Csc& A = problem_.A;
  const std::vector<SocBlock>& socs = cones_.socs;
  const int num_orthant = cones_.num_orthant;
  const int nxy = problem_.n + problem_.p;
  // ---- graph of the reduced matrix (border excluded) and its ordering ----
  std::vector<std::pair<int, int>> edges;
  auto scalar_row_edges = [&](int r) {
    for (int e = gr_ptr[r]; e < gr_ptr[r + 1]; ++e) {
      for (int f = e + 1; f < gr_ptr[r + 1]; ++f) edges.emplace_back(gr_col[e], gr_col[f]);
    }
  };
  for (int r = 0; r < num_orthant; ++r) scalar_row_edges(r);
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    if (blk.expanded) {
      for (int r = blk.start; r < blk.start + blk.dim; ++r) scalar_row_edges(r);
    } else {
      for (int a = cone_var_ptr[k]; a < cone_var_ptr[k + 1]; ++a) {
        for (int b2 = a + 1; b2 < cone_var_ptr[k + 1]; ++b2) edges.emplace_back(cone_var[a], cone_var[b2]);
      }
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int q = A.ptr[j]; q < A.ptr[j + 1]; ++q) edges.emplace_back(j, n + A.idx[q]);
  }
  std::vector<int> adj_ptr(nxy + 1, 0), adj;
  {
    for (auto& e : edges) {
      if (e.first > e.second) std::swap(e.first, e.second);
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (const auto& e : edges) {
      ++adj_ptr[e.first + 1];
      ++adj_ptr[e.second + 1];
    }
    for (int v = 0; v < nxy; ++v) adj_ptr[v + 1] += adj_ptr[v];
    adj.assign(adj_ptr[nxy], 0);
    std::vector<int> next(adj_ptr.begin(), adj_ptr.end() - 1);
    for (const auto& e : edges) {
      adj[next[e.first]++] = e.second;
      adj[next[e.second]++] = e.first;
    }
  }
  const std::vector<int> order = ReverseCuthillMcKee(nxy, adj_ptr, adj);
  nr = nxy + 2 * num_expanded_;
  r_pinv.assign(nr, 0);
  for (int k = 0; k < nxy; ++k) r_pinv[order[k]] = k;
  for (int k = nxy; k < nr; ++k) r_pinv[k] = k;  // border rows last, in cone order

  // ---- profile ----
  std::vector<int> first(nr);
  long long stored = 0;
  for (int k = 0; k < nxy; ++k) {
    const int v = order[k];
    int f = k;
    for (int q = adj_ptr[v]; q < adj_ptr[v + 1]; ++q) f = std::min(f, r_pinv[adj[q]]);
    first[k] = f;
    stored += k - f + 1;
  }
  if (automatic && stored > static_cast<long long>(max_profile_per_row) * std::max(nxy, 1)) return false;
  {
    int q = 0;
    for (std::size_t k = 0; k < socs.size(); ++k) {
      if (!socs[k].expanded) continue;
      int f = nxy + 2 * q;
      for (int a = cone_var_ptr[k]; a < cone_var_ptr[k + 1]; ++a) f = std::min(f, r_pinv[cone_var[a]]);
      first[nxy + 2 * q] = f;
      first[nxy + 2 * q + 1] = f;
      ++q;
    }
  }
  sky.Analyze(first);
  return true;
}

void ReducedKkt::AssignSlots() {
  const int n = problem_.n;
  const int p = problem_.p;
  const int m = problem_.m;
  const Csc& A = problem_.A;
  const std::vector<SocBlock>& socs = cones_.socs;
  const int num_orthant = cones_.num_orthant;
  const int nxy = problem_.n + problem_.p;
  // ---- slots ----
  r_diag_slot.assign(nr, 0);
  for (int k = 0; k < nr; ++k) r_diag_slot[k] = Slot(k, k);
  r_sign.assign(nr, 1);
  for (int i = 0; i < p; ++i) r_sign[r_pinv[n + i]] = -1;
  for (int q = 0; q < num_expanded_; ++q) r_sign[r_pinv[nxy + 2 * q + 1]] = -1;
  r_a_slot.assign(A.idx.size(), 0);
  for (int j = 0; j < n; ++j) {
    for (int q = A.ptr[j]; q < A.ptr[j + 1]; ++q) r_a_slot[q] = Slot(j, n + A.idx[q]);
  }
  pair_ptr.assign(m + 1, 0);
  pair_slot.clear();
  std::vector<char> scalar_row(m, 0);
  for (int r = 0; r < num_orthant; ++r) scalar_row[r] = 1;
  for (const SocBlock& blk : socs) {
    if (blk.expanded) std::fill(scalar_row.begin() + blk.start, scalar_row.begin() + blk.start + blk.dim, 1);
  }
  for (int r = 0; r < m; ++r) {
    if (scalar_row[r]) {
      for (int e = gr_ptr[r]; e < gr_ptr[r + 1]; ++e) {
        for (int f = e; f < gr_ptr[r + 1]; ++f) pair_slot.push_back(Slot(gr_col[e], gr_col[f]));
      }
    }
    pair_ptr[r + 1] = static_cast<int>(pair_slot.size());
  }
  cone_pair_ptr.assign(socs.size() + 1, 0);
  cone_pair_slot.clear();
  border_u_slot.clear();
  border_v_slot.clear();
  std::size_t max_local = 0;
  {
    int q = 0;
    for (std::size_t k = 0; k < socs.size(); ++k) {
      const SocBlock& blk = socs[k];
      const int begin = cone_var_ptr[k], end = cone_var_ptr[k + 1];
      if (blk.expanded) {
        for (int a = begin; a < end; ++a) {
          border_v_slot.push_back(Slot(nxy + 2 * q, cone_var[a]));
          border_u_slot.push_back(Slot(nxy + 2 * q + 1, cone_var[a]));
        }
        ++q;
      } else {
        for (int a = begin; a < end; ++a) {
          for (int b2 = a; b2 < end; ++b2) cone_pair_slot.push_back(Slot(cone_var[a], cone_var[b2]));
        }
        max_local = std::max(max_local, static_cast<std::size_t>(blk.dim) * (end - begin));
      }
      cone_pair_ptr[k + 1] = static_cast<int>(cone_pair_slot.size());
    }
  }
  std::size_t max_vars = 0;
  for (std::size_t k = 0; k < socs.size(); ++k) {
    max_vars = std::max(max_vars, static_cast<std::size_t>(cone_var_ptr[k + 1] - cone_var_ptr[k]));
  }
  local_g.assign(std::max<std::size_t>(max_local, 2 * max_vars), 0.0);
  for (Eigen::VectorXd* v : {&red1, &red2}) v->setZero(nr);
  for (Eigen::VectorXd* v : {&red_t1, &red_t2, &red_m1}) v->setZero(m);
  red_n.setZero(n);
}

// The constant parts of the reduced matrix: +-delta on the diagonal, A, the border's +-1; and the
// products of G's entries that the scaled terms multiply.
void ReducedKkt::LoadConstantValues() {
  const int n = problem_.n;
  const int p = problem_.p;
  const int m = problem_.m;
  const Csc& A = problem_.A;
  const Csc& G = problem_.G;
  const std::vector<SocBlock>& socs = cones_.socs;
  const double delta = static_reg_;
  const int nxy = n + p;
  sky.SetZero();
  double* v = sky.values();
  for (int j = 0; j < n; ++j) v[r_diag_slot[j]] = delta;
  for (int i = 0; i < p; ++i) v[r_diag_slot[n + i]] = -delta;
  for (int k = nxy; k < nr; k += 2) {
    v[r_diag_slot[k]] = 1.0;
    v[r_diag_slot[k + 1]] = -1.0;
  }
  for (std::size_t e = 0; e < A.val.size(); ++e) v[r_a_slot[e]] += A.val[e];
  r_constant.assign(v, v + sky.num_stored());

  const double* gv = G.val.data();
  pair_coef.resize(pair_slot.size());
  for (int r = 0; r < m; ++r) {
    if (pair_ptr[r] == pair_ptr[r + 1]) continue;
    double* coef = pair_coef.data() + pair_ptr[r];
    for (int e = gr_ptr[r]; e < gr_ptr[r + 1]; ++e) {
      for (int f = e; f < gr_ptr[r + 1]; ++f) *coef++ = gv[gr_val[e]] * gv[gr_val[f]];
    }
  }
  cone_pair_coef.assign(cone_pair_slot.size(), 0.0);
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    if (blk.expanded) continue;
    const int nv = cone_var_ptr[k + 1] - cone_var_ptr[k];
    double* gl = local_g.data();  // d x nv, row-major
    std::fill(gl, gl + blk.dim * nv, 0.0);
    for (int r = 0; r < blk.dim; ++r) {
      for (int e = gr_ptr[blk.start + r]; e < gr_ptr[blk.start + r + 1]; ++e) gl[r * nv + gr_local[e]] = gv[gr_val[e]];
    }
    double* coef = cone_pair_coef.data() + cone_pair_ptr[k];
    for (int a = 0; a < nv; ++a) {
      for (int b2 = a; b2 < nv; ++b2) {
        double sum = gl[a] * gl[b2];
        for (int r = 1; r < blk.dim; ++r) sum -= gl[r * nv + a] * gl[r * nv + b2];
        *coef++ = sum;
      }
    }
  }
}

// The reduced matrix [G' W^{-2} G + delta I, A'; A, -delta I] plus, per expanded cone, its border.
// Small cones: W'W = eta^2 (2 wbar wbar' - J), so W^{-2} = eta^{-2} (2 vb vb' - J) with vb = J wbar and
// their block is eta^{-2} (2 q q' - Gc' J Gc) with q = Gc' vb. Expanded cones: W^{-2} = eta^{-2} (D +
// ut ut' - vt vt') with ut = J u, vt = J v from the decomposition of W'W in the augmented method, so the
// cone adds eta^{-2} G' D G to the band and the columns G' ut / eta (row with pivot -1) and
// G' vt / eta (row with pivot +1) to the border.
int ReducedKkt::Factor(const SolverOptions& options) {
  const int num_orthant = cones_.num_orthant;
  const std::vector<SocBlock>& socs = cones_.socs;
  const Eigen::VectorXd& hinv_orthant = cones_.hinv_orthant;
  const Eigen::VectorXd& wbar = cones_.wbar;
  const std::vector<double>& eta = cones_.eta;
  const Csc& G = problem_.G;
  double* v = sky.values();
  std::copy(r_constant.begin(), r_constant.end(), v);
  const double* gv = G.val.data();
  auto scalar_row = [&](int r, double weight) {
    const int* slot = pair_slot.data() + pair_ptr[r];
    const double* coef = pair_coef.data() + pair_ptr[r];
    const int count = pair_ptr[r + 1] - pair_ptr[r];
    for (int t = 0; t < count; ++t) v[slot[t]] += weight * coef[t];
  };
  for (int r = 0; r < num_orthant; ++r) scalar_row(r, hinv_orthant[r]);
  int border = 0;
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    const double* w = wbar.data() + blk.start;
    const double inv_eta = 1.0 / eta[k];
    const double inv_e2 = inv_eta * inv_eta;
    const int d = blk.dim;
    const int var0 = cone_var_ptr[k];
    const int nv = cone_var_ptr[k + 1] - var0;
    if (blk.expanded) {
      const ExpandedCone x = ExpandCone(w[0]);
      const double d0 = x.d0, u0 = x.u0, u1 = x.u1, v1 = x.v1;
      scalar_row(blk.start, inv_e2 * d0);
      for (int r = 1; r < d; ++r) scalar_row(blk.start + r, inv_e2);
      double* au = local_g.data();
      double* av = au + nv;
      std::fill(au, au + 2 * nv, 0.0);
      for (int r = 0; r < d; ++r) {
        const double ut = r == 0 ? u0 : -u1 * w[r];
        const double vt = r == 0 ? 0.0 : -v1 * w[r];
        for (int e = gr_ptr[blk.start + r]; e < gr_ptr[blk.start + r + 1]; ++e) {
          const double g = gv[gr_val[e]];
          au[gr_local[e]] += g * ut;
          av[gr_local[e]] += g * vt;
        }
      }
      for (int a = 0; a < nv; ++a) {
        v[border_u_slot[border + a]] = au[a] * inv_eta;
        v[border_v_slot[border + a]] = av[a] * inv_eta;
      }
      border += nv;
    } else {
      double* q = local_g.data();
      std::fill(q, q + nv, 0.0);
      for (int r = 0; r < d; ++r) {
        const double vb = r == 0 ? w[0] : -w[r];
        for (int e = gr_ptr[blk.start + r]; e < gr_ptr[blk.start + r + 1]; ++e) q[gr_local[e]] += gv[gr_val[e]] * vb;
      }
      const int* slot = cone_pair_slot.data() + cone_pair_ptr[k];
      const double* coef = cone_pair_coef.data() + cone_pair_ptr[k];
      for (int a = 0; a < nv; ++a) {
        const double qa = 2.0 * q[a];
        for (int b2 = a; b2 < nv; ++b2) v[*slot++] += inv_e2 * (qa * q[b2] - *coef++);
      }
    }
  }
  return sky.Factor(r_sign.data(), options.dynamic_regularization_threshold, options.dynamic_regularization);
}

// red = [r1 + G' W^{-2} r3; r2; 0] in skyline order, t = W^{-2} r3.
void ReducedKkt::ReducedRhs(const Eigen::VectorXd& rhs, Eigen::VectorXd& red, Eigen::VectorXd& t) {
  const int n = problem_.n;
  const int p = problem_.p;
  const Csc& G = problem_.G;
  cones_.ApplyH<true>(rhs.data() + n + p, t.data());
  G.MultiplyTransposed(t.data(), red_n.data());
  for (int j = 0; j < n; ++j) red[r_pinv[j]] = rhs[j] + red_n[j];
  for (int i = 0; i < p; ++i) red[r_pinv[n + i]] = rhs[n + i];
  for (int k = n + p; k < nr; ++k) red[k] = 0.0;
}

// x, y from the solved reduced system; z = W^{-2} (G x - r3) = W^{-2} G x - t.
void ReducedKkt::ReducedSolution(const Eigen::VectorXd& red, const Eigen::VectorXd& t, Eigen::VectorXd& sol) {
  const int n = problem_.n;
  const int p = problem_.p;
  const int m = problem_.m;
  const int num_kkt = problem_.num_kkt;
  const Csc& G = problem_.G;
  for (int j = 0; j < n; ++j) sol[j] = red[r_pinv[j]];
  for (int i = 0; i < p; ++i) sol[n + i] = red[r_pinv[n + i]];
  G.Multiply(sol.data(), red_m1.data());
  cones_.ApplyH<true>(red_m1.data(), sol.data() + n + p);
  sol.segment(n + p, m) -= t;
  if (num_kkt > n + p + m) sol.tail(num_kkt - n - p - m).setZero();
}

void ReducedKkt::Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol) {
  ReducedRhs(rhs, red1, red_t1);
  sky.Solve(red1.data());
  ReducedSolution(red1, red_t1, sol);
}

void ReducedKkt::Solve2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a, const Eigen::VectorXd& rhs_b,
                        Eigen::VectorXd& sol_b) {
  ReducedRhs(rhs_a, red1, red_t1);
  ReducedRhs(rhs_b, red2, red_t2);
  sky.Solve2(red1.data(), red2.data());
  ReducedSolution(red1, red_t1, sol_a);
  ReducedSolution(red2, red_t2, sol_b);
}

void ReducedKkt::FullKktMultiply(const Eigen::VectorXd& v, Eigen::VectorXd& out) {
  const int n = problem_.n;
  const int p = problem_.p;
  const int m = problem_.m;
  const Csc& A = problem_.A;
  const Csc& G = problem_.G;
  A.MultiplyTransposed(v.data() + n, out.data());
  G.MultiplyTransposed(v.data() + n + p, red_n.data());
  out.head(n) += red_n;
  A.Multiply(v.data(), out.data() + n);
  G.Multiply(v.data(), out.data() + n + p);
  cones_.ApplyH<false>(v.data() + n + p, red_m1.data());
  out.segment(n + p, m) -= red_m1;
}

// Refinement on the full unregularized system: its residual also catches the rounding of forming
// G' W^{-2} G (entries of W^{-2} span many orders of magnitude near the optimum), which refining the
// reduced system alone does not (measured: twice the iterations on the temporal problems).
int ReducedKkt::Refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const RefinementSettings& settings) {
  int steps = 0;
  RefineSolution(
      rhs, sol, full_res, full_corr, problem_.n + problem_.p + problem_.m, settings,
      [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { FullKktMultiply(v, out); },
      [&](const Eigen::VectorXd& r, Eigen::VectorXd& out) { Solve(r, out); }, &steps);
  return steps;
}

}  // namespace

std::unique_ptr<KktSystem> MakeReducedKkt(const InternalProblem& problem, const Cones& cones, bool automatic,
                                          const SolverOptions& options) {
  auto kkt = std::make_unique<ReducedKkt>(problem, cones);
  if (!kkt->Analyze(automatic, options)) return nullptr;
  return kkt;
}

}  // namespace timeopt::conic::internal
