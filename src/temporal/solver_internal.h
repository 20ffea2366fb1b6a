#pragma once

// Library-internal: the temporal skeleton's finishing step, shared by the one-solve path
// (temporal_solver.cpp) and the jerk-limited sequential convex programme (jerk_solver.cpp).

#include <vector>

#include "timeopt/temporal/discretization.h"
#include "timeopt/temporal/temporal_result.h"

namespace timeopt::internal {

// In a backend's message of an infeasible verdict that is only local (Ipopt on the exact jerk
// rows, which are not convex): the jerk-limited solve then asks the convex problem without them.
inline constexpr const char* kLocalVerdict = "this is a local verdict";

// Fills total_time, objective, piece_durations, profile and the dense feasibility ratios (with a
// jerk limit, max_jerk_ratio too) of an optimal result from the discretization's free values x.
// May throw std::invalid_argument when the values make no profile.
void FinishOptimalResult(const TemporalProblem& problem, const TemporalDiscretization& d,
                         const std::vector<double>& x, TemporalResult* result);

}  // namespace timeopt::internal
