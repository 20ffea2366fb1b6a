#include "termination.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "internal_problem.h"

namespace timeopt::conic::internal {

Termination::Decision Termination::Check(const IterateMeasures& it, int iteration, double step, bool reduced_method,
                                         const CertificateData& data, const std::function<double()>& elapsed_seconds) {
  Decision decision;
  auto stop = [&decision](Status status, std::string message) {
    decision.action = Action::kStop;
    decision.status = status;
    decision.message = std::move(message);
    return decision;
  };
  if (!std::isfinite(it.pres) || !std::isfinite(it.dres) || !std::isfinite(it.gap) || !std::isfinite(it.mu)) {
    return stop(Status::kNumericalError, "non-finite iterate");
  }
  const double pd_gap = std::abs(it.pcost - it.dcost);
  const double gap_scale = std::min(std::abs(it.pcost), std::abs(it.dcost));
  const bool gap_ok =
      (it.gap <= options_.absolute_gap_tolerance || it.gap <= options_.relative_gap_tolerance * gap_scale) &&
      (pd_gap <= options_.absolute_gap_tolerance || pd_gap <= options_.relative_gap_tolerance * gap_scale);
  if (it.pres <= options_.feasibility_tolerance && it.dres <= options_.feasibility_tolerance && gap_ok) {
    return stop(Status::kOptimal, "tolerances met");
  }
  if (!CheckMerit(it, pd_gap, gap_scale, iteration, step, reduced_method, &decision)) return decision;
  if (it.kappa > it.tau && CheckInfeasibility(it, data, options_, &decision)) return decision;
  if (iteration >= options_.max_iterations) return stop(Status::kIterationLimit, "max_iterations reached");
  if (elapsed_seconds() > options_.max_solve_time_seconds) {
    return stop(Status::kIterationLimit, "max_solve_time_seconds reached");
  }
  return decision;
}

bool Termination::CheckMerit(const IterateMeasures& it, double pd_gap, double gap_scale, int iteration, double step,
                             bool reduced_method, Decision* decision) {
  const double worst_gap = std::max(it.gap, pd_gap);
  const double gap_merit =
      std::min(worst_gap / options_.absolute_gap_tolerance, worst_gap / (options_.relative_gap_tolerance * gap_scale));
  const double merit =
      std::max({it.pres / options_.feasibility_tolerance, it.dres / options_.feasibility_tolerance, gap_merit});
  // Lookback: a full step from an iterate near the tolerances that does not end the solve may have
  // traded one criterion for another (the gap met, the primal residual spoiled by rounding in the
  // last solves); the midpoint of that step often meets all of them. It is measured once per step
  // (no KKT solve; the callback sees the iteration number again) and the iteration goes on from it.
  if (best_iteration_ == iteration - 1 && !looked_back_ && best_merit_ <= options_.lookback_merit &&
      step > options_.lookback_min_step) {
    looked_back_ = true;
    decision->action = Action::kLookback;
    return false;
  }
  looked_back_ = false;
  if (merit < best_merit_) {
    best_iteration_ = iteration;
    best_merit_ = merit;
    have_best_ = true;
    decision->save_best = true;
    // The reduced tolerances never ask for more than the strict ones.
    const double reduced_feas = std::max(options_.reduced_feasibility_tolerance, options_.feasibility_tolerance);
    const double reduced_gap =
        std::max({options_.reduced_gap_tolerance, options_.absolute_gap_tolerance, options_.relative_gap_tolerance});
    best_reduced_ok_ = it.pres <= reduced_feas && it.dres <= reduced_feas &&
                       (worst_gap <= reduced_gap || worst_gap <= reduced_gap * gap_scale);
  }
  // Progress: the merit or mu halved since the last mark (mu alone keeps falling on infeasible
  // problems, whose merit does not, until a certificate is found).
  if (merit < 0.5 * progress_merit_ || it.mu < 0.5 * progress_mu_) {
    progress_merit_ = std::min(progress_merit_, merit);
    progress_mu_ = std::min(progress_mu_, it.mu);
    progress_iteration_ = iteration;
  }
  // Near the optimum a jump of the merit (see divergence_merit_factor) is rounding taking over (the
  // KKT solves lose the last digits as the scaling degenerates), not a phase that recovers: stop at
  // once and return the best iterate instead of wandering until the stall window closes.
  if (best_reduced_ok_ && merit > options_.divergence_merit_factor * best_merit_) {
    if (!reduced_method) {
      decision->action = Action::kStop;
      decision->status = Status::kNumericalError;
      char factor[32];
      std::snprintf(factor, sizeof(factor), "%g", options_.divergence_merit_factor);
      decision->message =
          std::string("the merit rose ") + factor + "-fold from the best iterate (rounding near the optimum)";
      return false;
    }
    // The reduced method forms G'W^{-2}G, whose rounding can spoil the direction when the scaling
    // is extreme (seen on small random SOCPs: the dual residual jumped from 2e-7 to 4e-2 and no
    // refinement recovered it). The augmented system does not form it: back to the best iterate,
    // and on with that method.
    progress_merit_ = best_merit_;
    progress_iteration_ = iteration;
    decision->action = Action::kSwitchToAugmented;
    return false;
  }
  // Near the optimum (the best iterate meets the reduced tolerances) a short stall ends the
  // iteration; elsewhere slow phases are normal, so the window is longer.
  const int window =
      best_reduced_ok_ ? options_.stall_iterations : options_.slow_phase_stall_factor * options_.stall_iterations;
  if (iteration - progress_iteration_ >= window) {
    decision->action = Action::kStop;
    decision->status = Status::kNumericalError;
    decision->message = "no progress in " + std::to_string(window) + " iterations";
    return false;
  }
  return true;
}

bool Termination::CheckInfeasibility(const IterateMeasures& it, const CertificateData& data,
                                     const SolverOptions& options, Decision* decision) {
  const int n = static_cast<int>(data.Aty.size());
  const int p = static_cast<int>(data.Ax.size());
  const int m = static_cast<int>(data.s.size());
  // Primal infeasibility: b'y + h'z < 0 with A'y + G'z ~ 0.
  const double bz = it.by + it.hz;
  if (bz < 0.0) {
    data.scratch_n = data.Aty + data.Gtz;
    const double res = NormInf(data.scratch_n.data(), n) / -bz;
    if (res <= options.infeasibility_tolerance) {
      decision->action = Action::kStop;
      decision->status = Status::kPrimalInfeasible;
      decision->message = "certificate of primal infeasibility found";
      return true;
    }
  }
  // Dual infeasibility: c'x < 0 with A x ~ 0 and G x + s ~ 0.
  if (it.cx < 0.0) {
    data.scratch_m = data.Gx + data.s;
    const double res = std::max(NormInf(data.Ax.data(), p), NormInf(data.scratch_m.data(), m)) / -it.cx;
    if (res <= options.infeasibility_tolerance) {
      decision->action = Action::kStop;
      decision->status = Status::kDualInfeasible;
      decision->message = "certificate of dual infeasibility (unboundedness) found";
      return true;
    }
  }
  return false;
}

bool Termination::FallBackToBest(Status* status, std::string* message, bool* reduced_accuracy) const {
  if (!((*status == Status::kNumericalError || *status == Status::kIterationLimit) && have_best_)) return false;
  if (best_reduced_ok_) {
    *message = "reduced accuracy (" + *message + "; the best iterate meets the reduced tolerances)";
    *status = Status::kOptimal;
    *reduced_accuracy = true;
  }
  return true;
}

}  // namespace timeopt::conic::internal
