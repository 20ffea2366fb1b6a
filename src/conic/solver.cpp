#include "timeopt/conic/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

#include "skyline_ldl.h"
#include "sparse_ldl.h"

namespace timeopt::conic {

const char* ToString(Status status) {
  switch (status) {
    case Status::kOptimal: return "optimal";
    case Status::kPrimalInfeasible: return "primal_infeasible";
    case Status::kDualInfeasible: return "dual_infeasible";
    case Status::kIterationLimit: return "iteration_limit";
    case Status::kNumericalError: return "numerical_error";
    case Status::kNotSolved: return "not_solved";
  }
  return "unknown";
}

const char* ToString(KktMethod method) {
  switch (method) {
    case KktMethod::kAutomatic: return "automatic";
    case KktMethod::kAugmentedSparse: return "augmented_sparse";
    case KktMethod::kReducedBanded: return "reduced_banded";
  }
  return "unknown";
}

std::string Result::BriefReport() const {
  char buffer[320];
  std::snprintf(buffer, sizeof(buffer),
                "%s: primal %.10g dual %.10g gap %.2e pres %.2e dres %.2e, %d iterations, %.3f ms",
                ToString(status), primal_objective, dual_objective, gap, primal_residual,
                dual_residual, iterations, 1e3 * solve_time_seconds);
  std::string report(buffer);
  if (!message.empty()) report += " (" + message + ")";
  return report;
}

bool SolverOptions::IsValid(std::string* error) const {
  auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(feasibility_tolerance)) return fail("feasibility_tolerance must be positive and finite");
  if (!positive(absolute_gap_tolerance)) return fail("absolute_gap_tolerance must be positive and finite");
  if (!positive(relative_gap_tolerance)) return fail("relative_gap_tolerance must be positive and finite");
  if (!positive(infeasibility_tolerance)) return fail("infeasibility_tolerance must be positive and finite");
  if (max_iterations < 0) return fail("max_iterations must be >= 0");
  if (!(max_solve_time_in_seconds > 0.0)) return fail("max_solve_time_in_seconds must be positive");
  if (!(step_fraction > 0.0 && step_fraction < 1.0)) return fail("step_fraction must be in (0, 1)");
  if (!(min_step > 0.0 && min_step < 1.0)) return fail("min_step must be in (0, 1)");
  if (!(reduced_feasibility_tolerance >= 0.0)) return fail("reduced_feasibility_tolerance must be >= 0");
  if (!(reduced_gap_tolerance >= 0.0)) return fail("reduced_gap_tolerance must be >= 0");
  if (stall_iterations < 1) return fail("stall_iterations must be >= 1");
  if (!(static_regularization >= 0.0 && std::isfinite(static_regularization))) {
    return fail("static_regularization must be >= 0 and finite");
  }
  if (!(dynamic_regularization_threshold >= 0.0 && std::isfinite(dynamic_regularization_threshold))) {
    return fail("dynamic_regularization_threshold must be >= 0 and finite");
  }
  if (!positive(dynamic_regularization)) return fail("dynamic_regularization must be positive and finite");
  if (max_refinement_steps < 0) return fail("max_refinement_steps must be >= 0");
  if (max_affine_refinement_steps < 0) return fail("max_affine_refinement_steps must be >= 0");
  if (!(refinement_tolerance >= 0.0)) return fail("refinement_tolerance must be >= 0");
  if (!(refinement_mu_factor >= 0.0 && std::isfinite(refinement_mu_factor))) {
    return fail("refinement_mu_factor must be >= 0 and finite");
  }
  if (!(refinement_stagnation > 0.0 && refinement_stagnation <= 1.0)) {
    return fail("refinement_stagnation must be in (0, 1]");
  }
  if (sparse_cone_min_dimension < 1) return fail("sparse_cone_min_dimension must be >= 1");
  return true;
}

