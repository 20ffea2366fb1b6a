#pragma once

// Library-internal: why a temporal problem is infeasible, and the closest boundary speeds that
// are not (TemporalResult::infeasibility, TemporalProblem::relax_boundary; temporal_solver.cpp).

#include <optional>
#include <string>

#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/temporal/temporal_result.h"

namespace timeopt::internal {

// The boundary velocities scaled by these factors (<= 1) make the problem feasible.
struct RelaxedSpeeds {
  double start_factor = 1.0;
  double end_factor = 1.0;
};

// The cause of an infeasible problem, from reachability along the path where its rows make a
// chain (the paper's and certified rows without lambda_a or a jerk limit), else from `message`
// (the presolve's or the solver's). Sets *relaxed when lowering the boundary speeds helps.
TemporalResult::Infeasibility DiagnoseInfeasible(const TemporalProblem& problem, const std::string& message,
                                                 std::optional<RelaxedSpeeds>* relaxed);

}  // namespace timeopt::internal
