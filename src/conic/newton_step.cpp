// One interior-point iteration's Newton step: Mehrotra predictor-corrector on the homogeneous
// embedding, the step to the cone boundary and the search for a strictly interior trial point.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "workspace.h"

namespace timeopt::conic {

Solver::Workspace::StepOutcome Solver::Workspace::NewtonStep(const Options& options,
                                                             const internal::IterateMeasures& it, int iteration) {
  StepOutcome out;
  if (!cones.ComputeScaling(s, z, dtmp1)) {
    out.failure = "iterate left the cone interior at iteration " + std::to_string(iteration);
    return out;
  }
  refinement_floor = options.refinement_mu_factor * it.mu;
  const int refinements_before = refinement_counter;
  const double denom = FactorAndSolve(options);

  // ---- predictor (affine scaling) ----
  double dtau_a = 0.0, dkappa_a = 0.0;
  const double cone_step_a =
      Direction(options, denom, 1.0, tau * kappa, options.max_affine_refinement_steps, true, &dtau_a, &dkappa_a);
  const double alpha_a = std::min(1.0, MaxStep(cone_step_a, dtau_a, dkappa_a));
  double sigma = std::pow(1.0 - alpha_a, 3);
  sigma = std::min(1.0, std::max(0.0, sigma));
  out.sigma = sigma;

  // ---- corrector: d_s = lambda o lambda + (W^{-1} ds_a) o (W dz_a) - sigma mu e ----
  const double d_kappa = tau * kappa + dtau_a * dkappa_a - sigma * it.mu;
  double dtau = 0.0, dkappa = 0.0;
  DirectionRhs(true, sigma * it.mu, 1.0 - sigma);  // ds_aff, dz_aff set by the predictor's direction
  const double cone_step =
      Direction(options, denom, 1.0 - sigma, d_kappa, options.max_refinement_steps, false, &dtau, &dkappa);
  double step = std::min(1.0, options.step_fraction * MaxStep(cone_step, dtau, dkappa));
  out.step = step;
  out.refinements = refinement_counter - refinements_before;

  // ---- step ----
  if (!std::isfinite(step) || !std::isfinite(dtau) || !std::isfinite(dx.squaredNorm()) ||
      !std::isfinite(dz.squaredNorm()) || !std::isfinite(ds.squaredNorm()) || !std::isfinite(dy.squaredNorm())) {
    out.failure = "non-finite search direction";
    return out;
  }
  if (step < options.min_step) {
    out.failure = "step length below min_step";
    return out;
  }
  if (!FindInteriorStep(options, dtau, dkappa, &step)) {
    out.step = step;
    out.failure = "no step keeps the iterate inside the cones";
    return out;
  }
  out.step = step;
  x += step * dx;
  y += step * dy;
  s.swap(dtmp1);
  z.swap(dtmp3);
  tau += step * dtau;
  kappa += step * dkappa;
  return out;
}

double Solver::Workspace::FactorAndSolve(const Options& options) {
  const int n = data.n, p = data.p, m = data.m;
  // sol1 = K^{-1} [-c; b; h] (unrefined: only the combined direction is refined, one refined solve
  // per iteration), solved in one sweep with the affine direction's right-hand side.
  rhs1.head(n) = -data.c;
  rhs1.segment(n, p) = data.b;
  rhs1.segment(n + p, m) = data.h;
  // The predictor's right-hand side: d_s = lambda o lambda.
  DirectionRhs(false, 0.0, 1.0);
  // Near the optimum the scaling spans ~20 orders of magnitude and the LDL' of a large system can
  // break down (pivots of the wrong sign replaced by the hundred, then overflow: seen on random
  // SOCPs of 10,000+ variables, one iteration before the tolerances). The static regularization is
  // then raised (regularization_boost_factor), for the rest of the solve, and the factorization
  // redone; refinement on the unregularized system recovers the accuracy.
  for (;;) {
    dynamic_regularizations += kkt->Factor(options);
    kkt->Solve2(rhs1, sol1, rhs2, sol2);
    if (std::isfinite(sol1.squaredNorm()) && std::isfinite(sol2.squaredNorm())) break;
    if (regularization_boosts == options.max_regularization_boosts) break;  // reported as non-finite
    ++regularization_boosts;
    kkt->SetStaticRegularization(options.regularization_boost_factor * kkt->static_regularization());
  }
  return data.c.dot(sol1.head(n)) + data.b.dot(sol1.segment(n, p)) + data.h.dot(sol1.segment(n + p, m)) - kappa / tau;
}

void Solver::Workspace::DirectionRhs(bool corrector, double sigma_mu, double eta_r) {
  const int n = data.n, p = data.p, m = data.m, N = data.num_kkt;
  cones.ComplementarityRhs(corrector, sigma_mu, eta_r, ds_aff, dz_aff, rz, ldiv, dtmp2, rhs2.data() + n + p);
  rhs2.head(n) = -eta_r * rx;
  rhs2.segment(n, p) = -eta_r * ry;
  if (N > n + p + m) rhs2.tail(N - n - p - m).setZero();
}

double Solver::Workspace::Direction(const Options& options, double denom, double eta_r, double d_kappa,
                                    int refinement_steps, bool solved, double* dtau, double* dkappa) {
  const int n = data.n, p = data.p, m = data.m;
  if (!solved) kkt->Solve(rhs2, sol2);
  const double numer = -eta_r * rtau + d_kappa / tau -
                       (data.c.dot(sol2.head(n)) + data.b.dot(sol2.segment(n, p)) + data.h.dot(sol2.segment(n + p, m)));
  *dtau = numer / denom;
  if (refinement_steps > 0) {
    // Refine the combined direction K (sol2 + dtau sol1) = rhs2 + dtau rhs1 once, instead of
    // refining sol1 and sol2 separately (a solve and two products less per iteration).
    sol2 += *dtau * sol1;
    rhs2 += *dtau * rhs1;
    internal::RefinementSettings settings;
    settings.tolerance = options.refinement_tolerance;
    settings.floor = refinement_floor;
    settings.stagnation = options.refinement_stagnation;
    settings.max_steps = refinement_steps;
    refinement_counter += kkt->Refine(rhs2, sol2, settings);
    dx = sol2.head(n);
    dy = sol2.segment(n, p);
    dz = sol2.segment(n + p, m);
  } else {
    dx = sol2.head(n) + *dtau * sol1.head(n);
    dy = sol2.segment(n, p) + *dtau * sol1.segment(n, p);
    dz = sol2.segment(n + p, m) + *dtau * sol1.segment(n + p, m);
  }
  // ds = -W (lambda \ d_s) - W'W dz, so W^{-1} ds = -(lambda \ d_s) - W dz.
  const double cone_step = cones.CompleteDirection(dz, ldiv, dtmp2, dz_aff, ds, ds_aff);
  *dkappa = -(d_kappa + kappa * *dtau) / tau;
  return cone_step;
}

// Step to the boundary, computed in the scaled space: s + a ds in K iff lambda + a W^{-1} ds in K,
// and z + a dz in K iff lambda + a W dz in K (W maps K onto K). lambda is well centered, so the root
// of the cone's quadratic is well conditioned there, unlike at s or z themselves.
double Solver::Workspace::MaxStep(double cone_step, double dtau, double dkappa) const {
  double alpha = cone_step;
  if (dtau < 0.0) alpha = std::min(alpha, -tau / dtau);
  if (dkappa < 0.0) alpha = std::min(alpha, -kappa / dkappa);
  return alpha;
}

// The exact step keeps the iterate inside the cones, but rounding can put a nearly active cone on its
// boundary (e.g. s0 - ||s1|| of a cone with large entries); the step is shortened until the new point
// is strictly interior so that the next scaling exists.
bool Solver::Workspace::FindInteriorStep(const Options& options, double dtau, double dkappa, double* step) {
  for (int trial = 0; trial < options.max_step_trials && *step >= options.min_step; ++trial) {
    if (tau + *step * dtau > 0.0 && kappa + *step * dkappa > 0.0) {
      dtmp1 = s + *step * ds;
      dtmp3 = z + *step * dz;
      if (cones.StrictlyInterior(dtmp1.data()) && cones.StrictlyInterior(dtmp3.data())) return true;
    }
    *step *= 0.5;
  }
  return false;
}

}  // namespace timeopt::conic