namespace {

double NormInf(const double* v, int n) {
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

// One second-order cone of the internal problem (rotated cones are already mapped to standard ones).
struct SocBlock {
  int start = 0;          // first row in z and s
  int dim = 0;
  bool rotated = false;   // the first two rows were transformed
  bool expanded = false;  // scaling enters the KKT system by the sparse expansion
  int ext = -1;           // KKT index of the first of the two expansion rows (if expanded)
  int slot_offset = 0;    // offset into dense_slots (dense) or expansion slots (expanded)
};

constexpr double kSqrtHalf = 0.70710678118654752440;

// Per-cone kernels, templated on the dimension: D = 3 (most cones of path-like problems) is fully
// unrolled by the compiler, D = 0 reads the dimension at run time.
template <int D>
inline void ApplyWCone(const double* w, double eta, const double* v, double* o, int dim) {
  const int d = D > 0 ? D : dim;
  double w1v1 = 0.0;
  for (int i = 1; i < d; ++i) w1v1 += w[i] * v[i];
  const double coef = v[0] + w1v1 / (1.0 + w[0]);
  const double v0 = v[0];
  o[0] = eta * (w[0] * v0 + w1v1);
  for (int i = 1; i < d; ++i) o[i] = eta * (v[i] + coef * w[i]);
}

// out = eta^2 (2 wbar wbar' - J) v (the cone's block of W'W) if Inverse is false, and
// out = eta^{-2} (2 vb vb' - J) v with vb = J wbar (its inverse) if Inverse is true: one pass each.
template <int D, bool Inverse>
inline void ApplyHCone(const double* w, double eta, const double* v, double* o, int dim) {
  const int d = D > 0 ? D : dim;
  const double sign = Inverse ? -1.0 : 1.0;
  double t = w[0] * v[0];
  for (int i = 1; i < d; ++i) t += sign * w[i] * v[i];
  const double e2 = Inverse ? 1.0 / (eta * eta) : eta * eta;
  const double t2 = 2.0 * t;
  o[0] = e2 * (t2 * w[0] - v[0]);
  for (int i = 1; i < d; ++i) o[i] = e2 * (v[i] + sign * t2 * w[i]);
}

// Nesterov-Todd scaling point wbar (w0^2 - ||w1||^2 = 1) and factor eta of one cone, the scaled point
// lambda = W z and its step data (see InverseStepCone): lbar = lambda / sqrt(det lambda),
// isd = 1 / sqrt(det lambda), ilb = 1 / (lbar0 + 1). False if s, z or lambda is not strictly inside.
template <int D>
inline bool NtScalingCone(const double* sv, const double* zv, double* w, double& eta, double* lam, double* lbar,
                          double& isd, double& ilb, int dim) {
  const int d = D > 0 ? D : dim;
  double s1 = 0.0, z1 = 0.0, sz = 0.0;
  for (int i = 1; i < d; ++i) {
    s1 += sv[i] * sv[i];
    z1 += zv[i] * zv[i];
    sz += sv[i] * zv[i];
  }
  s1 = std::sqrt(s1);
  z1 = std::sqrt(z1);
  const double sres = (sv[0] - s1) * (sv[0] + s1);
  const double zres = (zv[0] - z1) * (zv[0] + z1);
  if (!(sv[0] - s1 > 0.0 && zv[0] - z1 > 0.0 && sres > 0.0 && zres > 0.0)) return false;
  const double sn = std::sqrt(sres), zn = std::sqrt(zres);
  const double dot = (sv[0] * zv[0] + sz) / (sn * zn);  // sbar'zbar >= 1
  const double gamma = std::sqrt(0.5 * (1.0 + dot));
  const double f = 0.5 / gamma;
  double w1 = 0.0;
  for (int i = 1; i < d; ++i) {
    // Divisions, not products with 1 / sn: the last digits of w decide whether the final
    // iterations of borderline problems reach 1e-8 (measured on the known-optimum tests).
    w[i] = f * (sv[i] / sn - zv[i] / zn);
    w1 += w[i] * w[i];
  }
  // w0 = f (sbar0 + zbar0), restored to w0^2 - ||w1||^2 = 1 against rounding.
  w[0] = std::sqrt(1.0 + w1);
  eta = std::sqrt(sn / zn);
  // lambda = W z with the W just computed, and its step data from lambda itself: the closed form of
  // lbar (gamma, ...) is exact, but steps computed from it instead of from W z ended in a stalled
  // dual residual near the optimum (measured on the known-optimum tests).
  ApplyWCone<D>(w, eta, zv, lam, dim);
  double l1 = 0.0;
  for (int i = 1; i < d; ++i) l1 += lam[i] * lam[i];
  l1 = std::sqrt(l1);
  const double det = (lam[0] - l1) * (lam[0] + l1);
  if (!(lam[0] - l1 > 0.0 && det > 0.0)) return false;
  isd = 1.0 / std::sqrt(det);
  for (int i = 0; i < d; ++i) lbar[i] = lam[i] * isd;
  ilb = 1.0 / (lbar[0] + 1.0);
  return true;
}

// The inverse of the largest step a with lam + a d in the cone, for lam strictly inside, from
// lbar = lam / sqrt(det lam), isd = 1 / sqrt(det lam) and ilb = 1 / (lbar0 + 1): the hyperbolic
// rotation that maps lbar to e maps d to rho = (lbar0 d0 - lbar1'd1, d1 - f lbar1) isd with
// f = (lbar0 d0 - lbar1'd1 + d0) ilb, and lam + a d stays inside iff a (||rho1|| - rho0) < 1. Returns
// ||rho1|| - rho0 (<= 0: no limit); one square root, no division.
template <int D>
inline double InverseStepCone(const double* lbar, double isd, double ilb, const double* dv, int dim) {
  const int d = D > 0 ? D : dim;
  double l1d1 = 0.0;
  for (int i = 1; i < d; ++i) l1d1 += lbar[i] * dv[i];
  const double ld = lbar[0] * dv[0] - l1d1;
  const double f = (ld + dv[0]) * ilb;
  double r1 = 0.0;
  for (int i = 1; i < d; ++i) {
    const double r = dv[i] - f * lbar[i];
    r1 += r * r;
  }
  return (std::sqrt(r1) - ld) * isd;
}

// Reverse Cuthill-McKee order of an undirected graph in adjacency-list (CSR) form: order[k] is the
// node placed k-th. Every connected component starts from a pseudo-peripheral node (George and Liu),
// and neighbours are visited by increasing degree, which gives a small bandwidth on path-like graphs.
std::vector<int> ReverseCuthillMcKee(int nodes, const std::vector<int>& adj_ptr, const std::vector<int>& adj) {
  std::vector<int> order;
  order.reserve(nodes);
  std::vector<char> placed(nodes, 0);
  std::vector<int> stamp(nodes, -1), queue(nodes), neighbours;
  int stamp_id = 0;
  auto degree = [&](int v) { return adj_ptr[v + 1] - adj_ptr[v]; };
  // Breadth-first levels from root; returns the eccentricity and leaves the last level in
  // queue[last_begin, last_end).
  int last_begin = 0, last_end = 0;
  auto levels = [&](int root) {
    const int id = stamp_id++;
    int head = 0, tail = 0, depth = 0;
    queue[tail++] = root;
    stamp[root] = id;
    while (head < tail) {
      const int level_end = tail;
      last_begin = head;
      last_end = level_end;
      for (; head < level_end; ++head) {
        const int v = queue[head];
        for (int q = adj_ptr[v]; q < adj_ptr[v + 1]; ++q) {
          const int u = adj[q];
          if (stamp[u] != id) {
            stamp[u] = id;
            queue[tail++] = u;
          }
        }
      }
      if (tail > level_end) ++depth;
    }
    return depth;
  };
  for (int start = 0; start < nodes; ++start) {
    if (placed[start]) continue;
    int root = start;
    int eccentricity = levels(root);
    for (int guard = 0; guard < 8; ++guard) {
      int candidate = queue[last_begin];
      for (int q = last_begin; q < last_end; ++q) {
        if (degree(queue[q]) < degree(candidate)) candidate = queue[q];
      }
      const int e = levels(candidate);
      if (e <= eccentricity) break;
      root = candidate;
      eccentricity = e;
    }
    const std::size_t begin = order.size();
    order.push_back(root);
    placed[root] = 1;
    for (std::size_t head = begin; head < order.size(); ++head) {
      const int v = order[head];
      neighbours.clear();
      for (int q = adj_ptr[v]; q < adj_ptr[v + 1]; ++q) {
        if (!placed[adj[q]]) {
          placed[adj[q]] = 1;
          neighbours.push_back(adj[q]);
        }
      }
      std::sort(neighbours.begin(), neighbours.end(), [&](int a, int b) {
        return degree(a) != degree(b) ? degree(a) < degree(b) : a < b;
      });
      order.insert(order.end(), neighbours.begin(), neighbours.end());
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

}  // namespace

struct Solver::Workspace {
  // ---------------- pattern signature (what must match for reuse) ----------------
  bool analyzed = false;
  int n = 0, p = 0, m = 0;
  ConeSpec cones;
  int sparse_min_dim = 0;
  std::vector<int> sig_a_ptr, sig_a_idx, sig_g_ptr, sig_g_idx;

  // ---------------- internal problem data ----------------
  int num_orthant = 0;
  int degree = 0;
  std::vector<SocBlock> socs;
  Csc A;   // p x n
  Csc G;   // m x n, rotated rows transformed
  // For every stored entry of the user's G (in InnerIterator order): where it goes in G.val.
  std::vector<int> g_target0, g_target1;  // g_target1 = -1 if only one target
  std::vector<double> g_coef0, g_coef1;
  std::vector<signed char> row_kind;      // 0 normal, 1 first rotated row, 2 second rotated row
  Eigen::VectorXd c, b, h;                // internal copies (h transformed)

  // ---------------- KKT system ----------------
  int num_kkt = 0;
  std::vector<int> perm, pinv;           // perm[new] = old, pinv[old] = new
  std::vector<int> k_ptr, k_idx;         // permuted upper triangle, diagonal last in each column
  std::vector<double> k_val;
  std::vector<signed char> k_sign;       // expected pivot sign (permuted)
  std::vector<double> k_reg;             // static regularization on the diagonal (permuted)
  std::vector<int> diag_slot;            // unpermuted index -> slot of its diagonal
  std::vector<int> a_slot, g_slot;       // per internal A / G entry -> slot of (col, row) entry
  std::vector<int> dense_slots;          // per dense cone: strict upper triangle slots, row-major
  std::vector<int> u_slots, v_slots;     // per expanded cone: slot of (z_i, u-row), (z_i, v-row)
  SparseLdl ldl;

  // ---------------- iterates and work vectors ----------------
  Eigen::VectorXd x, y, z, s;
  double tau = 1.0, kappa = 1.0;
  Eigen::VectorXd rx, ry, rz;              // residuals
  Eigen::VectorXd Ax, Gx, Aty, Gtz;        // products
  Eigen::VectorXd w_orthant;               // orthant scaling sqrt(s/z)
  Eigen::VectorXd h_orthant, hinv_orthant; // s/z and z/s (orthant blocks of W'W and its inverse)
  Eigen::VectorXd wbar;                    // SOC scaling vectors (rows of socs)
  std::vector<double> eta;                 // SOC scaling factors
  Eigen::VectorXd lambda;                  // scaled point W z
  // Step data of lambda, once per iteration: orthant rows 1 / lambda_i, cone rows lambda / sqrt(det);
  // per cone 1 / sqrt(det lambda) and 1 / (lbar0 + 1) (see InverseStepCone).
  Eigen::VectorXd lambda_step;
  std::vector<double> lambda_isd, lambda_ilb;
  Eigen::VectorXd rhs1, sol1, rhs2, sol2;  // unpermuted KKT vectors of size num_kkt
  Eigen::VectorXd perm_rhs, perm_sol, perm_res, perm_corr;
  Eigen::VectorXd dx, dy, dz, ds, ds_aff, dz_aff, dtmp1, dtmp2, dtmp3, ldiv;
  Eigen::VectorXd best_x, best_y, best_z, best_s;
  std::vector<double> local_cone;          // scratch of the largest cone (fused passes)
  double best_tau = 1.0, best_kappa = 1.0;

  int refinement_counter = 0;
  double refinement_floor = 0.0;  // refinement_mu_factor * mu of the current iteration
  // The static regularization in use: Options::static_regularization, raised 100-fold (for the rest
  // of the solve) each time a factorization breaks down (see Solve).
  double static_reg = 0.0;

  // ---------------- reduced (normal-equation) KKT path ----------------
  // Unknowns of the reduced system, unpermuted: x_j -> j, y_i -> n + i, and per expanded cone q two
  // border unknowns n + p + 2q (its v-row, pivot +1) and n + p + 2q + 1 (its u-row, pivot -1).
  KktMethod method_option = KktMethod::kAutomatic;  // part of the pattern signature
  bool reduced = false;                 // the method chosen by Analyze
  int nr = 0;
  std::vector<int> r_pinv;              // unpermuted reduced unknown -> skyline row
  std::vector<signed char> r_sign;      // expected pivot sign per skyline row
  SkylineLdl sky;
  std::vector<int> r_diag_slot;         // per unpermuted reduced unknown
  std::vector<int> r_a_slot;            // per internal A entry: slot of (y_i, x_j)
  // G by rows: row r has entries [gr_ptr[r], gr_ptr[r+1]) with column gr_col and index gr_val into G.val.
  std::vector<int> gr_ptr, gr_col, gr_val;
  // Rows scaled by a scalar (orthant rows, rows of expanded cones): slots of the products of their
  // entries e <= f (row-major over the row's entries), starting at pair_ptr[r].
  std::vector<int> pair_ptr, pair_slot;
  std::vector<double> pair_coef;        // g_e g_f per pair (constant while the data are)
  std::vector<double> cone_pair_coef;   // per dense-cone pair (a, b): (Gc' J Gc)_ab, constant
  std::vector<double> r_constant;       // skyline values that do not change: A, +-delta, border +-1
  // Small (dense) and expanded cones: the union of the columns of their rows (cone_var_ptr per entry of
  // socs), each row entry's position in that union (gr_local), the slots of the union's pairs a <= b
  // (dense cones, from cone_pair_ptr) and the border slots (expanded cones, one per union column).
  std::vector<int> cone_var_ptr, cone_var, gr_local, cone_pair_ptr, cone_pair_slot, border_u_slot,
      border_v_slot;
  std::vector<double> local_g;          // dense scratch of one cone
  Eigen::VectorXd red1, red2;           // skyline-ordered vectors of size nr
  Eigen::VectorXd red_t1, red_t2, red_m1, red_n;  // sizes m, m, m, n
  Eigen::VectorXd full_res, full_corr;  // size num_kkt

  bool PatternMatches(const Problem& problem, int min_dim, KktMethod method) const;
  void Analyze(const Problem& problem, int min_dim, KktMethod method);
  void AnalyzeAugmented();
  // Builds the reduced system's ordering and profile; returns false (and builds nothing) if `automatic`
  // and the profile is too wide for the banded method to pay off.
  bool AnalyzeReduced(bool automatic);
  void LoadValues(const Problem& problem, const Options& options);

  // Cone operations on vectors of size m.
  bool ComputeScaling();
  // out = W'W in (Inverse false) or (W'W)^{-1} in (Inverse true).
  template <bool Inverse>
  void ApplyH(const double* in, double* out) const;
  bool StrictlyInterior(const double* u) const;  // the test that ComputeScaling relies on
  void AddIdentity(double* u, double alpha) const;

  // Fused passes of the Newton step (one sweep over the cones each).
  // The cone part of a direction's right-hand side: with d = lambda o lambda (predictor) or
  // d = lambda o lambda + ds_aff o dz_aff - sigma_mu e (corrector), sets ldiv = lambda \ d,
  // dtmp2 = W ldiv and rhs_z = -eta_r rz + dtmp2.
  void ComplementarityRhs(bool corrector, double sigma_mu, double eta_r, double* rhs_z);
  // Completes a direction from dz: dz_aff = W dz, ds = -dtmp2 - W dz_aff, ds_aff = -ldiv - dz_aff
  // (= W^{-1} ds); returns the largest step keeping lambda + a ds_aff and lambda + a dz_aff in K.
  double CompleteDirection();
  // dtmp1 = s + step ds and dtmp3 = z + step dz; true if both are strictly inside K.
  bool TrialPoint(double step);

  // Loads the current scaling into the KKT matrix and factorizes it; returns the number of
  // dynamically regularized pivots.
  int FactorKkt(const Options& options);
  void UpdateKktScaling(double delta);
  int Factor(const Options& options);
  int FactorReduced(const Options& options);
  void LoadReducedValues();
  // Sets static_reg and the KKT entries that depend on it (the scaled entries follow at the next
  // FactorKkt).
  void SetStaticRegularization(double delta);
  // Leaves the reduced method for the augmented one in the middle of a solve (the data and the
  // regularization in use are reloaded); the next Solve() analyzes the pattern afresh.
  void SwitchToAugmented();
  void LoadAugmentedData();  // A and G into the augmented KKT matrix
  // The iterate (x, y, z, s, tau, kappa) moves halfway back to the best one saved (the lookback in
  // Solve: from a step taken at the best iterate, the midpoint of that step).
  void MoveHalfwayToBest() {
    x = 0.5 * (x + best_x);
    y = 0.5 * (y + best_y);
    z = 0.5 * (z + best_z);
    s = 0.5 * (s + best_s);
    tau = 0.5 * (tau + best_tau);
    kappa = 0.5 * (kappa + best_kappa);
  }
  // The iterate (x, y, z, s, tau, kappa) becomes the best one saved.
  void RestoreBest() {
    x = best_x;
    y = best_y;
    z = best_z;
    s = best_s;
    tau = best_tau;
    kappa = best_kappa;
  }
  // Reduced path: sol = K^{-1} rhs (unrefined, unpermuted full vectors) for one or two right-hand sides.
  void SolveReduced(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol);
  void SolveReduced2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a, const Eigen::VectorXd& rhs_b,
                     Eigen::VectorXd& sol_b);
  void ReducedRhs(const Eigen::VectorXd& rhs, Eigen::VectorXd& red, Eigen::VectorXd& t);
  void ReducedSolution(const Eigen::VectorXd& red, const Eigen::VectorXd& t, Eigen::VectorXd& sol);
  // out = K v for the unregularized full system in (x, y, z) (unpermuted; the expansion entries of
  // out are not touched).
  void FullKktMultiply(const Eigen::VectorXd& v, Eigen::VectorXd& out);
  void RefineReduced(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const Options& options,
                     int max_refinement_steps);
  // The refinement loop shared by both methods, on the first `len` entries: multiply(v, out) sets
  // out = K v (unregularized), correct(r, out) sets out = K~^{-1} r (the factor). res and cand are
  // work vectors. Returns true if sol changed.
  template <typename Multiply, typename Correct>
  bool Refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, Eigen::VectorXd& res, Eigen::VectorXd& cand,
              int len, const Options& options, int max_steps, Multiply multiply, Correct correct);
  // Solves K sol = rhs (unpermuted vectors) with iterative refinement on the unregularized matrix.
  void SolveKkt(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const Options& options,
                int max_refinement_steps);
  // Two unrefined solves in one sweep over the factor.
  void SolveKkt2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a, const Eigen::VectorXd& rhs_b,
                 Eigen::VectorXd& sol_b);
  // Iterative refinement of sol (an approximate solution of K sol = rhs, unpermuted) on the
  // unregularized matrix.
  void RefineKkt(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const Options& options,
                 int max_refinement_steps);
  void KktMultiplyUnregularized(const double* v, double* out) const;  // permuted space
};

bool Solver::Workspace::PatternMatches(const Problem& problem, int min_dim, KktMethod method) const {
  if (!analyzed || min_dim != sparse_min_dim || method != method_option) return false;
  if (problem.num_variables() != n || problem.num_equalities() != p || problem.num_cone_rows() != m) {
    return false;
  }
  if (problem.cones.num_nonnegative != cones.num_nonnegative || problem.cones.soc_dims != cones.soc_dims ||
      problem.cones.rotated_dims != cones.rotated_dims) {
    return false;
  }
  auto same = [](const Eigen::SparseMatrix<double>& M, const std::vector<int>& ptr,
                 const std::vector<int>& idx) {
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

void Solver::Workspace::Analyze(const Problem& problem, int min_dim, KktMethod method) {
  n = problem.num_variables();
  method_option = method;
  p = problem.num_equalities();
  m = problem.num_cone_rows();
  cones = problem.cones;
  sparse_min_dim = min_dim;
  auto signature = [](const Eigen::SparseMatrix<double>& M, std::vector<int>& ptr,
                      std::vector<int>& idx) {
    ptr.assign(M.outerSize() + 1, 0);
    idx.clear();
    for (int j = 0; j < M.outerSize(); ++j) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(M, j); it; ++it) idx.push_back(it.row());
      ptr[j + 1] = static_cast<int>(idx.size());
    }
  };
  signature(problem.A, sig_a_ptr, sig_a_idx);
  signature(problem.G, sig_g_ptr, sig_g_idx);

  // ---- cones ----
  num_orthant = cones.num_nonnegative;
  degree = cones.Degree();
  socs.clear();
  row_kind.assign(m, 0);
  int row = num_orthant;
  int ext = n + p + m;
  int dense_count = 0, expanded_count = 0;
  auto add_cone = [&](int dim, bool rotated) {
    SocBlock blk;
    blk.start = row;
    blk.dim = dim;
    blk.rotated = rotated;
    blk.expanded = dim >= min_dim && dim >= 2;
    if (blk.expanded) {
      blk.ext = ext;
      ext += 2;
      blk.slot_offset = expanded_count;
      expanded_count += dim;
    } else {
      blk.slot_offset = dense_count;
      dense_count += dim * (dim - 1) / 2;
    }
    if (rotated) {
      row_kind[row] = 1;
      row_kind[row + 1] = 2;
    }
    socs.push_back(blk);
    row += dim;
  };
  for (int d : cones.soc_dims) add_cone(d, false);
  for (int d : cones.rotated_dims) add_cone(d, true);
  num_kkt = ext;

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
      const int r0 = row_kind[r] == 2 ? r - 1 : r;
      const int count = row_kind[r] == 0 ? 1 : 2;
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
      if (row_kind[r] == 0) {
        g_target0[q] = position[r];
        g_coef0[q] = 1.0;
      } else {
        // t0 = (s0 + s1)/sqrt2, t1 = (s0 - s1)/sqrt2.
        const int r0 = row_kind[r] == 1 ? r : r - 1;
        g_target0[q] = position[r0];
        g_coef0[q] = kSqrtHalf;
        g_target1[q] = position[r0 + 1];
        g_coef1[q] = row_kind[r] == 1 ? kSqrtHalf : -kSqrtHalf;
      }
    }
    G.ptr[j + 1] = static_cast<int>(G.idx.size());
  }
  G.val.assign(G.idx.size(), 0.0);

  // ---- KKT method ----
  reduced = method != KktMethod::kAugmentedSparse && AnalyzeReduced(method == KktMethod::kAutomatic);
  if (!reduced) AnalyzeAugmented();

  // ---- work memory ----
  for (Eigen::VectorXd* v : {&x, &rx, &Aty, &Gtz, &dx, &best_x}) v->setZero(n);
  for (Eigen::VectorXd* v : {&y, &ry, &Ax, &dy, &best_y}) v->setZero(p);
  for (Eigen::VectorXd* v : {&z, &s, &rz, &Gx, &w_orthant, &h_orthant, &hinv_orthant, &wbar, &lambda, &lambda_step, &dz, &ds, &ds_aff, &dz_aff,
                             &dtmp1, &dtmp2, &dtmp3, &ldiv, &best_z, &best_s}) {
    v->setZero(m);
  }
  for (Eigen::VectorXd* v : {&rhs1, &sol1, &rhs2, &sol2, &full_res, &full_corr}) v->setZero(num_kkt);
  eta.assign(socs.size(), 1.0);
  lambda_isd.assign(socs.size(), 1.0);
  lambda_ilb.assign(socs.size(), 0.5);
  {
    int largest = 0;
    for (const SocBlock& blk : socs) largest = std::max(largest, blk.dim);
    local_cone.assign(largest, 0.0);
  }
  analyzed = true;
}

