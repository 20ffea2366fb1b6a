#include "workspace.h"

#include <algorithm>
#include <vector>

namespace timeopt::conic {

bool Solver::Workspace::PatternMatches(const Problem& problem, const Options& options) const {
  if (!analyzed || options.sparse_cone_min_dimension != sparse_min_dim || options.kkt_method != method_option ||
      options.reduced_max_expanded_cones != reduced_max_expanded_cones ||
      options.reduced_max_profile_per_row != reduced_max_profile_per_row ||
      options.max_factor_bytes != max_factor_bytes) {
    return false;
  }
  return data.SamePattern(problem);
}

void Solver::Workspace::Analyze(const Problem& problem, const Options& options) {
  sparse_min_dim = options.sparse_cone_min_dimension;
  method_option = options.kkt_method;
  reduced_max_expanded_cones = options.reduced_max_expanded_cones;
  reduced_max_profile_per_row = options.reduced_max_profile_per_row;
  max_factor_bytes = options.max_factor_bytes;
  analyzed = false;  // until the analysis below has passed (it throws for a factor above the budget)
  const int n = problem.num_variables(), p = problem.num_equalities(), m = problem.num_cone_rows();
  const int num_kkt = cones.Layout(problem.cones, sparse_min_dim, n + p + m);
  data.Analyze(problem, cones, num_kkt);

  // ---- KKT method ----
  kkt.reset();
  if (method_option != KktMethod::kAugmentedSparse) {
    kkt = internal::MakeReducedKkt(data, cones, method_option == KktMethod::kAutomatic, options);
  }
  if (!kkt) kkt = internal::MakeAugmentedKkt(data, cones, max_factor_bytes);

  // ---- work memory ----
  for (Eigen::VectorXd* v : {&x, &rx, &Aty, &Gtz, &dx, &best_x}) v->setZero(n);
  for (Eigen::VectorXd* v : {&y, &ry, &Ax, &dy, &best_y}) v->setZero(p);
  for (Eigen::VectorXd* v :
       {&z, &s, &rz, &Gx, &dz, &ds, &ds_aff, &dz_aff, &dtmp1, &dtmp2, &dtmp3, &ldiv, &best_z, &best_s}) {
    v->setZero(m);
  }
  for (Eigen::VectorXd* v : {&rhs1, &sol1, &rhs2, &sol2}) v->setZero(num_kkt);
  analyzed = true;
}

void Solver::Workspace::LoadValues(const Problem& problem, const Options& options) {
  data.LoadValues(problem, cones);
  kkt->LoadData();
  kkt->SetStaticRegularization(options.static_regularization);
}

void Solver::Workspace::SwitchToAugmented() {
  const double delta = kkt->static_regularization();
  kkt = internal::MakeAugmentedKkt(data, cones, max_factor_bytes);
  kkt->LoadData();
  kkt->SetStaticRegularization(delta);
  analyzed = false;
}

void Solver::Workspace::Initialize() {
  // Every complementarity product equals mu = 1, so no cone starts off the central path. (A
  // least-squares start, shifted into the cones, put single rows at s_i z_i ~ 1e-3 mu on long path
  // problems; the first iterations then took steps below 0.01: 30 instead of 24 iterations at 20,000
  // cells.)
  x.setZero();
  y.setZero();
  s.setZero();
  z.setZero();
  if (data.m > 0) {
    cones.AddIdentity(s.data(), 1.0);
    cones.AddIdentity(z.data(), 1.0);
  }
  tau = 1.0;
  kappa = 1.0;
}

internal::IterateMeasures Solver::Workspace::Measure(double norm_c, double norm_b, double norm_h) {
  using internal::NormInf;
  const int n = data.n, p = data.p, m = data.m;
  // ---- residuals of the homogeneous embedding ----
  data.A.Multiply(x.data(), Ax.data());
  data.G.Multiply(x.data(), Gx.data());
  data.A.MultiplyTransposed(y.data(), Aty.data());
  data.G.MultiplyTransposed(z.data(), Gtz.data());
  rx = Aty + Gtz + tau * data.c;
  ry = Ax - tau * data.b;
  rz = Gx + s - tau * data.h;
  internal::IterateMeasures it;
  it.tau = tau;
  it.kappa = kappa;
  it.cx = data.c.dot(x);
  it.by = data.b.dot(y);
  it.hz = data.h.dot(z);
  rtau = kappa + it.cx + it.by + it.hz;
  const double sz = s.dot(z);
  it.mu = (sz + tau * kappa) / (static_cast<double>(cones.degree) + 1.0);

  // ---- convergence measures on (x, y, z, s) / tau ----
  it.pcost = it.cx / tau;
  it.dcost = -(it.by + it.hz) / tau;
  it.gap = sz / (tau * tau);
  it.pres = std::max(NormInf(ry.data(), p), NormInf(rz.data(), m)) / tau /
            std::max({1.0, norm_b, norm_h, NormInf(Ax.data(), p) / tau, NormInf(Gx.data(), m) / tau,
                      NormInf(s.data(), m) / tau});
  it.dres =
      NormInf(rx.data(), n) / tau / std::max({1.0, norm_c, NormInf(Aty.data(), n) / tau, NormInf(Gtz.data(), n) / tau});
  return it;
}

void Solver::Workspace::SaveBest() {
  best_x = x;
  best_y = y;
  best_z = z;
  best_s = s;
  best_tau = tau;
  best_kappa = kappa;
}

void Solver::Workspace::MoveHalfwayToBest() {
  x = 0.5 * (x + best_x);
  y = 0.5 * (y + best_y);
  z = 0.5 * (z + best_z);
  s = 0.5 * (s + best_s);
  tau = 0.5 * (tau + best_tau);
  kappa = 0.5 * (kappa + best_kappa);
}

void Solver::Workspace::RestoreBest() {
  x = best_x;
  y = best_y;
  z = best_z;
  s = best_s;
  tau = best_tau;
  kappa = best_kappa;
}

namespace {

// Rows of a rotated cone back to the user's coordinates (the 45-degree turn is its own inverse).
void Unrotate(const std::vector<internal::SocBlock>& socs, Eigen::VectorXd& v) {
  for (const internal::SocBlock& blk : socs) {
    if (!blk.rotated) continue;
    const double t0 = v[blk.start], t1 = v[blk.start + 1];
    v[blk.start] = internal::kSqrtHalf * (t0 + t1);
    v[blk.start + 1] = internal::kSqrtHalf * (t0 - t1);
  }
}

}  // namespace

void Solver::Workspace::ExportSolution(Status status, Result* result) const {
  result->x.setZero(data.n);
  result->y.setZero(data.p);
  result->z.setZero(data.m);
  result->s.setZero(data.m);
  if (status == Status::kPrimalInfeasible) {
    const double scale = -1.0 / (data.b.dot(y) + data.h.dot(z));
    result->y = scale * y;
    result->z = scale * z;
    Unrotate(cones.socs, result->z);
  } else if (status == Status::kDualInfeasible) {
    const double scale = -1.0 / data.c.dot(x);
    result->x = scale * x;
    result->s = scale * s;
    Unrotate(cones.socs, result->s);
  } else {
    const double inv = 1.0 / tau;
    result->x = inv * x;
    result->y = inv * y;
    result->z = inv * z;
    result->s = inv * s;
    Unrotate(cones.socs, result->z);
    Unrotate(cones.socs, result->s);
  }
}

}  // namespace timeopt::conic
