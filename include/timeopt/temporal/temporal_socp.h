#pragma once

// The second-order cone program of the SOCP backend, for other conic solvers.

#include "timeopt/conic/problem.h"
#include "timeopt/temporal/temporal_problem.h"

namespace timeopt {

// The conic program the SOCP backend solves for `problem` (see socp_backend.cpp for its variables
// and cones): variables x (the free values of b = sdot^2 on the grid), then c, d and, when rho > 0,
// t; its optimal value is the result's objective J. Exposed so that the same problem can be handed
// to another conic solver, e.g. written with conic::WriteCbf. A jerk-limited problem
// (limits.max_jerk set) is solved as a sequence of convex programmes, one per linearization of its
// jerk rows; for it this is the same problem without the jerk limit (its paper or certified rows
// on K cells per piece). Throws std::invalid_argument for an invalid problem (the message names
// the field) and when there is no program to build: presolve already proves the problem
// infeasible, or every grid value is fixed.
conic::Problem BuildTemporalSocp(const TemporalProblem& problem);

}  // namespace timeopt