bool Solver::Workspace::AnalyzeReduced(bool automatic) {
  int num_expanded = 0;
  for (const SocBlock& blk : socs) num_expanded += blk.expanded ? 1 : 0;
  const int nxy = n + p;
  // The x block G' W^{-2} G is singular (up to the regularization) unless G has full column rank, for
  // which m >= n and no empty column are necessary: otherwise the elimination meets pivots of size
  // delta and the factor overflows. Border rows are full width; beyond a few of them the augmented
  // system is the better choice.
  if (m < n || (automatic && num_expanded > 8)) return false;
  for (int j = 0; j < n; ++j) {
    if (G.ptr[j] == G.ptr[j + 1]) return false;
  }

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
  nr = nxy + 2 * num_expanded;
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
  if (automatic && stored > 16LL * std::max(nxy, 1)) {
    reduced = false;
    return false;
  }
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
  auto slot = [&](int a, int b2) {  // unpermuted reduced unknowns
    const int i = r_pinv[a], j = r_pinv[b2];
    return i >= j ? sky.Slot(i, j) : sky.Slot(j, i);
  };

  // ---- slots ----
  r_diag_slot.assign(nr, 0);
  for (int k = 0; k < nr; ++k) r_diag_slot[k] = slot(k, k);
  r_sign.assign(nr, 1);
  for (int i = 0; i < p; ++i) r_sign[r_pinv[n + i]] = -1;
  for (int q = 0; q < num_expanded; ++q) r_sign[r_pinv[nxy + 2 * q + 1]] = -1;
  r_a_slot.assign(A.idx.size(), 0);
  for (int j = 0; j < n; ++j) {
    for (int q = A.ptr[j]; q < A.ptr[j + 1]; ++q) r_a_slot[q] = slot(j, n + A.idx[q]);
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
        for (int f = e; f < gr_ptr[r + 1]; ++f) pair_slot.push_back(slot(gr_col[e], gr_col[f]));
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
          border_v_slot.push_back(slot(nxy + 2 * q, cone_var[a]));
          border_u_slot.push_back(slot(nxy + 2 * q + 1, cone_var[a]));
        }
        ++q;
      } else {
        for (int a = begin; a < end; ++a) {
          for (int b2 = a; b2 < end; ++b2) cone_pair_slot.push_back(slot(cone_var[a], cone_var[b2]));
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
  return true;
}

void Solver::Workspace::AnalyzeAugmented() {
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

  ldl.Analyze(num_kkt, k_ptr, k_idx);
  for (Eigen::VectorXd* v : {&perm_rhs, &perm_sol, &perm_res, &perm_corr}) v->setZero(num_kkt);
}

void Solver::Workspace::LoadValues(const Problem& problem, const Options& options) {
  c = problem.c;
  b = problem.b;
  h = problem.h;
  for (const SocBlock& blk : socs) {
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
  if (!reduced) LoadAugmentedData();
  SetStaticRegularization(options.static_regularization);
}

void Solver::Workspace::LoadAugmentedData() {
  for (std::size_t e = 0; e < A.val.size(); ++e) k_val[a_slot[e]] = A.val[e];
  for (std::size_t e = 0; e < G.val.size(); ++e) k_val[g_slot[e]] = G.val[e];
}

void Solver::Workspace::SwitchToAugmented() {
  reduced = false;
  AnalyzeAugmented();
  LoadAugmentedData();
  SetStaticRegularization(static_reg);
  analyzed = false;
}

void Solver::Workspace::SetStaticRegularization(double delta) {
  static_reg = delta;
  if (reduced) {
    LoadReducedValues();
    return;
  }
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

// ---------------------------------------------------------------------------------------------
// Cone operations. Orthant rows [0, num_orthant), then the second-order cones in `socs`.

bool Solver::Workspace::ComputeScaling() {
  if (num_orthant > 0) {
    // Branch-free (vectorized) passes; the interior test first.
    const auto so = s.head(num_orthant).array();
    const auto zo = z.head(num_orthant).array();
    if (!(so.minCoeff() > 0.0 && zo.minCoeff() > 0.0)) return false;  // also catches NaN
    // One division and one root per row: with r = 1 / (s z), lambda = sqrt(s z) (= w z),
    // 1 / lambda = lambda r, w = sqrt(s / z) = s / lambda, s / z = s^2 r and z / s = z^2 r.
    auto lo = lambda.head(num_orthant).array();
    auto li = lambda_step.head(num_orthant).array();
    auto r = dtmp1.head(num_orthant).array();  // scratch
    r = (so * zo).inverse();
    lo = (so * zo).sqrt();
    li = lo * r;
    w_orthant.head(num_orthant).array() = so * li;
    h_orthant.head(num_orthant).array() = so.square() * r;
    hinv_orthant.head(num_orthant).array() = zo.square() * r;
  }
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    const int o = blk.start;
    const bool ok =
        blk.dim == 3
            ? NtScalingCone<3>(s.data() + o, z.data() + o, wbar.data() + o, eta[k], lambda.data() + o,
                               lambda_step.data() + o, lambda_isd[k], lambda_ilb[k], 3)
            : NtScalingCone<0>(s.data() + o, z.data() + o, wbar.data() + o, eta[k], lambda.data() + o,
                               lambda_step.data() + o, lambda_isd[k], lambda_ilb[k], blk.dim);
    if (!ok) return false;
  }
  return true;
}

template <bool Inverse>
void Solver::Workspace::ApplyH(const double* in, double* out) const {
  const double* h = Inverse ? hinv_orthant.data() : h_orthant.data();
  for (int i = 0; i < num_orthant; ++i) out[i] = h[i] * in[i];
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    const double* w = wbar.data() + blk.start;
    if (blk.dim == 3) {
      ApplyHCone<3, Inverse>(w, eta[k], in + blk.start, out + blk.start, 3);
    } else {
      ApplyHCone<0, Inverse>(w, eta[k], in + blk.start, out + blk.start, blk.dim);
    }
  }
}

bool Solver::Workspace::StrictlyInterior(const double* u) const {
  if (num_orthant > 0 && !(Eigen::Map<const Eigen::VectorXd>(u, num_orthant).minCoeff() > 0.0)) return false;
  for (const SocBlock& blk : socs) {
    double n1 = 0.0;
    for (int i = 1; i < blk.dim; ++i) n1 += u[blk.start + i] * u[blk.start + i];
    n1 = std::sqrt(n1);
    const double u0 = u[blk.start];
    if (!(u0 - n1 > 0.0 && (u0 - n1) * (u0 + n1) > 0.0)) return false;
  }
  return true;
}

void Solver::Workspace::AddIdentity(double* u, double alpha) const {
  for (int i = 0; i < num_orthant; ++i) u[i] += alpha;
  for (const SocBlock& blk : socs) u[blk.start] += alpha;
}

// ---------------------------------------------------------------------------------------------
// Fused passes of the Newton step.

namespace {

// out = u o v for one cone.
template <int D>
inline void JordanProductCone(const double* u, const double* v, double* out, int dim) {
  const int d = D > 0 ? D : dim;
  double dot = u[0] * v[0];
  for (int i = 1; i < d; ++i) dot += u[i] * v[i];
  for (int i = 1; i < d; ++i) out[i] = u[0] * v[i] + v[0] * u[i];
  out[0] = dot;
}

// out = l \ v for one cone (l strictly inside).
template <int D>
inline void JordanDivideCone(const double* l, const double* v, double* out, int dim) {
  const int d = D > 0 ? D : dim;
  double l1 = 0.0, l1v1 = 0.0;
  for (int i = 1; i < d; ++i) {
    l1 += l[i] * l[i];
    l1v1 += l[i] * v[i];
  }
  const double det = l[0] * l[0] - l1;
  const double u0 = (l[0] * v[0] - l1v1) / det;
  const double inv_l0 = 1.0 / l[0];
  for (int i = 1; i < d; ++i) out[i] = (v[i] - u0 * l[i]) * inv_l0;
  out[0] = u0;
}

}  // namespace

void Solver::Workspace::ComplementarityRhs(bool corrector, double sigma_mu, double eta_r, double* rhs_z) {
  const double* l = lambda.data();
  const double* a = ds_aff.data();
  const double* b = dz_aff.data();
  const double* r = rz.data();
  double* ld = ldiv.data();
  double* t2 = dtmp2.data();
  for (int i = 0; i < num_orthant; ++i) {
    double d = l[i] * l[i];
    if (corrector) d += a[i] * b[i] - sigma_mu;
    ld[i] = d * lambda_step[i];
    t2[i] = w_orthant[i] * ld[i];
    rhs_z[i] = -eta_r * r[i] + t2[i];
  }
  double d[64];
  std::vector<double>& big = local_cone;
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    const int o = blk.start;
    const double* w = wbar.data() + o;
    double* dv = blk.dim <= 64 ? d : big.data();
    if (blk.dim == 3) {
      JordanProductCone<3>(l + o, l + o, dv, 3);
      if (corrector) {
        double e[3];
        JordanProductCone<3>(a + o, b + o, e, 3);
        for (int i = 0; i < 3; ++i) dv[i] += e[i];
        dv[0] -= sigma_mu;
      }
      JordanDivideCone<3>(l + o, dv, ld + o, 3);
      ApplyWCone<3>(w, eta[k], ld + o, t2 + o, 3);
      for (int i = 0; i < 3; ++i) rhs_z[o + i] = -eta_r * r[o + i] + t2[o + i];
    } else {
      const int dim = blk.dim;
      JordanProductCone<0>(l + o, l + o, dv, dim);
      if (corrector) {
        // The Jordan product added entry by entry (no second buffer for large cones).
        double dot = a[o] * b[o];
        for (int i = 1; i < dim; ++i) {
          dot += a[o + i] * b[o + i];
          dv[i] += a[o] * b[o + i] + b[o] * a[o + i];
        }
        dv[0] += dot - sigma_mu;
      }
      JordanDivideCone<0>(l + o, dv, ld + o, dim);
      ApplyWCone<0>(w, eta[k], ld + o, t2 + o, dim);
      for (int i = 0; i < dim; ++i) rhs_z[o + i] = -eta_r * r[o + i] + t2[o + i];
    }
  }
}

