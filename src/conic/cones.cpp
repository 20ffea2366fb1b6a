#include "cones.h"

#include <algorithm>
#include <limits>

namespace timeopt::conic::internal {

namespace {

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

int Cones::Layout(const ConeSpec& spec, int sparse_min_dim, int first_ext) {
  num_orthant = spec.num_nonnegative;
  degree = spec.Degree();
  num_rows = spec.NumRows();
  socs.clear();
  row_kind.assign(num_rows, 0);
  int row = num_orthant;
  int ext = first_ext;
  int dense_count = 0, expanded_count = 0;
  auto add_cone = [&](int dim, bool rotated) {
    SocBlock blk;
    blk.start = row;
    blk.dim = dim;
    blk.rotated = rotated;
    blk.expanded = dim >= sparse_min_dim && dim >= 2;
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
  for (int d : spec.soc_dims) add_cone(d, false);
  for (int d : spec.rotated_dims) add_cone(d, true);

  for (Eigen::VectorXd* v : {&w_orthant, &h_orthant, &hinv_orthant, &wbar, &lambda, &lambda_step}) {
    v->setZero(num_rows);
  }
  eta.assign(socs.size(), 1.0);
  lambda_isd.assign(socs.size(), 1.0);
  lambda_ilb.assign(socs.size(), 0.5);
  int largest = 0;
  for (const SocBlock& blk : socs) largest = std::max(largest, blk.dim);
  local_cone.assign(largest, 0.0);
  return ext;
}

int Cones::num_expanded() const {
  int count = 0;
  for (const SocBlock& blk : socs) count += blk.expanded ? 1 : 0;
  return count;
}

bool Cones::ComputeScaling(const Eigen::VectorXd& s, const Eigen::VectorXd& z, Eigen::VectorXd& scratch) {
  if (num_orthant > 0) {
    // Branch-free (vectorized) passes; the interior test first.
    const auto so = s.head(num_orthant).array();
    const auto zo = z.head(num_orthant).array();
    if (!(so.minCoeff() > 0.0 && zo.minCoeff() > 0.0)) return false;  // also catches NaN
    // One division and one root per row: with r = 1 / (s z), lambda = sqrt(s z) (= w z),
    // 1 / lambda = lambda r, w = sqrt(s / z) = s / lambda, s / z = s^2 r and z / s = z^2 r.
    auto lo = lambda.head(num_orthant).array();
    auto li = lambda_step.head(num_orthant).array();
    auto r = scratch.head(num_orthant).array();
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
    const bool ok = blk.dim == 3
                        ? NtScalingCone<3>(s.data() + o, z.data() + o, wbar.data() + o, eta[k], lambda.data() + o,
                                           lambda_step.data() + o, lambda_isd[k], lambda_ilb[k], 3)
                        : NtScalingCone<0>(s.data() + o, z.data() + o, wbar.data() + o, eta[k], lambda.data() + o,
                                           lambda_step.data() + o, lambda_isd[k], lambda_ilb[k], blk.dim);
    if (!ok) return false;
  }
  return true;
}

template <bool Inverse>
void Cones::ApplyH(const double* in, double* out) const {
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

bool Cones::StrictlyInterior(const double* u) const {
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

void Cones::AddIdentity(double* u, double alpha) const {
  for (int i = 0; i < num_orthant; ++i) u[i] += alpha;
  for (const SocBlock& blk : socs) u[blk.start] += alpha;
}

void Cones::ComplementarityRhs(bool corrector, double sigma_mu, double eta_r, const Eigen::VectorXd& winv_ds,
                               const Eigen::VectorXd& w_dz, const Eigen::VectorXd& rz, Eigen::VectorXd& ldiv,
                               Eigen::VectorXd& w_ldiv, double* rhs_z) {
  const double* l = lambda.data();
  const double* a = winv_ds.data();
  const double* b = w_dz.data();
  const double* r = rz.data();
  double* ld = ldiv.data();
  double* t2 = w_ldiv.data();
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

double Cones::CompleteDirection(const Eigen::VectorXd& dz, const Eigen::VectorXd& ldiv, const Eigen::VectorXd& w_ldiv,
                                Eigen::VectorXd& w_dz, Eigen::VectorXd& ds, Eigen::VectorXd& winv_ds) {
  const double* dzv = dz.data();
  const double* ld = ldiv.data();
  const double* t2 = w_ldiv.data();
  double* dza = w_dz.data();
  double* dsa = winv_ds.data();
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

template void Cones::ApplyH<false>(const double* in, double* out) const;
template void Cones::ApplyH<true>(const double* in, double* out) const;

}  // namespace timeopt::conic::internal
