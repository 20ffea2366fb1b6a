#pragma once
// Cone algebra of the interior-point solver (private to the conic module): the layout of the cone
// K = R+^l x Q^d1 x ... along the rows of s and z, the Nesterov-Todd scaling W of the current iterate,
// the scaled point lambda = W z, the Jordan product and division, and the step to the cone boundary.
//
// Second-order cones Q^d = {u : u0 >= ||u1||} are scaled by W = eta (2 wbar wbar' - J) restricted to
// the cone's rows, with J = diag(1, -1, ..., -1), wbar0^2 - ||wbar1||^2 = 1 and eta^2 = sqrt(det s /
// det z) (Nesterov and Todd 1997; Vandenberghe, "The CVXOPT linear and quadratic cone program
// solvers", 2010, section 4). Rotated cones are mapped to standard ones before they get here, by the
// orthogonal transform of their first two rows.

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "timeopt/conic/problem.h"

namespace timeopt::conic::internal {

constexpr double kSqrtHalf = 0.70710678118654752440;

// One second-order cone of the internal problem (rotated cones are already mapped to standard ones).
struct SocBlock {
  int start = 0;  // first row in z and s
  int dim = 0;
  bool rotated = false;   // the first two rows were transformed
  bool expanded = false;  // scaling enters the KKT system by the sparse expansion
  int ext = -1;           // KKT index of the first of the two expansion rows (if expanded)
  int slot_offset = 0;    // offset into the dense-cone slots (dense) or expansion slots (expanded)
};

// Per-cone kernels, templated on the dimension: D = 3 (most cones of path-like problems) is fully
// unrolled by the compiler, D = 0 reads the dimension at run time.

// o = W v for one cone: eta (wbar0 v0 + wbar1'v1, v1 + (v0 + wbar1'v1 / (1 + wbar0)) wbar1).
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

// The cones of the internal problem and the Nesterov-Todd scaling of the current iterate. Orthant
// rows [0, num_orthant) come first, then the second-order cones in `socs`. All vectors have the m
// rows of s and z; the scaling is recomputed once per iteration by ComputeScaling.
// The expanded form of a second-order cone's scaling in the KKT system: with w the NT scaling
// vector (w0 = w[0]), W'W = eta^2 (D + u u' - v v'), D = diag(d0, 1, ..., 1), u = (u0, u1 w1),
// v = (0, v1 w1), and d0 = 1 / (2 (2 w0^2 - 1)) so that D - v v' stays positive definite
// (quasi-definiteness). Shared by both KKT methods.
struct ExpandedCone {
  double d0, u0, u1, v1;
};
inline ExpandedCone ExpandCone(double w0) {
  const double t2 = 2.0 * w0 * w0 - 1.0;
  const double d0 = 0.5 / t2;
  const double u0 = std::sqrt(t2 - d0);
  return {d0, u0, 2.0 * w0 / u0, std::sqrt(2.0 * (1.0 + d0)) / u0};
}

struct Cones {
  // ---- layout ----
  int num_rows = 0;  // m
  int num_orthant = 0;
  int degree = 0;  // barrier parameter: one per orthant row and per cone
  std::vector<SocBlock> socs;
  // Per row: 0 normal, 1 first row of a rotated cone, 2 its second row.
  std::vector<signed char> row_kind;

  // ---- scaling of the current iterate ----
  Eigen::VectorXd w_orthant;                // orthant scaling sqrt(s/z)
  Eigen::VectorXd h_orthant, hinv_orthant;  // s/z and z/s (orthant blocks of W'W and its inverse)
  Eigen::VectorXd wbar;                     // cone scaling points (rows of socs)
  std::vector<double> eta;                  // cone scaling factors
  Eigen::VectorXd lambda;                   // scaled point W z (= W^{-T} s)
  // Step data of lambda, once per iteration: orthant rows 1 / lambda_i, cone rows lambda / sqrt(det);
  // per cone 1 / sqrt(det lambda) and 1 / (lbar0 + 1) (see InverseStepCone in cones.cpp).
  Eigen::VectorXd lambda_step;
  std::vector<double> lambda_isd, lambda_ilb;
  std::vector<double> local_cone;  // scratch of the largest cone (fused passes)

  // Lays out the orthant rows, then the cones of spec.soc_dims, then those of spec.rotated_dims. Cones
  // of at least `sparse_min_dim` rows (and at least 2) are expanded, their two extra KKT rows each
  // numbered from `first_ext` on; returns the KKT size (first_ext + 2 per expanded cone). Sizes the
  // scaling vectors.
  int Layout(const ConeSpec& spec, int sparse_min_dim, int first_ext);
  int num_expanded() const;

  // The scaling at (s, z) (and lambda with its step data); false if s, z or lambda is not strictly
  // inside K. `scratch` has m entries.
  bool ComputeScaling(const Eigen::VectorXd& s, const Eigen::VectorXd& z, Eigen::VectorXd& scratch);
  // out = W'W in (Inverse false) or (W'W)^{-1} in (Inverse true).
  template <bool Inverse>
  void ApplyH(const double* in, double* out) const;
  // True if u is strictly inside K, by the same test as ComputeScaling.
  bool StrictlyInterior(const double* u) const;
  // u += alpha e, e the identity of K (1 on orthant rows and on the first row of each cone).
  void AddIdentity(double* u, double alpha) const;

  // Fused passes of the Newton step (one sweep over the cones each).
  // The cone part of a direction's right-hand side: with d = lambda o lambda (predictor) or
  // d = lambda o lambda + winv_ds o w_dz - sigma_mu e (corrector), sets ldiv = lambda \ d,
  // w_ldiv = W ldiv and rhs_z = -eta_r rz + w_ldiv.
  void ComplementarityRhs(bool corrector, double sigma_mu, double eta_r, const Eigen::VectorXd& winv_ds,
                          const Eigen::VectorXd& w_dz, const Eigen::VectorXd& rz, Eigen::VectorXd& ldiv,
                          Eigen::VectorXd& w_ldiv, double* rhs_z);
  // Completes a direction from dz: w_dz = W dz, ds = -w_ldiv - W w_dz, winv_ds = -ldiv - w_dz
  // (= W^{-1} ds); returns the largest step keeping lambda + a winv_ds and lambda + a w_dz in K
  // (infinity if none limits it, 0 if the direction is NaN).
  double CompleteDirection(const Eigen::VectorXd& dz, const Eigen::VectorXd& ldiv, const Eigen::VectorXd& w_ldiv,
                           Eigen::VectorXd& w_dz, Eigen::VectorXd& ds, Eigen::VectorXd& winv_ds);
};

}  // namespace timeopt::conic::internal