double Solver::Workspace::CompleteDirection() {
  const double* dzv = dz.data();
  const double* ld = ldiv.data();
  const double* t2 = dtmp2.data();
  double* dza = dz_aff.data();
  double* dsa = ds_aff.data();
  double* dsv = ds.data();
  for (int i = 0; i < num_orthant; ++i) {
    const double w = w_orthant[i];
    dza[i] = w * dzv[i];
    dsv[i] = -t2[i] - w * dza[i];
    dsa[i] = -ld[i] - dza[i];
  }
  // The largest inverse step over all rows and cones (no divisions: 1 / lambda is precomputed).
  double worst = 0.0;
  if (num_orthant > 0) {
    const auto li = lambda_step.head(num_orthant).array();
    worst = std::max((-Eigen::Map<const Eigen::ArrayXd>(dsa, num_orthant) * li).maxCoeff(),
                     (-Eigen::Map<const Eigen::ArrayXd>(dza, num_orthant) * li).maxCoeff());
  }
  double tmp[64];
  std::vector<double>& big = local_cone;
  const double* lbar = lambda_step.data();
  for (std::size_t k = 0; k < socs.size(); ++k) {
    const SocBlock& blk = socs[k];
    const int o = blk.start;
    const double* w = wbar.data() + o;
    if (blk.dim == 3) {
      ApplyWCone<3>(w, eta[k], dzv + o, dza + o, 3);
      ApplyWCone<3>(w, eta[k], dza + o, tmp, 3);
      for (int i = 0; i < 3; ++i) {
        dsv[o + i] = -t2[o + i] - tmp[i];
        dsa[o + i] = -ld[o + i] - dza[o + i];
      }
      worst = std::max(worst, std::max(InverseStepCone<3>(lbar + o, lambda_isd[k], lambda_ilb[k], dsa + o, 3),
                                       InverseStepCone<3>(lbar + o, lambda_isd[k], lambda_ilb[k], dza + o, 3)));
    } else {
      const int dim = blk.dim;
      double* tv = dim <= 64 ? tmp : big.data();
      ApplyWCone<0>(w, eta[k], dzv + o, dza + o, dim);
      ApplyWCone<0>(w, eta[k], dza + o, tv, dim);
      for (int i = 0; i < dim; ++i) {
        dsv[o + i] = -t2[o + i] - tv[i];
        dsa[o + i] = -ld[o + i] - dza[o + i];
      }
      worst = std::max(worst, std::max(InverseStepCone<0>(lbar + o, lambda_isd[k], lambda_ilb[k], dsa + o, dim),
                                       InverseStepCone<0>(lbar + o, lambda_isd[k], lambda_ilb[k], dza + o, dim)));
    }
  }
  if (!(worst == worst)) return 0.0;  // NaN: no step
  return worst > 0.0 ? 1.0 / worst : std::numeric_limits<double>::infinity();
}

