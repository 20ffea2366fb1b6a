#pragma once

// The second-order cone program of the SOCP backend, for other conic solvers.

#include "timeopt/conic/problem.h"
#include "timeopt/temporal/discretization.h"

namespace timeopt {

// The conic program the SOCP backend solves (see socp_backend.cpp for its variables and cones):
// variables x (the discretization's free values), then c, d and, when rho > 0, t; its optimal value
// is the objective J of the discretization. Exposed so that the same problem can be handed to another
// conic solver, e.g. written with conic::WriteCbf. Throws std::invalid_argument when there is no
// program to build: presolve already proved d infeasible, or every grid value is fixed.
conic::Problem BuildTemporalSocp(const TemporalDiscretization& d);

}  // namespace timeopt
