// Status and method names, Result::BriefReport and the check of SolverOptions.

#include "timeopt/conic/solver.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "timeopt/core/enum_strings.h"

namespace timeopt::conic {

const char* ToString(Status status) {
  switch (status) {
    case Status::kOptimal:
      return "optimal";
    case Status::kPrimalInfeasible:
      return "primal_infeasible";
    case Status::kDualInfeasible:
      return "dual_infeasible";
    case Status::kIterationLimit:
      return "iteration_limit";
    case Status::kNumericalError:
      return "numerical_error";
    case Status::kNotSolved:
      return "not_solved";
  }
  return "unknown";
}

const char* ToString(KktMethod method) {
  switch (method) {
    case KktMethod::kAutomatic:
      return "automatic";
    case KktMethod::kAugmentedSparse:
      return "augmented_sparse";
    case KktMethod::kReducedBanded:
      return "reduced_banded";
  }
  return "unknown";
}

bool FromString(const std::string& text, Status* status) { return EnumFromString(text, kStatuses, status); }

bool FromString(const std::string& text, KktMethod* method) { return EnumFromString(text, kKktMethods, method); }

std::string Result::BriefReport() const {
  char buffer[320];
  std::snprintf(buffer, sizeof(buffer),
                "%s: primal %.10g dual %.10g gap %.2e pres %.2e dres %.2e, %d iterations, %.3f ms", ToString(status),
                primal_objective, dual_objective, gap, primal_residual, dual_residual, iterations,
                1e3 * solve_time_seconds);
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
  if (!(max_solve_time_seconds > 0.0)) return fail("max_solve_time_seconds must be positive");
  if (!(step_fraction > 0.0 && step_fraction < 1.0)) return fail("step_fraction must be in (0, 1)");
  if (!(min_step > 0.0 && min_step < 1.0)) return fail("min_step must be in (0, 1)");
  if (!(reduced_feasibility_tolerance >= 0.0)) return fail("reduced_feasibility_tolerance must be >= 0");
  if (!(reduced_gap_tolerance >= 0.0)) return fail("reduced_gap_tolerance must be >= 0");
  if (stall_iterations < 1) return fail("stall_iterations must be >= 1");
  if (max_factor_bytes < 0) return fail("max_factor_bytes must be >= 0 (0: no limit)");
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
  if (reduced_max_expanded_cones < 0) return fail("reduced_max_expanded_cones must be >= 0");
  if (reduced_max_profile_per_row < 1) return fail("reduced_max_profile_per_row must be >= 1");
  if (slow_phase_stall_factor < 1) return fail("slow_phase_stall_factor must be >= 1");
  if (max_regularization_boosts < 0) return fail("max_regularization_boosts must be >= 0");
  if (!(regularization_boost_factor > 1.0 && std::isfinite(regularization_boost_factor))) {
    return fail("regularization_boost_factor must be > 1 and finite");
  }
  if (max_step_trials < 1) return fail("max_step_trials must be >= 1");
  if (!(lookback_merit >= 0.0)) return fail("lookback_merit must be >= 0");
  if (!(lookback_min_step >= 0.0 && lookback_min_step <= 1.0)) return fail("lookback_min_step must be in [0, 1]");
  if (!(divergence_merit_factor > 1.0)) return fail("divergence_merit_factor must be > 1");
  return true;
}

}  // namespace timeopt::conic