bool Solver::Workspace::TrialPoint(double step) {
  dtmp1 = s + step * ds;
  dtmp3 = z + step * dz;
  return StrictlyInterior(dtmp1.data()) && StrictlyInterior(dtmp3.data());
}

// ---------------------------------------------------------------------------------------------
// KKT system.

int Solver::Workspace::FactorKkt(const Options& options) {
  if (reduced) return FactorReduced(options);
  UpdateKktScaling(static_reg);
  return Factor(options);
}

// The constant parts of the reduced matrix: +-delta on the diagonal, A, the border's +-1; and the
// products of G's entries that the scaled terms multiply.
void Solver::Workspace::LoadReducedValues() {
  const double delta = static_reg;
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
// ut ut' - vt vt') with ut = J u, vt = J v from the decomposition of W'W in UpdateKktScaling, so the
// cone adds eta^{-2} G' D G to the band and the columns G' ut / eta (row with pivot -1) and
// G' vt / eta (row with pivot +1) to the border.
int Solver::Workspace::FactorReduced(const Options& options) {
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
      const double w0 = w[0];
      const double t2 = 2.0 * w0 * w0 - 1.0;
      const double d0 = 0.5 / t2;
      const double u0 = std::sqrt(t2 - d0);
      const double u1 = 2.0 * w0 / u0;
      const double v1 = std::sqrt(2.0 * (1.0 + d0)) / u0;
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
void Solver::Workspace::ReducedRhs(const Eigen::VectorXd& rhs, Eigen::VectorXd& red, Eigen::VectorXd& t) {
  ApplyH<true>(rhs.data() + n + p, t.data());
  G.MultiplyTransposed(t.data(), red_n.data());
  for (int j = 0; j < n; ++j) red[r_pinv[j]] = rhs[j] + red_n[j];
  for (int i = 0; i < p; ++i) red[r_pinv[n + i]] = rhs[n + i];
  for (int k = n + p; k < nr; ++k) red[k] = 0.0;
}

// x, y from the solved reduced system; z = W^{-2} (G x - r3) = W^{-2} G x - t.
void Solver::Workspace::ReducedSolution(const Eigen::VectorXd& red, const Eigen::VectorXd& t,
                                        Eigen::VectorXd& sol) {
  for (int j = 0; j < n; ++j) sol[j] = red[r_pinv[j]];
  for (int i = 0; i < p; ++i) sol[n + i] = red[r_pinv[n + i]];
  G.Multiply(sol.data(), red_m1.data());
  ApplyH<true>(red_m1.data(), sol.data() + n + p);
  sol.segment(n + p, m) -= t;
  if (num_kkt > n + p + m) sol.tail(num_kkt - n - p - m).setZero();
}

void Solver::Workspace::SolveReduced(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol) {
  ReducedRhs(rhs, red1, red_t1);
  sky.Solve(red1.data());
  ReducedSolution(red1, red_t1, sol);
}

void Solver::Workspace::SolveReduced2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a,
                                      const Eigen::VectorXd& rhs_b, Eigen::VectorXd& sol_b) {
  ReducedRhs(rhs_a, red1, red_t1);
  ReducedRhs(rhs_b, red2, red_t2);
  sky.Solve2(red1.data(), red2.data());
  ReducedSolution(red1, red_t1, sol_a);
  ReducedSolution(red2, red_t2, sol_b);
}

void Solver::Workspace::FullKktMultiply(const Eigen::VectorXd& v, Eigen::VectorXd& out) {
  A.MultiplyTransposed(v.data() + n, out.data());
  G.MultiplyTransposed(v.data() + n + p, red_n.data());
  out.head(n) += red_n;
  A.Multiply(v.data(), out.data() + n);
  G.Multiply(v.data(), out.data() + n + p);
  ApplyH<false>(v.data() + n + p, red_m1.data());
  out.segment(n + p, m) -= red_m1;
}

// Refinement on the full unregularized system: its residual also catches the rounding of forming
// G' W^{-2} G (entries of W^{-2} span many orders of magnitude near the optimum), which refining the
// reduced system alone does not (measured: twice the iterations on the temporal problems).
template <typename Multiply, typename Correct>
bool Solver::Workspace::Refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, Eigen::VectorXd& res,
                               Eigen::VectorXd& cand, int len, const Options& options, int max_steps,
                               Multiply multiply, Correct correct) {
  const double bound = std::max(options.refinement_tolerance, refinement_floor) * (1.0 + NormInf(rhs.data(), len));
  multiply(sol, res);
  res.head(len) = rhs.head(len) - res.head(len);
  double norm = NormInf(res.data(), len);
  bool changed = false;
  for (int step = 0; step < max_steps && norm > bound; ++step) {
    // Candidate sol + K~^{-1} r, accepted only if it reduces the residual of the exact system.
    correct(res, cand);
    cand.head(len) += sol.head(len);
    multiply(cand, res);
    res.head(len) = rhs.head(len) - res.head(len);
    const double new_norm = NormInf(res.data(), len);
    ++refinement_counter;
    if (!(new_norm < norm)) break;  // no progress (or NaN): keep the previous solution
    sol.head(len) = cand.head(len);
    changed = true;
    if (new_norm > options.refinement_stagnation * norm) break;  // slow: not worth another solve
    norm = new_norm;
  }
  return changed;
}

void Solver::Workspace::RefineReduced(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const Options& options,
                                      int max_refinement_steps) {
  Refine(rhs, sol, full_res, full_corr, n + p + m, options, max_refinement_steps,
         [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { FullKktMultiply(v, out); },
         [&](const Eigen::VectorXd& r, Eigen::VectorXd& out) { SolveReduced(r, out); });
}

void Solver::Workspace::UpdateKktScaling(double delta) {
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
      // W'W = eta^2 (D + u u' - v v'), D = diag(d0, 1, ..., 1), u = (u0, u1 w1), v = (0, v1 w1), with
      // d0 = 1 / (2 (2 w0^2 - 1)) so that D - v v' stays positive definite (quasi-definiteness).
      const double w0 = w[0];
      const double t2 = 2.0 * w0 * w0 - 1.0;
      const double d0 = 0.5 / t2;
      const double u0 = std::sqrt(t2 - d0);
      const double u1 = 2.0 * w0 / u0;
      const double v1 = std::sqrt(2.0 * (1.0 + d0)) / u0;
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

int Solver::Workspace::Factor(const Options& options) {
  return ldl.Factor(k_val.data(), k_sign.data(), options.dynamic_regularization_threshold,
                    options.dynamic_regularization);
}

void Solver::Workspace::KktMultiplyUnregularized(const double* v, double* out) const {
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

void Solver::Workspace::SolveKkt(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const Options& options,
                                 int max_refinement_steps) {
  if (reduced) {
    SolveReduced(rhs, sol);
    if (max_refinement_steps > 0) RefineReduced(rhs, sol, options, max_refinement_steps);
    return;
  }
  for (int k = 0; k < num_kkt; ++k) perm_sol[k] = rhs[perm[k]];
  ldl.Solve(perm_sol.data());
  for (int k = 0; k < num_kkt; ++k) sol[perm[k]] = perm_sol[k];
  if (max_refinement_steps > 0) RefineKkt(rhs, sol, options, max_refinement_steps);
}

void Solver::Workspace::SolveKkt2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a,
                                  const Eigen::VectorXd& rhs_b, Eigen::VectorXd& sol_b) {
  if (reduced) {
    SolveReduced2(rhs_a, sol_a, rhs_b, sol_b);
    return;
  }
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

void Solver::Workspace::RefineKkt(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const Options& options,
                                  int max_refinement_steps) {
  if (reduced) {
    RefineReduced(rhs, sol, options, max_refinement_steps);
    return;
  }
  for (int k = 0; k < num_kkt; ++k) {
    perm_rhs[k] = rhs[perm[k]];
    perm_sol[k] = sol[perm[k]];
  }
  const bool changed = Refine(
      perm_rhs, perm_sol, perm_res, perm_corr, num_kkt, options, max_refinement_steps,
      [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { KktMultiplyUnregularized(v.data(), out.data()); },
      [&](const Eigen::VectorXd& r, Eigen::VectorXd& out) {
        out = r;
        ldl.Solve(out.data());
      });
  if (changed) {
    for (int k = 0; k < num_kkt; ++k) sol[perm[k]] = perm_sol[k];
  }
}

// ---------------------------------------------------------------------------------------------

Solver::Solver(Options options) : options_(std::move(options)), workspace_(std::make_unique<Workspace>()) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("Solver::Options: " + error);
}

Solver::~Solver() = default;
Solver::Solver(Solver&&) noexcept = default;
Solver& Solver::operator=(Solver&&) noexcept = default;

void Solver::set_options(const Options& options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("Solver::Options: " + error);
  options_ = options;
}

Result Solver::Solve(const Problem& problem) {
  using Clock = std::chrono::steady_clock;
  const auto start_time = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start_time).count(); };

  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("Solver::Options: " + error);
  problem.Validate();

  if (!workspace_) workspace_ = std::make_unique<Workspace>();
  Workspace& W = *workspace_;
  Result result;
  result.reused_symbolic =
      W.PatternMatches(problem, options_.sparse_cone_min_dimension, options_.kkt_method);
  if (!result.reused_symbolic) W.Analyze(problem, options_.sparse_cone_min_dimension, options_.kkt_method);
  W.LoadValues(problem, options_);
  W.refinement_counter = 0;

  const int n = W.n, p = W.p, m = W.m, N = W.num_kkt;
  const double norm_c = NormInf(W.c.data(), n);
  const double norm_b = NormInf(W.b.data(), p);
  const double norm_h = NormInf(W.h.data(), m);
  int dynamic_regs = 0;
  int regularization_boosts = 0;

  // ---- initial point: the centered point of the embedding ----
  // x = 0, y = 0, s = z = e (the identity of each cone), tau = kappa = 1: every complementarity
  // product equals mu = 1, so no cone starts off the central path. (A least-squares start, shifted
  // into the cones, put single rows at s_i z_i ~ 1e-3 mu on long path problems; the first
  // iterations then took steps below 0.01: 30 instead of 24 iterations at 20,000 cells.)
  W.x.setZero();
  W.y.setZero();
  W.s.setZero();
  W.z.setZero();
  if (m > 0) {
    W.AddIdentity(W.s.data(), 1.0);
    W.AddIdentity(W.z.data(), 1.0);
  }
  W.tau = 1.0;
  W.kappa = 1.0;

  const double nu = static_cast<double>(W.degree);
  Status status = Status::kIterationLimit;
  std::string message;
  int iteration = 0;
  double step = 0.0, sigma = 0.0;
  int best_iteration = -1;   // iteration of the best iterate
  bool looked_back = false;  // the current iterate is a lookback midpoint
  int iteration_refinements = 0;
  double pres = 0.0, dres = 0.0, pcost = 0.0, dcost = 0.0, gap = 0.0;
  // Best iterate so far by the merit max(pres / tol, dres / tol, gap / gap tol): returned if the
  // iteration stalls, and accepted as kOptimal with reduced accuracy if it meets the reduced tolerances.
  double best_merit = std::numeric_limits<double>::infinity();
  double progress_merit = std::numeric_limits<double>::infinity();
  double progress_mu = std::numeric_limits<double>::infinity();
  int progress_iteration = 0;
  bool have_best = false;
  bool best_reduced_ok = false;
  bool reduced_accuracy = false;

  for (;; ++iteration) {
    // ---- residuals of the homogeneous embedding ----
    W.A.Multiply(W.x.data(), W.Ax.data());
    W.G.Multiply(W.x.data(), W.Gx.data());
    W.A.MultiplyTransposed(W.y.data(), W.Aty.data());
    W.G.MultiplyTransposed(W.z.data(), W.Gtz.data());
    const double tau = W.tau, kappa = W.kappa;
    W.rx = W.Aty + W.Gtz + tau * W.c;
    W.ry = W.Ax - tau * W.b;
    W.rz = W.Gx + W.s - tau * W.h;
    const double cx = W.c.dot(W.x), by = W.b.dot(W.y), hz = W.h.dot(W.z);
    const double rtau = kappa + cx + by + hz;
    const double sz = W.s.dot(W.z);
    const double mu = (sz + tau * kappa) / (nu + 1.0);

    // ---- convergence measures on (x, y, z, s) / tau ----
    pcost = cx / tau;
    dcost = -(by + hz) / tau;
    gap = sz / (tau * tau);
    pres = std::max(NormInf(W.ry.data(), p), NormInf(W.rz.data(), m)) / tau /
           std::max({1.0, norm_b, norm_h, NormInf(W.Ax.data(), p) / tau, NormInf(W.Gx.data(), m) / tau,
                     NormInf(W.s.data(), m) / tau});
    dres = NormInf(W.rx.data(), n) / tau /
           std::max({1.0, norm_c, NormInf(W.Aty.data(), n) / tau, NormInf(W.Gtz.data(), n) / tau});

    if (options_.callback) {
      IterationInfo info;
      info.iteration = iteration;
      info.primal_objective = pcost;
      info.dual_objective = dcost;
      info.gap = gap;
      info.primal_residual = pres;
      info.dual_residual = dres;
      info.tau = tau;
      info.kappa = kappa;
      info.mu = mu;
      info.step = step;
      info.sigma = sigma;
      info.refinement_steps = iteration_refinements;
      options_.callback(info);
    }

    if (!std::isfinite(pres) || !std::isfinite(dres) || !std::isfinite(gap) || !std::isfinite(mu)) {
      status = Status::kNumericalError;
      message = "non-finite iterate";
      break;
    }

    // ---- termination ----
    const double pd_gap = std::abs(pcost - dcost);
    const double gap_scale = std::min(std::abs(pcost), std::abs(dcost));
    const bool gap_ok = (gap <= options_.absolute_gap_tolerance ||
                         gap <= options_.relative_gap_tolerance * gap_scale) &&
                        (pd_gap <= options_.absolute_gap_tolerance ||
                         pd_gap <= options_.relative_gap_tolerance * gap_scale);
    if (pres <= options_.feasibility_tolerance && dres <= options_.feasibility_tolerance && gap_ok) {
      status = Status::kOptimal;
      message = "tolerances met";
      break;
    }
    {
      const double worst_gap = std::max(gap, pd_gap);
      const double gap_merit = std::min(worst_gap / options_.absolute_gap_tolerance,
                                        worst_gap / (options_.relative_gap_tolerance * gap_scale));
      const double merit = std::max({pres / options_.feasibility_tolerance,
                                     dres / options_.feasibility_tolerance, gap_merit});
      // Lookback: a full step from an iterate within 10x of the tolerances that does not end the
      // solve may have traded one criterion for another (the gap met, the primal residual spoiled by
      // rounding in the last solves); the midpoint of that step often meets all of them. It is
      // measured once per step (no KKT solve; the callback sees the iteration number again) and the
      // iteration goes on from it.
      constexpr double kLookbackMerit = 10.0;
      // A shorter step moved the iterate too little to have traded criteria, and its midpoint is
      // nearly the best iterate again.
      constexpr double kLookbackMinStep = 0.2;
      if (best_iteration == iteration - 1 && !looked_back && best_merit <= kLookbackMerit &&
          step > kLookbackMinStep) {
        step *= 0.5;
        W.MoveHalfwayToBest();
        looked_back = true;
        --iteration;
        continue;
      }
      looked_back = false;
      if (merit < best_merit) {
        best_iteration = iteration;
        best_merit = merit;
        have_best = true;
        W.best_x = W.x;
        W.best_y = W.y;
        W.best_z = W.z;
        W.best_s = W.s;
        W.best_tau = tau;
        W.best_kappa = kappa;
        // The reduced tolerances never ask for more than the strict ones.
        const double reduced_feas = std::max(options_.reduced_feasibility_tolerance, options_.feasibility_tolerance);
        const double reduced_gap = std::max({options_.reduced_gap_tolerance, options_.absolute_gap_tolerance,
                                             options_.relative_gap_tolerance});
        best_reduced_ok = pres <= reduced_feas && dres <= reduced_feas &&
                          (worst_gap <= reduced_gap || worst_gap <= reduced_gap * gap_scale);
      }
      // Progress: the merit or mu halved since the last mark (mu alone keeps falling on infeasible
      // problems, whose merit does not, until a certificate is found).
      if (merit < 0.5 * progress_merit || mu < 0.5 * progress_mu) {
        progress_merit = std::min(progress_merit, merit);
        progress_mu = std::min(progress_mu, mu);
        progress_iteration = iteration;
      }
      // Near the optimum a jump of the merit by 1000x is rounding taking over (the KKT solves lose the
      // last digits as the scaling degenerates), not a phase that recovers: stop at once and return
      // the best iterate instead of wandering until the stall window closes.
      constexpr double kDivergence = 1e3;  // merit factor; the breakdowns seen rose ~1e4-fold at once
      if (best_reduced_ok && merit > kDivergence * best_merit) {
        if (!W.reduced) {
          status = Status::kNumericalError;
          message = "the merit rose 1000-fold from the best iterate (rounding near the optimum)";
          break;
        }
        // The reduced method forms G'W^{-2}G, whose rounding can spoil the direction when the scaling
        // is extreme (seen on small random SOCPs: the dual residual jumped from 2e-7 to 4e-2 and no
        // refinement recovered it). The augmented system does not form it: back to the best iterate,
        // and on with that method.
        W.SwitchToAugmented();
        W.RestoreBest();
        progress_merit = best_merit;
        progress_iteration = iteration;
        continue;
      }
      // Near the optimum (the best iterate meets the reduced tolerances) a short stall ends the
      // iteration; elsewhere slow phases are normal, so the window is four times longer.
      const int window = best_reduced_ok ? options_.stall_iterations : 4 * options_.stall_iterations;
      if (iteration - progress_iteration >= window) {
        status = Status::kNumericalError;
        message = "no progress in " + std::to_string(window) + " iterations";
        break;
      }
    }
    if (kappa > tau) {
      // Primal infeasibility: b'y + h'z < 0 with A'y + G'z ~ 0.
      const double bz = by + hz;
      if (bz < 0.0) {
        W.dx = W.Aty + W.Gtz;  // dx is free scratch here (no allocation in the loop)
        const double res = NormInf(W.dx.data(), n) / -bz;
        if (res <= options_.infeasibility_tolerance) {
          status = Status::kPrimalInfeasible;
          message = "certificate of primal infeasibility found";
          break;
        }
      }
      if (cx < 0.0) {
        W.dz = W.Gx + W.s;  // dz is free scratch here
        const double res = std::max(NormInf(W.Ax.data(), p), NormInf(W.dz.data(), m)) / -cx;
        if (res <= options_.infeasibility_tolerance) {
          status = Status::kDualInfeasible;
          message = "certificate of dual infeasibility (unboundedness) found";
          break;
        }
      }
    }
    if (iteration >= options_.max_iterations) {
      status = Status::kIterationLimit;
      message = "max_iterations reached";
      break;
    }
    if (elapsed() > options_.max_solve_time_in_seconds) {
      status = Status::kIterationLimit;
      message = "max_solve_time_in_seconds reached";
      break;
    }

    // ---- scaling and factorization ----
    if (!W.ComputeScaling()) {
      status = Status::kNumericalError;
      message = "iterate left the cone interior at iteration " + std::to_string(iteration);
      break;
    }
    W.refinement_floor = options_.refinement_mu_factor * mu;
    const int refinements_before = W.refinement_counter;

    // sol1 = K^{-1} [-c; b; h] (unrefined: only the combined direction below is refined, one refined
    // solve per iteration), solved in one sweep with the affine direction's right-hand side.
    W.rhs1.head(n) = -W.c;
    W.rhs1.segment(n, p) = W.b;
    W.rhs1.segment(n + p, m) = W.h;

    // Right-hand side of a Newton direction for the residual weight `eta_r` and complementarity
    // right-hand side d_s (see ComplementarityRhs): rhs2, with ldiv = lambda \ d_s and dtmp2 = W ldiv.
    auto direction_rhs = [&](bool corrector, double sigma_mu, double eta_r) {
      W.ComplementarityRhs(corrector, sigma_mu, eta_r, W.rhs2.data() + n + p);
      W.rhs2.head(n) = -eta_r * W.rx;
      W.rhs2.segment(n, p) = -eta_r * W.ry;
      if (N > n + p + m) W.rhs2.tail(N - n - p - m).setZero();
    };
    // The predictor's right-hand side: d_s = lambda o lambda.
    direction_rhs(false, 0.0, 1.0);
    // Near the optimum the scaling spans ~20 orders of magnitude and the LDL' of a large system can
    // break down (pivots of the wrong sign replaced by the hundred, then overflow: seen on random
    // SOCPs of 10,000+ variables, one iteration before the tolerances). The static regularization is
    // then raised 100-fold, for the rest of the solve, and the factorization redone; refinement on
    // the unregularized system recovers the accuracy.
    constexpr int kMaxRegularizationBoosts = 3;
    for (;;) {
      dynamic_regs += W.FactorKkt(options_);
      W.SolveKkt2(W.rhs1, W.sol1, W.rhs2, W.sol2);
      if (std::isfinite(W.sol1.squaredNorm()) && std::isfinite(W.sol2.squaredNorm())) break;
      if (regularization_boosts == kMaxRegularizationBoosts) break;  // reported below as non-finite
      ++regularization_boosts;
      W.SetStaticRegularization(100.0 * W.static_reg);
    }
    const double denom = W.c.dot(W.sol1.head(n)) + W.b.dot(W.sol1.segment(n, p)) +
                         W.h.dot(W.sol1.segment(n + p, m)) - kappa / tau;

    // Completes the Newton direction whose rhs2 is set and (if `solved`) solved into sol2. Fills dx,
    // dy, dz, ds, and W^{-1} ds, W dz (in ds_aff, dz_aff, for the step length and the corrector);
    // returns (dtau, dkappa).
    double cone_step = 0.0;  // set by direction: the cones' step limit
    auto direction = [&](double eta_r, double d_kappa, int refinement_steps, bool solved, double& dtau,
                         double& dkappa) {
      if (!solved) W.SolveKkt(W.rhs2, W.sol2, options_, 0);
      const double numer = -eta_r * rtau + d_kappa / tau -
                           (W.c.dot(W.sol2.head(n)) + W.b.dot(W.sol2.segment(n, p)) +
                            W.h.dot(W.sol2.segment(n + p, m)));
      dtau = numer / denom;
      if (refinement_steps > 0) {
        // Refine the combined direction K (sol2 + dtau sol1) = rhs2 + dtau rhs1 once, instead of
        // refining sol1 and sol2 separately (a solve and two products less per iteration).
        W.sol2 += dtau * W.sol1;
        W.rhs2 += dtau * W.rhs1;
        W.RefineKkt(W.rhs2, W.sol2, options_, refinement_steps);
        W.dx = W.sol2.head(n);
        W.dy = W.sol2.segment(n, p);
        W.dz = W.sol2.segment(n + p, m);
      } else {
        W.dx = W.sol2.head(n) + dtau * W.sol1.head(n);
        W.dy = W.sol2.segment(n, p) + dtau * W.sol1.segment(n, p);
        W.dz = W.sol2.segment(n + p, m) + dtau * W.sol1.segment(n + p, m);
      }
      // ds = -W (lambda \ d_s) - W'W dz, so W^{-1} ds = -(lambda \ d_s) - W dz.
      cone_step = W.CompleteDirection();
      dkappa = -(d_kappa + kappa * dtau) / tau;
    };
    // Step to the boundary, computed in the scaled space: s + a ds in K iff lambda + a W^{-1} ds in K,
    // and z + a dz in K iff lambda + a W dz in K (W maps K onto K). lambda is well centered, so the
    // root of the cone's quadratic is well conditioned there, unlike at s or z themselves.
    // Uses W^{-1} ds in ds_aff and W dz in dz_aff (set by direction).
    auto max_step = [&](double dtau, double dkappa) {
      double alpha = cone_step;
      if (dtau < 0.0) alpha = std::min(alpha, -tau / dtau);
      if (dkappa < 0.0) alpha = std::min(alpha, -kappa / dkappa);
      return alpha;
    };

    // ---- predictor (affine scaling) ----
    double dtau_a = 0.0, dkappa_a = 0.0;
    direction(1.0, tau * kappa, options_.max_affine_refinement_steps, true, dtau_a, dkappa_a);
    const double alpha_a = std::min(1.0, max_step(dtau_a, dkappa_a));
    sigma = std::pow(1.0 - alpha_a, 3);
    sigma = std::min(1.0, std::max(0.0, sigma));

    // ---- corrector: d_s = lambda o lambda + (W^{-1} ds_a) o (W dz_a) - sigma mu e ----
    const double d_kappa = tau * kappa + dtau_a * dkappa_a - sigma * mu;
    double dtau = 0.0, dkappa = 0.0;
    direction_rhs(true, sigma * mu, 1.0 - sigma);  // ds_aff, dz_aff set by the predictor's direction
    direction(1.0 - sigma, d_kappa, options_.max_refinement_steps, false, dtau, dkappa);
    step = std::min(1.0, options_.step_fraction * max_step(dtau, dkappa));
    iteration_refinements = W.refinement_counter - refinements_before;

    if (!std::isfinite(step) || !std::isfinite(dtau) || !std::isfinite(W.dx.squaredNorm()) ||
        !std::isfinite(W.dz.squaredNorm()) || !std::isfinite(W.ds.squaredNorm()) ||
        !std::isfinite(W.dy.squaredNorm())) {
      status = Status::kNumericalError;
      message = "non-finite search direction";
      break;
    }
    if (step < options_.min_step) {
      status = Status::kNumericalError;
      message = "step length below min_step";
      break;
    }
    // The exact step keeps the iterate inside the cones, but rounding can put a nearly active cone on
    // its boundary (e.g. s0 - ||s1|| of a cone with large entries); shorten the step until the new
    // point is strictly interior so that the next scaling exists.
    bool interior = false;
    for (int attempt = 0; attempt < 40 && step >= options_.min_step; ++attempt) {
      if (W.tau + step * dtau > 0.0 && W.kappa + step * dkappa > 0.0 && W.TrialPoint(step)) {
        interior = true;
        break;
      }
      step *= 0.5;
    }
    if (!interior) {
      status = Status::kNumericalError;
      message = "no step keeps the iterate inside the cones";
      break;
    }
    W.x += step * W.dx;
    W.y += step * W.dy;
    W.s.swap(W.dtmp1);
    W.z.swap(W.dtmp3);
    W.tau += step * dtau;
    W.kappa += step * dkappa;
  }

  // ---- stalled or stopped: fall back to the best iterate ----
  if ((status == Status::kNumericalError || status == Status::kIterationLimit) && have_best) {
    W.RestoreBest();
    if (best_reduced_ok) {
      message = "reduced accuracy (" + message + "; the best iterate meets the reduced tolerances)";
      status = Status::kOptimal;
      reduced_accuracy = true;
    }
  }

  // ---- output in the user's coordinates ----
  result.status = status;
  result.reduced_accuracy = reduced_accuracy;
  result.message = message;
  result.iterations = iteration;
  result.num_refinement_steps = W.refinement_counter;
  result.num_dynamic_regularizations = dynamic_regs;
  result.num_regularization_boosts = regularization_boosts;
  result.kkt_method = W.reduced ? KktMethod::kReducedBanded : KktMethod::kAugmentedSparse;
  if (W.reduced) {
    result.kkt_size = W.nr;
    result.kkt_nonzeros = W.sky.num_stored();
    result.factor_nonzeros = W.sky.num_stored() - W.nr;
  } else {
    result.kkt_size = N;
    result.kkt_nonzeros = static_cast<long long>(W.k_idx.size());
    result.factor_nonzeros = W.ldl.num_factor_nonzeros();
  }
  result.x.setZero(n);
  result.y.setZero(p);
  result.z.setZero(m);
  result.s.setZero(m);
  auto unrotate = [&](Eigen::VectorXd& v) {
    for (const SocBlock& blk : W.socs) {
      if (!blk.rotated) continue;
      const double t0 = v[blk.start], t1 = v[blk.start + 1];
      v[blk.start] = kSqrtHalf * (t0 + t1);
      v[blk.start + 1] = kSqrtHalf * (t0 - t1);
    }
  };
  if (status == Status::kPrimalInfeasible) {
    const double scale = -1.0 / (W.b.dot(W.y) + W.h.dot(W.z));
    result.y = scale * W.y;
    result.z = scale * W.z;
    unrotate(result.z);
  } else if (status == Status::kDualInfeasible) {
    const double scale = -1.0 / W.c.dot(W.x);
    result.x = scale * W.x;
    result.s = scale * W.s;
    unrotate(result.s);
  } else {
    const double inv = 1.0 / W.tau;
    result.x = inv * W.x;
    result.y = inv * W.y;
    result.z = inv * W.z;
    result.s = inv * W.s;
    unrotate(result.z);
    unrotate(result.s);
  }
  // Objectives and residuals in the user's data (for certificates: of the normalized ray).
  result.primal_objective = problem.c.dot(result.x);
  result.dual_objective = -problem.b.dot(result.y) - problem.h.dot(result.z);
  result.gap = result.s.dot(result.z);
  {
    const Eigen::VectorXd Ax = problem.A * result.x;
    const Eigen::VectorXd Gx = problem.G * result.x;
    const Eigen::VectorXd Aty = problem.A.transpose() * result.y;
    const Eigen::VectorXd Gtz = problem.G.transpose() * result.z;
    auto ninf = [](const Eigen::VectorXd& v) { return v.size() ? v.lpNorm<Eigen::Infinity>() : 0.0; };
    if (status == Status::kPrimalInfeasible) {
      result.primal_residual = 0.0;
      result.dual_residual = ninf(Aty + Gtz);
    } else if (status == Status::kDualInfeasible) {
      result.primal_residual = std::max(ninf(Ax), ninf(Gx + result.s));
      result.dual_residual = 0.0;
    } else {
      result.primal_residual =
          std::max(ninf(Ax - problem.b), ninf(Gx + result.s - problem.h)) /
          std::max({1.0, ninf(problem.b), ninf(problem.h), ninf(Ax), ninf(Gx), ninf(result.s)});
      result.dual_residual = ninf(problem.c + Aty + Gtz) /
                             std::max({1.0, ninf(problem.c), ninf(Aty), ninf(Gtz)});
    }
  }
  result.solve_time_seconds = elapsed();
  return result;
}

}  // namespace timeopt::conic
